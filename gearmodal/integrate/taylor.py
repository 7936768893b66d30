"""All-numba Taylor propagation of the exact method (DESIGN 3.2), for event-dense runs.

Inside one contact state the motion is linear, ``M q'' + C_s q' + K_s q = F(t) + f_s`` with the
force linear over each output step (first-order hold), so the exact solution from any instant
is an entire function of time whose Taylor coefficients follow from the recursion::

    a_0 = q,  a_1 = v,
    (k + 1)(k + 2) a_(k+2) = g_k - M^-1 K_s a_k - (k + 1) M^-1 C_s a_(k+1)        (T1)
    g_0 = M^-1 (F(t) + f_s),  g_1 = M^-1 F',  g_k = 0 for k >= 2

(``q(t + tau) = sum_k a_k tau^k``). A piece of length ``h`` with ``rho h <= reach``, ``rho`` a
bound of the spectral radius of every contact state's first-order matrix, is summed to
machine precision by ``n_terms`` terms (truncation ~ ``reach^n_terms / n_terms!``); the scaled
coefficients ``b_k = a_k h^k`` are kept so that nothing overflows in stiff states, and a piece
whose last terms are not negligible against its largest (a state stiffer than the bound) is
halved by rescaling ``b_k`` by ``2^-k`` until they are.

No per-state setup beyond two rank-one sums (``M^-1 K_s``, ``M^-1 C_s`` from the always-active
part plus the closed contacts): a new contact state costs nothing like the augmented matrix
exponential of :mod:`gearmodal.integrate.system`, which is what makes runs in which almost
every event enters a new state (a carrier rattling in its clearance against three planets)
cheap. Events: every contact's gap polynomial over the piece (the Taylor series of the exact
solution projected on the contact) is bounded above by its start value plus its positive
coefficients; where that bound does not exclude a crossing (and for every gap that has
crossed by the piece's end) it is searched for its first root by Bernstein subdivision
(:func:`first_root`), which cannot miss a root of the polynomial, and located to adjacent
floating-point numbers. No sampling of the gaps is involved, so the piece length is set by
the series alone (``REACH``), not by a fraction of the fastest period. Right after an event
that came quickly, the next piece is a quarter as long with fewer terms (the next event is
likely near).

The kernel's layout: :func:`taylor_run` takes its arguments in the named bundles of
:mod:`gearmodal.integrate.bundles` and walks the pieces through named phases (the force terms
of a stretch and of a piece, the time events and load knots that end a piece, its series, the
gaps at its ends, the first crossing, the output rows, the switch), each a function inlined
into the loop (``inline="always"``). Numba takes and drops a reference on every array bound at
a call boundary, inlined or not; the phases read borrowed views
(:mod:`gearmodal.integrate.borrow`: no meminfo, so those operations skip their atomic
instruction), the kernel's own arrays kept alive to both returns by ``owners``. (Before the
views, the same split made the event-dense gear rattle 5.8 times slower: 920 atomic
operations per piece against 37.)
"""

from __future__ import annotations

import functools
import math
import types
import weakref

import numba
import numpy as np

from ..errors import SolveError
from .borrow import alive, borrowed
from .bundles import (
    Bound,
    Call,
    Chain,
    Channels,
    ContactRows,
    Forcing,
    Loads,
    Out,
    Peaks,
    PeakWork,
    PieceState,
    RootWork,
    Schedule,
    Search,
    Sparse,
    System,
    TurnChannels,
    Turning,
    TurningWork,
    Turns,
    TurnWork,
)
from .kernels import SIMULTANEOUS, _bisect_up
from .kernels import _poly as _hpoly

#: rho * (piece length) at most this: every modal component turns by at most 6 rad per piece.
#: The largest term of a mode's series, REACH^6 / 6! = 65 times its amplitude, bounds the
#: cancellation (under two digits). Pieces run through output times; on the coupled turbine
#: run 4 cost 10-15 % more gearbox time and 8 saved 3-5 % for 6x the cancellation
REACH = 6.0
#: terms of the series at REACH (``terms_for(REACH)``): REACH^N / N! = 1.6e-17
N_TERMS = 40
#: stack size of the Bernstein subdivision, and its smallest interval (2^-DEPTH of a piece,
#: below the resolution of a double in [0, 1])
DEPTH = 60
MIN_WIDTH = 2.0**-DEPTH
#: a system re-based to a slightly different speed reuses the previous bound times this
RHO_SPEED = 1.01
#: contact switches applied as rank-one updates before the state's matrices are rebuilt
REFRESH = 64
#: the last two scaled terms (times k, for the velocities) must be below this fraction of the
#: largest one. Stricter than the truncation bound of ``terms_for`` (the first omitted term):
#: a piece at the full reach whose fastest mode dominates the rows is halved once (review
#: finding; costs time only, 3 of 563 pieces on the planetary stage)
TAIL = 1e-15
#: a term of a turning harmonic's exponential series ``E_h`` (modulus 1 at its start) below
#: this ends it in the Cauchy products (P3): what is left is below 1e-20 of the piece's
#: largest coefficient, far under the series' own truncation (``TAIL``)
E_TINY = 2.0**-70
#: event-free pieces a new contact state runs on the bound over every state before its own
#: bound is computed (an eigenproblem of size n). On the planetary stage's double-contact
#: transient (219 states in 310 events) 1 computes 65 bounds, 2 computes 3: 4.4 and 3.6 ms
#: against 5.8 ms for every state met; the turbine's states last thousands of pieces
LAZY = 2
#: right after an event that came within this fraction of the longest piece, the next piece
#: is this fraction long (fewer terms: the next event is likely near); 0.1-0.6 measured on
#: the planetary stage, 0.25-0.4 best
DENSE = 0.25
#: resolution of the per-piece term count (fractions of the reach)
TERM_BINS = 64
#: numba fast-math flags of the small dense loops: reassociation (vectorised sums and maxima)
#: but no "no NaN / no inf" assumption, so that a non-finite state is still seen as such
FAST = {"reassoc", "nsz", "arcp", "contract"}


def terms_for(reach: float, tol: float = 3e-17) -> int:
    """Smallest number of terms whose truncation bound ``reach^n / n!`` is below ``tol``."""
    n, term = 1, reach
    while term > tol and n < 200:
        n += 1
        term *= reach / n
    return n


@functools.lru_cache(maxsize=16)
def _term_table(reach: float, n_terms: int = 0) -> tuple:
    """Terms by the piece's reach ``rho h``, in 64ths of ``reach`` rounded up, plus the full
    count last (at least 6: the forcing enters at the 4th term; the tail check guards every
    piece anyway). An explicit ``n_terms`` (> 0) is used for every piece. Constants of the
    run's settings: computed once per process (65 ``terms_for`` loops, ~0.15 ms)."""
    full = n_terms if n_terms else terms_for(reach)
    if n_terms:
        return (full,) * (TERM_BINS + 1)
    return tuple(min(max(terms_for(reach * j / TERM_BINS), 6), full)
                 for j in range(TERM_BINS)) + (full,)


@numba.njit(cache=True)
def _toggle(U, W, kc, cc, off, e, sign, MKC, acc):
    """Add (sign 1) or remove (sign -1) contact ``e``'s rank-one terms in place."""
    n = W.shape[1]
    ke, ce, fe = sign * kc[e], sign * cc[e], sign * kc[e] * off[e]
    for i in range(n):
        ui = U[e, i]
        if ui != 0.0:
            acc[i] += fe * ui
            for j in range(n):
                wj = W[e, j]
                MKC[i, j] += ke * ui * wj
                MKC[i, n + j] += ce * ui * wj


@numba.njit(cache=True)
def _state_matrices(MK0, MC0, U, W, kc, cc, off, s, MKC, acc):
    """``M^-1 K_s``, ``M^-1 C_s`` and ``M^-1 f_s`` of contact state ``s`` (rank-one sums of
    ``u_e w_e^T``, ``u_e = M^-1 w_e``, over the closed contacts; system.matrices)."""
    n = MK0.shape[0]
    for i in range(n):
        acc[i] = 0.0
        for j in range(n):
            MKC[i, j] = MK0[i, j]
            MKC[i, n + j] = MC0[i, j]
    for e in range(W.shape[0]):
        if s[e]:
            _toggle(U, W, kc, cc, off, e, 1.0, MKC, acc)


@numba.njit(cache=True, fastmath=True)
def _coefficients_frozen(MKC, g0, g1, q, v, h, B, y, HF, harmonic):
    """:func:`_coefficients` of a system that does not turn (no harmonics): (T1) alone. Its
    loop is the frozen part of :func:`_coefficients` written out again on purpose: a helper
    shared per term took and dropped an atomic reference count on each of its arrays every
    term (12-14 % of the planetary stage's event-dense run, measured before the kernel read
    borrowed views; :func:`_cauchy` is such a helper now, on borrowed views), and the turning
    function called for a frozen run costs 8 % on that run (2.72 against 2.50 ms). Both are
    checked against closed forms (frozen: tests/validation/test_exactness.py; turning:
    tests/validation/test_rotating_geometry.py). ``HF`` (n_terms, n): the scaled Taylor rows
    ``g_k h^k`` of the harmonic loads (:func:`_harmonic_rows`), added where ``harmonic``."""
    n_terms, n = B.shape
    n2 = n - n % 2
    width = MKC.shape[1]
    h2 = h * h
    for i in range(n):
        B[0, i] = q[i]
        B[1, i] = v[i] * h
    for k in range(n_terms - 2):
        den = 1.0 / ((k + 1.0) * (k + 2.0))
        c2 = -h2 * den
        c1 = -(k + 1.0) * h * den
        for j in range(n):
            y[j] = B[k, j] * c2
            y[n + j] = B[k + 1, j] * c1
        for i in range(0, n2, 2):
            a0 = 0.0
            a1 = 0.0
            for j in range(width):
                yj = y[j]
                a0 += MKC[i, j] * yj
                a1 += MKC[i + 1, j] * yj
            B[k + 2, i] = a0
            B[k + 2, i + 1] = a1
        for i in range(n2, n):
            a = 0.0
            for j in range(width):
                a += MKC[i, j] * y[j]
            B[k + 2, i] = a
        if k == 0:
            for i in range(n):
                B[2, i] += g0[i] * h2 * den
        elif k == 1:
            for i in range(n):
                B[3, i] += g1[i] * h2 * h * den
        if harmonic:
            for i in range(n):
                B[k + 2, i] += HF[k, i] * h2 * den


@numba.njit(cache=True, inline="always")
def _cauchy(k, B, h_lo, rates, tw):
    """The Cauchy products (T2) of what term ``k`` knows, into ``tw.Y`` (``b_0 .. b_k``) and,
    with ``rates``, ``tw.Yd`` (``b_1 .. b_(k+1)``), harmonics from ``h_lo``; the turning
    coordinates' row ``k + 1`` of ``B`` into ``tw.Bt``. (Inlined into :func:`_coefficients`'
    per-term loop, it binds its six fields every term: references on borrowed views, calls
    that return at once; the 600 kW turbine's gearbox, the one user, is at parity with the
    loop written out, benchmarks/kernel_ab.py.)"""
    tcols, E, EL, Y, Yd, Bt = tw[0], tw[5], tw[6], tw[7], tw[8], tw[9]
    n_terms = B.shape[0]
    nT = tcols.shape[0]
    if k + 1 < n_terms:
        for c in range(nT):
            Bt[k + 1, c] = B[k + 1, tcols[c]]
    for hh in range(h_lo, E.shape[0]):
        for c in range(nT):
            Y[0, hh, k, c] = 0.0
            Y[1, hh, k, c] = 0.0
        for j in range(min(k + 1, EL[hh])):
            er = E[hh, j].real
            ei = E[hh, j].imag
            for c in range(nT):
                b = Bt[k - j, c]
                Y[0, hh, k, c] += er * b
                Y[1, hh, k, c] += ei * b
        if rates and k + 1 < n_terms:
            for c in range(nT):
                Yd[0, hh, k, c] = 0.0
                Yd[1, hh, k, c] = 0.0
            for j in range(min(k + 1, EL[hh])):
                f = k - j + 1.0
                er = E[hh, j].real * f
                ei = E[hh, j].imag * f
                for c in range(nT):
                    b = Bt[k - j + 1, c]
                    Yd[0, hh, k, c] += er * b
                    Yd[1, hh, k, c] += ei * b


@numba.njit(cache=True, fastmath=True)
def _coefficients(MKC, g0, g1, q, v, h, B, tw, cturn, loads, harmonic):
    """Scaled Taylor rows ``B[k] = a_k h^k`` of the positions: the frozen part by (T1) with
    the forcing terms ``g0`` (the force at the piece's start) and ``g1`` (its rate), one
    contiguous product per term with ``MKC = [M^-1 K_s, M^-1 C_s, Z]`` (``y``: scratch of its
    width), plus, for a system that turns, the turning harmonics of
    :mod:`gearmodal.integrate.periodic` by Cauchy products with the piece's exponential series
    ``E`` (H1, n_terms) ((P2), ``E[0]`` the constant 1):

        Y_h[k] = sum_j E_h[j] b_(k-j),   Yd_h[k] = sum_j E_h[j] (k - j + 1) b_(k-j+1)
        b_(k+2) += h^2 den (-Re sum_h ZK_h Y_h[k] - Re sum_h ZC_h Yd_h[k] / h
                            - Re sum_(h, e closed) TU_(h,e) (E_h * f_e)[k]
                            + Re sum_h (E_h[k] GV_h + h E_h[k-1] GVS_h))                (T2)

    with ``den = 1 / ((k + 1)(k + 2))``, the turning contacts' penetration series ``P[e, k] =
    Re sum_h TW_(h,e) . Y_h[k] - OFS[e, k]`` (also kept for their root search), ``PD`` the
    series of ``w . q_s`` and their force series ``f_e = kt P + ct PD / h`` (``FT``).
    ``Y``, ``Yd`` (H1, n_terms, nT) complex and ``FT`` are scratch; ``GV``, ``GVS`` (H1, n) the
    turning loads ``M^-1 Z_h u`` at the piece's start and their rates. ``Y``, ``Yd`` hold
    real and imaginary parts in their first axis (2, H1, n_terms, nT) and ``Bt`` (n_terms, nT)
    the turning coordinates' rows of ``B``: real, contiguous sums that vectorise. ``HF`` as
    :func:`_coefficients_frozen` (the harmonic loads, their turning products included).
    ``zsrc``: the Z columns ``MKC`` keeps, by their place in the full layout
    (:func:`_turning_columns`).
    The geometry's parts, the scratch and the piece's turning inputs come in the bundle ``tw``
    (:data:`~.bundles.TurningWork`)."""
    tcols, urows, TW, TU, y, E, EL, Y, Yd, Bt, OFS, kt, ct, closed, P, PD, FT, GV, GVS, HF, \
        zsrc = tw
    n_terms, n = B.shape
    n2 = n - n % 2
    width = MKC.shape[1]  # 2 n, or more with the turning columns
    H1 = E.shape[0]
    nT = tcols.shape[0]
    nTC = TW.shape[1]
    h2 = h * h
    # what the turning parts need: the rate products for a turning damping (``cturn``) or a
    # turning contact with damping; the constant harmonic for the contacts' rows only;
    # ``loads``: some turning load is nonzero over this output step
    rates = cturn
    for e in range(nTC):
        if ct[e] != 0.0:
            rates = True
    h_lo = 0 if nTC > 0 else 1
    for i in range(n):
        B[0, i] = q[i]
        B[1, i] = v[i] * h
    for c in range(nT):
        Bt[0, c] = B[0, tcols[c]]
    for k in range(n_terms):
        _cauchy(k, B, h_lo, rates, tw)
        for e in range(nTC):
            pr = -OFS[e, k]
            pd = 0.0
            for hh in range(H1):
                for c in range(nT):
                    w = TW[hh, e, c]
                    pr += w.real * Y[0, hh, k, c] - w.imag * Y[1, hh, k, c]
                    if rates and k + 1 < n_terms:
                        pd += w.real * Yd[0, hh, k, c] - w.imag * Yd[1, hh, k, c]
            P[e, k] = pr
            PD[e, k] = pd
            FT[e, k] = kt[e] * pr + ct[e] * pd / h if closed[e] else 0.0
        if k + 2 >= n_terms:
            continue
        den = 1.0 / ((k + 1.0) * (k + 2.0))
        # the turning rows' inputs, laid out as the columns Z of MKC (_turning_columns):
        # [Re Y_h, Im Y_h] per harmonic h >= 1, then [Re Yd_h, Im Yd_h] with a turning damping
        ck = -h2 * den
        cd = -h * den
        o = 2 * n
        for hh in range(1, H1):
            for c in range(nT):
                y[o + c] = ck * Y[0, hh, k, c]
                y[o + nT + c] = ck * Y[1, hh, k, c]
            o += 2 * nT
        if cturn:
            for hh in range(1, H1):
                for c in range(nT):
                    y[o + c] = cd * Yd[0, hh, k, c]
                    y[o + nT + c] = cd * Yd[1, hh, k, c]
                o += 2 * nT
        if zsrc.shape[0] < o - 2 * n:  # the kept Z columns, in place (zsrc[j] >= j)
            for j in range(zsrc.shape[0]):
                y[2 * n + j] = y[2 * n + zsrc[j]]
        # the frozen part of (T1): B[k + 2] = MKC [c2 B[k]; c1 B[k + 1]; y_Z]
        c2 = -h2 * den
        c1 = -(k + 1.0) * h * den
        for j in range(n):
            y[j] = B[k, j] * c2
            y[n + j] = B[k + 1, j] * c1
        # two rows at a time: two independent sums hide the latency of each (-12 %)
        for i in range(0, n2, 2):
            a0 = 0.0
            a1 = 0.0
            for j in range(width):
                yj = y[j]
                a0 += MKC[i, j] * yj
                a1 += MKC[i + 1, j] * yj
            B[k + 2, i] = a0
            B[k + 2, i + 1] = a1
        for i in range(n2, n):
            a = 0.0
            for j in range(width):
                a += MKC[i, j] * y[j]
            B[k + 2, i] = a
        if k == 0:
            for i in range(n):
                B[2, i] += g0[i] * h2 * den
        elif k == 1:
            for i in range(n):
                B[3, i] += g1[i] * h2 * h * den
        if harmonic:
            for i in range(n):
                B[k + 2, i] += HF[k, i] * h2 * den
        if loads:
            for hh in range(1, H1):
                if k > EL[hh]:
                    continue  # E_h[k] = E_h[k - 1] = 0 (P3)
                ek = E[hh, k] * h2 * den
                ek1 = E[hh, k - 1] * (h2 * h * den) if k > 0 else 0j
                for i in range(n):
                    B[k + 2, i] += (ek * GV[hh, i] + ek1 * GVS[hh, i]).real
        for e in range(nTC):
            if not closed[e]:
                continue
            for hh in range(H1):
                fe = 0j
                for j in range(min(k + 1, EL[hh])):
                    fe += E[hh, j] * FT[e, k - j]
                fe *= h2 * den
                for i in urows:
                    B[k + 2, i] -= (TU[hh, e, i] * fe).real


