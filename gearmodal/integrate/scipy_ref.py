"""``scipy.integrate.solve_ivp`` reference method with one event function per contact.

Within a contact state the right-hand side is ``A_s x + Bm F(t)``; every contact's penetration
is an event function (terminal, direction set by its state). At an event the state switches and
the solver restarts from the located point. Its limits, as documented by SciPy: events are
found from sign changes between the solver's own steps, so two crossings inside one solver step
(a brief contact, a graze) are missed, and the accuracy is that of ``rtol``/``atol``. A run
whose energy on its output rows grows beyond what its initial state and loads supplied (a
missed contact lets the bodies pass through it) stops with a :class:`~gearmodal.SolveError`
(:mod:`.energy`).

It is also the one method that integrates the exactly round bearing clearance
(``clearance_shape="round"``, (R1) of :mod:`gearmodal.model.clearance`): a nonlinear force
``k (|d| - c) + c_d |d|'`` along ``d / |d|`` while in contact, with ``|d| - c`` as one more
event function; its events are logged with contact ``radial``.

An alternating mesh stiffness (``Mesh.alternation``) is followed by ending the solver's span
at every scheduled change and restarting with the new stiffness (exact switching times).

A turning system (frames turning against each other, ``system.turning``) is integrated as the
time-varying system it is: stiffness, damping, contact rows and load map evaluated at each
instant's azimuth (:meth:`PiecewiseLinearSystem.at`), independently of the exact method's
series, which it checks.
"""

from __future__ import annotations

import numpy as np

from ..errors import ModelError, SolveError
from .energy import audit_rows
from .loads import force_at
from .stretch import Stretch
from .system import PiecewiseLinearSystem

#: crossings within this fraction of ``dt`` of a located event (and at least within the event
#: location's tolerance) switch with it: ``solve_ivp`` misses a root at its restart point
#: once rounding has put the restart state past it
TIE = 1e-9


def run_scipy(stretch: Stretch, scipy_method: str = "RK45", rtol: float = 1e-6, atol: float = 1e-12,
              max_events: int = 10_000_000, **options):
    """Integrate ``stretch`` (:class:`~gearmodal.integrate.stretch.Stretch`: its ``system``
    from ``(x0, s0)`` over ``n_steps`` output steps of ``dt``, with its ``F``, ``azimuth0``
    and ``loads``) with ``solve_ivp`` (``scipy_method``, ``rtol``, ``atol``, ``options``),
    restarting at every contact event and scheduled stiffness change; returns the states at
    the output times, the contact states there, the event log and ``{"nfev"}``."""
    from scipy.integrate import solve_ivp  # here: scipy.integrate and what it loads cost a
    # process 30 MB that a run of another method need not pay

    system, n_steps = stretch.system, stretch.n_steps
    if system.turning and system.asm.round is not None:
        raise ModelError("method", "= 'scipy' does not integrate a round clearance on turning "
                         "geometry")
    run = _Run(system, stretch.dt, n_steps, stretch.F, stretch.x0, stretch.s0, stretch.azimuth0,
               stretch.loads)

    def solve(rhs, span, x, t_eval, dense, events):
        try:
            return solve_ivp(rhs, span, x, method=scipy_method, t_eval=t_eval,
                             dense_output=dense, events=events, rtol=rtol, atol=atol,
                             **options)
        except ValueError as err:  # scipy's own event root-finding can fail on flat events
            raise SolveError("simulate", f"scipy ({scipy_method}) event location failed at "
                             f"t = {span[0]:.9g} s: {err}") from None

    while run.filled <= n_steps:
        run.apply_schedule()
        run.wake()
        rhs = run.rhs()
        idx = [e for e in range(run.nc + run.rd.nr)
               if e not in run.muted and e not in run.resting]
        t_stop, t_eval, extra = run.span_end()
        sol = solve(rhs, (run.t, t_stop), run.x, None if run.muted else
                    (np.append(t_eval, t_stop) if extra else t_eval), bool(run.muted),
                    run.event_functions(idx) or None)
        run.nfev += sol.nfev
        if not sol.success and sol.status != 1:
            raise SolveError("simulate", f"scipy ({scipy_method}) failed: {sol.message}")
        run.keep_rows(sol, t_eval, t_stop, extra)
        if sol.status != 1:
            if run.muted:  # the short muted span ended without an event: continue normally
                run.end_muted(sol, t_stop)
                continue
            if t_stop < run.t_grid[-1]:  # at a scheduled stiffness change
                run.x, run.t = np.asarray(sol.y)[:, -1].copy(), float(t_stop)
                continue
            break
        run.at_event(sol, idx, rhs)
        if len(run.events) > max_events:
            raise SolveError("simulate", f"scipy: more than {max_events} events")
    F = stretch.F if stretch.loads is None else stretch.F + force_at(stretch.loads,
                                                                     run.t_grid)
    audit_rows(stretch, run.X, run.S, F, "scipy",
               f"its events were located at rtol = {rtol:g} (a contact missed or crossed "
               "late lets the bodies pass through it): tighten rtol or use method='exact'")
    return run.X, run.S, run.events, {"nfev": run.nfev}


