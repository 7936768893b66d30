"""Turning geometry as data of the exact method: the harmonics of the rows that turn
(DESIGN 3.2, rotating geometry).

Where a frame turns against another (a carrier against the housing and the ground), the
assembled stiffness, damping, contact rows, offsets and load map are trigonometric polynomials
of the input azimuth ``psi`` (:class:`~gearmodal.integrate.azimuth.AzimuthAssembler` finds
their coefficients exactly)::

    X(psi) = sum_h a_h cos(h psi) + b_h sin(h psi) = Re sum_h Z_h e^(i h psi),
    Z_h = a_h - i b_h                                                            (P1)

Over a piece that starts at azimuth ``psi_p`` and turns at ``Omega`` (``psi = psi_p + Omega
tau``), in the piece's own time ``s = tau / h`` (0..1)::

    e^(i h psi) = e^(i h psi_p) sum_j E_j s^j,   E_j = (i h Omega h)^j / j!             (P2)

so the Taylor coefficients of every turning quantity are known, and those of its product with
the state's series are a Cauchy product. :func:`gearmodal.integrate.taylor.taylor_run` sums
the series of the time-varying system with them (its (T2)); a contact whose row turns is
searched for crossings on the series of its exact gap ``w(psi(t)) q(t) - offset(psi(t))``.
The coefficients decay like ``(h Omega h)^j / j!``: a few terms at any gear-train speed.

:func:`periodic_data` splits an assembly into its constant part (``a_0``: handled as a frozen
system) and the turning harmonics (``h >= 1``, restricted to the few coordinates they touch).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..errors import ModelError

#: relative size below which a harmonic coefficient is rounding (AzimuthAssembler's rule)
ZERO = 1e-13


@dataclasses.dataclass
class Periodic:
    """Harmonic data of a system's turning geometry (module docstring; arrays for the kernel).

    harm : (H1,) harmonic orders per input radian, ``harm[0] = 0`` (whole numbers for the
        turning frames, any real order for offset waves: run-out, transmission error).
    tcols : (nT,) the coordinates any turning row or matrix touches.
    ZK, ZC : (H1, n, nT) ``M^-1 Z_h`` of the turning stiffness and damping (``h = 0``: zero,
        the constant part is the frozen system's).
    tc_idx : (nTC,) contacts whose row or offset turns.
    TW : (H1, nTC, nT) their rows' harmonics on ``tcols`` (``h = 0``: the constant part).
    TOFF : (H1, nTC) their offsets' harmonics.
    TU : (H1, nTC, n) ``M^-1`` times their rows' harmonics.
    krows : the rows where ``ZK`` or ``ZC`` is nonzero (the kernel's products skip the rest).
    urows : the rows where ``TU`` is nonzero.
    """

    harm: np.ndarray
    tcols: np.ndarray
    ZK: np.ndarray
    ZC: np.ndarray
    tc_idx: np.ndarray
    TW: np.ndarray
    TOFF: np.ndarray
    TU: np.ndarray
    krows: np.ndarray
    urows: np.ndarray


def _complex(coef, key):
    """``Z_h = a_h - i b_h`` of field ``key`` (P1), (H1, ...)."""
    a, b = coef[key]
    return a - 1j * b


def _live(Z: np.ndarray) -> np.ndarray:
    """Mask over the trailing entries of ``Z`` (H1, ...) that have a nonzero harmonic h >= 1."""
    scale = max(float(np.abs(Z).max(initial=0.0)), 1e-300)
    return np.abs(Z[1:]).max(axis=0) > ZERO * scale


def periodic_data(geo, Minv: np.ndarray) -> tuple[dict, Periodic | None]:
    """``(constant, periodic)`` of an :class:`AzimuthAssembler` ``geo``: the constant parts
    (``a_0``) of ``K``, ``C``, the contact rows and offsets and the load map ``B`` by field
    name, and the :class:`Periodic` data of what turns (``None`` when nothing does). The mass,
    gyroscopic and centripetal matrices must not turn (a body whose inertia turns against its
    frame is not modelled)."""
    if not geo.exact:
        raise ModelError("model", "its geometry is not a trigonometric polynomial of the input "
                         "azimuth (frames turning at speed ratios other than 0 and 1 against "
                         "each other): the exact method cannot integrate it")
    coef = geo.coef
    n = geo.template.n
    constant = {key: (geo.constant[key] if key in geo.constant else coef[key][0][0])
                for key in ("K", "C", "B", "contacts.W", "contacts.offset")}
    H1 = len(geo.harmonics)
    if H1 == 1:
        return constant, None
    for key in ("M", "G", "K_cent", "K_geom", "f_cent"):
        if key not in geo.constant and np.any(_live(_complex(coef, key))):
            raise ModelError("model", f"its {key} depends on the input azimuth: not modelled "
                             "by the exact method")
    # (complex always: one compiled kernel for every model)
    ZKf = _complex(coef, "K") if "K" not in geo.constant else np.zeros((H1, n, n), complex)
    ZCf = _complex(coef, "C") if "C" not in geo.constant else np.zeros((H1, n, n), complex)
    Wz, Oz = (_complex(coef, key) if key not in geo.constant
              else np.concatenate([geo.constant[key][None].astype(complex),
                                   np.zeros((H1 - 1,) + geo.constant[key].shape)])
              for key in ("contacts.W", "contacts.offset"))
    kcols = _live(ZKf).any(axis=0) | _live(ZKf).any(axis=1) | _live(ZCf).any(axis=0)
    turning_rows = _live(Wz).any(axis=1) | _live(Oz) if Wz.shape[1] else np.zeros(0, bool)
    tc_idx = np.flatnonzero(turning_rows)
    wcols = (np.abs(Wz[:, tc_idx]).max(axis=(0, 1)) > 0 if len(tc_idx)
             else np.zeros(n, bool))
    if not (kcols.any() or len(tc_idx)):
        return constant, None
    tcols = np.flatnonzero(kcols | wcols)
    ZK = np.einsum("ij,hjk->hik", Minv, ZKf[:, :, tcols])
    ZC = np.einsum("ij,hjk->hik", Minv, ZCf[:, :, tcols])
    ZK[0] = 0.0
    ZC[0] = 0.0
    krows = np.flatnonzero((np.abs(ZK) + np.abs(ZC)).max(axis=(0, 2)) > 0)
    TW = np.ascontiguousarray(Wz[:, tc_idx][:, :, tcols])
    TU = np.ascontiguousarray(np.einsum("ij,hej->hei", Minv, Wz[:, tc_idx]))
    urows = np.flatnonzero(np.abs(TU).max(axis=(0, 1)) > 0) if len(tc_idx) else np.zeros(0, int)
    per = Periodic(harm=np.asarray(geo.harmonics, dtype=float), tcols=tcols.astype(np.int64),
                   ZK=np.ascontiguousarray(ZK), ZC=np.ascontiguousarray(ZC),
                   tc_idx=tc_idx.astype(np.int64), TW=TW,
                   TOFF=np.ascontiguousarray(Oz[:, tc_idx]), TU=TU,
                   krows=krows.astype(np.int64), urows=urows.astype(np.int64))
    # the frozen system's constant rows: a turning contact's row lives in Periodic only
    constant["contacts.W"] = constant["contacts.W"].copy()
    constant["contacts.W"][tc_idx] = 0.0
    constant["contacts.offset"] = constant["contacts.offset"].copy()
    constant["contacts.offset"][tc_idx] = 0.0
    return constant, per


def load_harmonics(geo, Minv: np.ndarray, columns: list[int], extra: np.ndarray | None = None):
    """``(MinvU, GT)``: ``M^-1`` times the constant part of the load map's ``columns`` (n, m)
    and its turning harmonics (H1, n, m) complex (``GT[0]`` zero); ``extra`` (n, k) constant
    force columns appended (the centrifugal force)."""
    Bz = _complex(geo.coef, "B")[:, :, columns] if "B" not in geo.constant else None
    B0 = geo.constant["B"][:, columns] if Bz is None else Bz[0].real
    cols = [B0] + ([extra] if extra is not None else [])
    MinvU = np.ascontiguousarray(Minv @ np.concatenate(cols, axis=1))
    H1 = len(geo.harmonics)
    GT = np.zeros((H1, Minv.shape[0], MinvU.shape[1]), dtype=complex)
    if Bz is not None:
        GT[1:, :, :len(columns)] = np.einsum("ij,hjk->hik", Minv, Bz[1:])
    return MinvU, GT


def frozen() -> tuple[Periodic, np.ndarray]:
    """Empty turning data for a frozen system (one harmonic, no columns) and its ``GT``."""
    z = np.zeros((1, 0, 0), dtype=complex)
    per = Periodic(harm=np.zeros(1), tcols=np.zeros(0, dtype=np.int64),
                   ZK=z, ZC=z, tc_idx=np.zeros(0, dtype=np.int64),
                   TW=z, TOFF=np.zeros((1, 0), dtype=complex), TU=z,
                   krows=np.zeros(0, dtype=np.int64), urows=np.zeros(0, dtype=np.int64))
    return per, np.zeros((1, 0, 0), dtype=complex)
