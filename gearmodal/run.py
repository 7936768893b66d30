"""One path from a scene to a run, and the protocol every run result follows (issue 37).

:func:`run` is the one place that knows the three kinds of run a scene makes: the exact step
ladder (``method = "auto"``, :mod:`gearmodal.auto`), the turbine with its gearbox and a gearbox
alone (:func:`gearmodal.single.one_run`, which the ladder's rungs run too).
:meth:`gearmodal.scene.Scene.simulate`, ``gearmodal simulate`` and :func:`gearmodal.sweep` go
through it.

Whatever ran, the result follows :class:`RunResult`: ``gearbox`` (the
:class:`~gearmodal.SimulationResult`), ``turbine`` (the turbine's side or None), ``choice``
(the step ladder's :class:`~gearmodal.FidelityChoice` or None), ``save`` and ``plot``. A caller
reads those instead of asking what kind of result it holds.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol, runtime_checkable

from .auto import LEVELS, FidelityChoice, choose, chosen_result
from .errors import ModelError
from .single import one_run


@runtime_checkable
class RunResult(Protocol):
    """What every run result offers (module docstring)."""

    @property
    def gearbox(self) -> Any: ...

    @property
    def turbine(self) -> Any: ...

    @property
    def choice(self) -> FidelityChoice | None: ...

    def save(self, directory, format: str = "parquet") -> Path: ...

    def plot(self): ...


@dataclass
class ChosenRun:
    """The run ``method = "auto"`` chose: the chosen rung's ``result`` (a gearbox or a turbine
    run) wrapped with the ``choice`` that made it (:func:`gearmodal.auto.choose`)."""

    result: Any
    choice: FidelityChoice

    @property
    def gearbox(self):
        """The chosen rung's :class:`~gearmodal.SimulationResult`."""
        return self.result.gearbox

    @property
    def turbine(self):
        """The chosen rung's turbine side, or None."""
        return self.result.turbine

    def save(self, directory, format: str = "parquet") -> Path:
        """The chosen rung's result, and the ladder's table beside it
        (:meth:`FidelityChoice.save`)."""
        out = self.result.save(directory, format)
        self.choice.save(out)
        return out

    def plot(self):
        """The chosen rung's figure."""
        return self.result.plot()

    @property
    def auto(self) -> FidelityChoice:
        """The choice (``choice``; the name the result carried before)."""
        return self.choice

    def __getattr__(self, name: str):
        # the chosen rung's result as it was returned before (``forces``, ``stats``, ...)
        if name.startswith("__") or name in ("result", "choice"):
            raise AttributeError(name)
        return getattr(self.result, name)


def run(scene, progress: Callable[[int, int], None] | None = None, out=None,
        store=None) -> RunResult:
    """Run ``scene`` (:class:`gearmodal.scene.Scene`) and return its result.

    ``progress(i, n)``: called as the run goes (the turbine: after each aerodynamic step; the
    step ladder: after each rung, of at most ``n``); a gearbox alone runs in one call.
    ``out``: a directory the run's tables stream to (constant memory; not with ``method =
    "auto"``, whose rungs have their own ``store``). ``store``: where the step ladder keeps its
    rungs to resume (``method = "auto"`` only).
    """
    if scene.method == "auto":
        if out is not None:
            raise ModelError("out", "method = 'auto' keeps its rungs in its own store; "
                             "save the chosen result instead")
        step = None if progress is None else (lambda lv, st, row: progress(lv + 1, LEVELS))
        choice = choose(scene, scene.tolerance, store=store, progress=step)
        return ChosenRun(chosen_result(choice, "scene.tolerance"), choice)
    if store is not None:
        raise ModelError("store", "is the step ladder's (method = 'auto'); give out=DIR to "
                         "stream a run")
    return one_run(scene, progress, out)
