"""Selective mass scaling: the fidelity rung that slows the fast mesh modes (issue 19).

The exact method sums each piece's series over ``rho h <= 6`` with ``rho`` the fastest
frequency of the system; on the 600 kW drivetrain the kHz mesh modes (the sun's torsion on its
flanks at 3.1 kHz, the pinions at 2.1-2.3 kHz) set ``rho`` while the turbine's loads excite
nothing above a few hundred Hz. This rung adds mass only along the modes above a chosen
frequency ``f_top`` (selective mass scaling, as explicit finite-element codes use it)::

    M' = M + M Phi_H diag(alpha) Phi_H^T M,   alpha_j = (f_j / f_top)^2 - 1          (S1)

with ``Phi_H`` the mass-normalised modes above ``f_top``. Every mode that is mass-orthogonal to
``Phi_H`` keeps its frequency and shape exactly, and each mode of ``Phi_H`` drops to ``f_top``.
The stiffness, every contact's gap and force, the loads (gravity and centrifugal forces from
the true masses) are untouched: static load paths are exact, the dynamics above ``f_top`` are
slowed.

Turning geometry: ``M'`` must not depend on the azimuth. The modes are taken of an
**interior**: every DOF except a *boundary* that covers every turning stiffness entry, with the
boundary held, in the contact state with every flank named ``front`` closed (the loaded
operating state). The interior's stiffness then does not turn, so neither does ``M'``. Two
passes: the first holds the smallest such cover (on the 600 kW drivetrain the housing's
translation, where the carrier-frame stage meets the ground frame), the second the DOFs on the
other side of the turning entries (the carrier, sun and ring translations), so that the
housing's own stiff modes (the parallel shafts on their bearings) are slowed too; the second
pass works on the first's ``M'``. In each pass two subspaces are protected (``Phi_H`` is taken
mass-orthogonal to them, so ``M'`` does not change them): the interior's free motions (the
drivetrain rotation: its inertia stays exact) and its static response to the boundary at every
azimuth (the interior following the housing: the gearbox translation modes near 10 Hz stay
exact).

What it changes is measured (``benchmarks/turbine_speed.py``, the fidelity ladder): the
frequencies of the interior's modes above ``f_top`` and the impacts they carry.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.linalg as sla

from .errors import ModelError


def _boundary(Kturn: np.ndarray) -> list[int]:
    """A small set of DOFs covering every turning stiffness entry (greedy vertex cover: a
    DOF with a turning diagonal entry first, then the DOF touching most uncovered entries)."""
    A = Kturn | Kturn.T
    cover = [int(i) for i in np.flatnonzero(np.diag(A))]
    A = A.copy()
    A[cover, :] = False
    A[:, cover] = False
    while A.any():
        i = int(np.argmax(A.sum(axis=1)))
        cover.append(i)
        A[i, :] = False
        A[:, i] = False
    return sorted(cover)


def _scale(K: np.ndarray, M: np.ndarray, a, b, bnd: list[int], f_top: float, scale: float):
    """(S1) on the interior (every DOF but ``bnd``) of stiffness ``K``, mass ``M``; the
    coupling harmonics ``a``, ``b`` (of ``K``) give the protected static responses.
    Returns the added mass (n, n) and the slowed frequencies."""
    n = K.shape[0]
    ii = np.array([i for i in range(n) if i not in set(bnd)], dtype=int)
    Kii, Mii = K[np.ix_(ii, ii)], M[np.ix_(ii, ii)]
    # protected: the interior's static response to the boundary at every azimuth (the
    # harmonics of the coupling block), and its free motions
    prot = [sla.null_space(Kii)]
    for arr in (a, b):
        for h in range(arr.shape[0]):
            blk = arr[h][np.ix_(ii, bnd)]
            if np.abs(blk).max(initial=0.0) > 1e-12 * scale:
                prot.append(np.linalg.lstsq(Kii, blk, rcond=None)[0])
    S = np.concatenate(prot, axis=1)
    Z = sla.null_space((Mii @ S).T) if S.shape[1] else np.eye(len(ii))
    w, Y = sla.eigh(Z.T @ Kii @ Z, Z.T @ Mii @ Z)
    V = Z @ Y
    f = np.sqrt(np.abs(w)) / (2.0 * math.pi)
    hi = f > f_top
    MV = Mii @ V[:, hi]
    dM = np.zeros((n, n))
    dM[np.ix_(ii, ii)] = (MV * ((f[hi] / f_top) ** 2 - 1.0)) @ MV.T   # (S1)
    return dM, f[hi].tolist()


#: the rung the turbine studies (double contact, mounting azimuth, fatigue) run on unless told
#: otherwise (0 or None there: the full model). Its error on the coupled 600 kW run is in
#: benchmarks/RESULTS.md: 0.05 % on the reference gearbox's four ladder quantities, the
#: rattling clearance gearbox within its own scatter
STUDY_TOP_FREQUENCY_HZ = 500.0


def study_rung(top_frequency_hz: float | None) -> float | None:
    """A study's ``top_frequency_hz``: ``None`` or 0 is the full model (``None`` returned),
    else the frequency (Hz, > 0)."""
    if top_frequency_hz is None or top_frequency_hz == 0:
        return None
    if not (isinstance(top_frequency_hz, (int, float)) and math.isfinite(top_frequency_hz)
            and top_frequency_hz > 0):
        raise ModelError("top_frequency_hz", f"= {top_frequency_hz!r}: a frequency > 0 Hz, "
                         "or 0 for the full model")
    return float(top_frequency_hz)


def scaled_mass(geo, f_top: float) -> tuple[np.ndarray, dict]:
    """``(M', info)`` of (S1) for the azimuth assembler ``geo`` of a model (module
    docstring). ``info``: ``boundary`` (the DOF names held in each pass), ``scaled`` (the
    frequencies slowed to ``f_top`` in each pass, Hz)."""
    if not (isinstance(f_top, (int, float)) and math.isfinite(f_top) and f_top > 0):
        raise ModelError("top_frequency_hz", f"= {f_top!r}: must be a finite frequency > 0 Hz")
    asm = geo.template
    n = asm.n
    a, b = geo.coef["K"]
    scale = max(float(np.abs(a[0]).max(initial=0.0)), 1e-300)
    if a.shape[0] > 1:
        turn = (np.abs(a[1:]).max(axis=0) + np.abs(b[1:]).max(axis=0)) > 1e-12 * scale
    else:
        turn = np.zeros((n, n), dtype=bool)
    c = asm.contacts
    front = np.array([name == "front" for name in c.contact], dtype=bool)
    # the operating state: the constant part of the front flanks' rows (a turning row is
    # not part of the interior's stiffness)
    W0 = geo.coef["contacts.W"][0][0] if "contacts.W" in geo.coef else c.W
    K = a[0] + (W0[front].T * c.stiffness[front]) @ W0[front]
    # pass 1: the interior of the smallest cover of the turning entries; pass 2 (a turning
    # model): the interior of the other side, the first boundary's neighbours held
    covers = [_boundary(turn)]
    if covers[0]:
        other = sorted({int(j) for i in covers[0] for j in np.flatnonzero(turn[i] | turn[:, i])}
                       - set(covers[0]))
        covers.append(other)
    Ms = asm.M.copy()
    info: dict = {"boundary": [], "scaled": []}
    for bnd in covers:
        if len(bnd) >= n:
            continue
        dM, slowed = _scale(K, Ms, a, b, bnd, f_top, scale)
        Ms = Ms + dM
        info["boundary"].append([asm.dof_names[i] for i in bnd])
        info["scaled"].append(slowed)
    return 0.5 * (Ms + Ms.T), info