@numba.njit(cache=True, fastmath=FAST)
def _converged(B, tail):
    n_terms, n = B.shape
    big = 0.0
    for k in range(n_terms):
        row = 0.0
        for i in range(n):  # row by row: a contiguous max that vectorises
            row = max(row, abs(B[k, i]))
        big = max(big, row * max(k, 1))
    if big == 0.0 or not np.isfinite(big):
        return True  # (a non-finite state is reported by the caller)
    last = 0.0
    for k in range(n_terms - 2, n_terms):
        row = 0.0
        for i in range(n):
            row = max(row, abs(B[k, i]))
        last = max(last, row * k)
    return last <= tail * big


@numba.njit(cache=True, fastmath=FAST)
def _evaluate(B, tau, h, q, v):
    """Positions and velocities at ``tau`` (0..1 of the piece) from the scaled rows (Horner,
    term by term over all coordinates: contiguous rows that vectorise)."""
    n_terms, n = B.shape
    top = n_terms - 1
    for i in range(n):
        q[i] = B[top, i]
        v[i] = top * B[top, i]
    for k in range(n_terms - 2, 0, -1):
        for i in range(n):
            q[i] = q[i] * tau + B[k, i]
            v[i] = v[i] * tau + k * B[k, i]
    for i in range(n):
        q[i] = q[i] * tau + B[0, i]
        v[i] = v[i] / h


@numba.njit(cache=True, inline="always")
def _gaps(wptr, widx, wval, off, s, q, v, g, r):
    """Signed gaps (> 0: the contact must switch) and their rates (``W`` by sparse rows)."""
    nc = off.shape[0]
    for e in range(nc):
        p = -off[e]
        rr = 0.0
        for jj in range(wptr[e], wptr[e + 1]):
            i = widx[jj]
            p += wval[jj] * q[i]
            rr += wval[jj] * v[i]
        sg = -1.0 if s[e] else 1.0
        g[e] = sg * p
        r[e] = sg * rr


#: Pascal's triangle ``PASCAL[i, k] = C(i, k)`` and ``INV_BINOM[d, k] = 1 / C(d, k)`` up to
#: degree ``TABLE_DEGREE`` (a full-reach piece has degree 23), frozen into the compiled
#: kernels as constants: the basis change of :func:`_bernstein` as vectorised sums
TABLE_DEGREE = 40
PASCAL = np.zeros((TABLE_DEGREE + 1, TABLE_DEGREE + 1))
for _i in range(TABLE_DEGREE + 1):
    for _k in range(_i + 1):
        PASCAL[_i, _k] = math.comb(_i, _k)
INV_BINOM = np.where(PASCAL > 0, 1.0 / np.where(PASCAL > 0, PASCAL, 1.0), 0.0)


@numba.njit(cache=True, fastmath=FAST)
def _bernstein(c, b):
    """Bernstein coefficients on [0, 1] of ``sum c_k tau^k``: ``b_i = sum_(k <= i) C(i, k) /
    C(d, k) c_k`` (the monomial-to-Bernstein basis change) as vectorised dot products over
    the tabulated binomials, last row first so that ``b`` can hold the scaled ``c`` (3x
    faster than repeated summation, a chain of dependent additions, which is kept beyond
    ``TABLE_DEGREE``)."""
    d = c.shape[0] - 1
    if d <= TABLE_DEGREE:
        for k in range(d + 1):
            b[k] = c[k] * INV_BINOM[d, k]
        for i in range(d, -1, -1):
            acc = 0.0
            for k in range(i + 1):
                acc += PASCAL[i, k] * b[k]
            b[i] = acc
        return
    binom = 1.0
    for k in range(d + 1):
        b[k] = c[k] / binom
        binom = binom * (d - k) / (k + 1.0)
    for j in range(1, d + 1):
        for i in range(d, j - 1, -1):
            b[i] += b[i - 1]


@numba.njit(cache=True, inline="always")
def _split_rows(work, top, rw):
    """de Casteljau at 1/2 of the Bernstein coefficients in row ``top`` of ``work``: the right
    half's into row ``top``, the left half's into row ``top + 1`` (row ``rw``: scratch). By
    index, not by row views: each view takes and drops an atomic reference count (with the
    other views of the search, 14 % of the planetary stage's event-dense run)."""
    d = work.shape[1] - 1
    for i in range(d + 1):
        work[rw, i] = work[top, i]
    work[top + 1, 0] = work[rw, 0]
    work[top, d] = work[rw, d]
    for r in range(1, d + 1):
        for i in range(d - r + 1):
            work[rw, i] = 0.5 * (work[rw, i] + work[rw, i + 1])
        work[top + 1, r] = work[rw, 0]
        work[top, d - r] = work[rw, d - r]


@numba.njit(cache=True, fastmath=FAST)
def _row_max(work, r):
    """Largest entry of row ``r`` (a vectorised maximum)."""
    mx = work[r, 0]
    for i in range(1, work.shape[1]):
        mx = max(mx, work[r, i])
    return mx


@numba.njit(cache=True, inline="always")
def _value_slope(coef, t):
    """``g(t)`` and ``g'(t)`` by one Horner pass (two independent chains: about the latency
    of one)."""
    m = coef.shape[0]
    g = coef[m - 1]
    dg = 0.0
    for k in range(m - 2, -1, -1):
        dg = dg * t + g
        g = g * t + coef[k]
    return g, dg


@numba.njit(cache=True)
def _refine(coef, lo, hi, glo, ghi):
    """The crossing of ``g`` inside [lo, hi] (``glo = g(lo) <= 0 < ghi = g(hi)``, one root):
    Newton's method kept inside the bracket (bisection when a step leaves it), the bracket
    closed around the converged point, then bisection to adjacent floating-point numbers;
    returns the upper end (g > 0)."""
    x = (lo * ghi - hi * glo) / (ghi - glo) if ghi > glo else 0.5 * (lo + hi)
    if not (lo < x < hi):
        x = 0.5 * (lo + hi)
    for _ in range(40):
        gx, dx = _value_slope(coef, x)
        if gx > 0.0:
            hi = x
        else:
            lo = x
        if hi - lo <= 4.0 * np.spacing(hi):
            break
        xn = x - gx / dx if dx != 0.0 else 0.5 * (lo + hi)
        if gx == 0.0 or abs(xn - x) <= 4.0 * np.spacing(x):
            # converged: close the bracket a few units in the last place either side
            d = 4.0 * np.spacing(x)
            if lo < x - d and _hpoly(coef, x - d) <= 0.0:
                lo = x - d
            if x + d < hi and _hpoly(coef, x + d) > 0.0:
                hi = x + d
            break
        x = xn if lo < xn < hi else 0.5 * (lo + hi)
    return _bisect_up(coef, lo, hi)


@numba.njit(cache=True)
def first_root(coef, work, stk):
    """First crossing of ``g(tau) = sum coef[k] tau^k`` from <= 0 to > 0 in [0, 1]; ``inf``
    if none (callers search [0, L] by scaling ``coef[k]`` by ``L^k``).

    Rigorous root isolation by Bernstein subdivision: an interval whose Bernstein
    coefficients are all <= 0 holds no crossing (convex hull property); one whose coefficients
    change sign once holds exactly one (Descartes' rule for the Bernstein basis), located by
    Newton's method and bisection on ``g`` to adjacent floating-point numbers (the returned
    point has g > 0); otherwise it is halved, left half first. A negative ``g(0)`` plus the
    positive coefficients below zero excludes a root at once. At tau = 0, a gap that is due
    (positive and rising, or zero with its first nonzero derivative positive) gives 0; a gap
    left positive by rounding but receding is treated as zero. ``work`` (depth + 5, d + 1)
    and ``stk`` (2, depth + 1) are scratch.
    """
    d = coef.shape[0] - 1
    if work.shape[1] != d + 1:  # (rows of another width would be read past the polynomial)
        raise ValueError("first_root: work needs one column per coefficient")
    big = 0.0
    for k in range(d + 1):
        if not np.isfinite(coef[k]):
            return np.inf  # a non-finite state: the caller reports it, no search can end
        big = max(big, abs(coef[k]))
    g0 = coef[0]
    if g0 > 0.0 and (d == 0 or coef[1] > 0.0):
        return 0.0
    if g0 < 0.0:
        # g <= g0 + sum of the positive coefficients on [0, 1]: often enough
        ub = g0
        for k in range(1, d + 1):
            if coef[k] > 0.0:
                ub += coef[k]
        if ub <= 0.0:
            return np.inf
    depth_max = work.shape[0] - 5
    poly = coef
    if big > 1e300:
        # the basis change and Horner's sums reach (d + 1) max |c_k|: scaled by a power of two
        # (the same roots, exactly) they cannot overflow into inf - inf (review finding: such
        # intervals were split down to MIN_WIDTH)
        poly = work[depth_max + 4]
        f = math.ldexp(1.0, -math.frexp(big)[1])
        for k in range(d + 1):
            poly[k] = coef[k] * f
    if g0 >= 0.0:
        c = work[depth_max + 1]
        c[:] = poly
        c[0] = 0.0
        for k in range(1, d + 1):
            if c[k] != 0.0:
                if c[k] > 0.0:
                    return 0.0
                break
        _bernstein(c, work[0])
    else:
        _bernstein(poly, work[0])
    stk[0, 0] = 0.0
    stk[1, 0] = 1.0
    top = 1
    while top > 0:
        top -= 1
        a = stk[0, top]
        w = stk[1, top]
        # (the interval's Bernstein coefficients are row ``top``, read by index: no views)
        if _row_max(work, top) <= 0.0:
            continue  # the usual outcome for a flagged near miss: no crossing, no split
        if work[top, 0] > 0.0:
            return a  # the left neighbours hold no crossing
        changes = 0
        prev = work[top, 0]
        for i in range(1, d + 1):
            bi = work[top, i]
            if bi != 0.0:
                if prev != 0.0 and (bi > 0.0) != (prev > 0.0):
                    changes += 1
                prev = bi
        if changes == 1 and work[top, d] > 0.0:
            hi = a + w
            ghi = _hpoly(poly, hi)
            if ghi > 0.0:
                return _refine(poly, a, hi, _hpoly(poly, a), ghi)
        if top + 2 > depth_max or w < MIN_WIDTH:
            # below the resolution of time (or out of stack): a crossing at the right end if
            # the polynomial ends positive there, else none in this interval
            if work[top, d] > 0.0:
                return a + w
            continue
        _split_rows(work, top, depth_max + 1)  # right half in row top, left in top + 1
        stk[0, top] = a + 0.5 * w
        stk[1, top] = 0.5 * w
        stk[0, top + 1] = a
        stk[1, top + 1] = 0.5 * w
        top += 2
    return np.inf


# -- exact peaks (DESIGN 3.2: load statistics from the exact solution) -------------------------
@numba.njit(cache=True)
def _shift(c, m, lo, w, out):
    """``out[k]`` (k < m): the coefficients in ``sigma`` of ``c(lo + w sigma)`` (a Taylor shift
    by ``lo`` by repeated synthetic division, then the scaling by ``w``)."""
    for k in range(m):
        out[k] = c[k]
    if lo != 0.0:
        for i in range(m - 1):
            for j in range(m - 2, i - 1, -1):
                out[j] += lo * out[j + 1]
    sc = 1.0
    for k in range(m):
        out[k] *= sc
        sc *= w


#: terms of the cheap first bound of :func:`poly_max` (the rest bounded by its magnitudes)
GATE_TERMS = 12


@numba.njit(cache=True, inline="always")
def _upper(c, n, a, b, level, e):
    """A bound of the interior values of ``p(tau) = sum_(k < n) c_k tau^k`` on ``[a, b]``
    (0 <= a <= b <= 1), or ``-inf`` when ``p`` is monotone there (``p'(0)`` dominates the rest
    of ``p'``: its maximum is at an end): the largest Bernstein coefficient of ``p`` on ``[a,
    b]`` (convex hull property), first of its first ``GATE_TERMS`` terms plus a bound of the
    rest (``|tau| <= b``: a tenth of the work), returned if at most ``level``, else of all.
    ``e``: scratch (n)."""
    if n < 3 or b <= a:
        return -np.inf
    rest = 0.0
    sc = 1.0
    for k in range(2, n):
        sc *= b
        rest += k * abs(c[k]) * sc
    if abs(c[1]) > rest:
        return -np.inf
    if n > GATE_TERMS:
        tail = 0.0
        sc = 1.0
        for k in range(n):
            if k >= GATE_TERMS:
                tail += abs(c[k]) * sc
            sc *= b
        _shift(c, GATE_TERMS, a, b - a, e)
        _bernstein(e[:GATE_TERMS], e[:GATE_TERMS])
        top = e[0]
        for k in range(1, GATE_TERMS):
            top = max(top, e[k])
        if top + tail <= level:
            return top + tail
    _shift(c, n, a, b - a, e)
    _bernstein(e[:n], e[:n])
    top = e[0]
    for k in range(1, n):
        top = max(top, e[k])
    return top


@numba.njit(cache=True, inline="always")
def _next_turn(d, m, lo, b, sign, e, work, stk):
    """The next root of ``p'`` (``d``, m terms) on ``[lo, b]`` where ``sign p'`` crosses from
    <= 0 to > 0 (``sign`` -1: a maximum of ``p``, +1: a minimum), by :func:`first_root` on
    ``p'`` shifted to ``[lo, b]``; ``inf`` if none. The alternating walk of :func:`poly_max`
    and :func:`poly_turns` (each search starts where its function is not positive)."""
    w = b - lo
    if w <= 0.0:
        return np.inf
    _shift(d, m, lo, w, e)
    for k in range(m):
        e[k] *= sign
    r = first_root(e[:m], work, stk)
    return r if r == np.inf else lo + w * r


@numba.njit(cache=True)
def poly_max(c, a, b, thr, d, e, wflat, stk, counts):
    """``(value, tau)``: the largest value of ``p(tau) = sum_k c_k tau^k`` on ``[a, b]`` and
    where, if it exceeds ``thr`` (else a value <= ``thr``: the caller holds a larger one).
    Candidates are the ends and every interior maximum, a crossing of ``-p'`` from <= 0 to > 0
    found by :func:`first_root` (Bernstein subdivision: none missed) on ``p'`` shifted to what
    is left of the interval; the searches alternate with the minima (crossings of ``p'``) so
    that each starts where its function is not positive, and are skipped where
    :func:`_upper` shows no value above ``thr`` and the ends. A maximum is located to rounding
    (``p`` is flat there: the value is exact to rounding). ``d``, ``e`` (len(c)) and ``wflat``
    ((DEPTH + 5) len(c)), ``stk`` (2, DEPTH + 1): scratch; ``counts[6]``: the searches."""
    n = c.shape[0]
    best = _hpoly(c, a)
    where = a
    vb = _hpoly(c, b)
    if vb > best:
        best = vb
        where = b
    if _upper(c, n, a, b, max(thr, best), e) <= max(thr, best):
        return best, where
    counts[6] += 1
    m = n - 1
    for k in range(m):
        d[k] = (k + 1.0) * c[k + 1]
    work = wflat[:(DEPTH + 5) * m].reshape((DEPTH + 5, m))
    lo = a
    # each search starts where its function is <= 0 (first_root's premise): -p' (a maximum)
    # where p rises at a, else p' (the minimum before the next maximum)
    sign = 1.0 if _hpoly(d[:m], a) < 0.0 else -1.0
    for _ in range(2 * m + 2):  # p' has at most m - 1 roots
        r = _next_turn(d, m, lo, b, sign, e, work, stk)
        if r == np.inf:
            break
        tau = min(r, b)
        if sign < 0.0:
            v = _hpoly(c, tau)
            if v > best:
                best = v
                where = tau
            if _upper(c, n, tau, b, max(thr, best), e) <= max(thr, best):
                break  # nothing higher in the rest
        lo = tau
        sign = -sign
    return best, where


