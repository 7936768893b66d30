"""Numba hot loops of the exact integrator (compiled with ``cache=True``).

:func:`fast_steps` propagates whole output steps in one contact state while no contact is a
candidate for a state change; the first step that might hold an event is handed back to the
Python event logic (:mod:`gearmodal.integrate.exact`), which uses the same candidate test
(:func:`candidate`).
"""

from __future__ import annotations

import math

import numba
import numpy as np

#: a receding gap whose Hermite interpolant comes this close to contact (relative to the
#: change of the gap over the piece) is examined for a hidden brief contact (both propagators)
GRAZE_MARGIN = 0.25
#: crossings closer than this fraction of the propagator's time unit are switched together
#: (symmetric planets, a flank opening as its back flank closes); the same window applies time
#: events due at a piece's end. The unit: dt for the expm propagator, which steps by it; for
#: the Taylor propagator the system's own time scale (the piece length of the bound over
#: every state, ``REACH / rho``, at most the call's span), so that its solution does not
#: depend on the output step (a run at half the step takes the same pieces, bit for bit)
SIMULTANEOUS = 1e-13


@numba.njit(cache=True)
def hermite_max(g0, d0, g1, d1, L):
    """Maximum over [0, L] of the cubic Hermite interpolant of values g0, g1 and slopes d0,
    d1 at the ends."""
    c = d0 * L
    a = 2.0 * g0 - 2.0 * g1 + c + d1 * L
    b = -3.0 * g0 + 3.0 * g1 - 2.0 * c - d1 * L
    best = max(g0, g1)
    qa, qb, qc = 3.0 * a, 2.0 * b, c
    if abs(qa) > 1e-300:
        disc = qb * qb - 4.0 * qa * qc
        if disc >= 0.0:
            sq = math.sqrt(disc)
            for sgn in (1.0, -1.0):
                t = (-qb + sgn * sq) / (2.0 * qa)
                if 0.0 < t < 1.0:
                    best = max(best, ((a * t + b) * t + c) * t + g0)
    elif abs(qb) > 1e-300:
        t = -qc / qb
        if 0.0 < t < 1.0:
            best = max(best, ((a * t + b) * t + c) * t + g0)
    return best


@numba.njit(cache=True)
def candidate(ga, ra, gb, rb, L, margin):
    """True if a contact whose signed gap g (> 0 means it must switch) goes from (ga, ra) to
    (gb, rb) over a piece of length L may change state inside the piece: a sign change, or a
    Hermite interpolant of the end values and rates that comes within ``margin`` times the rate
    scale of contact. The interpolant is tested whatever the signs of the end rates: a gap that
    rises and falls back (a cubic under a linearly varying load in free flight, or a drift
    plus a fast mode) can have rates of one sign at both ends."""
    if gb > 0.0:
        return True
    scale = abs(ra * L) + abs(rb * L)
    if scale == 0.0:
        return False
    # the interpolant's Bernstein control points (ga, ga + ra L / 3, gb - rb L / 3, gb) bound
    # it from above (convex hull): most gaps are cleared by them without the extremum's root
    if max(ga, gb, ga + ra * L / 3.0, gb - rb * L / 3.0) <= -margin * scale:
        return False
    return hermite_max(ga, ra, gb, rb, L) > -margin * scale


@numba.njit(cache=True)
def _signed(W, off, sgn, x, n):
    nc = W.shape[0]
    g = np.empty(nc)
    r = np.empty(nc)
    for e in range(nc):
        p = -off[e]
        v = 0.0
        for i in range(n):
            p += W[e, i] * x[i]
            v += W[e, i] * x[n + i]
        g[e] = sgn[e] * p
        r[e] = sgn[e] * v
    return g, r


