"""The turbine side (DESIGN 2.5): wind, rotor aerodynamics, generator, start-up and operation,
and the elastic turbine's structure (DESIGN 2.5a: :mod:`.structure`, :func:`nrel5mw.flexible`).

>>> import gearmodal as gm
>>> tb = gm.turbine.load_turbine("studies/turbines/600kw_turbine.toml")
>>> run = gm.turbine.simulate_turbine(tb, gm.turbine.Wind(mean_speed=10.0), 20.0)
>>> 10.0 < run.cut_in_time < 14.0
True
"""

from .airfoil import Airfoil
from .drivetrain import DrivetrainResult, simulate_drivetrain
from .generator import InductionGenerator
from .rotor import LOAD_COLUMNS, Rotor
from .turbine import Turbine, TurbineResult, load_turbine, simulate_turbine
from .wind import Wind

#: submodules loaded on first use (``gm.turbine.nrel5mw.flexible()``): they pull in the deck
#: readers and pybmodes, which a gearbox-only session does not need
_LAZY = ("nrel5mw", "structure", "bodies", "elastodyn", "assumed_modes")


def __getattr__(name: str):
    if name in _LAZY:
        import importlib

        return importlib.import_module(f"{__name__}.{name}")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = ["LOAD_COLUMNS", "Airfoil", "DrivetrainResult", "InductionGenerator", "Rotor",
           "Turbine", "TurbineResult", "Wind", "load_turbine", "simulate_drivetrain",
           "simulate_turbine"]