@numba.njit(cache=True, inline="always")
def _row_series(Bv, nt, h, ptr, idx, val, j, k_, c_, off_, out, tmp):
    """``out[k]`` (k < nt): the scaled series of ``k_ (w . q - off_) + c_ w . v`` of sparse
    row ``j`` (a contact's force while closed, a spring's force) over the piece ``Bv``."""
    for k in range(nt):
        a = 0.0
        for jj in range(ptr[j], ptr[j + 1]):
            a += val[jj] * Bv[k, idx[jj]]
        tmp[k] = a
    tmp[0] -= off_
    for k in range(nt):
        out[k] = k_ * tmp[k]
        if k + 1 < nt:
            out[k] += c_ * (k + 1.0) * tmp[k + 1] / h


@numba.njit(cache=True, inline="always")
def _radial_square(Bv, nt, h, chans, rx, ry, fx, fy, P, tmp):
    """The series of a spring channel's squared magnitude over the piece ``Bv``: ``F_x^2 +
    F_y^2`` of sparse rows ``rx`` and ``ry`` (``ry < 0``: ``F_x^2`` alone) into ``P``; returns
    its number of terms, its last terms, together below rounding of its size, left out (a
    degree near the series' own instead of twice it). ``fx``, ``fy``: the components'; the
    rows, stiffness and damping of ``chans`` (:data:`~.bundles.Channels`)."""
    sptr, sidx, sval = chans.rows
    sk = chans.sk
    sc = chans.sc
    two = ry >= 0
    _row_series(Bv, nt, h, sptr, sidx, sval, rx, sk[rx], sc[rx], 0.0, fx, tmp)
    if two:
        _row_series(Bv, nt, h, sptr, sidx, sval, ry, sk[ry], sc[ry], 0.0, fy, tmp)
    m2 = 2 * nt - 1
    size = 0.0
    for j in range(m2):
        a = 0.0
        for i in range(max(0, j - nt + 1), min(j, nt - 1) + 1):
            a += fx[i] * fx[j - i]
            if two:
                a += fy[i] * fy[j - i]
        P[j] = a
        size += abs(a)
    tail = 0.0
    while m2 > 2 and tail + abs(P[m2 - 1]) <= 1e-17 * size:
        tail += abs(P[m2 - 1])
        m2 -= 1
    return m2


#: terms of a row's series formed for its first bound (:func:`_low_bound`): the rest is
#: bounded by the magnitudes of the coordinates' terms from there on, ``REACH^16 / 16!`` = 0.13
#: of the fastest mode's amplitude at most (the full series' magnitudes would allow
#: ``e^REACH`` = 400 times it: a ripple of 0.03 % of a tooth force defeated that bound)
LOW_TERMS = 16


@numba.njit(cache=True, inline="always")
def _low_bound(Bv, L, h, te, rows, j, law, tq, td, tmp, e, upper):
    """A bound over ``[0, te]`` of the piece of the row's force ``k_ (w . q - off_) + c_ w .
    v`` (row ``j`` of ``rows``, :data:`~.bundles.Sparse`; ``law``: ``(k_, c_, off_)``;
    ``upper``: of the force, else of its magnitude): the Bernstein coefficients of its series'
    first ``L`` terms (convex hull) plus the magnitudes of the rest (``tq``, ``td``: each
    coordinate's sums of ``|b_k|`` and ``k |b_k|`` from ``L`` on)."""
    ptr, idx, val = rows
    k_, c_, off_ = law
    _row_series(Bv, L, h, ptr, idx, val, j, k_, c_, off_, e, tmp)  # the first L terms
    rest = 0.0
    for jj in range(ptr[j], ptr[j + 1]):
        w = abs(val[jj])
        rest += w * (abs(k_) * tq[idx[jj]] + abs(c_) * td[idx[jj]] / h)
    sc = 1.0
    for k in range(L):
        e[k] *= sc
        sc *= te
    _bernstein(e[:L], e[:L])
    top = e[0] if upper else abs(e[0])
    for k in range(1, L):
        top = max(top, e[k] if upper else abs(e[k]))
    return top + rest


@numba.njit(cache=True, inline="always")
def _level(PB, EP, b, col, e, root):
    """What a piece of channel ``col`` must exceed to matter: its bin's peak and, for a contact
    ``e >= 0``, its episode's (the smaller); squared for a radial channel (``root``)."""
    thr = PB[b, col, 0]
    if e >= 0:
        thr = min(thr, EP[e, 0])
    if root and thr > -np.inf:
        thr = thr * abs(thr)
    return thr


@numba.njit(cache=True, inline="always")
def _record(v, tv, b, col, e, PB, EP):
    """Value ``v`` at time ``tv`` into bin ``b`` of channel ``col`` and contact ``e``'s episode
    (``e >= 0``), where it is larger."""
    if v > PB[b, col, 0]:
        PB[b, col, 0] = v
        PB[b, col, 1] = tv
    if e >= 0 and v > EP[e, 0]:
        EP[e, 0] = v
        EP[e, 1] = tv


@numba.njit(cache=True)
def _bin_max(P, span, b0, b1, col, e, root, pk, sw, counts):
    """The maximum of ``P`` (over the piece ``span = (t_abs, h, te)``: from ``t_abs`` (s),
    length ``h``, up to ``te``) in each peak bin it touches into ``PB[b, col]`` and, for a
    contact (``e >= 0``), into its episode's ``EP[e]`` (of ``pk``, :data:`~.bundles.Peaks`);
    ``root``: ``P`` is a square, the channel its root; ``sw``: :data:`~.bundles.Search`."""
    t_abs, h, te = span
    pbin, PB, EP = pk.pbin, pk.PB, pk.EP
    d, ee, wflat, stk = sw
    for b in range(b0, b1 + 1):
        ta = 0.0 if b == b0 else (b * pbin - t_abs) / h
        tb = te if b == b1 else ((b + 1) * pbin - t_abs) / h
        ta = min(max(ta, 0.0), te)
        tb = min(max(tb, ta), te)
        v, tau = poly_max(P, ta, tb, _level(PB, EP, b, col, e, root), d, ee, wflat, stk,
                          counts)
        _record(math.sqrt(max(v, 0.0)) if root else v, t_abs + tau * h, b, col, e, PB, EP)


@numba.njit(cache=True)
def resolve_peak(col, e, root, pk, sw, counts):
    """Search the pending piece of channel ``col`` (:func:`_track_peaks`) for its maximum into
    its bin and, for a contact ``e >= 0``, its episode (of ``pk``, :data:`~.bundles.Peaks`);
    ``root``: a radial channel (its square pending); ``sw``: :data:`~.bundles.Search`."""
    PC, PM, PN, PB, EP = pk.PC, pk.PM, pk.PN, pk.PB, pk.EP
    d, ee, wflat, stk = sw
    if PM[col, 0] == -np.inf:
        return
    PM[col, 0] = -np.inf
    m = PN[col]
    t_abs, h, te, b = PM[col, 1], PM[col, 2], PM[col, 3], int(PM[col, 4])
    counts[5] += 1
    v, tau = poly_max(PC[col, :m], 0.0, te, _level(PB, EP, b, col, e, root), d, ee, wflat,
                      stk, counts)
    _record(math.sqrt(max(v, 0.0)) if root else v, t_abs + tau * h, b, col, e, PB, EP)


@numba.njit(cache=True)
def resolve_all(nc, pk, sw, counts):
    """Every pending piece searched (the end of a run, a re-basing)."""
    for col in range(pk.PM.shape[0]):
        resolve_peak(col, col if col < nc else -1, col >= nc, pk, sw, counts)


@numba.njit(cache=True, inline="always")
def _offer(col, e, root, P, m, span, b, v, tau, pk, sw, counts):
    """One piece of channel ``col`` in one bin ``b``: ``P`` (m terms; a radial channel's
    square) with its larger end value ``v`` at ``tau`` (the channel's value, not squared).
    The end value is taken at once; an interior maximum matters only above what the bin (and
    the episode) hold, so the piece is searched only if its bound (:func:`_upper`) exceeds
    that, and lazily: it waits as the channel's pending piece, dropped as soon as a later end
    value rises above its bound (a rising force: nearly every piece), searched when a second
    one needs the place, at the bin's or episode's end and at the run's. ``span``: the piece
    ``(t_abs, h, te)``; ``pk``: :data:`~.bundles.Peaks`; ``sw``: :data:`~.bundles.Search`."""
    t_abs, h, te = span
    PC, PM, PN, PB, EP = pk.PC, pk.PM, pk.PN, pk.PB, pk.EP
    ee = sw.e
    _record(v, t_abs + tau * h, b, col, e, PB, EP)
    level = _level(PB, EP, b, col, e, root)
    if PM[col, 0] != -np.inf and PM[col, 0] <= level:
        PM[col, 0] = -np.inf  # the pending piece cannot hold anything higher any more
    counts[4] += 1
    ub = _upper(P, m, 0.0, te, level, ee)
    if ub <= level:
        return
    if PM[col, 0] != -np.inf:
        resolve_peak(col, e, root, pk, sw, counts)
        level = _level(PB, EP, b, col, e, root)
        if ub <= level:
            return
    for k in range(m):
        PC[col, k] = P[k]
    PN[col] = m
    PM[col, 0] = ub
    PM[col, 1] = t_abs
    PM[col, 2] = h
    PM[col, 3] = te
    PM[col, 4] = b


