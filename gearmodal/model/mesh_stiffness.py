"""Mesh stiffness alternating between single and double tooth-pair contact (a fidelity rung).

A spur mesh with transverse contact ratio ``eps`` in (1, 2) has two tooth pairs in contact for
the fraction ``eps - 1`` of each mesh period and one pair for the rest. With the mesh phase
``phi`` (mesh periods; ``frac(phi)`` is the position in the period) the stiffness is the
rectangular wave

    (M1)  k(phi) = k_d  if frac(phi) < eps - 1,  else k_s;   k_d = r k_s,

whose mean ``k_s ((2 - eps) + r (eps - 1))`` is the mesh's ``stiffness`` (ISO 6336's mean mesh
stiffness c_gamma), so

    (M2)  k_s = stiffness / ((2 - eps) + r (eps - 1)).

The default ratio ``r = 1.75`` makes the mean equal ISO 6336-1's c_gamma = c' (0.75 eps + 0.25)
with the single-pair stiffness c' for every ``eps``: c' ((2 - eps) + r (eps - 1)) =
c' (0.75 eps + 0.25) gives r = 1.75.

The phase runs on the nominal rotation of the gears, linear in the input azimuth ``psi``:

    (M3)  phi = rate psi + phase,   rate = z_a |n_a - n_f| / (2 pi),

``z_a`` the teeth of gear a, ``n_a`` its speed ratio and ``n_f`` that of the frame holding the
line of centres (the carrier for a planet mesh, the housing for a parallel stage); the same for
gear b. Within a frozen segment the azimuth advances at the frozen input speed, so the switching
times are known in advance (:meth:`MeshVariation.schedule`) and the exact method switches the
stiffness at them exactly (a rank-one change of the state matrix, as a contact event). The
transverse contact ratio of standard gears (addendum one module, no profile shift):

    (M4)  eps = (sqrt(ra_a^2 - rb_a^2) +- sqrt(ra_b^2 - rb_b^2) -+ a sin alpha_t)
                / (pi m_t cos alpha_t)

with the upper signs for an external pair (``a = r_a + r_b``, ``ra = r + m``) and the lower
ones for an internal pair, gear a the ring (``a = r_a - r_b``, ``ra_a = r_a - m``). Helical
overlap smooths the wave; it is not modelled (give ``contact_ratio`` to represent it). Both
flanks of a mesh follow the same wave; the back flank's tooth-pair cycle is really shifted by
the tooth thickness, which is not modelled (the back flank carries load only in rattle or
double contact).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import ModelError

#: default double-pair over single-pair stiffness (ISO 6336-1 mean, module docstring)
STIFFNESS_RATIO = 1.75


def contact_ratio(a, b, internal: bool) -> float:
    """Transverse contact ratio (M4) of gears ``a`` and ``b`` (``a`` the ring if internal)."""
    m_n = a.module
    alpha = a.transverse_pressure_angle
    m_t = m_n / math.cos(a.helix_angle)
    ra, rb = a.pitch_radius, b.pitch_radius
    pa = math.sqrt(max((ra - m_n if internal else ra + m_n) ** 2 - a.base_radius**2, 0.0))
    pb = math.sqrt(max((rb + m_n) ** 2 - b.base_radius**2, 0.0))
    if internal:
        length = pb - pa + (ra - rb) * math.sin(alpha)
    else:
        length = pa + pb - (ra + rb) * math.sin(alpha)
    return length / (math.pi * m_t * math.cos(alpha))


@dataclass
class MeshVariation:
    """The alternating contacts of an assembly: one entry per contact row (a mesh's two
    flanks each), with ``rate`` (mesh periods per rad of input azimuth, M3), ``phase``
    (periods), ``double`` (``eps - 1``), ``k_single`` and ``k_double`` (N/m, M2)."""

    rows: np.ndarray
    rate: np.ndarray
    phase: np.ndarray
    double: np.ndarray
    k_single: np.ndarray
    k_double: np.ndarray

    def __len__(self) -> int:
        return len(self.rows)

    def stiffness(self, psi, backward: bool = False) -> np.ndarray:
        """Stiffness (M1) of every entry at input azimuths ``psi`` (rad): (len(psi), len).

        The value just after the instant in time: with the azimuth rising, (M1) as written;
        ``backward`` (the input turning backwards) takes the limit from below in ``phi``, so a
        run starting on a boundary starts with the interval it enters."""
        phi = np.multiply.outer(np.atleast_1d(np.asarray(psi, dtype=float)), self.rate) \
            + self.phase
        f = phi - np.floor(phi)
        double = ((f > 0.0) & (f <= self.double)) if backward else (f < self.double)
        return np.where(double, self.k_double, self.k_single)

    def table(self, k: np.ndarray, psi, backward: bool = False) -> np.ndarray:
        """Every contact's stiffness at input azimuths ``psi``: ``k`` (the means, one per
        contact) with the alternating rows at their (M1) values; (len(psi), len(k))."""
        out = np.repeat(np.asarray(k, dtype=float)[None, :], np.size(psi), axis=0)
        out[:, self.rows] = self.stiffness(psi, backward)
        return out

    def schedule(self, psi0: float, omega: float, t_end: float):
        """The stiffness changes in ``(0, t_end]`` when the input azimuth is ``psi0 + omega t``
        (rad, rad/s): ``(times, rows, k)`` sorted by time, each the new stiffness of a contact
        row from that time on (the wave is right-continuous, M1)."""
        if not len(self) or omega == 0.0 or not t_end > 0.0:
            return np.zeros(0), np.zeros(0, dtype=np.int64), np.zeros(0)
        times, rows, ks = [], [], []
        for i in range(len(self)):
            u0 = self.rate[i] * psi0 + self.phase[i]
            du = self.rate[i] * omega  # periods per second
            if du == 0.0:
                continue
            u1 = u0 + du * t_end
            up = du > 0.0
            lo, hi = min(u0, u1), max(u0, u1)
            base = np.arange(math.floor(lo) - 1, math.floor(hi) + 2, dtype=float)
            for u, enters_double in ((base, up), (base + self.double[i], not up)):
                t = (u - u0) / du
                ok = (t > 0.0) & (t <= t_end)
                times.append(t[ok])
                rows.append(np.full(int(ok.sum()), self.rows[i], dtype=np.int64))
                ks.append(np.full(int(ok.sum()), self.k_double[i] if enters_double
                                  else self.k_single[i]))
        if not times:
            return np.zeros(0), np.zeros(0, dtype=np.int64), np.zeros(0)
        t = np.concatenate(times)
        order = np.argsort(t, kind="stable")
        return t[order], np.concatenate(rows)[order], np.concatenate(ks)[order]


def mesh_rate(model, mesh, a, b) -> float:
    """Mesh periods per rad of input azimuth (M3) of ``mesh`` between bodies ``a`` and ``b``."""
    from .components import Gear

    if not (isinstance(a, Gear) and isinstance(b, Gear)):
        raise ModelError(f"{mesh.name}.alternation", "needs tooth counts: both gears must be "
                         "gm.Gear (a lin_parker_stage carries no tooth data)")
    frames = dict.fromkeys((a.frame, b.frame))
    for f in frames:
        nf = model.frames[f].speed_ratio if f in model.frames else 0.0
        ra = a.teeth * abs(a.speed_ratio - nf)
        rb = b.teeth * abs(b.speed_ratio - nf)
        if math.isclose(ra, rb, rel_tol=1e-9, abs_tol=1e-12):
            if ra == 0.0:
                raise ModelError(f"{mesh.name}.alternation", f"{a.name!r} and {b.name!r} do "
                                 "not turn against their frame (speed ratios), so the mesh "
                                 "has no frequency")
            return ra / (2.0 * math.pi)
    raise ModelError(f"{mesh.name}.alternation", f"the speed ratios of {a.name!r} and "
                     f"{b.name!r} do not roll on each other (teeth x speed relative to "
                     "their frame differ), so the mesh frequency is undefined")


def variation_of(model, mesh, a, b, internal: bool):
    """``(rate, phase, eps - 1, k_single, k_double)`` of an alternating ``mesh``."""
    rate = mesh_rate(model, mesh, a, b)
    eps = mesh.contact_ratio
    if eps is None:
        eps = contact_ratio(a, b, internal)
        if not 1.0 < eps < 2.0:
            raise ModelError(f"{mesh.name}.contact_ratio", f"the gears' contact ratio is "
                             f"{eps:.3f}, outside (1, 2) where single and double pairs "
                             "alternate; give contact_ratio")
    r = mesh.stiffness_ratio
    k_s = mesh.stiffness / ((2.0 - eps) + r * (eps - 1.0))  # (M2)
    return rate, mesh.phase, eps - 1.0, k_s, r * k_s
