"""Time integration of the piecewise-linear contact model: ``gm.simulate`` (DESIGN 3.2).

One function in front, interchangeable methods behind it:

- ``method="exact"``: event-driven exact propagation (:mod:`.exact`);
- ``method="newmark"``: Newmark average acceleration, fixed step, events by interpolation
  (:mod:`.newmark`);
- ``method="scipy"``: ``scipy.integrate.solve_ivp`` with event functions (:mod:`.scipy_ref`;
  options ``scipy_method``, ``rtol``, ``atol`` pass through).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable

import numpy as np
import pandas as pd

from ..assembly import Assembly
from ..errors import ModelError
from ..model.model import Model
from .exact import run_exact
from .newmark import run_newmark
from .result import EVENT_COLUMNS, SimulationResult
from .scipy_ref import run_scipy
from .system import PiecewiseLinearSystem

METHODS = {"exact": run_exact, "newmark": run_newmark, "scipy": run_scipy}

__all__ = ["METHODS", "SimulationResult", "simulate"]


def _load_grid(asm: Assembly, loads, t: np.ndarray) -> np.ndarray:
    """Load values (n_times, n_loads) on the time grid from constants, callables of time or
    pandas Series indexed by time (linear interpolation, ends held)."""
    U = np.zeros((len(t), len(asm.load_names)))
    for name, val in (loads or {}).items():
        if name not in asm.load_names:
            raise ModelError(f"loads.{name}", "no such load; available: "
                             + ", ".join(asm.load_names))
        j = asm.load_names.index(name)
        if isinstance(val, pd.Series):
            idx = np.asarray(val.index, dtype=float)
            if len(idx) < 1 or np.any(np.diff(idx) <= 0):
                raise ModelError(f"loads.{name}", "a Series must be indexed by increasing time")
            U[:, j] = np.interp(t, idx, val.to_numpy(dtype=float))
        elif callable(val):
            U[:, j] = [float(val(tt)) for tt in t]
        else:
            try:
                U[:, j] = float(val)
            except (TypeError, ValueError):
                raise ModelError(f"loads.{name}", f"= {val!r}: expected a number (N or N m), a "
                                 "callable of time or a pandas Series") from None
        if not np.all(np.isfinite(U[:, j])):
            raise ModelError(f"loads.{name}", "has non-finite values")
    return U


def _initial(asm: Assembly, values, label: str) -> np.ndarray:
    out = np.zeros(asm.n)
    for name, val in (values or {}).items():
        if name not in asm.dof_names:
            raise ModelError(f"{label}.{name}", "no such DOF; available: "
                             + ", ".join(asm.dof_names))
        out[asm.dof_names.index(name)] = float(val)
    return out


def simulate(model, t_end: float, *, dt: float, loads: dict | None = None,
             q0: dict | None = None, v0: dict | None = None, method: str = "exact",
             speed_rpm: float = 0.0, **options) -> SimulationResult:
    """Simulate the nonlinear contact dynamics of ``model`` from 0 to ``t_end`` (s).

    Parameters
    ----------
    model : :class:`gearmodal.Model` (or an :class:`Assembly`).
    t_end : end time, s. dt : propagation and output step, s (the exact method detects every
        state change inside a step regardless of ``dt``).
    loads : ``{load name: value}`` with a constant, a callable of time or a pandas Series
        indexed by time (linear in between); N or N m.
    q0, v0 : initial displacements and velocities by DOF name (others 0). The initial contact
        state follows from ``q0`` (a contact is closed when it penetrates).
    method : ``"exact"``, ``"newmark"`` or ``"scipy"``.
    speed_rpm : input speed at which gyroscopic/centripetal terms are frozen.
    options : method options: ``max_events_per_step`` (exact), ``scipy_method``, ``rtol``,
        ``atol`` (scipy).

    Examples
    --------
    >>> import math, gearmodal as gm
    >>> p = gm.Gear(20, 0.004, math.radians(20), mass=1.0, inertia=1e-3)
    >>> w = gm.Gear(40, 0.004, math.radians(20), mass=4.0, inertia=1.6e-2)
    >>> pair = gm.gear_pair(p, w, mesh_stiffness=2e8, backlash=1e-4)
    >>> sim = gm.simulate(pair, 0.01, dt=1e-4, v0={"pinion.theta": 1.0})
    >>> sim.events[["element", "contact", "state_after"]].head(2).values.tolist()
    [['mesh', 'front', 'closed'], ['mesh', 'front', 'open']]
    """
    if method not in METHODS:
        raise ModelError("method", f"= {method!r}: must be one of {', '.join(map(repr, METHODS))}")
    for label, val in (("t_end", t_end), ("dt", dt)):
        if not isinstance(val, (int, float)) or isinstance(val, bool) or not math.isfinite(val) \
                or val <= 0:
            raise ModelError(label, f"= {val!r}: must be a finite number > 0 s")
    n_steps = int(math.ceil(t_end / dt - 1e-9))
    if n_steps > 50_000_000:
        raise ModelError("dt", f"= {dt!r}: {n_steps} steps to {t_end} s is more than 5e7")
    if isinstance(model, Assembly):
        asm, name = model, ""
    elif isinstance(model, Model):
        asm, name = model.assemble(), model.name
    else:
        raise TypeError(f"expected a gm.Model, got {type(model).__name__}")
    system = PiecewiseLinearSystem(asm, speed_rpm)
    t = np.arange(n_steps + 1) * dt
    U = _load_grid(asm, loads, t)
    F = U @ asm.B.T + system.f_const[None, :]
    x0 = np.concatenate([_initial(asm, q0, "q0"), _initial(asm, v0, "v0")])
    s0 = system.penetration(x0) > 0
    runner: Callable = METHODS[method]
    cpu = time.process_time()
    X, S, events, stats = runner(system, dt, n_steps, F, x0, s0, **options)
    stats = {**stats, "cpu_s": time.process_time() - cpu, "n_events": len(events),
             "n_steps": n_steps}
    return _result(system, t, X, S, events, s0, stats,
                   {"model": name, "method": method, "t_end": t_end, "dt": dt,
                    "speed_rpm": speed_rpm, "options": options,
                    "loads": {k: (v if isinstance(v, (int, float)) else type(v).__name__)
                              for k, v in (loads or {}).items()},
                    "q0": q0 or {}, "v0": v0 or {}})


def _result(system, t, X, S, events, s0, stats, settings) -> SimulationResult:
    asm = system.asm
    n = system.n
    q = pd.DataFrame(X[:, :n], index=pd.Index(t, name="time"), columns=asm.dof_names)
    v = pd.DataFrame(X[:, n:], index=q.index, columns=asm.dof_names)
    c = asm.contacts
    P = X[:, :n] @ system.W.T - system.offset
    R = X[:, n:] @ system.W.T
    Fc = np.where(S, system.k * P + system.c * R, 0.0)
    cols: dict[str, np.ndarray] = {}
    for e, (el, ct, kind) in enumerate(zip(c.element, c.contact, c.kind, strict=True)):
        if kind == "mesh":
            cols[f"{el}.{ct}"] = Fc[:, e]
        else:
            key = f"{el}.{ct[:-1]}"
            sign = 1.0 if ct.endswith("+") else -1.0
            cols[key] = cols.get(key, 0.0) + sign * Fc[:, e]
    sp = asm.springs
    if sp is not None and len(sp):
        Fs = (X[:, :n] @ sp.W.T) * sp.stiffness + (X[:, n:] @ sp.W.T) * sp.damping
        for e, (el, ct) in enumerate(zip(sp.element, sp.contact, strict=True)):
            cols[f"{el}.{ct}"] = Fs[:, e]
    forces = pd.DataFrame(cols, index=q.index)
    rows = [(te, c.element[e], c.contact[e], "closed" if b else "open",
             "closed" if a else "open", r, f) for te, e, b, a, r, f in events]
    ev = pd.DataFrame(rows, columns=EVENT_COLUMNS)
    state = pd.DataFrame(S, index=q.index, columns=system.names)
    init = {system.names[e]: bool(s0[e]) for e in range(len(s0))}
    return SimulationResult(t=t, q=q, v=v, forces=forces, events=ev, contact_state=state,
                            settings=settings, initial_state=init, stats=stats)