@numba.njit(cache=True)
def fast_steps(Phi, G0, G1, fs, F, k0, k_end, x, gaps, margin, dt, X):
    """Propagate from output step k0 with ``x`` while no contact is a candidate; rows
    ``X[k0 + 1 .. k]`` are written. ``gaps``: the gap rows, offsets and signs
    (:data:`~.bundles.GapRows`). Returns k, the index of the first step not taken (k_end
    when all were taken)."""
    W, off, sgn = gaps
    N = x.shape[0]
    n = N // 2
    nc = W.shape[0]
    ga, ra = _signed(W, off, sgn, x, n)
    x1 = np.empty(N)
    gb = np.empty(nc)
    rb = np.empty(nc)
    k = k0
    while k < k_end:
        for a in range(N):
            acc = fs[a]
            for b in range(N):
                acc += Phi[a, b] * x[b]
            for b in range(n):
                acc += G0[a, b] * F[k, b] + G1[a, b] * F[k + 1, b]
            x1[a] = acc
        hit = False
        for e in range(nc):
            p = -off[e]
            r = 0.0
            for i in range(n):
                p += W[e, i] * x1[i]
                r += W[e, i] * x1[n + i]
            gb[e] = sgn[e] * p
            rb[e] = sgn[e] * r
            if candidate(ga[e], ra[e], gb[e], rb[e], dt, margin):
                hit = True
                break
        if hit:
            return k
        for a in range(N):
            x[a] = x1[a]
            X[k + 1, a] = x1[a]
        for e in range(nc):
            ga[e] = gb[e]
            ra[e] = rb[e]
        k += 1
    return k


@numba.njit(cache=True)
def taylor_coefficients(A, Minv, x, F, dF, fcon, n_terms):
    """Rows ``y_k = x^(k) / k!`` of the Taylor series of the exact solution of
    ``x' = A x + [0; Minv (F + fcon + dF t)]`` at t = 0."""
    N = x.shape[0]
    n = N // 2
    Y = np.empty((n_terms, N))
    Y[0, :] = x
    y = A @ x
    y[n:] += Minv @ (F + fcon)
    Y[1, :] = y
    y = A @ y
    y[n:] += Minv @ dF
    Y[2, :] = y / 2.0
    # y_k = A y_(k-1) / k: the factorial is divided out as we go, so that stiff states
    # (large rho) do not overflow the intermediate powers
    for k in range(3, n_terms):
        Y[k, :] = (A @ Y[k - 1]) / k
    return Y


@numba.njit(cache=True)
def _poly(coef, t):
    m = coef.shape[0]
    g = coef[m - 1]
    for k in range(m - 2, -1, -1):
        g = g * t + coef[k]
    return g


@numba.njit(cache=True)
def _dpoly(coef, t):
    m = coef.shape[0]
    g = (m - 1) * coef[m - 1]
    for k in range(m - 2, 0, -1):
        g = g * t + k * coef[k]
    return g


@numba.njit(cache=True)
def _bisect_up(coef, lo, hi):
    """Last representable bracket of a crossing from <= 0 at lo to > 0 at hi; returns hi."""
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if mid <= lo or mid >= hi:
            break
        if _poly(coef, mid) > 0.0:
            hi = mid
        else:
            lo = mid
    return hi


