"""Load a saved run of either kind: a directory written by ``SimulationResult.save`` or by a
turbine run's ``DrivetrainResult.save`` (the stores of :func:`gearmodal.sweep` and the fidelity
ladder keep results so)."""

from __future__ import annotations

from pathlib import Path

from .integrate import SimulationResult
from .turbine import DrivetrainResult

__all__ = ["load_run"]


def load_run(directory) -> SimulationResult | DrivetrainResult:
    """The run saved in ``directory``: a :class:`~gearmodal.turbine.DrivetrainResult` when it
    holds one (``drivetrain.json``), else a :class:`~gearmodal.SimulationResult`."""
    d = Path(directory)
    if (d / "drivetrain.json").exists():
        return DrivetrainResult.load(d)
    return SimulationResult.load(d)
