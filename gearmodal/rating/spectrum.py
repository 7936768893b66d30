"""ISO 6336-6 under a load spectrum: Palmgren-Miner damage and the equivalent safety factors.

A gear's flank and root see one load cycle per tooth engagement. Given a spectrum of a mesh's
flank force against the model input's revolutions (a load revolution distribution: level
bins with revolutions), each bin's stress is that of ISO 6336 at the bin's upper force (the
conservative edge) and its cycles are the input's revolutions times the gear's load cycles
per input revolution. With the S-N curve of ISO 6336-2/-3 (the life factors Z_NT, Y_NT of
case-hardened steel, :mod:`gearmodal.rating.iso6336`)::

    D = sum_i n_i / N(sigma_i),   N(sigma) from sigma = sigma_ref Z_NT(N)            (ISO 6336-6, 5)

``sigma_ref`` the permissible stress without its life factor (sigma_Hlim Z_L Z_v Z_R Z_W Z_X
for pitting; sigma_Flim Y_ST Y_deltarelT Y_RrelT Y_X Y_M for the root). The reference line
ends at 1e10 cycles (0.85, the tables' last value): stresses below it do no damage, as the
steady rating's life factor stays 0.85 beyond (so a constant spectrum rates as the steady
load at any number of cycles); with ``long_life="optimum"`` stresses below the knee do none.
Above the static limit (Z_NT 1.6, Y_NT 2.5) a single cycle fails the gear (D = infinity).
The equivalent safety factor is the factor on every stress that makes D = 1 (bisection on its
logarithm).

From a dynamic run's forces the dynamics are in the loads: the spectrum rating takes
K_A = K_gamma = K_v = 1 and keeps the standard's face and transverse factors, which the model
does not resolve.
"""

from __future__ import annotations

import math

import numpy as np

#: the knees of the S-N lines (ISO 6336-2 Table 2, ISO 6336-3 Table 3, case-hardened steel):
#: (static cycles, static factor, knee cycles, slope below the knee, slope beyond it)
PITTING = (1e5, 1.6, 5e7, 0.0756, 0.0307)
BENDING = (1e3, 2.5, 3e6, 0.115, 0.02)


def cycles_to_failure(z: np.ndarray, kind: str, optimum: bool = False) -> np.ndarray:
    """N at the stress ratio ``z = sigma / sigma_ref`` on the S-N line of ``kind``
    ("pitting" or "bending"): 0 above the static limit, infinite below the knee with
    ``optimum``."""
    n_st, z_st, n_k, s1, s2 = PITTING if kind == "pitting" else BENDING
    z = np.asarray(z, dtype=float)
    with np.errstate(divide="ignore", over="ignore"):
        above = n_k * z ** (-1.0 / s1)
        below = np.full_like(z, np.inf) if optimum else n_k * z ** (-1.0 / s2)
    end = (n_k / 1e10) ** s2  # the line's end at 1e10 cycles (0.85)
    below = np.where(z < end * (1 - 1e-12), np.inf, below)
    n = np.where(z > 1.0, above, below)
    n = np.where(z >= z_st * (1 + 1e-12), 0.0, n)
    return np.where(z <= 0.0, np.inf, n)


def damage(stress: np.ndarray, cycles: np.ndarray, reference: float, kind: str,
           optimum: bool = False) -> float:
    """Palmgren-Miner damage of ``cycles`` at ``stress`` (arrays, MPa) against ``reference``
    (MPa, the permissible stress without its life factor)."""
    cycles = np.asarray(cycles, dtype=float)
    used = cycles > 0
    if not used.any():
        return 0.0
    n = cycles_to_failure(np.asarray(stress, dtype=float)[used] / reference, kind, optimum)
    if np.any(n == 0.0):
        return math.inf
    return float(np.sum(cycles[used] / n))


def equivalent_safety(stress: np.ndarray, cycles: np.ndarray, reference: float, kind: str,
                      optimum: bool = False) -> float:
    """The factor on every stress of the spectrum that makes its damage 1 (ISO 6336-6's
    safety factor under a spectrum); ``inf`` for a spectrum without load."""
    stress = np.asarray(stress, dtype=float)
    if not np.any((np.asarray(cycles) > 0) & (stress > 0)):
        return math.inf
    lo, hi = -12.0, 12.0  # log of the factor
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if damage(stress * math.exp(mid), cycles, reference, kind, optimum) > 1.0:
            hi = mid
        else:
            lo = mid
        if hi - lo < 1e-12:
            break
    return math.exp(0.5 * (lo + hi))