@numba.njit(cache=True)
def poly_first_root(coef, L, n_samples):
    """First crossing of ``g(t) = sum coef[k] t^k`` from <= 0 to > 0 in [0, L]; ``inf`` if
    none. Immediately 0 when g is due at t = 0 (positive and rising, or touching with its first
    nonzero derivative pointing inwards). The samples bracket sign changes; between two
    non-positive samples whose derivatives go from rising to falling, the maximum is located
    on the derivative, so that a positive bump narrower than the sample spacing is found."""
    m = coef.shape[0]
    g0 = coef[0]
    if g0 > 0.0 and coef[1] > 0.0:
        return 0.0
    if g0 == 0.0:
        for k in range(1, m):
            if coef[k] != 0.0:
                if coef[k] > 0.0:
                    return 0.0
                break
    prev_t = 0.0
    prev_g = g0
    prev_d = coef[1]
    for i in range(1, n_samples):
        t = L * i / (n_samples - 1)
        g = _poly(coef, t)
        d = _dpoly(coef, t)
        if g > 0.0 and prev_g <= 0.0:
            return _bisect_up(coef, prev_t, t)
        if g <= 0.0 and prev_g <= 0.0 and prev_d > 0.0 and d < 0.0:
            lo, hi = prev_t, t  # derivative + at lo, - at hi: a maximum inside
            for _ in range(200):
                mid = 0.5 * (lo + hi)
                if mid <= lo or mid >= hi:
                    break
                if _dpoly(coef, mid) > 0.0:
                    lo = mid
                else:
                    hi = mid
            if _poly(coef, hi) > 0.0:
                return _bisect_up(coef, prev_t, hi)
            if _poly(coef, lo) > 0.0:
                return _bisect_up(coef, prev_t, lo)
        prev_t, prev_g, prev_d = t, g, d
    return np.inf


@numba.njit(cache=True)
def taylor_eval(Y, delta):
    """``sum_k Y[k] delta^k`` by Horner's rule."""
    m, N = Y.shape
    out = Y[m - 1].copy()
    for k in range(m - 2, -1, -1):
        for a in range(N):
            out[a] = out[a] * delta + Y[k, a]
    return out


@numba.njit(cache=True)
def _piece(PHI, G0, G1, FS, j, x, Fa, Fb):
    return PHI[j] @ x + G0[j] @ Fa + G1[j] @ Fb + FS[j]


@numba.njit(cache=True)
def _taylor_first(ode, gaps, x, Fa, dF, L, cand, n_terms, n_samples, simultaneous):
    """Earliest crossing among candidates on [0, L] on the Taylor series at x (the state's
    ``ode``: :data:`~.bundles.StateODE`; ``gaps``: :data:`~.bundles.GapRows`): returns
    (tau or inf, mask of contacts switching together, Taylor rows)."""
    A, Minv, fcon = ode
    W, off, sgn = gaps
    n = x.shape[0] // 2
    Y = taylor_coefficients(A, Minv, x, Fa, dF, fcon, n_terms)
    nc = W.shape[0]
    roots = np.full(nc, np.inf)
    coef = np.empty(n_terms)
    best = np.inf
    for e in range(nc):
        if not cand[e]:
            continue
        for k in range(n_terms):
            acc = 0.0
            for i in range(n):
                acc += W[e, i] * Y[k, i]
            coef[k] = sgn[e] * acc
        coef[0] -= sgn[e] * off[e]
        roots[e] = poly_first_root(coef, L, n_samples)
        best = min(best, roots[e])
    mask = np.zeros(nc, dtype=numba.boolean)
    if best < np.inf:
        for e in range(nc):
            mask[e] = roots[e] <= best + simultaneous
    return best, mask, Y