@numba.njit(cache=True)
def _track_peaks(Bv, nt, span, con, chans, pk, pw, sw, counts):
    """Exact maxima over the piece ``Bv`` (from absolute time ``t_abs``, length ``h``, up to
    ``te`` of it: the piece's end or its first event) of every closed contact's force (into its
    episode ``EP`` and the peak bins ``PB[:, e]``) and of every spring channel's magnitude
    (rows ``chp``: one row's ``|F|`` or a pair's ``sqrt(F_x^2 + F_y^2)``, into ``PB[:, nc +
    ch]``). A row's series is formed only where its first bound (:func:`_low_bound`) does not
    keep it below what the bins and the episode hold already, and searched as :func:`_offer`
    says (``PC``, ``PM``, ``PN``: each channel's pending piece: its terms, ``(bound, t_abs, h,
    te, bin)`` (bound ``-inf``: none) and its number of terms). ``counts[4]``: rows offered
    (:func:`_offer`), ``counts[5]``: pieces searched (:func:`poly_max`), ``counts[6]``: of
    those, searched for interior maxima. The piece is ``span = (t_abs, h, te)``; the rest
    comes in the bundles of :mod:`gearmodal.integrate.bundles`: ``con`` (ContactRows),
    ``chans`` (Channels), ``pk`` (Peaks), ``pw`` (PeakWork), ``sw`` (Search)."""
    t_abs, h, te = span
    s, kc, cc, off, wrows, tc_idx, FT = con.s, con.kc, con.cc, con.off, con.rows, con.tc_idx, \
        con.FT
    wptr, widx, wval = wrows
    srows, sk, sc, chp = chans
    EP, PB, pbin, PM = pk.EP, pk.PB, pk.pbin, pk.PM
    tq, td, fx, fy, P, tmp = pw
    ee = sw.e
    n = Bv.shape[1]
    nc = off.shape[0]
    nb = PB.shape[0]
    L = min(LOW_TERMS, nt)
    for i in range(n):  # the first bound's tails
        a = 0.0
        ad = 0.0
        for k in range(L, nt):
            x = abs(Bv[k, i])
            a += x
            ad += k * x
        tq[i] = a
        td[i] = ad
    b0 = min(int(t_abs // pbin), nb - 1)
    b1 = min(int((t_abs + te * h) // pbin), nb - 1)
    for col in range(PM.shape[0]):  # a pending piece of an earlier bin: its bin is done
        if PM[col, 0] != -np.inf and (int(PM[col, 4]) != b0 or b1 != b0):
            resolve_peak(col, col if col < nc else -1, col >= nc, pk, sw, counts)
    for e in range(nc):
        if not s[e]:
            continue
        thr = EP[e, 0]
        for b in range(b0, b1 + 1):
            thr = min(thr, PB[b, e, 0])
        et = -1
        for j in range(tc_idx.shape[0]):
            if tc_idx[j] == e:
                et = j
        if et < 0:
            if thr > -np.inf and _low_bound(Bv, L, h, te, wrows, e, (kc[e], cc[e], off[e]),
                                            tq, td, tmp, ee, True) <= thr:
                continue
            _row_series(Bv, nt, h, wptr, widx, wval, e, kc[e], cc[e], off[e], fx, tmp)
        else:  # a turning contact: its force series (T2)
            for k in range(nt):
                fx[k] = FT[et, k]
        if b0 == b1:  # one bin (nearly every piece)
            v0 = fx[0]
            v1 = fx[nt - 1]
            for k in range(nt - 2, -1, -1):
                v1 = v1 * te + fx[k]
            v, tau = (v1, te) if v1 > v0 else (v0, 0.0)
            _offer(e, e, False, fx, nt, span, b0, v, tau, pk, sw, counts)
        else:
            counts[5] += 1
            _bin_max(fx[:nt], span, b0, b1, e, e, False, pk, sw, counts)
    for ch in range(chp.shape[0]):
        col = nc + ch
        thr = PB[b0, col, 0]
        for b in range(b0 + 1, b1 + 1):
            thr = min(thr, PB[b, col, 0])
        two = chp[ch, 1] >= 0
        if thr > 0.0:
            r = chp[ch, 0]
            bx = _low_bound(Bv, L, h, te, srows, r, (sk[r], sc[r], 0.0), tq, td, tmp, ee,
                            False)
            by = 0.0
            if two:
                r = chp[ch, 1]
                by = _low_bound(Bv, L, h, te, srows, r, (sk[r], sc[r], 0.0), tq, td, tmp,
                                ee, False)
            if bx * bx + by * by <= thr * thr:
                continue
        m2 = _radial_square(Bv, nt, h, chans, chp[ch, 0], chp[ch, 1], fx, fy, P, tmp)
        if b0 == b1:
            v0 = P[0]
            v1 = P[m2 - 1]
            for k in range(m2 - 2, -1, -1):
                v1 = v1 * te + P[k]
            v, tau = (v1, te) if v1 > v0 else (v0, 0.0)
            _offer(col, -1, True, P, m2, span, b0, math.sqrt(max(v, 0.0)), tau, pk, sw, counts)
        else:
            counts[5] += 1
            _bin_max(P[:m2], span, b0, b1, col, -1, True, pk, sw, counts)


# -- exact turning points (DESIGN 3.2; issue 34 item 3: fatigue from the exact solution) ---------
#: a piece over which a channel moves by less than this fraction of its size is flat: its
#: derivative's roots would be rounding, not turning points
FLAT = 1e-14


@numba.njit(cache=True)
def poly_turns(c, n, te, taus, d, e, wflat, stk):
    """The interior extrema of ``p(tau) = sum_(k < n) c_k tau^k`` on ``(0, te)``, in order,
    into ``taus``; returns their number. None where ``p'(0)`` dominates the rest of ``p'``
    (monotone) or the piece is flat to rounding (:data:`FLAT`). Else the Bernstein
    coefficients of ``p'`` on ``[0, te]`` decide (Descartes' rule for the Bernstein basis):
    no sign change, no extremum; one, exactly one, located by Newton's method and bisection
    (:func:`_refine`); more, every crossing of ``p'`` (a minimum) or ``-p'`` (a maximum) by
    :func:`first_root` (Bernstein subdivision: none missed, located to rounding) on ``p'``
    shifted to what is left of the interval, the searches alternating so that each starts
    where its function is not positive (as :func:`poly_max`). ``d``, ``e`` (n), ``wflat``
    ((DEPTH + 5) n), ``stk``: scratch."""
    if n < 3 or te <= 0.0:
        return 0
    size = abs(c[0])
    var = 0.0
    rest = 0.0
    sc = 1.0
    for k in range(1, n):
        if k >= 2:
            rest += k * abs(c[k]) * sc  # sc = te^(k - 1)
        sc *= te
        var += abs(c[k]) * sc
    if var <= FLAT * (size + var) or abs(c[1]) > rest:
        return 0
    m = n - 1
    for k in range(m):
        d[k] = (k + 1.0) * c[k + 1]
    _shift(d, m, 0.0, te, e)  # p' on [0, te] as a polynomial on [0, 1]
    _bernstein(e[:m], e[:m])
    changes = 0
    prev = 0.0
    for k in range(m):
        if e[k] != 0.0:
            if prev != 0.0 and (e[k] > 0.0) != (prev > 0.0):
                changes += 1
            prev = e[k]
    if changes == 0:
        return 0
    if changes == 1 and e[0] != 0.0 and e[m - 1] != 0.0:
        _shift(d, m, 0.0, te, e)
        sign = 1.0 if e[0] < 0.0 else -1.0  # g = sign p' rises through 0 once
        for k in range(m):
            e[k] *= sign
        r = _refine(e[:m], 0.0, 1.0, _hpoly(e[:m], 0.0), _hpoly(e[:m], 1.0))
        if r >= 1.0:
            return 0
        taus[0] = te * r
        return 1
    work = wflat[:(DEPTH + 5) * m].reshape((DEPTH + 5, m))
    lo = 0.0
    sign = 1.0 if _hpoly(d[:m], 0.0) < 0.0 else -1.0
    cnt = 0
    for _ in range(2 * m + 2):  # p' has at most m - 1 roots
        tau = _next_turn(d, m, lo, te, sign, e, work, stk)
        if tau == np.inf or tau >= te:
            break  # none left, or at the piece's end (its end value, not an extremum)
        taus[cnt] = tau
        cnt += 1
        lo = tau
        sign = -sign
    return cnt


@numba.njit(cache=True, inline="always")
def _feed(ch, t, v, TS, TP, ntp):
    """The next value ``v`` at time ``t`` of turning channel ``ch``: ``TS[ch]`` holds its last
    point (time, value), direction (+-1, 0: none yet), whether it has one and a jump flag; the
    last point is written to ``TP`` (time, channel, value) once the direction changes there
    (a turning point), the channel's first point at once. A plateau counts once. Returns the
    rows of ``TP`` used."""
    if TS[ch, 3] == 0.0:
        TS[ch, 0] = t
        TS[ch, 1] = v
        TS[ch, 2] = 0.0
        TS[ch, 3] = 1.0
        TP[ntp, 0] = t
        TP[ntp, 1] = ch
        TP[ntp, 2] = v
        return ntp + 1
    pv = TS[ch, 1]
    if v == pv:
        return ntp
    dv = 1.0 if v > pv else -1.0
    if TS[ch, 2] != 0.0 and dv != TS[ch, 2]:
        TP[ntp, 0] = TS[ch, 0]
        TP[ntp, 1] = ch
        TP[ntp, 2] = pv
        ntp += 1
    TS[ch, 0] = t
    TS[ch, 1] = v
    TS[ch, 2] = dv
    return ntp


@numba.njit(cache=True, inline="always")
def _level_bin(TS, ch, v):
    """The level bin of channel ``ch`` at value ``v`` (:mod:`.turns`: its ``ne`` edges
    ``TS[ch, LEVEL0:LEVEL0 + ne]``): bin ``j`` holds ``[e_j, e_(j+1))``, values below the
    first edge are in bin 0 and from the last edge on in bin ``ne - 2`` (as
    :func:`gearmodal.fatigue.load_duration` clips them)."""
    ne = int(TS[ch, 6])
    lo = 0
    hi = ne
    while lo < hi:  # the edges <= v
        mid = (lo + hi) // 2
        if TS[ch, LEVEL0 + mid] <= v:
            lo = mid + 1
        else:
            hi = mid
    return float(min(max(lo - 1, 0), ne - 2))


@numba.njit(cache=True)
def _level_row(TP, ntp, t, ch, b, rev, tau):
    """A level change of channel ``ch`` (in bin ``b`` from time ``t`` on, ``tau`` into the
    piece) appended to ``TP`` as ``(t, -(ch + 1), b, R)``, ``R`` the input's revolutions from
    the run's start (rad; ``rev``: :func:`_track_turns`'s, NaN without an input); room is
    the caller's (:func:`_track_turns`)."""
    TP[ntp, 0] = t
    TP[ntp, 1] = -(ch + 1.0)
    TP[ntp, 2] = b
    TP[ntp, 3] = _revolutions(rev, tau) if rev[1] > 0.0 else np.nan
    return ntp + 1


@numba.njit(cache=True)
def _level_jump(ch, t, v, TS, TP, ntp, rev):
    """Channel ``ch`` has value ``v`` at time ``t`` after a jump (its first point, a contact
    switching, a stiffness changing): its level bin set there (a row where it changes)."""
    if TS[ch, 6] < 2.0:
        return ntp
    b = _level_bin(TS, ch, v)
    if b != TS[ch, 5]:
        TS[ch, 5] = b
        ntp = _level_row(TP, ntp, t, ch, b, rev, 0.0)
    return ntp


@numba.njit(cache=True)
def _level_segment(ch, P, m, root, span, seg, TS, TP, ntp, g, rev):
    """Channel ``ch`` over ``seg = (ta, tb, vb)``: ``[ta, tb]`` of the piece ``span = (t_abs,
    h, te)`` (``P``: its series of ``m`` terms, monotone there; a radial channel's square with
    ``root``), ending at value ``vb``: every edge it passes, located on the series (Newton and
    bisection, :func:`_refine`, to adjacent floats) and written as a level change
    (:func:`_level_row`). ``g``: scratch of ``m``."""
    t_abs, h = span[0], span[1]
    ta, tb, vb = seg
    if TS[ch, 6] < 2.0:
        return ntp
    b_new = _level_bin(TS, ch, vb)
    b = TS[ch, 5]
    if b_new == b:
        return ntp
    up = b_new > b
    j = int(b) + 1 if up else int(b)
    while (up and j <= b_new) or (not up and j > b_new):
        edge = TS[ch, LEVEL0 + j]
        target = edge * abs(edge) if root else edge
        sign = 1.0 if up else -1.0  # g = sign (P - target) rises through 0 at the edge
        for k in range(m):
            g[k] = sign * P[k]
        g[0] -= sign * target
        glo = _hpoly(g[:m], ta)
        ghi = _hpoly(g[:m], tb)
        if glo > 0.0:
            tau = ta  # passed at the segment's start (rounding of the last piece's end)
        elif ghi <= 0.0:
            tau = tb
        else:
            tau = _refine(g[:m], ta, tb, glo, ghi)
        nb = float(j) if up else float(j - 1)
        TS[ch, 5] = nb
        ntp = _level_row(TP, ntp, t_abs + tau * h, ch, nb, rev, tau)
        j = j + 1 if up else j - 1
    return ntp


@numba.njit(cache=True)
def _piece_turns(ch, P, m, span, jump, root, TS, TP, ntp, taus, sw, rev):
    """Channel ``ch`` over one piece (``P``: its series of ``m`` terms, a radial channel's
    square with ``root``): its start value where the channel jumped there, its interior
    extrema (:func:`poly_turns`) and its end value, through :func:`_feed`; with level edges
    (``TS[ch, 6]``), every change of its level bin (:func:`_level_jump`,
    :func:`_level_segment`: the piece is monotone between its extrema). Returns the rows of
    ``TP`` used. ``span``: the piece ``(t_abs, h, te)``; ``sw``: :data:`~.bundles.Search`."""
    t_abs, h, te = span
    d, e, wflat, stk = sw
    if jump:
        v = P[0]
        v = math.sqrt(max(v, 0.0)) if root else v
        ntp = _level_jump(ch, t_abs, v, TS, TP, ntp, rev)
        ntp = _feed(ch, t_abs, v, TS, TP, ntp)
    # the last terms, together below rounding of the piece's size, left out of the search
    size = 0.0
    sc = 1.0
    for k in range(m):
        size += abs(P[k]) * sc
        sc *= te
    ms = m
    tail = 0.0
    sc = te ** (m - 1)
    while ms > 2 and tail + abs(P[ms - 1]) * sc <= 1e-17 * size:
        tail += abs(P[ms - 1]) * sc
        ms -= 1
        sc = sc / te if te > 0.0 else 0.0
    cnt = poly_turns(P, ms, te, taus, d, e, wflat, stk)
    levels = TS[ch, 6] >= 2.0
    ta = 0.0
    for i in range(cnt + 1):
        tb = taus[i] if i < cnt else te
        v = _hpoly(P[:m], tb)
        v = math.sqrt(max(v, 0.0)) if root else v
        if levels and _level_bin(TS, ch, v) != TS[ch, 5]:
            ntp = _level_segment(ch, P, m, root, span, (ta, tb, v), TS, TP, ntp, d, rev)
        ntp = _feed(ch, t_abs + tb * h, v, TS, TP, ntp)
        ta = tb
    return ntp


#: the columns of a turning channel's state ``TS`` (:class:`~.turns.TurnPoints`): its last
#: point's time and value, direction, has one, jump flag; level bin (-1: none yet), number of
#: level edges; in the first channel's row only: the input speed's sparse row (-1: none), the
#: reference speed (rad/s) it is added to and the input's revolutions from the run's start
#: (rad); the level edges from ``LEVEL0`` on
LEVEL0 = 10
#: Gauss-Legendre nodes and weights on [-1, 1] of the load integrals (:func:`_load_integrals`):
#: exact for polynomials of degree 31; a piece's series decays as ``REACH^k / k!`` (the
#: step's choice), so its powers are integrated to rounding on the turbine runs and to 3e-10
#: on a rattle (tests/test_levels.py holds it against a dense reference)
GAUSS_X, GAUSS_W = np.polynomial.legendre.leggauss(16)


@numba.njit(cache=True)
def _revolutions(rev, tau):
    """The input's revolutions (rad) from the run's start to ``tau`` into the piece: ``rev``
    holds those at the piece's start, the antiderivative ``A`` of its speed over the piece
    (``int Omega dt`` from the start) and the zeros of the speed inside it
    (:func:`_track_turns`), so ``R = R0 + sum |A(z_(i+1)) - A(z_i)|`` over the stretches
    between them, each of one sign."""
    na = int(rev[1])
    c = rev[2:2 + na]
    nz = int(rev[2 + na])
    R = rev[0]
    a = 0.0
    Aa = 0.0
    for i in range(nz + 1):
        b = rev[3 + na + i] if i < nz else tau
        if b > tau:
            b = tau
        Ab = _hpoly(c, b)
        R += abs(Ab - Aa)
        a = b
        Aa = Ab
        if a >= tau:
            break
    return R


@numba.njit(cache=True)
def _load_nodes(sp, ns, rev, t_abs, h, te, pbin, nb, XN, WN, BN, AQ):
    """The quadrature of the load integrals (:func:`_load_integrals`) over ``[0, te]`` of a
    piece: 16-point Gauss-Legendre (:data:`GAUSS_X`) on each part between the peak bins'
    edges and the input speed's zeros (``rev``, :func:`_revolutions`; a smooth integrand on
    each part), into ``XN`` (the nodes, in the piece's ``tau``), ``WN`` (their weights times
    ``|Omega| h``, ``Omega`` the input's speed: its series ``sp`` of ``ns`` terms, rad/s) and
    ``BN`` (their peak bins; absolute time ``t_abs + tau h``); ``AQ``: scratch. Returns the
    number of nodes."""
    ng = GAUSS_X.shape[0]
    b = min(int(t_abs // pbin), nb - 1)
    na = int(rev[1])
    nz = int(rev[2 + na])
    iz = 0
    a = 0.0
    cnt = 0
    while a < te:
        edge = te if b >= nb - 1 else min(max(((b + 1) * pbin - t_abs) / h, a), te)
        tb = edge
        if iz < nz and rev[3 + na + iz] < tb:
            tb = rev[3 + na + iz]
            iz += 1
        if tb > a:
            if cnt + ng > XN.shape[0]:
                raise ValueError("_load_nodes: more parts than the nodes' room")
            half = 0.5 * (tb - a)
            mid = 0.5 * (tb + a)
            for i in range(ng):
                XN[cnt] = mid + half * GAUSS_X[i]
                WN[cnt] = GAUSS_W[i] * half * h
                BN[cnt] = b
                cnt += 1
        if tb >= edge:
            b += 1
        a = tb
    _horner_at(sp, ns, XN, cnt, AQ)
    for i in range(cnt):
        WN[i] *= abs(AQ[i])
    return cnt


@numba.njit(cache=True, inline="always")
def _horner_at(c, m, X, cnt, out):
    """``out[i] = sum_(k < m) c_k X_i^k`` for ``i < cnt``: Horner's rule with the nodes in the
    inner loop (independent chains the compiler vectorises, not one dependent chain per
    node)."""
    for i in range(cnt):
        out[i] = c[m - 1]
    for k in range(m - 2, -1, -1):
        ck = c[k]
        for i in range(cnt):
            out[i] = out[i] * X[i] + ck


@numba.njit(cache=True)
def _load_integrals(P, m, XN, WN, BN, cnt, PB, col, AQ):
    """``int F^3 dN``, ``int F^(10/3) dN`` (:data:`gearmodal.fatigue.LOAD_INTEGRALS`: a ball
    and a roller bearing's exponents; ``dN = |Omega| dt``) and ``int dN`` over a piece, added
    to ``PB[b, col, 2:5]`` of each peak bin ``b`` it touches: ``P`` the series of a radial
    channel's square ``F^2`` (``m`` terms) at the ``cnt`` nodes ``XN`` of
    :func:`_load_nodes` (weights ``WN``, bins ``BN``; ``AQ``: scratch)."""
    _horner_at(P, m, XN, cnt, AQ)
    for i in range(cnt):
        f = math.sqrt(max(AQ[i], 0.0))
        w = WN[i]
        f3 = w * f * f * f
        b = BN[i]
        PB[b, col, 2] += f3
        PB[b, col, 3] += f3 * np.cbrt(f)
        PB[b, col, 4] += w


@numba.njit(cache=True)
def _track_turns(Bv, nt, span, con, chans, tch, TP, ntp, tkw, sw, PB, pbin):
    """The turning points over the piece ``Bv`` (from absolute time ``t_abs``, length ``h``, up
    to ``te`` of it) of every turning channel: the contact channels ``TCH`` (up to two
    contacts each, weights ``TCW``: a force column of one contact or a dead band's two sides;
    0 while open; a contact ``jumped`` at the piece's start: switched or its stiffness
    changed) and then the spring channels ``chp`` (a bearing's radial force, as
    :func:`_track_peaks`), and their level changes (:func:`_piece_turns`); a spring channel's
    load integrals into the peak bins ``PB`` (:func:`_load_integrals`, over the input speed's
    series, formed into ``spd``, where ``TS`` names its row, on the nodes ``XN``, ``WN``,
    ``BN`` of :func:`_load_nodes`, ``AQ`` scratch; ``rev``: the input's revolutions
    from the run's start, rad, at the piece's start, its antiderivative's number of terms and
    terms, the number of the speed's zeros in the piece and the zeros: :func:`_revolutions`,
    what the level changes carry). Returns ``TP`` (grown first to hold every row the piece
    may add) and its rows used. The piece is ``span = (t_abs, h, te)``; the rest comes in the
    bundles of :mod:`gearmodal.integrate.bundles`: ``con`` (ContactRows), ``chans``
    (Channels), ``tch`` (TurnChannels), ``tkw`` (TurnWork), ``sw`` (Search)."""
    t_abs, h, te = span
    s, jumped, kc, cc, off, tc_idx, FT = con.s, con.jumped, con.kc, con.cc, con.off, \
        con.tc_idx, con.FT
    wptr, widx, wval = con.rows
    (sptr, sidx, sval), _, _, chp = chans
    TCH, TCW, TS = tch
    fx, fy, P, tmp, taus, spd, rev, XN, WN, BN, AQ = tkw
    d, ee, wflat, stk = sw
    nct = TCH.shape[0]
    t1 = t_abs + te * h
    # room for every row the piece may add: each channel's turning points and, with level
    # edges, a level change per edge on each of its monotone stretches; the marks
    room = ntp + int(te * h / pbin) + 2
    for ch in range(TS.shape[0]):
        room += (taus.shape[0] + 2) * (1 + int(TS[ch, 6]))
    if room > TP.shape[0]:
        grown = np.empty((2 * TP.shape[0] + room, TP.shape[1]))
        grown[:ntp] = TP[:ntp]
        TP = grown
    # the input's speed (rad/s) and revolutions over the piece
    rev[1] = 0.0
    ns = 0
    if TS.shape[0] > 0 and TS[0, 7] >= 0.0:
        _row_series(Bv, nt, h, sptr, sidx, sval, int(TS[0, 7]), 0.0, 1.0, 0.0, spd, tmp)
        spd[0] += TS[0, 8]
        ns = nt - 1
        rev[0] = TS[0, 9]
        rev[1] = ns + 1.0
        rev[2] = 0.0
        for k in range(ns):
            rev[3 + k] = spd[k] * h / (k + 1.0)
        # the speed's zeros in the piece: the extrema of its antiderivative (poly_turns)
        na = ns + 1
        nz = poly_turns(rev[2:2 + na], na, te, taus, d, ee, wflat, stk)
        rev[2 + na] = nz
        for i in range(nz):
            rev[3 + na + i] = taus[i]
        # a mark of the input's revolutions at each peak bin's start inside the piece: a
        # level row of channel -1 (the rows' end)
        kb = int(t_abs // pbin) + 1
        while kb * pbin <= t1:
            ntp = _level_row(TP, ntp, kb * pbin, TS.shape[0], -1.0, rev,
                             (kb * pbin - t_abs) / h)
            kb += 1
    for ch in range(nct):
        closed = False
        jump = TS[ch, 4] != 0.0 or TS[ch, 3] == 0.0
        for j in range(2):
            e = TCH[ch, j]
            if e >= 0:
                if s[e]:
                    closed = True
                if jumped[e]:
                    jump = True
        TS[ch, 4] = 0.0
        if not closed:
            if jump:
                ntp = _level_jump(ch, t_abs, 0.0, TS, TP, ntp, rev)
                ntp = _feed(ch, t_abs, 0.0, TS, TP, ntp)
            ntp = _feed(ch, t1, 0.0, TS, TP, ntp)
            continue
        for k in range(nt):
            P[k] = 0.0
        for j in range(2):
            e = TCH[ch, j]
            if e < 0 or not s[e]:
                continue
            et = -1
            for jj in range(tc_idx.shape[0]):
                if tc_idx[jj] == e:
                    et = jj
            if et < 0:
                _row_series(Bv, nt, h, wptr, widx, wval, e, kc[e], cc[e], off[e], fx, tmp)
            else:  # a turning contact: its force series (T2)
                for k in range(nt):
                    fx[k] = FT[et, k]
            for k in range(nt):
                P[k] += TCW[ch, j] * fx[k]
        ntp = _piece_turns(ch, P, nt, span, jump, False, TS, TP, ntp, taus, sw, rev)
    nq = 0
    if ns and TS.shape[0] > nct:  # the load integrals' nodes (the same for every channel)
        need = GAUSS_X.shape[0] * (int(rev[2 + ns + 1]) + int(te * h / pbin) + 2)
        if need > XN.shape[0]:  # (a piece over many peak bins: scratch of its own)
            XN = np.empty(need)
            WN = np.empty(need)
            BN = np.empty(need, dtype=np.int64)
            AQ = np.empty(need)
        nq = _load_nodes(spd, ns, rev, t_abs, h, te, pbin, PB.shape[0], XN, WN, BN, AQ)
    for r in range(TS.shape[0] - nct):  # (none when the turning points are off)
        ch = nct + r
        jump = TS[ch, 4] != 0.0 or TS[ch, 3] == 0.0
        TS[ch, 4] = 0.0
        m2 = _radial_square(Bv, nt, h, chans, chp[r, 0], chp[r, 1], fx, fy, P, tmp)
        if nq:
            _load_integrals(P, m2, XN, WN, BN, nq, PB, off.shape[0] + r, AQ)
        ntp = _piece_turns(ch, P, m2, span, jump, True, TS, TP, ntp, taus, sw, rev)
    if rev[1] > 0.0:  # the revolutions at the next piece's start
        TS[0, 9] = _revolutions(rev, te)
    return TP, ntp


#: force samples within this fraction of their size from the line through a stretch's first
#: two are on it (the rounding of loads computed on a line, not a kink)
LINE_TOL = 1e-12


@numba.njit(cache=True)
def _stretch(F, k, n_steps):
    """The last output index ``k2`` (> k) such that the force samples ``F[k..k2]`` lie on the
    line through ``F[k]`` and ``F[k + 1]`` (to ``LINE_TOL``): the first-order hold has no kink
    before ``k2``, so the solution's series runs through the output times in between."""
    m = F.shape[1]
    k2 = k + 1
    while k2 < n_steps:
        j = k2 + 1
        for c in range(m):
            d = F[k + 1, c] - F[k, c]
            line = F[k, c] + (j - k) * d
            if abs(F[j, c] - line) > LINE_TOL * (abs(F[k, c]) + (j - k) * abs(d)):
                return k2
        k2 = j
    return k2


@numba.njit(cache=True)
def _harmonic_rows(HX, HNU, t, h, nt, HF):
    """Scaled Taylor rows ``HF[k] = g_k h^k`` (k < ``nt``) at time ``t`` of the harmonic loads
    ``g(t) = Re sum_j HX_j exp(i HNU_j t)`` (``M^-1`` times the load, (nh, n) complex):
    ``g_k h^k = Re sum_j HX_j exp(i HNU_j t) (i HNU_j h)^k / k!`` (T1's ``g_k`` of a load that
    is a harmonic, carried exactly as the turning geometry is)."""
    n = HX.shape[1]
    for k in range(nt):
        for i in range(n):
            HF[k, i] = 0.0
    for j in range(HX.shape[0]):
        z = complex(math.cos(HNU[j] * t), math.sin(HNU[j] * t))
        step = 1j * HNU[j] * h
        for k in range(nt):
            for i in range(n):
                HF[k, i] += (HX[j, i] * z).real
            z = z * step / (k + 1.0)


@numba.njit(cache=True, inline="always")
def _write(X, S, j, q, v, s):
    """Output row ``j``: the state ``(q, v)`` and the contact state ``s``."""
    n = q.shape[0]
    for i in range(n):
        X[j, i] = q[i]
        X[j, n + i] = v[i]
    for e in range(s.shape[0]):
        S[j, e] = s[e]


@numba.njit(cache=True)
def _turning_columns(n, geo):
    """The state matrix ``[M^-1 K_s, M^-1 C_s]`` (filled by :func:`_state_matrices`) and, for a
    turning system, the columns Z of the turning harmonics' rows (T2): Re/Im of ZK_h (h >= 1)
    on Re/Im of Y_h, then of ZC_h on Yd_h, one product. Z columns zero in every row are dropped
    (a harmonic touches only its own frame's coordinates: two turning carriers share few);
    ``zsrc`` maps the kept ones to their place in the full layout, where :func:`_coefficients`
    writes them first. Returns ``(MKC, zsrc, nz, cturn)``: ``nz`` the full layout's Z columns,
    ``cturn`` a turning damping (constant over the run)."""
    harm, tcols, krows, ZK, ZC = geo[2], geo[3], geo[4], geo[6], geo[7]
    H1 = harm.shape[0]
    nT = tcols.shape[0]
    cturn = False
    for hh in range(1, H1):
        for i in krows:
            for c in range(nT):
                if ZC[hh, i, c] != 0.0:
                    cturn = True
    nz = 2 * nT * (H1 - 1) * (2 if cturn else 1) if H1 > 1 else 0
    MKC = np.zeros((n, 2 * n + nz))
    o = 2 * n
    for hh in range(1, H1):
        for i in krows:
            for c in range(nT):
                MKC[i, o + c] = ZK[hh, i, c].real
                MKC[i, o + nT + c] = -ZK[hh, i, c].imag
        o += 2 * nT
    if cturn:
        for hh in range(1, H1):
            for i in krows:
                for c in range(nT):
                    MKC[i, o + c] = ZC[hh, i, c].real
                    MKC[i, o + nT + c] = -ZC[hh, i, c].imag
            o += 2 * nT
    nzk = 0
    zsrc = np.empty(nz, dtype=np.int64)
    for jz in range(nz):
        for i in range(n):
            if MKC[i, 2 * n + jz] != 0.0:
                zsrc[nzk] = jz
                nzk += 1
                break
    if nzk < nz:
        MKCc = np.empty((n, 2 * n + nzk))
        for i in range(n):
            for j in range(2 * n):
                MKCc[i, j] = MKC[i, j]
            for j in range(nzk):
                MKCc[i, 2 * n + j] = MKC[i, 2 * n + zsrc[j]]
        MKC = MKCc
    return MKC, zsrc[:nzk], nz, cturn


@numba.njit(cache=True)
def _scratch(x, s, sy, geo, n_terms, nz, zsrc):
    """The arrays :func:`taylor_run` works in, allocated once per call: the piece's series
    ``B`` (n_terms, n) and the bundles of :mod:`~gearmodal.integrate.bundles` its phases read
    (``PieceState`` from the start state ``x``, ``Forcing``, ``RootWork``, ``TurningWork``,
    ``ContactRows`` of contact state ``s``, ``PeakWork``, ``Search``, ``TurnWork``)."""
    W, wptr, widx, wval, kc, cc, off = sy[3], sy[4], sy[5], sy[6], sy[7], sy[8], sy[9]
    harm, tcols, urows, tc_idx, TW, TU = geo[2], geo[3], geo[5], geo[8], geo[9], geo[11]
    n = x.shape[0] // 2
    nc = W.shape[0]
    H1 = harm.shape[0]
    nT = tcols.shape[0]
    nTC = tc_idx.shape[0]
    st = PieceState(x[:n].copy(), x[n:].copy(), np.empty(n), np.empty(n), np.empty(nc),
                    np.empty(nc), np.empty(nc), np.empty(nc), np.empty(n), np.empty(n))
    c = np.complex128
    fo = Forcing(np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.zeros((H1, n), c),
                 np.zeros((H1, n), c), np.zeros((H1, n), c), np.zeros((H1, n), c), np.zeros(n),
                 np.zeros(n), np.zeros((H1, n), c), np.zeros((H1, n), c))
    stk = np.empty((2, DEPTH + 1))
    rw = RootWork(np.empty(n_terms), np.empty((DEPTH + 5) * n_terms), stk, np.empty(nc),
                  np.empty(n), np.empty(nc, dtype=np.int64), np.empty(nc))
    FT = np.zeros((nTC, n_terms))
    tw = TurningWork(tcols, urows, TW, TU, np.empty(2 * n + nz),
                     np.zeros((H1, n_terms), dtype=np.complex128),
                     np.full(H1, n_terms, dtype=np.int64),  # E_h's terms up to a negligible one
                     np.empty((2, H1, n_terms, nT)), np.empty((2, H1, n_terms, nT)),
                     np.empty((n_terms, nT)), np.zeros((nTC, n_terms)), np.empty(nTC),
                     np.empty(nTC), np.empty(nTC, dtype=np.bool_), np.zeros((nTC, n_terms)),
                     np.zeros((nTC, n_terms)), FT, fo.GV, fo.GVS, np.zeros((n_terms, n)), zsrc)
    # the contacts that jumped at the current piece's start (exact turning points)
    con = ContactRows(s, np.zeros(nc, dtype=np.bool_), kc, cc, off, Sparse(wptr, widx, wval),
                      tc_idx, FT)
    pfx = np.zeros(n_terms)
    pfy = np.zeros(n_terms)
    ptmp = np.zeros(n_terms)
    pP = np.zeros(2 * n_terms)
    pw = PeakWork(np.empty(n), np.empty(n), pfx, pfy, pP, ptmp)
    sw = Search(np.zeros(2 * n_terms), np.zeros(2 * n_terms),
                np.empty((DEPTH + 5) * 2 * n_terms), stk)
    nq = 16 * (2 * n_terms + 8)  # the load integrals' nodes, weights, bins, values
    tkw = TurnWork(pfx, pfy, pP, ptmp, np.empty(2 * n_terms), np.zeros(2 * n_terms),
                   np.zeros(6 * n_terms + 4), np.empty(nq), np.empty(nq),
                   np.empty(nq, dtype=np.int64), np.empty(nq))
    return np.empty((n_terms, n)), st, fo, rw, tw, con, pw, sw, tkw


@numba.njit(cache=True)
def _setup(x, s, sy, geo, n_terms, chain):
    """The state matrices ``MKC``, ``acc`` (:func:`_turning_columns`; a chained call's when
    ``chain`` carries them), whether they are carried, a turning damping and the scratch
    (:func:`_scratch`). ``x``, ``s``, ``sy``, ``geo`` are borrowed (taylor_run's arguments):
    the scratch's bundles hold views of them that own nothing, valid while the caller holds
    its arguments, i.e. through the call; nothing here is handed back to Python."""
    carry, MKC_in, acc_in, _ = chain
    n = x.shape[0] // 2
    MKC, zsrc, nz, cturn = _turning_columns(n, geo)
    acc = np.empty(n)
    carried = (carry.shape[0] >= 7 and carry[0] > 0.0 and MKC_in.shape[0] == n
               and MKC_in.shape[1] == MKC.shape[1] and acc_in.shape[0] == n)
    if carried:
        MKC = MKC_in
        acc = acc_in
    return MKC, acc, carried, cturn, _scratch(x, s, sy, geo, n_terms, nz, zsrc)


@numba.njit(cache=True, inline="always")
def _resume(carried, carry, h_max, tscale, sy, s, bound, rho_all, MKC, acc):
    """The loop's state at the call's start: where the last call left off (``carry``, see
    :func:`taylor_run`), else the state matrices of contact state ``s`` and its piece limit.
    Returns ``(toggled, dense, pending, survived, h_max, tscale)``."""
    if carried:
        return (int(carry[1]), carry[2] > 0.0, carry[3] > 0.0, int(carry[4]), carry[5],
                carry[6])
    MK0, MC0, U, W, kc, cc, off = sy[0], sy[1], sy[2], sy[3], sy[7], sy[8], sy[9]
    _state_matrices(MK0, MC0, U, W, kc, cc, off, s, MKC, acc)
    pending = False
    if bound[1]:
        h_max, tscale, pending = _piece_limit(s, bound, rho_all, h_max, True)
    return 0, False, pending, 0, h_max, tscale


@numba.njit(cache=True, inline="always")
def _tracked(peaks, chans, turns):
    """The tracking's bundles (:func:`_track_peaks`, :func:`_track_turns`) of the arguments,
    borrowed: ``Peaks``, ``Channels``, ``TurnChannels``."""
    track, EP, PB, pbin, PC, PM, PN, t_call = peaks
    (sptr, sidx, sval), ch_k, ch_c, ch_p = chans
    pk = Peaks(track, EP, PB, pbin, PC, PM, PN, t_call)
    chn = Channels(Sparse(sptr, sidx, sval), ch_k, ch_c, ch_p)
    return borrowed((pk, chn, TurnChannels(turns[0], turns[1], turns[2])))


@numba.njit(cache=True, inline="always")
def _refresh(toggled, sy, s, MKC, acc):
    """The state matrices rebuilt from scratch after ``REFRESH`` rank-one updates (their
    rounding). Returns the updates since."""
    if toggled < REFRESH:
        return toggled
    MK0, MC0, U, W, kc, cc, off = sy[0], sy[1], sy[2], sy[3], sy[7], sy[8], sy[9]
    _state_matrices(MK0, MC0, U, W, kc, cc, off, s, MKC, acc)
    return 0


@numba.njit(cache=True, inline="always")
def _leave(x, st, sched_pos, ip):
    """The call's end state and schedule entry, for the caller (and the next call)."""
    n = st.q.shape[0]
    x[:n] = st.q
    x[n:] = st.v
    sched_pos[0] = ip


@numba.njit(cache=True, inline="always")
def _keep(carry, toggled, dense, pending, survived, h_max, tscale):
    """What a chained call reads back (:func:`_resume`), into ``carry`` (when it has room)."""
    if carry.shape[0] >= 7:
        kept = (1.0, float(toggled), 1.0 if dense else 0.0, 1.0 if pending else 0.0,
                float(survived), h_max, tscale)
        for i in range(7):
            carry[i] = kept[i]


@numba.njit(cache=True, inline="always")
def _piece_length(t, remaining, h_max, dense, ip, sched_t):
    """The next piece's length from ``t``: up to the limit ``h_max`` (a quarter of it right
    after a quick succession of events, ``dense``: the next one is likely near, and a shorter
    piece needs fewer terms), the output time ``remaining`` ahead (no sliver before it) and
    the next time event ``sched_t[ip]``."""
    hm = DENSE * h_max if dense else h_max
    h = min(hm, remaining)
    if h < remaining and remaining - h < 1e-3 * hm:
        h = 0.5 * remaining  # no sliver before the output time
    if ip < sched_t.shape[0] and sched_t[ip] < t + h:
        h = sched_t[ip] - t  # the piece ends at the next time event
    return h


@numba.njit(cache=True, inline="always")
def _piece_end(t, h, remaining, t_end, sched_t, ip, TL, il, tie):
    """The time a piece from ``t`` ends: ``t_end`` exactly when it was the ``remaining`` time,
    and exactly the time event or load knot that it reaches to within ``tie``."""
    t = t_end if h == remaining else t + h
    if ip < sched_t.shape[0] and sched_t[ip] - t < tie:
        t = max(t, sched_t[ip])  # exactly at the time event
    if il + 2 < TL.shape[0] and TL[il + 1] - t < tie:
        t = max(t, TL[il + 1])  # exactly at the load knot
    return t


@numba.njit(cache=True, inline="always")
def _stretch_forces(F, k, k2, span, MinvU, GT, fo):
    """``M^-1 F`` at the stretch start (output step ``k``) and its rate (first-order hold) from
    the stretch's ends (``k2``, ``span`` s later), once per stretch, so that the force (and the
    solution) does not depend on the output step when the samples lie on one line; for a
    turning system the load harmonics ``GT`` likewise. Returns whether a turning load is
    nonzero."""
    return _line(F, k, k2, span, MinvU, GT, fo.gF, fo.gS, fo.VA, fo.VS)


@numba.njit(cache=True, inline="always")
def _line(F, a, b, span, MinvU, GT, g, gs, V, VS):
    """The line of force rows ``F[a]`` to ``F[b]``, ``span`` s apart, through ``M^-1 U``
    (``MinvU``): ``g = MinvU F[a]`` and its rate ``gs = MinvU (F[b] - F[a]) / span``; the
    turning harmonics ``GT`` likewise into ``V``, ``VS``. ``b = a``: a constant (rate 0).
    Returns whether a turning harmonic of the line is nonzero."""
    n = g.shape[0]
    m = F.shape[1]
    for i in range(n):
        a0 = 0.0
        a1 = 0.0
        for j in range(m):
            a0 += MinvU[i, j] * F[a, j]
            a1 += MinvU[i, j] * (F[b, j] - F[a, j])
        g[i] = a0
        gs[i] = a1 / span
    loads = False
    for hh in range(1, V.shape[0]):
        for i in range(n):
            z0 = 0j
            z1 = 0j
            for j in range(m):
                z0 += GT[hh, i, j] * F[a, j]
                z1 += GT[hh, i, j] * (F[b, j] - F[a, j])
            V[hh, i] = z0
            VS[hh, i] = z1 / span
            if z0 != 0.0 or z1 != 0.0:
                loads = True
    return loads


@numba.njit(cache=True, inline="always")
def _time_events(t, ip, sched, tie, sy, con, MKC, acc):
    """Apply the scheduled stiffness changes due by ``t`` (within ``tie``) from ``sched``'s
    entry ``ip`` on: a closed contact's as a rank-one update of ``MKC``, ``acc`` (its force
    steps with the stiffness: it jumped). Returns the next entry and the updates made."""
    sched_t, sched_e, sched_k, _ = sched
    U, W, kc, cc, off = sy[2], sy[3], sy[7], sy[8], sy[9]
    s, jumped = con.s, con.jumped
    flips = 0
    while ip < sched_t.shape[0] and sched_t[ip] <= t + tie:
        e = sched_e[ip]
        if s[e]:
            _toggle(U, W, kc, cc, off, e, -1.0, MKC, acc)
            kc[e] = sched_k[ip]
            _toggle(U, W, kc, cc, off, e, 1.0, MKC, acc)
            flips += 2
            jumped[e] = True
        else:
            kc[e] = sched_k[ip]
        ip += 1
    return ip, flips


@numba.njit(cache=True, inline="always")
def _knot_forces(t, h, il, due, tL0, turning_loads, tie, loads, fo):
    """The loads on their own knots ``loads.TL``: the knot interval ``il`` holding ``t``, and
    when it moved (or ``due``) its line ``M^-1 FL`` from the knot at or before ``t`` and its
    rate (``fo.gLa``, ``fo.gLs``; turning harmonics ``fo.VLa``, ``fo.VLs``); the piece ``h``
    ends at the next knot. Returns ``(il, h, tL0, turning_loads)``: the interval, the piece,
    the knot's time and whether a turning load of the knots is nonzero."""
    TL, FL, MinvUL, GTL = loads[0], loads[1], loads[2], loads[3]
    nk = TL.shape[0]
    while il + 2 < nk and TL[il + 1] <= t + tie:
        il += 1
        due = True
    if due:
        tL0 = TL[il]
        if nk > 1:
            turning_loads = _line(FL, il, il + 1, TL[il + 1] - TL[il], MinvUL, GTL, fo.gLa,
                                  fo.gLs, fo.VLa, fo.VLs)
        else:  # a single knot: a constant
            turning_loads = _line(FL, il, il, 1.0, MinvUL, GTL, fo.gLa, fo.gLs, fo.VLa,
                                  fo.VLs)
    if il + 2 < nk and t + tie < TL[il + 1] < t + h:
        h = TL[il + 1] - t  # the piece ends at the next load knot
    return il, h, tL0, turning_loads


@numba.njit(cache=True, inline="always")
def _piece_forces(t, tk, tL0, knots, acc, fo, tw, con):
    """The force terms at the piece's start ``t`` (the stretch started at ``tk``, the knot
    interval at ``tL0``; ``knots``: loads on their own knots): ``g0 = M^-1 (F + f_s)`` and its
    rate ``gR``, and for a turning system the turning loads ``GV``, ``GVS`` and the turning
    contacts' stiffness, damping and state."""
    gF, gS, g0, gR, gLa, gLs = fo.gF, fo.gS, fo.g0, fo.gR, fo.gLa, fo.gLs
    n = g0.shape[0]
    for i in range(n):
        g0[i] = acc[i] + gF[i] + gS[i] * (t - tk)
        gR[i] = gS[i]
    if knots:
        for i in range(n):
            g0[i] += gLa[i] + gLs[i] * (t - tL0)
            gR[i] += gLs[i]
    H1 = fo.VA.shape[0]
    if H1 > 1:
        VA, VS, GV, VST, VLa, VLs = fo.VA, fo.VS, fo.GV, fo.GVS, fo.VLa, fo.VLs
        s, kc, cc, tc_idx = con.s, con.kc, con.cc, con.tc_idx
        kt, ct, closed = tw.kt, tw.ct, tw.closed
        for e in range(tc_idx.shape[0]):
            kt[e] = kc[tc_idx[e]]
            ct[e] = cc[tc_idx[e]]
            closed[e] = s[tc_idx[e]]
        for hh in range(H1):
            for i in range(n):
                GV[hh, i] = VA[hh, i] + VS[hh, i] * (t - tk)
                VST[hh, i] = VS[hh, i]
                if knots:
                    GV[hh, i] += VLa[hh, i] + VLs[hh, i] * (t - tL0)
                    VST[hh, i] += VLs[hh, i]


@numba.njit(cache=True, inline="always")
def _turning_offsets(t, h, nt, geo, tw):
    """The exponential series of the piece ``[t, t + h]`` (P2), each up to its first negligible
    term (P3), and the turning contacts' offsets ``OFS``."""
    om, psi0, harm, TOFF = geo[0], geo[1], geo[2], geo[10]
    E, EL, OFS = tw.E, tw.EL, tw.OFS
    H1 = harm.shape[0]
    psi = psi0 + om * t
    for hh in range(H1):
        z = 1j * harm[hh] * om * h
        E[hh, 0] = complex(math.cos(harm[hh] * psi), math.sin(harm[hh] * psi))
        EL[hh] = nt
        for jj in range(1, nt):
            if EL[hh] < nt:
                E[hh, jj] = 0j
                continue
            E[hh, jj] = E[hh, jj - 1] * z / jj
            # |E_j| <= |z|^j / j! below E_TINY (|z| < 1: the rest smaller): the Cauchy
            # products stop there (P3)
            if abs(E[hh, jj]) < E_TINY and abs(z) < 1.0:
                EL[hh] = jj + 1
    for e in range(OFS.shape[0]):
        for kk in range(nt):
            a = 0.0
            for hh in range(H1):
                a += (TOFF[hh, e] * E[hh, kk]).real
            OFS[e, kk] = a


@numba.njit(cache=True, inline="always")
def _piece_series(t, h, Bv, st, MKC, fo, tw, geo, loads, counts, cturn, turning_loads):
    """The piece's scaled series ``Bv`` from ``(t, st.q, st.v)``, halved (the series of
    ``h / 2``) while its tail is not negligible (a state stiffer than the bound). Returns the
    piece's length."""
    HX, HNU = loads[4], loads[5]
    g0, gR, q, v, y, HF = fo.g0, fo.gR, st.q, st.v, tw.y, tw.HF  # bound once (a field read
    # is a reference taken and dropped where it is read)
    nt = Bv.shape[0]
    turning = geo[2].shape[0] > 1
    harmonic = HX.shape[0] > 0
    while True:
        counts[3] += nt
        if turning:
            _turning_offsets(t, h, nt, geo, tw)
        # (whole arrays, the first nt terms used: contiguous, no strided views; a system that
        # does not turn has no harmonics, its loops are empty)
        if harmonic:
            _harmonic_rows(HX, HNU, t, h, nt, HF)
        if turning:
            _coefficients(MKC, g0, gR, q, v, h, Bv, tw, cturn, turning_loads, harmonic)
        else:
            _coefficients_frozen(MKC, g0, gR, q, v, h, Bv, y, HF, harmonic)
        if _converged(Bv, TAIL):
            return h
        counts[1] += 1
        h *= 0.5


@numba.njit(cache=True, inline="always")
def _end_gaps(Bv, h, fresh, st, sy, con, tw):
    """The state at the piece's end ``(st.qb, st.vb)`` and the gaps and their rates at both
    ends (at the start only when not ``fresh``); a turning contact's from its series."""
    wptr, widx, wval, off = sy[4], sy[5], sy[6], sy[9]
    s, tc_idx = con.s, con.tc_idx
    ga, ra, gb, rb, P = st.ga, st.ra, st.gb, st.rb, tw.P
    _evaluate(Bv, 1.0, h, st.qb, st.vb)
    if not fresh:
        _gaps(wptr, widx, wval, off, s, st.q, st.v, ga, ra)
    _gaps(wptr, widx, wval, off, s, st.qb, st.vb, gb, rb)
    for e in range(tc_idx.shape[0]):
        c_ = tc_idx[e]
        sg = -1.0 if s[c_] else 1.0
        if not fresh:
            ga[c_] = sg * P[e, 0]
            ra[c_] = sg * P[e, 1] / h
        g1 = 0.0
        d1 = 0.0
        for kk in range(Bv.shape[0]):
            g1 += P[e, kk]
            d1 += kk * P[e, kk]
        gb[c_] = sg * g1
        rb[c_] = sg * d1 / h


@numba.njit(cache=True, inline="always")
def _first_crossing(Bv, h, tie, st, rw, sy, con, tw, counts):
    """The first contact-state change on the piece, as a fraction of ``h`` (``inf``: none);
    each contact's first root in ``rw.roots`` (``inf``: none before the first plus ``tie``).

    Contacts whose gap has crossed by the end come first, the likeliest earliest crossing
    (linear estimate) first: a certain root gives an early bound, and the others are searched
    only up to it (often rejected at once). Every other contact's gap polynomial is bounded on
    the piece (the start value plus the positive coefficients) and searched where that bound
    does not exclude a crossing (rigorous whatever the piece's length)."""
    off, wptr, widx, wval = sy[9], sy[4], sy[5], sy[6]
    s, tc_idx, P = con.s, con.tc_idx, tw.P
    coef, stk, roots, colsum, order, order_est = rw.coef, rw.stk, rw.roots, rw.colsum, \
        rw.order, rw.est
    ga, gb = st.ga, st.gb
    nt, n = Bv.shape
    nc = roots.shape[0]
    # the root search's scratch, contiguous at this width (a column slice of a wider array
    # would not vectorise)
    work = rw.wflat[:(DEPTH + 5) * nt].reshape((DEPTH + 5, nt))
    best = np.inf
    n_cert = 0
    for e in range(nc):
        roots[e] = np.inf
        if gb[e] > 0.0:
            est = ga[e] / (ga[e] - gb[e]) if ga[e] < 0.0 else 0.0
            jj = n_cert  # insertion by estimate (a handful of contacts)
            while jj > 0 and order_est[jj - 1] > est:
                order[jj] = order[jj - 1]
                order_est[jj] = order_est[jj - 1]
                jj -= 1
            order[jj] = e
            order_est[jj] = est
            n_cert += 1
    n_order = n_cert
    for e in range(nc):
        if gb[e] <= 0.0:
            order[n_order] = e
            n_order += 1
    # each coordinate's series summed in magnitude from the second order on (k >= 2): on the
    # piece a contact's gap is at most its start value, plus its first-order term where that
    # rises, plus sum_j |w_j| A_j, which clears most gaps without their series ((B1) a
    # fortiori)
    for i in range(n):
        colsum[i] = 0.0
    for kk in range(2, nt):
        for i in range(n):
            colsum[i] += abs(Bv[kk, i])
    for o in range(n_order):
        e = order[o]
        limit = min(best + tie / h, 1.0)
        sg = -1.0 if s[e] else 1.0
        if o >= n_cert and wptr[e + 1] > wptr[e]:
            g0e = -off[e]
            g1e = 0.0
            move = 0.0
            for jj in range(wptr[e], wptr[e + 1]):
                col = widx[jj]
                g0e += wval[jj] * Bv[0, col]
                g1e += wval[jj] * Bv[1, col]
                move += abs(wval[jj]) * colsum[col]
            if sg * g0e + max(sg * g1e, 0.0) + move < 0.0:
                continue  # no crossing on the piece
        # the gap's series, scaled to [0, limit]: nonzero by nonzero of the gap row
        # (independent sums over the terms; -5 % of the run against term by term)
        for kk in range(nt):
            coef[kk] = 0.0
        for jj in range(wptr[e], wptr[e + 1]):
            col = widx[jj]
            wv = wval[jj]
            for kk in range(nt):
                coef[kk] += wv * Bv[kk, col]
        for et in range(tc_idx.shape[0]):  # a turning contact: its gap's series (offset in it)
            if tc_idx[et] == e:
                for kk in range(nt):
                    coef[kk] = P[et, kk]
        scale = sg
        for kk in range(nt):
            coef[kk] *= scale
            scale *= limit
        coef[0] -= sg * off[e]
        if o >= n_cert and coef[0] < 0.0:
            ub = coef[0]
            for kk in range(1, nt):
                if coef[kk] > 0.0:
                    ub += coef[kk]
            if ub <= 0.0:
                continue  # no crossing on [0, limit] (B1)
        r = first_root(coef[:nt], work, stk)
        counts[2] += 1
        if r < np.inf:
            roots[e] = r * limit
            best = min(best, roots[e])
    return best


@numba.njit(cache=True, inline="always")
def _rows_inside(Bv, t0, h, t1, jn, last, k_org, dt, rows, st, s):
    """Write the output rows from ``jn`` (up to ``last``; row ``j`` at ``(j + k_org) dt``)
    before ``t1`` off the series of the piece from ``t0``. Returns the next row."""
    X, S = rows
    qo, vo = st.qo, st.vo
    while jn <= last and (jn + k_org) * dt < t1 - 1e-13 * dt:
        _evaluate(Bv, ((jn + k_org) * dt - t0) / h, h, qo, vo)
        _write(X, S, jn, qo, vo, s)
        jn += 1
    return jn


@numba.njit(cache=True, inline="always")
def _rows_at(t, jn, last, k_org, dt, rows, q, v, s):
    """Write the output rows from ``jn`` (up to ``last``) at ``t`` (to rounding): the state
    ``(q, v, s)``. Returns the next row."""
    X, S = rows
    while jn <= last and (jn + k_org) * dt <= t + 1e-13 * dt:
        _write(X, S, jn, q, v, s)
        jn += 1
    return jn


@numba.njit(cache=True, inline="always")
def _accept_end(st):
    """The piece's end state and gaps become the next piece's start."""
    # (the fields bound once: a field read in the loop is a reference taken per iteration)
    q, v, qb, vb, ga, ra, gb, rb = st.q, st.v, st.qb, st.vb, st.ga, st.ra, st.gb, st.rb
    for i in range(q.shape[0]):
        q[i] = qb[i]
        v[i] = vb[i]
    for e in range(ga.shape[0]):
        ga[e] = gb[e]
        ra[e] = rb[e]


@numba.njit(cache=True)
def _grown(EV, n_ev, room):
    """The event rows ``EV[:n_ev]`` in a buffer with at least ``room`` rows more."""
    grown = np.empty((max(2 * EV.shape[0], n_ev + room + 64), EV.shape[1]))
    grown[:n_ev] = EV[:n_ev]
    return grown


@numba.njit(cache=True, inline="always")
def _switch(piece, nt, log, rw, st, sy, con, tw, pk, sw, counts, mat):
    """Switch the contacts whose first root on the piece ``(t, h, best, tol)`` (``nt`` terms)
    lies within ``tol`` of the first (``t``: the event's time, the state ``st.q``, ``st.v``
    there), each logged as a row of ``log = (EV, n_ev)`` from ``n_ev`` (time, contact, before,
    after, rate, force, and on a row that opens a contact the peak force of the episode it
    ends and its time, else NaN) and applied to the state matrices ``mat = (MKC, acc)``.
    Returns ``(n_ev, switched, last)``: the next row, the contacts switched, the last one."""
    t, h, best, tol = piece
    EV, n_ev = log
    MKC, acc = mat
    U, W, kc, cc, off = sy[2], sy[3], sy[7], sy[8], sy[9]
    s, jumped, tc_idx = con.s, con.jumped, con.tc_idx
    P, PD, roots, q, v = tw.P, tw.PD, rw.roots, st.q, st.v
    track, EP, t_call = pk[0], pk[1], pk[7]
    switched = 0
    last = -1
    for e in range(roots.shape[0]):
        if roots[e] <= best + tol:
            before = s[e]
            s[e] = not before
            p = -off[e]
            rr = 0.0
            for i in range(q.shape[0]):
                p += W[e, i] * q[i]
                rr += W[e, i] * v[i]
            wv = rr
            for et in range(tc_idx.shape[0]):  # a turning contact: its series at the event
                if tc_idx[et] == e:
                    p, rr = _value_slope(P[et, :nt], best)
                    rr /= h
                    wv = _hpoly(PD[et, :nt], best) / h
            force = kc[e] * max(p, 0.0) + cc[e] * wv if s[e] else 0.0
            EV[n_ev, 0] = t
            EV[n_ev, 1] = e
            EV[n_ev, 2] = 1.0 if before else 0.0
            EV[n_ev, 3] = 1.0 if s[e] else 0.0
            EV[n_ev, 4] = rr
            EV[n_ev, 5] = force
            EV[n_ev, 6] = np.nan
            EV[n_ev, 7] = np.nan
            if track:
                if before:  # an episode ends: its peak on the row that ends it
                    resolve_peak(e, e, False, pk, sw, counts)
                    EV[n_ev, 6] = EP[e, 0]
                    EV[n_ev, 7] = EP[e, 1]
                    EP[e, 0] = -np.inf
                    EP[e, 1] = np.nan
                else:  # one begins, at the force it closes with
                    EP[e, 0] = force
                    EP[e, 1] = t_call + t
            n_ev += 1
            switched += 1
            last = e
            _toggle(U, W, kc, cc, off, e, 1.0 if s[e] else -1.0, MKC, acc)
            jumped[e] = True
    return n_ev, switched, last


@numba.njit(cache=True, inline="always")
def _piece_limit(s, bound, rho_all, h_all, compute):
    """The piece limit and term scale in contact state ``s`` from its own spectral bound
    (:func:`_state_rho`); with ``compute`` false a state not met before runs on the bound over
    every state ``rho_all`` until one of its pieces ends without an event (most states of a
    rattle or a double-contact transient live shorter than a piece: their eigenproblem would
    cost more than the longer pieces save). Returns ``(h_max, tscale, pending)``."""
    reach, Ksym, Wl, km, cb, kappa = bound[0], bound[2], bound[3], bound[4], bound[5], bound[6]
    keys, vals = bound[7], bound[8]
    rs = _state_rho(s, Ksym, Wl, km, cb, kappa, rho_all, keys, vals, compute)
    pending = rs < 0.0
    if pending:
        rs = rho_all
    h_max = reach / rs if rs > 0.0 else h_all
    return h_max, TERM_BINS * rs / reach, pending


@numba.njit(cache=True)
def taylor_run(sy, call, out, sched, geo, bound, loads, peaks, chans, turns, chain):
    """Propagate output steps ``call.k0 .. call.n_steps - 1`` from state ``call.x`` in contact
    state ``call.s`` (the arguments: the bundles of :mod:`gearmodal.integrate.bundles`).

    ``call.F`` (n_steps + 1, m) is the generalised force at the output times in the basis of
    ``sy.MinvU`` (linear in between); rows ``X[k + 1]``, ``S[k + 1]`` are written after each
    step and every contact-state change appended to ``out.EV`` from row ``out.n_ev``
    (:func:`_switch`). Returns ``(status, k, n_ev, contact, EV, TP, ntp, MKC, acc)``: status
    0 = done; 2 = more than ``max_events`` changes inside step ``k``, the last at ``contact``;
    ``EV`` and ``TP`` the event and turning-point rows (larger arrays than the ones passed if
    they ran full), ``MKC``, ``acc`` the state matrices (a chained call's carry).
    ``out.counts`` (int64, 7) accumulates the pieces summed, the pieces halved, the gap
    polynomials searched, the Taylor rows computed and the peak work (:func:`_track_peaks`).
    ``call.tie`` (s): crossings this close are switched together, time events this close to a
    piece's end are applied there (nothing that moves the solution depends on ``dt``, which
    only places the output rows). The scheduled stiffness changes ``sched`` end a piece at
    their time (:func:`_time_events`), as the knots of ``loads`` do (:func:`_knot_forces`);
    harmonic loads and turning geometry ``geo`` are summed into every piece's series
    (:func:`_piece_series`); exact peaks and turning points of the contacts and the spring
    channels ``chans`` are tracked on every piece (``peaks.track``; times absolute,
    ``peaks.t_call`` this call's start).

    A run advanced over several calls (:class:`~gearmodal.integrate.stepper.Stepper`): row
    ``j`` is at time ``(j + call.k_org) dt`` and every time is from the run's start;
    ``chain.carry`` holds what the last call left (``carry[0] > 0``: ``chain.MKC``,
    ``chain.acc`` are its state matrices, then its refresh count, dense flag, lazy-bound flag
    and count, piece limit and term scale) and is written at the end, so that the calls walk
    the pieces one call would; ``chain.t_span`` (2,), when given: the call's start and end
    times (the last row is the end state).
    """
    # the arguments the caller keeps through the call, borrowed (no reference counts:
    # borrow.py); not those returned (EV, TP) or carried (MKC_in, acc_in)
    sy, sched, geo, bound, loads = borrowed((sy, sched, geo, bound, loads))
    W, MinvU = sy[3], sy[10]
    F, x, s, k0, n_steps, k_org, dt, h_max, terms, tscale, tie, max_events = borrowed(call)
    X, S, EV, n_ev, counts = out
    rows, counts = borrowed(((X, S), counts))
    sched_t, sched_pos, TL, GT = sched[0], sched[3], loads[0], geo[12]
    pk, chn, tch = _tracked(peaks, chans, turns)
    track, t_call, TP, ntp = peaks[0], peaks[7], turns[3], turns[4]
    n_turn = turns[2].shape[0]  # channels: the contact channels, then the spring channels
    carry, t_span = borrowed((chain[0], chain[3]))
    # the kernel's own arrays, held by ``owners`` (named at both returns: alive) and read as
    # borrowed views; MKC and acc are returned, so the loop reads their views
    MKC, acc, carried, cturn, owners = _setup(x, s, sy, geo, terms[terms.shape[0] - 1], chain)
    B, st, fo, rw, tw, con, pw, sw, tkw = borrowed(owners)
    MKCb, accb = borrowed((MKC, acc))
    rho_all = tscale * bound[0] / TERM_BINS  # the bound over every state
    h_all = h_max
    toggled, dense, pending, survived, h_max, tscale = _resume(
        carried, carry, h_max, tscale, sy, s, bound, rho_all, MKCb, accb)
    k = k0
    ip = sched_pos[0]
    il, knots_due, tL0, loads_knots = 0, TL.shape[0] > 0, 0.0, False  # the knot interval
    spanned = t_span.shape[0] == 2  # given times: the call's last row is its end state
    last_row = n_steps - 1 if spanned else n_steps  # the last row read off a piece's series
    while k < n_steps:
        # the output steps from k on whose forces lie on one line: one stretch of pieces (the
        # force has no kink inside it), outputs read off the pieces' series
        k2 = _stretch(F, k, n_steps)
        tk = t_span[0] if (spanned and k == 0) else (k + k_org) * dt
        t_end = t_span[1] if (spanned and k2 == n_steps) else (k2 + k_org) * dt
        jn = k + 1  # the next output row, up to kl
        kl = min(k2, last_row)
        grid_loads = _stretch_forces(F, k, k2, (k2 - k) * dt, MinvU, GT, fo)
        t = tk
        count = 0  # the contact changes since the last output row
        fresh = False  # st.ga, st.ra hold the gaps at (t, q, v) in state s
        while True:
            if ip < sched_t.shape[0] and sched_t[ip] <= t + tie:  # a time event due
                ip, flips = _time_events(t, ip, sched, tie, sy, con, MKCb, accb)
                toggled += flips
            remaining = t_end - t
            if remaining <= tie:
                break
            h = _piece_length(t, remaining, h_max, dense, ip, sched_t)
            if TL.shape[0] > 0:
                il, h, tL0, loads_knots = _knot_forces(t, h, il, knots_due, tL0, loads_knots,
                                                       tie, loads, fo)
                knots_due = False
            # as many terms as the piece's own reach rho h needs
            nt = terms[min(max(int(math.ceil(h * tscale)), 0), terms.shape[0] - 1)]
            Bv = B[:nt]
            _piece_forces(t, tk, tL0, TL.shape[0] > 0, accb, fo, tw, con)
            counts[0] += 1
            turning_loads = grid_loads or loads_knots
            h = _piece_series(t, h, Bv, st, MKCb, fo, tw, geo, loads, counts, cturn,
                              turning_loads)
            _end_gaps(Bv, h, fresh, st, sy, con, tw)
            best = _first_crossing(Bv, h, tie, st, rw, sy, con, tw, counts)
            if track:  # exact peaks and turning points up to the first event
                frac = 1.0 if best == np.inf else best
                piece = (t_call + t, h, frac)
                _track_peaks(Bv, nt, piece, con, chn, pk, pw, sw, counts)
                if n_turn:
                    TP, ntp = _track_turns(Bv, nt, piece, con, chn, tch, TP, ntp, tkw, sw,
                                           pk.PB, pk.pbin)
                    con.jumped[:] = False
            if best == np.inf:  # no event: the piece's end is the next one's start
                t_old = t
                t = _piece_end(t, h, remaining, t_end, sched_t, ip, TL, il, tie)
                # the output times this piece passed: from its series (its end: the end state)
                j0 = jn
                jn = _rows_inside(Bv, t_old, h, t, jn, kl, k_org, dt, rows, st, s)
                jn = _rows_at(t, jn, kl, k_org, dt, rows, st.qb, st.vb, s)
                count = 0 if jn > j0 else count
                _accept_end(st)
                fresh, dense = True, False
                survived += 1
                if pending and survived >= LAZY:  # a lasting state: its own bound from now on
                    h_max, tscale, pending = _piece_limit(s, bound, rho_all, h_all, True)
                continue
            # an event at t + best h: the rows before it, then the switched contacts
            t_ev = t + best * h
            j0 = jn
            jn = _rows_inside(Bv, t, h, t_ev, jn, kl, k_org, dt, rows, st, s)
            count = 0 if jn > j0 else count
            _evaluate(Bv, best, h, st.q, st.v)
            fresh = False
            dense = best * h < DENSE * h_max
            t = t_ev
            if n_ev + W.shape[0] > EV.shape[0]:
                # the event buffer is full: a larger one, here (ending the stretch at an output
                # time for the caller to grow it would make the pieces depend on dt)
                EV = _grown(EV, n_ev, W.shape[0])
            n_ev, switched, last = _switch((t, h, best, tie / h), nt, (EV, n_ev), rw, st, sy,
                                           con, tw, pk, sw, counts, (MKCb, accb))
            count += switched
            toggled += switched
            if bound[1]:
                h_max, tscale, pending = _piece_limit(s, bound, rho_all, h_all, False)
                survived = 0
            if count > max_events:
                _leave(x, st, sched_pos, ip)
                alive(owners)
                return 2, jn - 1, n_ev, last, EV, TP, ntp, MKC, acc
            toggled = _refresh(toggled, sy, s, MKCb, accb)
            j0 = jn  # an output time at the event: the state after it
            jn = _rows_at(t, jn, kl, k_org, dt, rows, st.q, st.v, s)
            count = 0 if jn > j0 else count
        toggled = _refresh(toggled, sy, s, MKCb, accb)
        jn = _rows_at(np.inf, jn, k2, k_org, dt, rows, st.q, st.v, s)  # none left, normally
        k = k2
    _leave(x, st, sched_pos, ip)
    _keep(carry, toggled, dense, pending, survived, h_max, tscale)
    alive(owners)
    return 0, k, n_ev, -1, EV, TP, ntp, MKC, acc


def radius_bound(k: float, c: float) -> float:
    """``(c + sqrt(c^2 + 4 k)) / 2``: the spectral radius bound from the bounds ``k`` of the
    mass-normalised stiffness and ``c`` of the damping
    (:meth:`PiecewiseLinearSystem.spectral_bound`)."""
    return float(0.5 * (c + math.sqrt(c * c + 4.0 * k)))


def spectral_bound_all(system, parts: bool = False):
    """A bound of the spectral radius of ``A_s`` valid for every contact state ``s``, 1/s.

    As :meth:`PiecewiseLinearSystem.spectral_bound` (``|lam| <= (c + sqrt(c^2 + 4 k)) / 2``
    with ``k >= |L^-1 K_s L^-T|``, ``c >= |L^-1 C_s L^-T|``), with ``k`` and ``c`` bounded over
    all states: for symmetric always-active matrices every state lies between the always-active
    part plus all contacts of negative coefficient and plus all of positive coefficient (the
    contacts add semidefinite terms of their coefficient's sign; negative ones are the shaping
    ramps of a polygonal clearance), so its extreme eigenvalues lie between theirs; otherwise
    the triangle inequality over the contacts. ``parts``: return the bounds ``(k, c)``."""
    n = system.n
    if n == 0:
        return (0.0, 0.0) if parts else 0.0
    Li = system.Linv
    W = system.W
    Wl = W @ Li.T  # rows L^-1 w_e
    w2 = np.einsum("ij,ij->i", Wl, Wl)

    def norm_bound(H0, per_contact):
        """Bound of |L^-1 H_s L^-T| over every state (H0 always active)."""
        if not np.any(H0) and np.all(per_contact >= 0.0):
            # no always-active part (e.g. damping only at the contacts): every state lies
            # between 0 and all contacts closed, one eigenproblem
            hi = (Wl.T * per_contact) @ Wl
            return float(max(np.linalg.eigvalsh(hi)[-1], 0.0))
        A0 = Li @ H0 @ Li.T
        if np.abs(H0 - H0.T).max(initial=0.0) <= 1e-12 * np.abs(H0).max(initial=1e-300):
            # L^-1 (H0 + W^T D W) L^-T = A0 + Wl^T D Wl (D: the negative or positive part)
            lo = A0 + (Wl.T * np.minimum(per_contact, 0.0)) @ Wl
            hi = A0 + (Wl.T * np.maximum(per_contact, 0.0)) @ Wl
            e_lo = np.linalg.eigvalsh(lo)  # (eigvalsh reads one triangle: symmetric enough)
            e_hi = np.linalg.eigvalsh(hi)
            return float(max(abs(e_lo[0]), abs(e_lo[-1]), abs(e_hi[0]), abs(e_hi[-1])))
        return float(np.linalg.norm(A0, 2) + np.sum(np.abs(per_contact) * w2))

    k = norm_bound(system.K0, system.k_max)  # alternating meshes: max
    c = norm_bound(system.C0, system.c)
    if parts:
        return k, c
    return radius_bound(k, c)


#: contacts above which the per-state bound is not kept (its key is a bit mask of the state)
STATE_BOUND_CONTACTS = 62
#: slots of the table of states met (a power of two; when full, bounds are not stored)
STATE_TABLE = 1024


class StateBound:
    """Per-contact-state spectral bounds for :func:`taylor_run` (each state's pieces as long as
    its own fastest mode allows, not the stiffest state's).

    For a state ``s`` the bound is taken as for all states (:func:`spectral_bound_all`) but
    with only ``s``'s contacts closed, at the azimuth 0 of the geometry: its stiffness part an
    eigenproblem, its damping part ``min(c_all, |L^-1 C0 L^-T| + sum_(e in s) |c_e|
    |L^-1 w_e|^2)`` (the triangle inequality over the closed contacts only: contacts that
    never close, such as back flanks, no longer count), and times
    ``kappa = rho_all / rho_all(0)``: the ratio of the run's bound over every state (with its
    margins over the azimuth, the speed re-basing and the turning harmonics) to the same
    all-states formula at azimuth 0. So ``rho_s <= rho_all`` always, and ``rho_s`` carries the
    all-states margins. The kernel evaluates it once per lasting state (an eigenproblem of
    size ``n``, when ``LAZY`` pieces of the state have ended without an event; until then the
    state runs on ``rho_all``) and keeps it in a table by the state's bit mask; the series'
    tail check guards each piece as before."""

    def __init__(self, system, rho_all: float, parts: tuple | None = None):
        """``parts``: ``spectral_bound_all(system, parts=True)`` when already computed (a
        system that does not turn)."""
        f = system.at(0.0) if system.turning else {"K0": system.K0, "C0": system.C0,
                                                    "W": system.W}
        Li = system.Linv
        K = np.asarray(f["K0"], dtype=float)
        self.enabled = (0 < len(system.k) <= STATE_BOUND_CONTACTS
                        and np.abs(K - K.T).max(initial=0.0)
                        <= 1e-12 * np.abs(K).max(initial=1e-300))
        shim = types.SimpleNamespace(n=system.n, Linv=Li, W=f["W"], K0=K, C0=f["C0"],
                                     k=system.k, c=system.c,
                                     k_max=system.k_max)
        if parts is None or system.turning:
            parts = spectral_bound_all(shim, parts=True)
        k_all, c0 = parts
        rho0 = radius_bound(k_all, c0)
        self.kappa = max(float(rho_all) / max(rho0, 1e-300), 1.0)
        self.c0 = float(c0)
        A = Li @ K @ Li.T
        self.Ksym = np.ascontiguousarray(0.5 * (A + A.T))
        self.Wl = np.ascontiguousarray(np.asarray(f["W"], dtype=float) @ Li.T)
        # the damping part per state: [c_all, |L^-1 C0 L^-T|_2, |c_e| |L^-1 w_e|^2 ...]
        c_free = float(np.linalg.norm(Li @ np.asarray(f["C0"], dtype=float) @ Li.T, 2))
        c_e = np.abs(np.asarray(system.c, dtype=float)) * np.einsum("ij,ij->i", self.Wl,
                                                                    self.Wl)
        self.cb = np.ascontiguousarray(np.concatenate([[self.c0, c_free], c_e]))
        self.km = np.ascontiguousarray(np.asarray(shim.k_max, dtype=float))
        # an open-addressing table of the states met: keys (bit masks, -1 free), bounds
        self.keys = np.full(STATE_TABLE, -1, dtype=np.int64)
        self.vals = np.zeros(STATE_TABLE)

    @property
    def cache(self) -> dict:
        """The states met so far: ``{bit mask: bound}``."""
        used = self.keys >= 0
        return dict(zip(self.keys[used].tolist(), self.vals[used].tolist(), strict=True))

    def rescaled(self, factor: float) -> StateBound:
        """This bound for a system that differs only in its speed terms (the turbine's
        re-basing), with the margin ``factor`` (as the all-states bound is reused): the same
        arrays, ``kappa`` and the cached states' bounds times ``factor``."""
        out = object.__new__(StateBound)
        out.__dict__.update(self.__dict__)
        out.kappa = self.kappa * factor
        out.keys = self.keys.copy()
        out.vals = self.vals * factor
        return out

    def args(self) -> tuple:
        """The kernel's arguments (a disabled bound: empty arrays, every state at rho_all)."""
        if not self.enabled:
            z = np.zeros((0, 0))
            return (False, z, z, np.zeros(0), np.zeros(1), 1.0, self.keys, self.vals)
        return (True, self.Ksym, self.Wl, self.km, self.cb, self.kappa, self.keys, self.vals)


@numba.njit(cache=True)
def _state_rho(s, Ksym, Wl, km, cb, kappa, rho_all, keys, vals, compute=True):
    """The bound of contact state ``s`` (:class:`StateBound`), from the table ``keys``,
    ``vals`` (linear probing) or computed and stored there; with ``compute`` false, -1 when
    the state is not in the table yet. ``cb``: the damping parts (:attr:`StateBound.cb`)."""
    key = np.int64(0)
    for e in range(s.shape[0]):
        if s[e]:
            key |= np.int64(1) << np.int64(e)
    cap = keys.shape[0]
    slot = -1
    i = (key * np.int64(0x9E3779B1)) & (cap - 1)
    for _ in range(cap):
        if keys[i] == key:
            return vals[i]
        if keys[i] < 0:
            slot = i
            break
        i = (i + 1) & (cap - 1)
    if not compute:
        return -1.0
    n = Ksym.shape[0]
    H = Ksym.copy()
    for e in range(s.shape[0]):
        if s[e] and km[e] != 0.0:
            ke = km[e]
            for i in range(n):
                wi = ke * Wl[e, i]
                if wi != 0.0:
                    for j in range(n):
                        H[i, j] += wi * Wl[e, j]
    lam = np.linalg.eigvalsh(H)
    kk = max(abs(lam[0]), abs(lam[n - 1]))
    c0 = cb[0]
    cs = cb[1]
    for e in range(s.shape[0]):
        if s[e]:
            cs += cb[2 + e]
    c0 = min(c0, cs)
    r = min(rho_all, kappa * 0.5 * (c0 + math.sqrt(c0 * c0 + 4.0 * kk)))
    if slot >= 0:
        keys[slot] = key
        vals[slot] = r
    return r


#: azimuths at which a turning system's spectral bound is taken (the largest, with a margin)
BOUND_AZIMUTHS = 8


def spectral_bound_turning(system) -> float:
    """:func:`spectral_bound_all` of a turning system: the largest over ``BOUND_AZIMUTHS``
    azimuths of a turn, with a margin of twice the spread between the samples plus 2 %, plus
    the fastest turning harmonic ``H |Omega|`` (the geometry's own series, (P2) of
    :mod:`gearmodal.integrate.periodic`). The bound is a smooth function of the azimuth (the
    turning parts are bearings and supports, soft against the meshes: on the 600 kW
    drivetrain it does not change in the 13th digit); between the samples the tail check of
    every piece halves one the bound makes too long."""
    vals = []
    for j in range(BOUND_AZIMUTHS):
        f = system.at(2.0 * math.pi * j / BOUND_AZIMUTHS)
        shim = types.SimpleNamespace(n=system.n, Linv=system.Linv, W=f["W"], K0=f["K0"],
                                     C0=f["C0"], k=system.k, c=system.c,
                                     k_max=system.k_max)
        vals.append(spectral_bound_all(shim))
    hi, lo = max(vals), min(vals)
    top = float(np.max(system.periodic.harm)) * abs(system.omega)
    return hi * (1.02 + 2.0 * (hi - lo) / max(hi, 1e-300)) + top


class TaylorIntegrator:
    """Per frozen system: the arrays of :func:`taylor_run` (built once, reused by callers that
    advance one system in several calls)."""

    @property
    def sys(self):
        """The system (held weakly: ``__init__``)."""
        return self._sys()

    def __init__(self, system, dt: float, max_events_per_step: int = 200,
                 reach: float = REACH, n_terms: int | None = None):
        # weakly: the exact method's registry keeps an integrator as long as its system
        # lives, so the integrator must not keep the system alive (a long turbine run makes a
        # system per re-basing)
        self._sys = weakref.ref(system)
        self.dt = float(dt)
        self.max_events = int(max_events_per_step)
        self._basis_maps = None  # _loads: (basis, its rows, M^-1 rows, turning rows)
        Minv = system.Minv
        self.MK0 = np.ascontiguousarray(Minv @ system.K0)
        self.MC0 = np.ascontiguousarray(Minv @ system.C0)
        self.U = np.ascontiguousarray(system.W @ Minv.T)  # rows M^-1 w_e (Minv symmetric)
        # the gap rows by their nonzeros (a mesh or bearing touches a few DOFs)
        rows, cols = np.nonzero(system.W)  # row-major: each row's columns in order
        self.wptr = np.zeros(system.W.shape[0] + 1, dtype=np.int64)
        np.cumsum(np.bincount(rows, minlength=system.W.shape[0]), out=self.wptr[1:])
        self.widx = cols.astype(np.int64)
        self.wval = np.ascontiguousarray(system.W[rows, cols])
        base = system.rho_base
        parts = None
        if base:
            # a system that differs from the one that computed ``base`` only in its speed
            # terms (the turbine's re-basing): its bound with a margin, instead of ~1-3 ms of
            # eigenvalues; the series' tail check still halves any piece it makes too long
            self.rho = RHO_SPEED * float(base)
            rho_shared = float(base)  # passed on as is: margins do not compound
            sb = system.state_bound_base
        elif system.turning:
            self.rho = max(spectral_bound_turning(system), 1e-300)
            rho_shared = self.rho
        else:
            parts = spectral_bound_all(system, parts=True)  # shared with the state bound
            self.rho = max(radius_bound(*parts), 1e-300)
            rho_shared = self.rho
        self.reach = float(reach)
        if base and sb is not None:
            self.state_bound = sb.rescaled(RHO_SPEED)
            sb_shared = sb
        else:
            self.state_bound = StateBound(system, self.rho, parts)
            sb_shared = self.state_bound
        #: the bounds a system differing from this one only in its speed terms may reuse
        #: (:func:`gearmodal.integrate.exact.shared_bounds`)
        self.shared = (rho_shared, sb_shared)
        self.terms = np.array(_term_table(float(reach), int(n_terms or 0)), dtype=np.int64)
        self.n_terms = int(self.terms[-1])  # the full count, last in the table
        self.tscale = TERM_BINS * self.rho / reach
        self.h_max = reach / self.rho
        self.MinvU = np.ascontiguousarray(system.MinvU)
        self._carry = None  # (k, s, arrays) where a chained run's last call ended
        if system.turning:
            pr, GT = system.periodic, system.GT
            if GT.shape != (len(pr.harm),) + self.MinvU.shape:  # forces given as such
                GT = np.zeros((len(pr.harm),) + self.MinvU.shape, dtype=complex)
        else:
            from .periodic import frozen

            pr, GT = frozen()
        self.turning = (pr.harm, pr.tcols, pr.krows, pr.urows, pr.ZK, pr.ZC, pr.tc_idx, pr.TW,
                        pr.TOFF, pr.TU, np.ascontiguousarray(GT))

    def run(self, n_steps: int, F: np.ndarray, x0: np.ndarray, s0: np.ndarray,
            azimuth0: float = 0.0, loads=None, peaks=None, t0: float = 0.0,
            k_org: int | None = None, t_span: tuple | None = None):
        """``(X, S, events)`` over ``n_steps`` output steps (see :func:`run_exact`); the input
        azimuth at the start is ``azimuth0`` (rad: alternating mesh stiffness, turning
        geometry); ``loads``: ``(knot_t, knot_u, harmonic_u, harmonic_nu, basis)`` added to
        ``F`` (:meth:`_loads`); ``peaks``: a :class:`~gearmodal.integrate.peaks.PeakTracker`
        the exact peaks accumulate in (times from ``t0``, the run's time at this call's
        start, s). Events are rows of 8 (:func:`_switch`).

        ``k_org``: this call continues the last one from its output step ``k_org``
        (:class:`~gearmodal.integrate.stepper.Stepper`): times from the run's start (the
        knots' too, and the events'), ``azimuth0`` the azimuth at the run's start, the
        kernel's state where the last call left it, so that a run chopped into calls walks the
        pieces of one call; None: a call of its own (times from its start). ``t_span``: the
        call's start and end times from the run's start (with ``k_org``), when the caller's
        times are not ``k dt`` (:func:`taylor_run`)."""
        sysm = self.sys
        last = self._carry  # (k, s, arrays) where the last call ended
        chained = (k_org is not None and last is not None and last[0] == k_org
                   and np.array_equal(last[1], s0))
        t_org = 0.0 if k_org is None else k_org * self.dt
        span = np.empty(0)
        if t_span is not None and k_org is not None:
            span = np.array([float(t_span[0]), float(t_span[1])])
            t_org = span[0]
        lds = Loads(*self._loads(loads, azimuth0))
        if chained:
            kc = self._kc  # as the last call left it (its stiffness changes applied)
        else:
            kc = np.array(sysm.stiffness_at(azimuth0 + sysm.omega * t_org), dtype=float)
        sched = sysm.schedule(azimuth0 + sysm.omega * t_org, n_steps * self.dt)
        if k_org is not None and len(sched[0]):  # from the run's start (rounded: alternating)
            sched = (sched[0] + t_org,) + tuple(sched[1:])
        sched_pos = np.zeros(1, dtype=np.int64)
        X = np.empty((n_steps + 1, 2 * sysm.n))
        S = np.empty((n_steps + 1, sysm.n_contacts), dtype=bool)
        X[0], S[0] = x0, s0
        x = np.array(x0, dtype=float)
        s = np.array(s0, dtype=bool)
        EV = np.empty((max(64, 4 * (self.max_events + sysm.n_contacts + 1)), 8))  # grows
        if peaks is None:
            nc = sysm.n_contacts
            track = (False, np.zeros((nc, 2)), np.zeros((1, nc, 5)), 1.0,
                     np.zeros((nc, 1)), np.full((nc, 5), -np.inf), np.zeros(nc, dtype=np.int64))
            rows = (np.zeros(1, dtype=np.int64), np.zeros(0, dtype=np.int64), np.zeros(0),
                    np.zeros(0), np.zeros(0), np.zeros((0, 2), dtype=np.int64))
            turns = (np.zeros((0, 2), dtype=np.int64), np.zeros((0, 2)), np.zeros((0, 5)),
                     np.empty((1, 3)), 0)
        else:
            if 2 * self.n_terms - 1 > peaks.PC.shape[1]:  # (numba does not check bounds)
                raise ValueError(f"{self.n_terms} terms: the peak tracker holds pieces of at "
                                 f"most {(peaks.PC.shape[1] + 1) // 2}")
            peaks.ensure(t0 + n_steps * self.dt)
            track, rows, turns = peaks.args(), peaks.rows(), peaks.turns.args(sysm.omega)
        k, n_ev = 0, 0
        counts = np.zeros(7, dtype=np.int64)
        met = int((self.state_bound.keys >= 0).sum())  # states bounded before this run
        # the tie window (kernels.SIMULTANEOUS): on the system's time scale, the piece length
        # of the bound over every state, at most the call's span (a system with no stiffness
        # has rho = 0: its time scale is unbounded)
        tie = SIMULTANEOUS * min(self.h_max, n_steps * self.dt if k_org is None else 1.0)
        if k_org is None:
            carry, MKC, acc = np.zeros(0), np.zeros((0, 0)), np.zeros(0)
        elif chained:
            carry, MKC, acc = last[2]
        else:
            carry, MKC, acc = np.zeros(7), np.zeros((0, 0)), np.zeros(0)
        # (the bundles cross into numba as plain tuples: bundles.py)
        status, k, n_ev, contact, EV, TP, ntp, MKC, acc = taylor_run(*map(tuple, (
            System(self.MK0, self.MC0, self.U, sysm.W, self.wptr, self.widx, self.wval, kc,
                   sysm.c, sysm.offset, self.MinvU),
            Call(F, x, s, k, n_steps, 0 if k_org is None else int(k_org), self.dt, self.h_max,
                 self.terms, self.tscale, tie, self.max_events),
            Out(X, S, EV, n_ev, counts), Schedule(*sched, sched_pos),
            Turning(sysm.omega, float(azimuth0), *self.turning),
            Bound(self.reach, *self.state_bound.args()), lds,
            Peaks(*track, float(t0) if k_org is None else 0.0),
            Channels(rows[:3], *rows[3:]), Turns(*turns), Chain(carry, MKC, acc, span))))
        if k_org is not None:
            self._carry = ((k_org + n_steps, S[-1].copy(), (carry, MKC, acc)) if status == 0
                           else None)
            self._kc = kc
        if peaks is not None:
            peaks.turns.update(TP, ntp)
        if status != 0:
            raise SolveError(
                "max_events_per_step",
                f"more than {self.max_events} contact-state changes inside one step "
                f"ending near t = {(k + 1) * self.dt:.9g} s, last at contact "
                f"{sysm.names[int(contact)]!r} (tooth chatter or a Zeno sequence); reduce dt, "
                "add damping, or raise max_events_per_step")
        events = EV[:n_ev].copy()  # (time, contact, before, after, rate, force, peak, its time)
        self.counts = {"pieces": int(counts[0]), "halved": int(counts[1]),
                       "root_searches": int(counts[2]), "taylor_rows": int(counts[3]),
                       "peak_series": int(counts[4]), "peak_maxima": int(counts[5]),
                       "peak_searches": int(counts[6]),
                       "state_bounds": int((self.state_bound.keys >= 0).sum()) - met}
        return X, S, events

    def _loads(self, loads, azimuth0: float):
        """The kernel's load arrays ``TL, FL, MinvUL, GTL, HX, HNU`` from ``(knot_t, knot_u,
        harmonic_u, harmonic_nu, basis)`` (:class:`~gearmodal.integrate.driver.Method`; empty
        arrays for ``None``): load values acting through ``M^-1`` times the force rows
        ``basis`` (mF, mL) of the force grid's basis; a harmonic ``Re(u e^(i nu t))`` of them
        acts through that and, on a turning load map, through each turning harmonic ``h`` of
        it at ``h omega +- nu``."""
        sysm = self.sys
        n = sysm.n
        H1 = self.turning[-1].shape[0]
        if loads is None:
            return (np.empty(0), np.empty((0, 0)), np.empty((n, 0)),
                    np.empty((H1, n, 0), dtype=complex), np.empty((0, n), dtype=complex),
                    np.empty(0))
        kt, ku, hu, hnu, basis = loads
        harm = self.turning[0]
        cached = self._basis_maps
        if cached is not None and cached[0] is basis:  # a stepper's calls: the same basis
            rows, MinvUL, GTL = cached[1:]
        else:
            # the load columns' force rows in the integrator's basis (reduce: an input basis)
            rows = sysm.reduce(np.ascontiguousarray(np.asarray(basis, dtype=float).T))
            MinvUL = np.ascontiguousarray(self.MinvU @ rows.T)
            GTL = (np.ascontiguousarray(np.einsum("hij,lj->hil", self.turning[-1], rows))
                   if sysm.turning else np.zeros((H1, n, rows.shape[0]), dtype=complex))
            if isinstance(basis, np.ndarray):
                self._basis_maps = (basis, rows, MinvUL, GTL)
        HX, HNU = [], []
        for u, nu in zip(np.asarray(hu, dtype=complex), np.asarray(hnu, dtype=float),
                         strict=True):
            HX.append(MinvUL @ u)
            HNU.append(nu)
            for hh in range(1, len(harm) if sysm.turning else 0):
                rot = np.exp(1j * harm[hh] * azimuth0) / 2
                for amp, f in ((u, nu), (np.conj(u), -nu)):
                    x = (GTL[hh] @ amp) * rot
                    if np.any(x != 0):
                        HX.append(x)
                        HNU.append(harm[hh] * sysm.omega + f)
        HX = (np.ascontiguousarray(np.array(HX)) if HX
              else np.empty((0, n), dtype=complex))
        FL = np.ascontiguousarray(ku, dtype=float) if len(kt) else np.empty((0, rows.shape[0]))
        return (np.ascontiguousarray(kt, dtype=float), FL, MinvUL, GTL, HX,
                np.array(HNU, dtype=float))
