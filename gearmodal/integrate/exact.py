"""The exact event-driven piecewise-linear integrator (DESIGN 3.2).

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

import numpy as np
from scipy.optimize import brentq

from ..errors import ModelError
from .system import PiecewiseLinearSystem, Propagators, taylor_eval

#: a receding gap whose Hermite interpolant comes this close to contact (relative to the
#: change of the gap over the piece) is examined for a hidden brief contact
GRAZE_MARGIN = 0.25
#: samples of the Taylor polynomial used to bracket the first root inside a Taylor piece
TAYLOR_SAMPLES = 33
#: crossings closer than this fraction of dt are switched together (symmetric planets)
SIMULTANEOUS = 1e-13


def _hermite_max(g0, d0, g1, d1, L):
    """Maximum over [0, L] of the cubic Hermite interpolant (vectorised)."""
    # H(t) = a t^3 + b t^2 + c t + g0 on t in [0, 1], derivatives scaled by L
    c = d0 * L
    a = 2 * g0 - 2 * g1 + c + d1 * L
    b = -3 * g0 + 3 * g1 - 2 * c - d1 * L
    best = np.maximum(g0, g1)
    qa, qb, qc = 3 * a, 2 * b, c
    disc = qb * qb - 4 * qa * qc
    ok = disc >= 0
    sq = np.sqrt(np.where(ok, disc, 0.0))
    for sgn in (1.0, -1.0):
        with np.errstate(divide="ignore", invalid="ignore"):
            t = np.where(np.abs(qa) > 1e-300, (-qb + sgn * sq) / (2 * qa),
                         np.where(np.abs(qb) > 1e-300, -qc / qb, 0.0))
        inside = ok & (t > 0) & (t < 1)
        val = ((a * t + b) * t + c) * t + g0
        best = np.where(inside, np.maximum(best, val), best)
    return best


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
        self.sys = system
        self.dt = float(dt)
        self.prop = Propagators(system, dt)
        self.max_events = int(max_events_per_step)
        self.n = system.n

    # -- pieces ---------------------------------------------------------------------------
    def _piece(self, s, j, x, F0, F1):
        Phi, G0, G1 = self.prop.level(s, j)
        f = self.prop.state(s)["f"]
        return Phi @ x + G0 @ (F0 + f) + G1 @ (F1 + f)

    def _candidates(self, s, xa, xb, L, exclude=None):
        """Contacts that may change state between exact end states xa, xb of a piece."""
        sysm = self.sys
        sgn = np.where(s, -1.0, 1.0)  # look for g = sgn * p becoming > 0
        ga, gb = sgn * sysm.penetration(xa), sgn * sysm.penetration(xb)
        ra, rb = sgn * sysm.rate(xa), sgn * sysm.rate(xb)
        cand = gb > 0
        graze = (ra > 0) & (rb < 0) & ~cand
        if graze.any():
            idx = np.flatnonzero(graze)
            hm = _hermite_max(ga[idx], ra[idx], gb[idx], rb[idx], L)
            scale = np.abs(ra[idx] * L) + np.abs(rb[idx] * L)
            cand[idx] = hm > -GRAZE_MARGIN * scale
        if exclude is not None:
            cand &= ~exclude
        return cand

    def _taylor_roots(self, s, x, t, L, F_of, cand):
        """First crossing time (relative) of each candidate inside [0, L] on the Taylor series
        of the exact solution at ``x``; inf where there is none."""
        F0 = F_of(t)
        dF = (F_of(t + L) - F0) / L if L > 0 else np.zeros_like(F0)
        Y = self.prop.derivatives(s, x, F0, dF)
        n = self.n
        idx = np.flatnonzero(cand)
        W = self.sys.W[idx]
        sgn = np.where(s[idx], -1.0, 1.0)
        coef = (Y[:, :n] @ W.T) * sgn  # (terms, candidates)
        coef[0] -= sgn * self.sys.offset[idx]
        taus = np.linspace(0.0, L, TAYLOR_SAMPLES)
        powers = taus[:, None] ** np.arange(len(Y))[None, :]
        vals = powers @ coef  # (samples, candidates)
        out = np.full(len(idx), np.inf)
        for c in range(len(idx)):
            g = vals[:, c]
            if g[0] > 0 and coef[1, c] > 0:
                out[c] = 0.0  # already past its crossing and moving on: switch now
                continue
            pos = np.flatnonzero((g[1:] > 0) & (g[:-1] <= 0))
            if len(pos) == 0:
                continue
            k = pos[0]
            poly = coef[:, c]

            def gfun(tau, poly=poly):
                return np.polyval(poly[::-1], tau)

            out[c] = brentq(gfun, taus[k], taus[k + 1], xtol=1e-300, rtol=4 * np.finfo(float).eps,
                            maxiter=200)
        return idx, out, Y

    def _first_event(self, s, x, t, j, xb, F_of, cand):
        """Earliest crossing inside the level-j piece [t, t + dt/2^j]; returns
        (time, indices of contacts switching, exact state there) or None."""
        jt = self.prop.taylor_level(s)
        L = self.dt / 2**j
        if j >= jt:
            idx, roots, Y = self._taylor_roots(s, x, t, L, F_of, cand)
            if not np.isfinite(roots).any():
                return None
            tau = roots.min()
            same = idx[roots <= tau + SIMULTANEOUS * self.dt]
            return t + tau, same, taylor_eval(Y, tau)
        h = L / 2
        xm = self._piece(s, j + 1, x, F_of(t), F_of(t + h))
        c1 = self._candidates(s, x, xm, h) & cand
        if c1.any():
            r = self._first_event(s, x, t, j + 1, xm, F_of, c1)
            if r is not None:
                return r
        c2 = self._candidates(s, xm, xb, h) & cand
        if c2.any():
            return self._first_event(s, xm, t + h, j + 1, xb, F_of, c2)
        return None

    def advance(self, x, s, t, t_end, F_of, events, max_events):
        """Advance from ``t`` to ``t_end`` (at most one ``dt``) with every state change inside;
        returns (x, s). ``F_of(t)`` is the (linear-in-time within the step) generalised force."""
        count = 0
        while t < t_end:
            L_total = t_end - t
            # largest dyadic piece that fits and resolves the fastest dynamics of the state
            j = self.prop.resolve_level(s)
            while self.dt / 2**j > L_total * (1 + 1e-12) and j < 62:
                j += 1
            jt = self.prop.taylor_level(s)
            if j > jt:
                # a remainder shorter than the Taylor reach: exact series, with root search
                L = L_total
                cand = np.ones(self.sys.n_contacts, dtype=bool)
                idx, roots, Y = self._taylor_roots(s, x, t, L, F_of, cand)
                if np.isfinite(roots).any():
                    tau = roots.min()
                    same = idx[roots <= tau + SIMULTANEOUS * self.dt]
                    x = taylor_eval(Y, tau)
                    t, s = self._switch(t + tau, x, s, same, events)
                    count += len(same)
                    self._check_cap(count, same, t)
                    continue
                x = taylor_eval(Y, L)
                t = t_end
                break
            L = self.dt / 2**j
            t1 = t_end if abs((t + L) - t_end) <= 1e-12 * self.dt else t + L
            xb = self._piece(s, j, x, F_of(t), F_of(t1))
            cand = self._candidates(s, x, xb, L)
            if cand.any():
                ev = self._first_event(s, x, t, j, xb, F_of, cand)
                if ev is not None:
                    te, same, xe = ev
                    x = xe
                    t, s = self._switch(te, x, s, same, events)
                    count += len(same)
                    self._check_cap(count, same, t)
                    continue
            x, t = xb, t1
        return x, s

    def _check_cap(self, count, same, t):
        if count > self.max_events:
            name = self.sys.names[int(same[0])]
            raise ModelError(
                "max_events_per_step",
                f"more than {self.max_events} contact-state changes inside one step ending "
                f"near t = {t:.9g} s, last at contact {name!r} (tooth chatter or a Zeno "
                "sequence); reduce dt, add damping, or raise max_events_per_step")

    def _switch(self, te, x, s, same, events):
        s = s.copy()
        p = self.sys.penetration(x)
        r = self.sys.rate(x)
        for e in same:
            before = bool(s[e])
            s[e] = not before
            force = (self.sys.k[e] * max(p[e], 0.0) + self.sys.c[e] * r[e]) if s[e] else 0.0
            events.append((te, int(e), before, bool(s[e]), float(r[e]), float(force)))
        return te, s


def run_exact(system: PiecewiseLinearSystem, dt: float, n_steps: int, F_grid: np.ndarray,
              x0: np.ndarray, s0: np.ndarray, max_events_per_step: int = 200):
    """Integrate ``n_steps`` steps of ``dt`` from ``x0`` in contact state ``s0``.

    ``F_grid`` (n_steps + 1, n) is the generalised force at the output times (linear in
    between). Returns ``(X, S, events, stats)``: states (n_steps + 1, 2n), contact states
    (n_steps + 1, n_contacts), events as tuples (time, contact, before, after, rate, force).
    """
    integ = ExactIntegrator(system, dt, max_events_per_step)
    X = np.empty((n_steps + 1, 2 * system.n))
    S = np.empty((n_steps + 1, system.n_contacts), dtype=bool)
    X[0], S[0] = x0, s0
    x, s = x0.astype(float).copy(), s0.copy()
    events: list = []
    for k in range(n_steps):
        t0, t1 = k * dt, (k + 1) * dt
        F0, F1 = F_grid[k], F_grid[k + 1]

        def F_of(t, t0=t0, F0=F0, F1=F1):
            return F0 + (F1 - F0) * ((t - t0) / dt)

        x, s = integ.advance(x, s, t0, t1, F_of, events, max_events_per_step)
        if not np.all(np.isfinite(x)):
            raise ModelError("simulate", f"the solution is not finite at t = {t1:.9g} s")
        X[k + 1], S[k + 1] = x, s
    stats = {"exponentials": integ.prop.n_exponentials, "states": len(integ.prop._states)}
    return X, S, events, stats