@numba.njit(cache=True)
def advance_state(levels, ode, gaps, x, t, t_end, tk, F0, F1, dt, tol):
    """Advance from t to t_end (inside the output step starting at tk, force linear from F0 to
    F1) in one contact state; stop at the first state change. The bundles of
    :mod:`gearmodal.integrate.bundles`: the state's dyadic propagators ``levels``
    (:data:`~.bundles.Levels`), its first-order system ``ode`` (:data:`~.bundles.StateODE`),
    the gap rows ``gaps`` (:data:`~.bundles.GapRows`), and ``tol``: ``(j_resolve, j_taylor,
    margin, n_terms, n_samples, simultaneous)``.

    Returns (status, t, x, mask, level): status 0 = reached t_end; 1 = event at t (x is the
    exact state there, mask the switching contacts); 2 = the propagator of dyadic ``level`` is
    needed (nothing was advanced; compute it and call again).
    """
    PHI, G0, G1, FS, have = levels
    W, off, sgn = gaps
    j_resolve, j_taylor, margin, n_terms, n_samples, simultaneous = tol
    N = x.shape[0]
    n = N // 2
    nc = W.shape[0]
    slope = (F1 - F0) / dt
    empty = np.zeros(nc, dtype=numba.boolean)
    cap = 2 * (j_taylor + 2)
    SX = np.empty((cap, N))
    SXB = np.empty((cap, N))
    ST = np.empty(cap)
    SJ = np.empty(cap, dtype=np.int64)
    SC = np.zeros((cap, nc), dtype=numba.boolean)
    while t < t_end:
        L_total = t_end - t
        j = j_resolve
        while dt / 2.0**j > L_total * (1.0 + 1e-12) and j < 62:
            j += 1
        if j > j_taylor:
            cand = np.ones(nc, dtype=numba.boolean)
            Fa = F0 + slope * (t - tk)
            tau, mask, Y = _taylor_first(ode, gaps, x, Fa, slope, L_total, cand, n_terms,
                                         n_samples, simultaneous)
            if tau < np.inf:
                return 1, t + tau, taylor_eval(Y, tau), mask, 0
            return 0, t_end, taylor_eval(Y, L_total), empty, 0
        if not have[j]:
            return 2, t, x, empty, j
        L = dt / 2.0**j
        t1 = t_end if abs((t + L) - t_end) <= 1e-12 * dt else t + L
        xb = _piece(PHI, G0, G1, FS, j, x, F0 + slope * (t - tk), F0 + slope * (t1 - tk))
        ga, ra = _signed(W, off, sgn, x, n)
        gb, rb = _signed(W, off, sgn, xb, n)
        any_c = False
        cand = np.zeros(nc, dtype=numba.boolean)
        for e in range(nc):
            if candidate(ga[e], ra[e], gb[e], rb[e], L, margin):
                cand[e] = True
                any_c = True
        if any_c:
            # depth-first, left half first: the first root found is the earliest
            top = 0
            SX[0] = x
            SXB[0] = xb
            ST[0] = t
            SJ[0] = j
            SC[0] = cand
            top = 1
            while top > 0:
                top -= 1
                jj = SJ[top]
                ta = ST[top]
                xa = SX[top].copy()
                xbb = SXB[top].copy()
                cc = SC[top].copy()
                Lj = dt / 2.0**jj
                if jj >= j_taylor:
                    Fa = F0 + slope * (ta - tk)
                    tau, mask, Y = _taylor_first(ode, gaps, xa, Fa, slope, Lj, cc, n_terms,
                                                 n_samples, simultaneous)
                    if tau < np.inf:
                        return 1, ta + tau, taylor_eval(Y, tau), mask, 0
                    continue
                if not have[jj + 1]:
                    return 2, t, x, empty, jj + 1
                h = Lj / 2.0
                xm = _piece(PHI, G0, G1, FS, jj + 1, xa, F0 + slope * (ta - tk),
                            F0 + slope * (ta + h - tk))
                g1, r1 = _signed(W, off, sgn, xa, n)
                gm, rm = _signed(W, off, sgn, xm, n)
                g2, r2 = _signed(W, off, sgn, xbb, n)
                c_left = np.zeros(nc, dtype=numba.boolean)
                c_right = np.zeros(nc, dtype=numba.boolean)
                any_l = False
                any_r = False
                for e in range(nc):
                    if cc[e]:
                        if candidate(g1[e], r1[e], gm[e], rm[e], h, margin):
                            c_left[e] = True
                            any_l = True
                        if candidate(gm[e], rm[e], g2[e], r2[e], h, margin):
                            c_right[e] = True
                            any_r = True
                if any_r:
                    SX[top] = xm
                    SXB[top] = xbb
                    ST[top] = ta + h
                    SJ[top] = jj + 1
                    SC[top] = c_right
                    top += 1
                if any_l:
                    SX[top] = xa
                    SXB[top] = xm
                    ST[top] = ta
                    SJ[top] = jj + 1
                    SC[top] = c_left
                    top += 1
        x = xb
        t = t1
    return 0, t, x, empty, 0
