"""``scipy.integrate.solve_ivp`` reference method with one event function per contact.

Within a contact state the right-hand side is ``A_s x + Bm F(t)``; every contact's penetration
is an event function (terminal, direction set by its state). At an event the state switches and
the solver restarts from the located point. Its limits, as documented by SciPy: events are
found from sign changes between the solver's own steps, so two crossings inside one solver step
(a brief contact, a graze) are missed, and the accuracy is that of ``rtol``/``atol``.

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
from .loads import force_at
from .system import PiecewiseLinearSystem

#: crossings within this fraction of ``dt`` of a located event (and at least within the event
#: location's tolerance) switch with it: ``solve_ivp`` misses a root at its restart point
#: once rounding has put the restart state past it
TIE = 1e-9


def run_scipy(system: PiecewiseLinearSystem, dt: float, n_steps: int, F_grid: np.ndarray,
              x0: np.ndarray, s0: np.ndarray, scipy_method: str = "RK45", rtol: float = 1e-6,
              atol: float = 1e-12, max_events: int = 10_000_000, azimuth0: float = 0.0,
              loads=None, **options):
    from scipy.integrate import solve_ivp  # here: scipy.integrate and what it loads cost a
    # process 30 MB that a run of another method need not pay

    n = system.n
    turning = system.turning
    if turning and system.asm.round is not None:
        raise ModelError("method", "= 'scipy' does not integrate a round clearance on turning "
                         "geometry")

    def azimuth(tt):
        return azimuth0 + system.omega * tt

    t_grid = np.arange(n_steps + 1) * dt
    X = np.empty((n_steps + 1, 2 * n))
    S = np.empty((n_steps + 1, system.n_contacts), dtype=bool)
    X[0], S[0] = x0, s0
    x, s, t = x0.astype(float).copy(), s0.copy(), 0.0
    events = []
    filled = 1
    nfev = 0
    muted: set = set()  # contacts whose event is ignored for one short restart span
    # contacts resting on their gap (gap and rate exactly zero, the acceleration not across):
    # left out for a span that grows tenfold each time one is found resting again, from
    # 1e-6 dt (a pair at rest on a flank, no loads, restarted 1e-6 dt apart for ever: 1 ms did
    # not end in 20 s); when the span ends a contact whose gap has crossed switches then
    resting: dict[int, float] = {}  # contact -> time its event is armed again
    rest_span: dict[int, float] = {}  # contact -> its last resting span
    nc = system.n_contacts
    rd = _Round(system)
    sr = rd.radius(x) > rd.c  # round clearances in contact (indices nc + b in events)
    # alternating mesh stiffness: the solver restarts at every scheduled change
    ks = np.array(system.stiffness_at(azimuth0), dtype=float)
    sched_t, sched_e, sched_k = system.schedule(azimuth0, n_steps * dt)
    ip = 0
    while filled <= n_steps:
        while ip < len(sched_t) and sched_t[ip] <= t + 1e-13 * dt:
            ks[sched_e[ip]] = sched_k[ip]
            ip += 1
        woken = [e for e, tw in resting.items() if tw <= t]
        if woken:  # armed again: a gap that crossed while left out switches now
            pw, rw = system.penetration(x, azimuth(t)), system.rate(x, azimuth(t))
            wvw = system.velocity_term(x, azimuth(t))
            for e in woken:
                del resting[e]
                if (pw[e] > 0) != s[e]:
                    s = s.copy()
                    s[e] = not s[e]
                    rest_span.pop(e, None)
                    force = ks[e] * max(pw[e], 0.0) + system.c[e] * wvw[e] if s[e] else 0.0
                    events.append((float(t), int(e), not s[e], bool(s[e]), float(rw[e]),
                                   float(force)))
        A, f = system.first_order(s, ks)

        sr_now = sr.copy()  # the round clearances' state over this restart span

        ks_now = ks.copy()

        def rhs(ti, xx, A=A, f=f, Minv=system.Minv, sr=sr_now, s=s, ks=ks_now):
            k = min(int(ti / dt), n_steps - 1)
            w = ti / dt - k
            u = F_grid[k] * (1 - w) + F_grid[k + 1] * w
            if loads is not None:  # loads on their own time structure, at this instant
                u = u + force_at(loads, ti)[0]
            if turning:  # the time-varying system at this instant's azimuth
                A, f = system.first_order(s, ks, system.at(azimuth(ti)))
            F = system.generalized_force(u, azimuth(ti)) + f
            if rd.nr:
                F = F + rd.force(xx, sr)
            out = A @ xx
            out[n:] += Minv @ F
            return out

        def make(e, active):
            def ev(ti, xx):
                if turning:
                    fr = system.at(azimuth(ti))
                    return fr["W"][e] @ xx[:n] - fr["offset"][e]
                return system.W[e] @ xx[:n] - system.offset[e]
            ev.terminal = True
            ev.direction = -1.0 if active else 1.0
            return ev

        def make_round(b, active):
            def ev(tt, xx):
                return rd.radius(xx)[b] - rd.c[b]
            ev.terminal = True
            ev.direction = -1.0 if active else 1.0
            return ev

        idx = [e for e in range(nc + rd.nr) if e not in muted and e not in resting]
        evs = [make(e, bool(s[e])) if e < nc else make_round(e - nc, bool(sr[e - nc]))
               for e in idx]
        # a contact switched while tangent (gap and rate ~ 0) would fire again at the restart
        # point and flip forever: its event is muted over a span of 1e-6 dt after the restart
        t_stop = min(t + 1e-6 * dt, t_grid[-1]) if muted else t_grid[-1]
        if ip < len(sched_t):
            t_stop = min(t_stop, sched_t[ip])
        waking = [tr for tr in resting.values() if tr > t]
        if waking:  # a resting contact's event is armed again there
            t_stop = min(t_stop, min(waking))
        t_eval = t_grid[filled:]
        t_eval = t_eval[t_eval <= t_stop]
        # a span ending at a scheduled change also returns the state there
        extra = not muted and t_stop < t_grid[-1] and not (len(t_eval) and t_eval[-1] == t_stop)
        try:
            sol = solve_ivp(rhs, (t, t_stop), x, method=scipy_method,
                            t_eval=None if muted else (np.append(t_eval, t_stop) if extra
                                                        else t_eval),
                            dense_output=bool(muted),
                            events=evs or None, rtol=rtol, atol=atol, **options)
        except ValueError as err:  # scipy's own event root-finding can fail on flat events
            raise SolveError("simulate", f"scipy ({scipy_method}) event location failed at "
                             f"t = {t:.9g} s: {err}") from None
        nfev += sol.nfev
        if not sol.success and sol.status != 1:
            raise SolveError("simulate", f"scipy ({scipy_method}) failed: {sol.message}")
        if muted:
            t_end_span = sol.t_events and min((tt[0] for tt in sol.t_events if len(tt)),
                                              default=t_stop)
            t_end_span = t_stop if sol.status != 1 else t_end_span
            inside = t_eval[t_eval <= t_end_span]
            m = len(inside)
            if m:
                X[filled:filled + m] = sol.sol(inside).T
        else:
            m = len(sol.t)
            if extra and m and sol.t[-1] == t_stop:
                m -= 1  # the change's time, not an output time
            if m:
                X[filled:filled + m] = np.asarray(sol.y)[:, :m].T
        if m:
            S[filled:filled + m] = s
            filled += m
        if sol.status != 1:
            if muted:  # the short muted span ended without an event: continue normally
                x, t = np.asarray(sol.y)[:, -1].copy(), t_stop
                # a muted contact whose state no longer matches its gap switches now
                p, r = system.penetration(x, azimuth(t)), system.rate(x, azimuth(t))
                wv = system.velocity_term(x, azimuth(t))
                for e in sorted(muted):
                    if e >= nc:
                        sr = rd.switch(x, sr, e - nc, float(t), nc, events, check=True)
                        continue
                    if (p[e] > 0) != s[e]:
                        s = s.copy()
                        s[e] = not s[e]
                        force = ks[e] * max(p[e], 0.0) + system.c[e] * wv[e] if s[e] \
                            else 0.0
                        events.append((float(t), int(e), not s[e], bool(s[e]), float(r[e]),
                                       float(force)))
                muted = set()
                continue
            if t_stop < t_grid[-1]:  # at a scheduled stiffness change
                x, t = np.asarray(sol.y)[:, -1].copy(), float(t_stop)
                continue
            break
        # the earliest event(s)
        te = min(tt[0] for tt in sol.t_events if len(tt))
        fired_k = [k for k, tt in enumerate(sol.t_events) if len(tt) and tt[0] <= te]
        x = sol.y_events[fired_k[0]][0].copy()
        fired = [idx[k] for k in fired_k]
        if abs(te - t) <= 1e-12 * dt:
            # no progress since the restart. A contact resting on its gap (gap and rate zero)
            # whose acceleration does not carry it across does not switch: it rests until
            # the next output time
            acc = rhs(te, x)[n:]
            Wt = system.at(azimuth(te))["W"] if turning else system.W
            p0, r0 = system.penetration(x, azimuth(te)), system.rate(x, azimuth(te))
            rest = [e for e in fired if e < nc and p0[e] == 0.0 and r0[e] == 0.0
                    and ((Wt[e] @ acc >= 0.0) if s[e] else (Wt[e] @ acc <= 0.0))]
            if rest:
                for e in rest:
                    rest_span[e] = min(10.0 * rest_span.get(e, 1e-7 * dt), dt)
                    resting[e] = min(float(te) + rest_span[e], float(t_grid[-1]))
                fired = [e for e in fired if e not in rest]
                if not fired:
                    t = float(te)
                    continue
            muted |= set(fired)  # tangent contacts
        else:
            muted = set()
        r = system.rate(x, azimuth(te))
        wv = system.velocity_term(x, azimuth(te))
        # a contact at its own crossing at this instant (zero backlash: the back flank closes
        # as the front one opens) has its root at the start of the next span, which solve_ivp
        # misses once the located point's rounding has put it past the crossing: it switches
        # now, like the exact method's simultaneous roots. The window is at least the event
        # location's own tolerance (4 eps absolute and relative in time, scipy's root finder)
        p = system.penetration(x, azimuth(te))
        tie = np.abs(r) * max(TIE * dt, 16 * np.finfo(float).eps * (1.0 + abs(te)))
        tied = [e for e in range(nc) if e not in fired and abs(p[e]) <= tie[e]
                and r[e] != 0 and (r[e] > 0) != bool(s[e])]
        s = s.copy()
        for e in fired + tied:
            if e >= nc:
                sr = rd.switch(x, sr, e - nc, float(te), nc, events)
                continue
            before = bool(s[e])
            s[e] = not before
            force = system.c[e] * wv[e] if s[e] else 0.0
            events.append((float(te), int(e), before, bool(s[e]), float(r[e]), float(force)))
        if len(events) > max_events:
            raise SolveError("simulate", f"scipy: more than {max_events} events")
        t = float(te)
    return X, S, events, {"nfev": nfev}


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