class _Run:
    """The state of one :func:`run_scipy` run between its restarts: the solution so far (rows
    ``X``, ``S``, the event log), the current point ``(t, x)`` and contact state ``s`` (and the
    round clearances' ``sr``), the stiffness schedule, and the contacts left out of a span:
    ``muted`` (switched while tangent: left out for 1e-6 dt after the restart) and ``resting``
    (on their gap with gap and rate exactly zero and the acceleration not across: left out for
    a span that grows tenfold each time one is found resting again, from 1e-6 dt: a pair at
    rest on a flank, no loads, restarted 1e-6 dt apart for ever: 1 ms did not end in 20 s;
    when the span ends a contact whose gap has crossed switches then)."""

    def __init__(self, system, dt, n_steps, F_grid, x0, s0, azimuth0, loads):
        self.system, self.dt, self.n_steps, self.F_grid = system, dt, n_steps, F_grid
        self.azimuth0, self.loads = azimuth0, loads
        self.n, self.nc, self.turning = system.n, system.n_contacts, system.turning
        self.t_grid = np.arange(n_steps + 1) * dt
        self.X = np.empty((n_steps + 1, 2 * self.n))
        self.S = np.empty((n_steps + 1, self.nc), dtype=bool)
        self.X[0], self.S[0] = x0, s0
        self.x, self.s, self.t = x0.astype(float).copy(), s0.copy(), 0.0
        self.events: list = []
        self.filled, self.nfev = 1, 0
        self.muted: set = set()
        self.resting: dict[int, float] = {}  # contact -> time its event is armed again
        self.rest_span: dict[int, float] = {}  # contact -> its last resting span
        self.rd = _Round(system)
        self.sr = self.rd.radius(self.x) > self.rd.c  # round clearances in contact
        # alternating mesh stiffness: the solver restarts at every scheduled change
        self.ks = np.array(system.stiffness_at(azimuth0), dtype=float)
        self.sched = system.schedule(azimuth0, n_steps * dt)
        self.ip = 0

    def azimuth(self, tt):
        return self.azimuth0 + self.system.omega * tt

    def apply_schedule(self) -> None:
        """The stiffness changes scheduled up to now."""
        sched_t, sched_e, sched_k = self.sched
        while self.ip < len(sched_t) and sched_t[self.ip] <= self.t + 1e-13 * self.dt:
            self.ks[sched_e[self.ip]] = sched_k[self.ip]
            self.ip += 1

    def _flip(self, e, p, r, wv, t) -> bool:
        """Switch contact ``e`` to the side of its gap ``p`` and log it (rate ``r``, velocity
        term ``wv``), where it no longer matches; whether it switched."""
        if (p[e] > 0) != self.s[e]:
            self.s = self.s.copy()
            self.s[e] = not self.s[e]
            force = (self.ks[e] * max(p[e], 0.0) + self.system.c[e] * wv[e]) if self.s[e] \
                else 0.0
            self.events.append((float(t), int(e), not self.s[e], bool(self.s[e]),
                                float(r[e]), float(force)))
            return True
        return False

    def wake(self) -> None:
        """Resting contacts armed again: a gap that crossed while left out switches now."""
        woken = [e for e, tw in self.resting.items() if tw <= self.t]
        if not woken:
            return
        sy, az = self.system, self.azimuth(self.t)
        p, r, wv = sy.penetration(self.x, az), sy.rate(self.x, az), sy.velocity_term(self.x, az)
        for e in woken:
            del self.resting[e]
            if self._flip(e, p, r, wv, self.t):
                self.rest_span.pop(e, None)

    def rhs(self):
        """The right-hand side over the coming span (its contact states and stiffnesses)."""
        sy, n, dt, n_steps, F_grid = self.system, self.n, self.dt, self.n_steps, self.F_grid
        loads, turning, rd, azimuth = self.loads, self.turning, self.rd, self.azimuth
        A, f = sy.first_order(self.s, self.ks)
        Minv, sr, s, ks = sy.Minv, self.sr.copy(), self.s, self.ks.copy()  # this span's

        def rhs(ti, xx, A=A, f=f):
            k = min(int(ti / dt), n_steps - 1)
            w = ti / dt - k
            u = F_grid[k] * (1 - w) + F_grid[k + 1] * w
            if loads is not None:  # loads on their own time structure, at this instant
                u = u + force_at(loads, ti)[0]
            if turning:  # the time-varying system at this instant's azimuth
                A, f = sy.first_order(s, ks, sy.at(azimuth(ti)))
            F = sy.generalized_force(u, azimuth(ti)) + f
            if rd.nr:
                F = F + rd.force(xx, sr)
            out = A @ xx
            out[n:] += Minv @ F
            return out
        return rhs

    def event_functions(self, idx) -> list:
        """One terminal event per contact in ``idx`` (round clearances from ``nc`` on), its
        direction set by the contact's state."""
        sy, n, rd, turning, azimuth = self.system, self.n, self.rd, self.turning, self.azimuth

        def make(e, active):
            def ev(ti, xx):
                if turning:
                    fr = sy.at(azimuth(ti))
                    return fr["W"][e] @ xx[:n] - fr["offset"][e]
                return sy.W[e] @ xx[:n] - sy.offset[e]
            ev.terminal = True
            ev.direction = -1.0 if active else 1.0
            return ev

        def make_round(b, active):
            def ev(tt, xx):
                return rd.radius(xx)[b] - rd.c[b]
            ev.terminal = True
            ev.direction = -1.0 if active else 1.0
            return ev

        return [make(e, bool(self.s[e])) if e < self.nc
                else make_round(e - self.nc, bool(self.sr[e - self.nc])) for e in idx]

    def span_end(self):
        """Where the coming span ends (the run's end, a muted span's 1e-6 dt, the next scheduled
        change or a resting contact's waking), the output times inside it, and whether the end
        must be returned as well (a scheduled change between output times)."""
        t, t_grid = self.t, self.t_grid
        # a contact switched while tangent (gap and rate ~ 0) would fire again at the restart
        # point and flip forever: its event is muted over a span of 1e-6 dt after the restart
        t_stop = min(t + 1e-6 * self.dt, t_grid[-1]) if self.muted else t_grid[-1]
        sched_t = self.sched[0]
        if self.ip < len(sched_t):
            t_stop = min(t_stop, sched_t[self.ip])
        waking = [tr for tr in self.resting.values() if tr > t]
        if waking:  # a resting contact's event is armed again there
            t_stop = min(t_stop, min(waking))
        t_eval = t_grid[self.filled:]
        t_eval = t_eval[t_eval <= t_stop]
        # a span ending at a scheduled change also returns the state there
        extra = (not self.muted and t_stop < t_grid[-1]
                 and not (len(t_eval) and t_eval[-1] == t_stop))
        return t_stop, t_eval, extra

    def keep_rows(self, sol, t_eval, t_stop, extra) -> None:
        """The span's output rows (a muted span's from its dense output, up to its end)."""
        if self.muted:
            t_end_span = sol.t_events and min((tt[0] for tt in sol.t_events if len(tt)),
                                              default=t_stop)
            t_end_span = t_stop if sol.status != 1 else t_end_span
            inside = t_eval[t_eval <= t_end_span]
            m = len(inside)
            if m:
                self.X[self.filled:self.filled + m] = sol.sol(inside).T
        else:
            m = len(sol.t)
            if extra and m and sol.t[-1] == t_stop:
                m -= 1  # the change's time, not an output time
            if m:
                self.X[self.filled:self.filled + m] = np.asarray(sol.y)[:, :m].T
        if m:
            self.S[self.filled:self.filled + m] = self.s
            self.filled += m

    def end_muted(self, sol, t_stop) -> None:
        """A muted span that ended without an event: a muted contact whose state no longer
        matches its gap switches now."""
        self.x, self.t = np.asarray(sol.y)[:, -1].copy(), t_stop
        sy, az = self.system, self.azimuth(t_stop)
        p, r, wv = sy.penetration(self.x, az), sy.rate(self.x, az), sy.velocity_term(self.x, az)
        for e in sorted(self.muted):
            if e >= self.nc:
                self.sr = self.rd.switch(self.x, self.sr, e - self.nc, float(t_stop), self.nc,
                                         self.events, check=True)
            else:
                self._flip(e, p, r, wv, t_stop)
        self.muted = set()

    def _rest(self, te, fired, rhs) -> list:
        """No progress since the restart: a contact resting on its gap (gap and rate zero)
        whose acceleration does not carry it across does not switch, it rests (its span grown
        tenfold); returns the contacts that switch."""
        sy, n, x, az = self.system, self.n, self.x, self.azimuth(te)
        acc = rhs(te, x)[n:]
        Wt = sy.at(az)["W"] if self.turning else sy.W
        p0, r0 = sy.penetration(x, az), sy.rate(x, az)
        rest = [e for e in fired if e < self.nc and p0[e] == 0.0 and r0[e] == 0.0
                and ((Wt[e] @ acc >= 0.0) if self.s[e] else (Wt[e] @ acc <= 0.0))]
        for e in rest:
            self.rest_span[e] = min(10.0 * self.rest_span.get(e, 1e-7 * self.dt), self.dt)
            self.resting[e] = min(float(te) + self.rest_span[e], float(self.t_grid[-1]))
        return [e for e in fired if e not in rest]

    def at_event(self, sol, idx, rhs) -> None:
        """The earliest event(s) of the span: the contacts that fired (and those tied with
        them) switch there and are logged."""
        te = min(tt[0] for tt in sol.t_events if len(tt))
        fired_k = [k for k, tt in enumerate(sol.t_events) if len(tt) and tt[0] <= te]
        self.x = x = sol.y_events[fired_k[0]][0].copy()
        fired = [idx[k] for k in fired_k]
        if abs(te - self.t) <= 1e-12 * self.dt:
            fired = self._rest(te, fired, rhs)
            if not fired:
                self.t = float(te)
                return
            self.muted |= set(fired)  # tangent contacts
        else:
            self.muted = set()
        sy, nc, az = self.system, self.nc, self.azimuth(te)
        r, wv = sy.rate(x, az), sy.velocity_term(x, az)
        # a contact at its own crossing at this instant (zero backlash: the back flank closes
        # as the front one opens) has its root at the start of the next span, which solve_ivp
        # misses once the located point's rounding has put it past the crossing: it switches
        # now, like the exact method's simultaneous roots. The window is at least the event
        # location's own tolerance (4 eps absolute and relative in time, scipy's root finder)
        p = sy.penetration(x, az)
        tie = np.abs(r) * max(TIE * self.dt, 16 * np.finfo(float).eps * (1.0 + abs(te)))
        tied = [e for e in range(nc) if e not in fired and abs(p[e]) <= tie[e]
                and r[e] != 0 and (r[e] > 0) != bool(self.s[e])]
        self.s = self.s.copy()
        for e in fired + tied:
            if e >= nc:
                self.sr = self.rd.switch(x, self.sr, e - nc, float(te), nc, self.events)
                continue
            before = bool(self.s[e])
            self.s[e] = not before
            force = sy.c[e] * wv[e] if self.s[e] else 0.0
            self.events.append((float(te), int(e), before, bool(self.s[e]), float(r[e]),
                                float(force)))
        self.t = float(te)


