"""``scipy.integrate.solve_ivp`` reference method with one event function per contact.

Within a contact state the right-hand side is ``A_s x + Bm F(t)``; every contact's penetration
is an event function (terminal, direction set by its state). At an event the state switches and
the solver restarts from the located point. Its limits, as documented by SciPy: events are
found from sign changes between the solver's own steps, so two crossings inside one solver step
(a brief contact, a graze) are missed, and the accuracy is that of ``rtol``/``atol``.
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp

from ..errors import ModelError
from .system import PiecewiseLinearSystem


def run_scipy(system: PiecewiseLinearSystem, dt: float, n_steps: int, F_grid: np.ndarray,
              x0: np.ndarray, s0: np.ndarray, scipy_method: str = "RK45", rtol: float = 1e-6,
              atol: float = 1e-12, max_events: int = 10_000_000, **options):
    n = system.n
    t_grid = np.arange(n_steps + 1) * dt
    X = np.empty((n_steps + 1, 2 * n))
    S = np.empty((n_steps + 1, system.n_contacts), dtype=bool)
    X[0], S[0] = x0, s0
    x, s, t = x0.astype(float).copy(), s0.copy(), 0.0
    events = []
    filled = 1
    nfev = 0
    muted: set = set()  # contacts whose event is ignored for one short restart span
    while filled <= n_steps:
        A, f = system.first_order(s)

        def rhs(tt, xx, A=A, f=f, Minv=system.Minv):
            k = min(int(tt / dt), n_steps - 1)
            w = tt / dt - k
            F = F_grid[k] * (1 - w) + F_grid[k + 1] * w + f
            out = A @ xx
            out[n:] += Minv @ F
            return out

        def make(e, active):
            def ev(tt, xx):
                return system.W[e] @ xx[:n] - system.offset[e]
            ev.terminal = True
            ev.direction = -1.0 if active else 1.0
            return ev

        evs = [make(e, bool(s[e])) for e in range(system.n_contacts) if e not in muted]
        idx = [e for e in range(system.n_contacts) if e not in muted]
        # a contact switched while tangent (gap and rate ~ 0) would fire again at the restart
        # point and flip forever: its event is muted over a span of 1e-6 dt after the restart
        t_stop = min(t + 1e-6 * dt, t_grid[-1]) if muted else t_grid[-1]
        t_eval = t_grid[filled:]
        t_eval = t_eval[t_eval <= t_stop]
        try:
            sol = solve_ivp(rhs, (t, t_stop), x, method=scipy_method,
                            t_eval=None if muted else t_eval, dense_output=bool(muted),
                            events=evs or None, rtol=rtol, atol=atol, **options)
        except ValueError as err:  # scipy's own event root-finding can fail on flat events
            raise ModelError("simulate", f"scipy ({scipy_method}) event location failed at "
                             f"t = {t:.9g} s: {err}") from None
        nfev += sol.nfev
        if not sol.success and sol.status != 1:
            raise ModelError("simulate", f"scipy ({scipy_method}) failed: {sol.message}")
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
            if m:
                X[filled:filled + m] = np.asarray(sol.y).T
        if m:
            S[filled:filled + m] = s
            filled += m
        if sol.status != 1:
            if muted:  # the short muted span ended without an event: continue normally
                x, t = np.asarray(sol.y)[:, -1].copy(), t_stop
                # a muted contact whose state no longer matches its gap switches now
                p, r = system.penetration(x), system.rate(x)
                for e in sorted(muted):
                    if (p[e] > 0) != s[e]:
                        s = s.copy()
                        s[e] = not s[e]
                        force = system.k[e] * max(p[e], 0.0) + system.c[e] * r[e] if s[e] \
                            else 0.0
                        events.append((float(t), int(e), not s[e], bool(s[e]), float(r[e]),
                                       float(force)))
                muted = set()
                continue
            break
        # the earliest event(s)
        te = min(tt[0] for tt in sol.t_events if len(tt))
        fired_k = [k for k, tt in enumerate(sol.t_events) if len(tt) and tt[0] <= te]
        x = sol.y_events[fired_k[0]][0].copy()
        fired = [idx[k] for k in fired_k]
        if abs(te - t) <= 1e-12 * dt:
            muted |= set(fired)  # no progress since the restart: tangent contacts
        else:
            muted = set()
        r = system.rate(x)
        for e in fired:
            before = bool(s[e])
            s = s.copy()
            s[e] = not before
            force = system.c[e] * r[e] if s[e] else 0.0
            events.append((float(te), int(e), before, bool(s[e]), float(r[e]), float(force)))
        if len(events) > max_events:
            raise ModelError("simulate", f"scipy: more than {max_events} events")
        t = float(te)
    return X, S, events, {"nfev": nfev}
