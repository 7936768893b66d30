"""A scene's one run (no step ladder): the turbine with its gearbox
(:func:`gearmodal.turbine.simulate_drivetrain`) or the gearbox alone (:func:`gearmodal.simulate`).
:func:`gearmodal.run.run` makes it for a scene, :func:`gearmodal.auto.choose` for each rung.
"""

from __future__ import annotations

from collections.abc import Callable

from .integrate import simulate
from .turbine import simulate_drivetrain

__all__ = ["one_run"]


def one_run(scene, progress: Callable[[int, int], None] | None = None, out=None):
    """Run ``scene`` (:class:`gearmodal.scene.Scene`) once with its method (not ``"auto"``):
    a :class:`~gearmodal.turbine.DrivetrainResult` with a turbine, else a
    :class:`~gearmodal.SimulationResult`. ``progress``, ``out``: as :func:`gearmodal.run.run`."""
    if scene.turbine is not None:
        return simulate_drivetrain(scene.turbine, scene.wind, scene.model, scene.t_end,
                                   dt=scene.dt, method=scene.method, progress=progress,
                                   out=out, **scene.drivetrain, **scene.options)
    return simulate(scene.model, scene.t_end, dt=scene.dt, loads=scene.loads,
                    q0=scene.initial_q(), v0=scene.v0, method=scene.method,
                    speed_rpm=scene.speed_rpm, out=out, **scene.options)