class _Round:
    """The round clearances of a system (pairs of x/y rows of ``asm.round``), R1."""

    def __init__(self, system: PiecewiseLinearSystem):
        rd = system.asm.round
        self.n = system.n
        self.nr = 0 if rd is None else len(rd) // 2
        if self.nr:
            self.W = rd.W
            self.c = rd.offset[::2]
            self.k = rd.stiffness[::2]
            self.cd = rd.damping[::2]
        else:
            self.c = np.zeros(0)

    def radius(self, x: np.ndarray) -> np.ndarray:
        """|d| of each clearance (..., nr) for states ``x`` (..., 2n), m."""
        if not self.nr:
            return np.zeros(x.shape[:-1] + (0,))
        d = x[..., :self.n] @ self.W.T
        return np.hypot(d[..., 0::2], d[..., 1::2])

    def forces(self, x: np.ndarray, sr: np.ndarray) -> np.ndarray:
        """(..., nr, 2): the x/y force of each clearance on its deflection (0 where open), N,
        for states ``x`` (..., 2n) and contact flags ``sr`` (..., nr)."""
        d = x[..., :self.n] @ self.W.T
        dv = x[..., self.n:] @ self.W.T
        dx, dy, vx, vy = d[..., 0::2], d[..., 1::2], dv[..., 0::2], dv[..., 1::2]
        r = np.hypot(dx, dy)
        safe = np.where(r > 0, r, 1.0)
        ux, uy = dx / safe, dy / safe
        fr = np.where(sr, self.k * (r - self.c) + self.cd * (ux * vx + uy * vy), 0.0)
        return np.stack([fr * ux, fr * uy], axis=-1)

    def force(self, x: np.ndarray, sr: np.ndarray) -> np.ndarray:
        """Generalised force of the round clearances (they push back: ``-W^T f``)."""
        return -(self.W.T @ self.forces(x, sr).ravel())

    def switch(self, x, sr, b, t, nc, events, check=False):
        """Toggle clearance ``b`` (if ``check``: only where its state no longer matches)."""
        r = self.radius(x)[b]
        if check and (r > self.c[b]) == sr[b]:
            return sr
        sr = sr.copy()
        sr[b] = not sr[b]
        f = self.forces(x, sr)[b]
        d = self.W @ x[:self.n]
        dv = self.W @ x[self.n:]
        rate = (d[2 * b] * dv[2 * b] + d[2 * b + 1] * dv[2 * b + 1]) / max(r, 1e-300)
        events.append((t, nc + b, not sr[b], bool(sr[b]), float(rate),
                       float(np.hypot(*f))))
        return sr
