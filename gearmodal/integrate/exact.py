"""The exact event-driven piecewise-linear integrator (DESIGN 3.2).

Two propagators of the same exact solution: ``propagator="taylor"`` (the default,
:mod:`gearmodal.integrate.taylor`) and ``"expm"``, described here.

Between contact-state changes the system is linear and is propagated exactly by matrix
exponentials (first-order hold on the force, :mod:`gearmodal.integrate.system`). Every contact
has a gap linear in the state, so at the ends of any propagated piece its value and rate are
known exactly. A piece is searched for a state change when, for some contact, the gap changes
sign, or its rate changes sign from approaching to receding and the Hermite cubic through the
end values and rates reaches within ``GRAZE_MARGIN`` of contact (a brief contact or graze,
two crossings inside one piece). Pieces are never longer than half the fastest period of the
current contact state (``rho(A_s) h <= pi``), so that every modal component of a gap has at
most one extremum per piece; with ``dt`` below that no step is split. A flagged piece is
halved with the cached exact propagators of the next dyadic level until it is within the
Taylor reach of the exact solution, where the root is located on the Taylor series of the
exact solution to machine precision. The state is switched there, the event logged, and
propagation continues to the next output time. ``dt`` is a propagation and output step, never a
limit on what is detected.
"""

from __future__ import annotations

import weakref

import numpy as np

from ..errors import ModelError, SolveError
from .bundles import GapRows, Levels, StateODE
from .kernels import GRAZE_MARGIN, SIMULTANEOUS, advance_state, fast_steps
from .loads import force_at
from .stretch import Stretch
from .system import TAYLOR_TERMS, PiecewiseLinearSystem, Propagators
from .taylor import TaylorIntegrator

#: how the exact method propagates a contact state: "taylor" (series of the exact solution,
#: all in numba, no per-state setup) or "expm" (cached augmented exponentials per state)
PROPAGATORS = ("taylor", "expm")
#: the integrators of each system (the method owns them, the system is a value): callers that
#: advance one system in several calls (a stepper) keep its propagators and bounds
_INTEGRATORS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def shared_bounds(system: PiecewiseLinearSystem) -> tuple:
    """``(spectral bound, per-state bounds)`` the Taylor propagator computed for ``system``,
    which a system differing from it only in its speed terms may reuse
    (``PiecewiseLinearSystem(spectral_bound=..., state_bound=...)``); ``(None, None)`` when it
    has not run on it."""
    for integ in _INTEGRATORS.get(system, {}).values():
        if isinstance(integ, TaylorIntegrator):
            return integ.shared
    return None, None

#: samples of the Taylor polynomial used to bracket the first root inside a Taylor piece
TAYLOR_SAMPLES = 33


