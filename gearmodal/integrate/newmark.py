"""Newmark-beta reference method (average acceleration, fixed step, events by interpolation).

The family of HAWC2's solver, kept to check the exact method and to measure the trade: the
contact state is held over a step and switched after it when a gap changed sign; the event time
is logged by linear interpolation of the gap between the step ends. Its limits: a contact
shorter than a step, or two crossings inside one step, go unseen, and the state switch lags by
up to one step. Each switch at a step's end puts the contact's energy at that penetration in or
takes it out, so a coarse step on stiff contacts can feed energy without bound: every step is
audited against the system's energy balance (:mod:`.energy`), a run that makes more energy than
its initial state and loads supplied stops with a :class:`~gearmodal.SolveError`, and the
balance error of a finished run is its ``energy_error``.

A turning system (``system.turning``) is stepped with its matrices, contact rows and load map
evaluated at each step's end azimuth (one factorisation per step instead of one per contact
state).
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla

from ..errors import ModelError, SolveError
from .energy import EnergyAudit
from .stretch import Stretch

BETA, GAMMA = 0.25, 0.5


def run_newmark(stretch: Stretch):
    """Integrate ``stretch`` (:class:`~gearmodal.integrate.stretch.Stretch`) with
    Newmark's average acceleration: its ``system`` from ``(x0, s0)`` over ``n_steps`` steps
    of ``dt`` with the force grid ``F`` (its loads folded into ``F`` by the driver)."""
    system, dt, n_steps = stretch.system, stretch.dt, stretch.n_steps
    F_grid, x0, s0 = stretch.F, stretch.x0, stretch.s0
    azimuth0 = stretch.azimuth0
    system.asm.require_piecewise_linear("method='newmark'")
    if system.alternating:
        raise ModelError("method", "= 'newmark' does not follow an alternating mesh stiffness "
                         "(Mesh.alternation); use method='exact' or 'scipy'")
    n = system.n
    M = system.asm.M
    h = dt
    X = np.empty((n_steps + 1, 2 * n))
    S = np.empty((n_steps + 1, system.n_contacts), dtype=bool)
    q, v = x0[:n].copy(), x0[n:].copy()
    s = s0.copy()
    X[0], S[0] = x0, s0
    events = []
    cache = {}
    turning = system.turning

    def azimuth(k):
        return azimuth0 + system.omega * k * dt

    frozen: dict = {}  # a turning system's matrices at the last output time asked for

    def at(k):
        if frozen.get("k") != k:
            frozen.update(k=k, matrices=system.at(azimuth(k)))
        return frozen["matrices"]

    def mats(s, k):
        """Matrices of state ``s`` at output time ``k`` (cached per state when frozen)."""
        key = s.tobytes()
        if turning or key not in cache:
            K, C, f = system.matrices(s, frozen=at(k) if turning else None)
            Keff = M / (BETA * h * h) + GAMMA / (BETA * h) * C + K
            cache[key] = (K, C, f, sla.lu_factor(Keff))
        return cache[key]

    def load_at(k):
        return system.generalized_force(F_grid[k], azimuth(k))

    audit = EnergyAudit.of(stretch, "newmark", _HINT.format(dt=dt))
    t0 = stretch.t0
    K, C, f, lu = mats(s, 0)
    L0 = load_at(0)
    a = np.linalg.solve(M, L0 + f - C @ v - K @ q)
    p_prev = system.penetration(x0, azimuth(0))
    for k in range(n_steps):
        K, C, f, lu = mats(s, k + 1)
        L1 = load_at(k + 1)
        F1 = L1 + f
        rhs = (F1 + M @ (q / (BETA * h * h) + v / (BETA * h) + (0.5 / BETA - 1) * a)
               + C @ (GAMMA / (BETA * h) * q + (GAMMA / BETA - 1) * v
                      + h * (GAMMA / (2 * BETA) - 1) * a))
        q1 = sla.lu_solve(lu, rhs)
        a1 = (q1 - q) / (BETA * h * h) - v / (BETA * h) - (0.5 / BETA - 1) * a
        v1 = v + h * ((1 - GAMMA) * a + GAMMA * a1)
        q, v, a = q1, v1, a1
        x = np.concatenate([q, v])
        if not np.all(np.isfinite(x)):
            raise SolveError("method", f"= 'newmark': the solution is not finite at "
                             f"t = {t0 + (k + 1) * dt:.9g} s; " + _HINT.format(dt=dt))
        audit.step(x, azimuth(k + 1), L0, L1, C, t0 + (k + 1) * dt,
                   at(k + 1)["K0"] if turning else None)
        L0 = L1
        p = system.penetration(x, azimuth(k + 1))
        new = p > 0
        changed = np.flatnonzero(new != s)
        if len(changed):
            r = system.rate(x, azimuth(k + 1))
            wv = system.velocity_term(x, azimuth(k + 1))
            for e in changed:
                frac = p_prev[e] / (p_prev[e] - p[e]) if p_prev[e] != p[e] else 1.0
                te = (k + min(max(frac, 0.0), 1.0)) * dt
                force = system.k[e] * max(p[e], 0.0) + system.c[e] * wv[e] if new[e] else 0.0
                events.append((te, int(e), bool(s[e]), bool(new[e]), float(r[e]), float(force)))
            s = new
            # the acceleration consistent with the new state starts the next step
            K, C, f, lu = mats(s, k + 1)
            a = np.linalg.solve(M, L1 + f - C @ v - K @ q)
        p_prev = p
        X[k + 1], S[k + 1] = x, s
    return X, S, events, {"states": len(cache), "energy_error": audit.error}


_HINT = ("Newmark switches contacts at step ends, which lets stiff contacts penetrate too "
         "deep and feeds them energy at a coarse step: reduce dt (now {dt:g} s) or use "
         "method='exact' (benchmarks/RESULTS.md, stability map)")
