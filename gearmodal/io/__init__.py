"""Reading and writing: loads from aeroelastic codes' output files."""

from .aeroelastic import (
    OPENFAST_SHAFT,
    read_hawc2,
    read_loads,
    read_openfast,
    shaft_loads,
    si_factor,
)

__all__ = ["OPENFAST_SHAFT", "read_hawc2", "read_loads", "read_openfast", "shaft_loads",
           "si_factor"]