class ExactIntegrator:
    """Exact propagation with event detection for one frozen piecewise-linear system.

    Parameters
    ----------
    system : the first-order system (speed frozen).
    dt : output and propagation step, s.
    max_events_per_step : cap on state changes inside one step; exceeding it raises a
        :class:`ModelError` naming the contact (tooth chatter or a Zeno sequence).
    """

    def __init__(self, system: PiecewiseLinearSystem, dt: float, max_events_per_step: int = 200):
        self._sys = weakref.ref(system)  # weakly, as TaylorIntegrator's
        self.dt = float(dt)
        self.prop = Propagators(system, dt)
        self.max_events = int(max_events_per_step)
        self.n = system.n

    @property
    def sys(self) -> PiecewiseLinearSystem:
        """The system (held weakly)."""
        return self._sys()

    def stacks(self, s):
        """Per-state arrays for the numba kernel: propagators of dyadic levels 0..J (filled
        lazily), constant-force terms, and the flags of which levels exist."""
        d = self.prop.state(s)
        st = d.get("stack")
        if st is None:
            J = self.prop.taylor_level(s)
            N, m = 2 * self.n, self.sys.MinvU.shape[1]
            st = {"J": J, "resolve": self.prop.resolve_level(s),
                  "PHI": np.zeros((J + 1, N, N)), "G0": np.zeros((J + 1, N, m)),
                  "G1": np.zeros((J + 1, N, m)), "FS": np.zeros((J + 1, N)),
                  "have": np.zeros(J + 1, dtype=bool), "sgn": np.where(s, -1.0, 1.0)}
            # the kernels' bundles, once per state (the arrays fill in place), as plain
            # tuples (bundles.py)
            st["levels"] = tuple(Levels(st["PHI"], st["G0"], st["G1"], st["FS"], st["have"]))
            st["ode"] = tuple(StateODE(d["A"], self.sys.MinvU, d["f"]))
            st["gaps"] = tuple(GapRows(self.sys.W, self.sys.offset, st["sgn"]))
            st["tol"] = (st["resolve"], J, GRAZE_MARGIN, TAYLOR_TERMS, TAYLOR_SAMPLES,
                         SIMULTANEOUS * self.dt)
            d["stack"] = st
        return d, st

    def fill(self, s, j):
        d, st = self.stacks(s)
        Phi, G0, G1 = self.prop.level(s, j)
        st["PHI"][j], st["G0"][j], st["G1"][j] = Phi, G0, G1
        st["FS"][j] = (G0 + G1) @ d["f"]
        st["have"][j] = True

    def advance(self, x, s, t, t_end, F0, F1, events):
        """Advance from ``t`` to ``t_end`` inside the output step that starts at ``t`` (force
        linear from F0 to F1 over it) with every state change; returns (x, s)."""
        tk = t
        count = 0
        sysm = self.sys
        while True:
            _, st = self.stacks(s)
            status, t_new, x_new, mask, level = advance_state(
                st["levels"], st["ode"], st["gaps"], x, t, t_end, tk, F0, F1, self.dt,
                st["tol"])
            if status == 2:
                self.fill(s, int(level))
                continue
            x, t = x_new, t_new
            if status == 0:
                return x, s
            same = np.flatnonzero(mask)
            s = self._switch(t, x, s, same, events)
            count += len(same)
            if count > self.max_events:
                name = sysm.names[int(same[0])]
                raise SolveError(
                    "max_events_per_step",
                    f"more than {self.max_events} contact-state changes inside one step "
                    f"ending near t = {t:.9g} s, last at contact {name!r} (tooth chatter or a "
                    "Zeno sequence); reduce dt, add damping, or raise max_events_per_step")

    def _switch(self, te, x, s, same, events):
        s = s.copy()
        p = self.sys.penetration(x)
        r = self.sys.rate(x)
        for e in same:
            before = bool(s[e])
            s[e] = not before
            force = (self.sys.k[e] * max(p[e], 0.0) + self.sys.c[e] * r[e]) if s[e] else 0.0
            events.append((te, int(e), before, bool(s[e]), float(r[e]), float(force)))
        return s


def _check_finite(X: np.ndarray, dt: float) -> None:
    if not np.all(np.isfinite(X)):
        bad = int(np.flatnonzero(~np.all(np.isfinite(X), axis=1))[0])
        raise SolveError("simulate", f"the solution is not finite at t = {bad * dt:.9g} s")


