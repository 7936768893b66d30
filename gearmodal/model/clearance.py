"""A round bearing clearance as a sum of piecewise-linear facet contacts (DESIGN 2.3).

The exactly round clearance ``c`` with radial stiffness ``k`` pushes back with::

    F(d) = k (|d| - c) d / |d|   for |d| > c, else 0                                  (R1)

(``d`` the bearing's x/y deflection), which is not piecewise linear. Its piecewise-linear
stand-in here is a *ridge sum*: ``N`` facet directions ``n_i`` at ``2 pi i / N`` in the bearing
axes, and along each the same ``M`` compression-only ramps with offsets ``c_m >= c`` and
stiffnesses ``k_m`` (independent unilateral contacts, as a mesh flank)::

    F(d) = -sum_i sum_m k_m max(0, n_i . d - c_m) n_i                                (R2)

Every ramp is a contact of the exact method, so the force is continuous in ``d`` (no sliding
modes at polygon vertices, unlike a "most penetrated facet" rule) and derives from a potential
(energy is conserved). Spread evenly over directions (``N -> infinity``), one ramp gives the
radial force (per unit ``N k_m``)::

    (1 / 2 pi) int max(0, r cos psi - c_m) cos psi dpsi = h(r, c_m) / (2 pi),
    h(r, c_m) = r acos(c_m / r) - c_m sqrt(1 - c_m^2 / r^2)  (r > c_m), else 0          (R3)

The ``k_m`` are chosen so that ``sum_m N k_m h(r, c_m) / (2 pi)`` matches ``k (r - c)``: least
squares over ``c <= r <= 3 c`` (the range where (R1) bends) under two equalities that make the
match exact for ``r >> c`` (``h -> pi r / 2 - 2 c_m``)::

    sum_m N k_m = 4 k,     sum_m N k_m c_m = pi k c                                      (R4)

One ramp (``M = 1``, ``k_1 = 4 k / N``, ``c_1 = c``) is the classical rolling-element law: it
starts as ``(r - c)^(3/2)``, 44 % below (R1) at ``r = 1.3 c`` and ``0.27 k c`` below for large
``r``; ``M = 4`` (the default) is within 1 % of ``k c`` for every ``r`` in the continuum limit.
``N`` facets add an anisotropy that grows with ``r`` (:func:`force_law_error`, tabled by
``benchmarks/clearance_shape.py``: 16 facets 5.1 % of ``k c`` for ``r <= 3 c``, 20 % up to
``30 c``, where it is 0.7 % of the force; 64 facets 1.0 % and 2.6 %). Some ``k_m`` are
negative (they shape the start of contact); the stiffness of every reachable state, a prefix
of the ramps of each facet, is not (checked).
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import ModelError

#: ramps per facet (default, most) and the span of their offsets above the clearance, in
#: clearances
RAMPS = 4
MAX_RAMPS = 12
SPREAD = 1.0
#: the fit's range of radial deflections, in clearances (R4)
FIT_RANGE = 3.0


def ramp_force(r: np.ndarray, offset: float) -> np.ndarray:
    """``h(r, c_m)`` of (R3): radial force of one ramp spread over all directions, per unit
    ``N k_m / (2 pi)``; ``r`` and ``offset`` in m."""
    r = np.asarray(r, dtype=float)
    out = np.zeros_like(r)
    m = r > offset
    psi0 = np.arccos(offset / r[m])
    out[m] = r[m] * psi0 - offset * np.sin(psi0)
    return out


def ramp_offsets(clearance: float, ramps: int = RAMPS, spread: float = SPREAD) -> np.ndarray:
    """Offsets ``c_m`` (m): ``c (1 + spread (m / M)^2)``, denser where contact starts."""
    m = np.arange(ramps)
    return clearance * (1.0 + spread * (m / ramps) ** 2)


def polygon_ramps(clearance: float, stiffness: float, facets: int,
                  ramps: int = RAMPS) -> tuple[np.ndarray, np.ndarray]:
    """``(offsets, stiffnesses)`` of the ``ramps`` contacts of each of ``facets`` facets that
    stand in for a round clearance ``clearance`` (m) of radial stiffness ``stiffness``
    (N/m), by (R3)-(R4). Stiffnesses are per contact (N/m)."""
    if not (isinstance(ramps, int) and 1 <= ramps <= MAX_RAMPS):
        raise ModelError("ramps", f"= {ramps!r}: must be an integer in 1..{MAX_RAMPS}")
    c, k = float(clearance), float(stiffness)
    cm = ramp_offsets(c, ramps)
    if ramps == 1:
        x = np.array([4.0 * k])
    else:
        r = np.linspace(c, FIT_RANGE * c, 400)
        A = np.stack([ramp_force(r, o) for o in cm], axis=1) / (2.0 * math.pi)
        E = np.stack([np.ones(ramps), cm])
        e = np.array([4.0 * k, math.pi * k * c])
        # least squares with the equalities (R4): the KKT system, scaled to unit columns
        s = 1.0 / np.linalg.norm(A, axis=0)
        As, Es = A * s, E * s
        kkt = np.block([[As.T @ As, Es.T], [Es, np.zeros((2, 2))]])
        rhs = np.concatenate([As.T @ (k * (r - c)), e])
        x = np.linalg.solve(kkt, rhs)[:ramps] * s
    if np.any(np.cumsum(x) < -1e-12 * abs(k)):
        raise ModelError("ramps", f"= {ramps}: the fitted ramps give a negative stiffness")
    return cm, x / facets


def ridge_force(d: np.ndarray, clearance: float, stiffness: float, facets: int,
                ramps: int = RAMPS) -> np.ndarray:
    """(R2): the force (N, pushing back) of the facet ramps on deflections ``d`` (..., 2), m."""
    offsets, kms = polygon_ramps(clearance, stiffness, facets, ramps)
    a = 2.0 * math.pi * np.arange(facets) / facets
    nrm = np.stack([np.cos(a), np.sin(a)], axis=1)  # (N, 2)
    p = np.asarray(d, dtype=float) @ nrm.T  # (..., N)
    push = (np.maximum(p[..., None] - offsets, 0.0) * kms).sum(axis=-1)  # (..., N)
    return -(push @ nrm)


def force_law_error(facets: int, ramps: int = RAMPS, r_max: float = FIT_RANGE,
                    n_r: int = 81, n_angle: int = 9) -> float:
    """Largest difference between (R2) and the round law (R1) over ``c <= |d| <= r_max c``
    and every direction (one facet's sector, by symmetry), in units of ``k c``."""
    c, k = 1.0, 1.0
    r = np.linspace(c, r_max * c, n_r)
    phi = np.linspace(0.0, 2.0 * math.pi / facets, n_angle)
    d = np.stack(np.broadcast_arrays(r[:, None] * np.cos(phi), r[:, None] * np.sin(phi)),
                 axis=-1)
    f_round = -k * (r - c)[:, None, None] * d / r[:, None, None]
    return float(np.abs(ridge_force(d, c, k, facets, ramps) - f_round).max() / (k * c))