def run_exact(stretch: Stretch, max_events_per_step: int = 200, propagator: str = "taylor"):
    """Integrate ``stretch`` (:class:`~gearmodal.integrate.stretch.Stretch`):
    ``n_steps`` steps of ``dt`` from ``x0`` in contact state ``s0``.

    ``F`` (n_steps + 1, n) is the generalised force at the output times (linear in
    between); with an input basis on the system it must lie in it (checked). Returns
    ``(X, S, events, stats)``: states (n_steps + 1, 2n), contact states
    (n_steps + 1, n_contacts), events as rows (time, contact, before, after, rate, force):
    an (n, 6) array from the Taylor propagator, a list of tuples from ``"expm"``.

    ``propagator``: ``"taylor"`` (default) sums the Taylor series of the exact solution in
    numba from every event and over pieces of ``rho h <= 6`` (:mod:`gearmodal.integrate.taylor`;
    no per-state setup, the event loop never returns to Python); ``"expm"`` propagates with
    augmented exponentials cached per contact state and dyadic step (``ExactIntegrator``;
    ~170 us per new state, then one product per output step). Both are exact to rounding;
    ``"expm"`` pays off only when few contact states recur over many steps with ``dt`` much
    longer than the fastest period.

    ``azimuth0``: input azimuth at the start, rad; with alternating mesh stiffness
    (``Mesh.alternation``) the Taylor propagator switches each flank's stiffness at its
    scheduled times exactly (time events); ``"expm"`` does not support it.

    ``loads``: forces on their own time structure (:class:`~gearmodal.integrate.driver.Method`),
    which the Taylor propagator follows exactly (pieces end at their knots, harmonics are in
    every piece's series); ``"expm"`` holds them linear over each output step (sampled at the
    output times: its solution then depends on ``dt``).

    ``peaks``: a :class:`~gearmodal.integrate.peaks.PeakTracker` the Taylor propagator
    accumulates the exact peaks in (``t0``: the run's time at this call's start, s); ``"expm"``
    marks it sampled (``peaks.exact = False``).

    ``k_org``: the call continues a run at its output step ``k_org``
    (:class:`~gearmodal.integrate.driver.Method`, which gives it to the Taylor propagator
    only): ``azimuth0`` and the loads' times from the run's start, and the events' times
    returned; the propagator walks the pieces one call would. ``t_span``: the call's start
    and end times, when not ``k dt`` (a stepper's re-basing grid).
    """
    system, dt, n_steps = stretch.system, stretch.dt, stretch.n_steps
    F_grid, x0, s0 = stretch.F, stretch.x0, stretch.s0
    loads, peaks = stretch.loads, stretch.peaks
    system.asm.require_piecewise_linear("method='exact'")
    if propagator not in PROPAGATORS:
        raise ModelError("propagator", f"= {propagator!r}: must be one of "
                         + ", ".join(map(repr, PROPAGATORS)))
    if propagator == "expm" and system.turning:
        raise ModelError("propagator", "= 'expm' propagates frozen matrices and cannot follow "
                         "turning geometry (frames turning against each other at speed); use "
                         "propagator='taylor'")
    if propagator == "expm" and system.alternating:
        raise ModelError("propagator", "= 'expm' caches propagators per contact state and "
                         "cannot follow an alternating mesh stiffness (Mesh.alternation); use "
                         "propagator='taylor'")
    # the propagators belong to the frozen system: callers that advance one system in several
    # calls (the turbine co-simulation) keep them
    key = (propagator, float(dt), int(max_events_per_step))
    cache = _INTEGRATORS.setdefault(system, {})
    integ = cache.get(key)
    if integ is None:
        kind = TaylorIntegrator if propagator == "taylor" else ExactIntegrator
        integ = cache[key] = kind(system, dt, max_events_per_step)
    if peaks is not None and propagator != "taylor":
        peaks.exact = False
    if loads is not None and propagator != "taylor":
        F_grid = F_grid + force_at(loads, np.arange(n_steps + 1) * dt)
        loads = None
    F_grid = system.reduce(np.ascontiguousarray(F_grid, dtype=float))  # input basis, if any
    if propagator == "taylor":
        X, S, events = integ.run(n_steps, F_grid, x0, s0, stretch.azimuth0, loads, peaks,
                                 stretch.t0, stretch.k_org, stretch.t_span)
        _check_finite(X, dt)
        return X, S, events, {"exponentials": 0, **integ.counts}
    prop = integ.prop
    n_exp0, n_states0 = prop.n_exponentials, len(prop._states)
    X = np.empty((n_steps + 1, 2 * system.n))
    S = np.empty((n_steps + 1, system.n_contacts), dtype=bool)
    X[0], S[0] = x0, s0
    x, s = x0.astype(float).copy(), s0.copy()
    events: list = []
    k = 0
    while k < n_steps:
        if prop.resolve_level(s) == 0:
            # whole steps in this state, in numba, until a step may hold an event
            d, st = integ.stacks(s)
            if not st["have"][0]:
                integ.fill(s, 0)
            k_new = fast_steps(st["PHI"][0], st["G0"][0], st["G1"][0], st["FS"][0], F_grid, k,
                               n_steps, x, st["gaps"], GRAZE_MARGIN, dt, X)
            S[k + 1:k_new + 1] = s
            k = k_new
            if k == n_steps:
                break
        x, s = integ.advance(x, s, k * dt, (k + 1) * dt, F_grid[k], F_grid[k + 1], events)
        X[k + 1], S[k + 1] = x, s
        k += 1
    _check_finite(X, dt)
    stats = {"exponentials": prop.n_exponentials - n_exp0,
             "states": len(prop._states) - n_states0}
    return X, S, events, stats
