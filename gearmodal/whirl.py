"""What a rotordynamics engineer reads beside a mode's frequency: its whirl direction and its
logarithmic decrement (issue 23; as ROSS reports them).

**Whirl.** A mode ``q(t) = Re(phi e^(lambda t))`` (``Im lambda > 0``, the solvers' choice) moves
each body centre on an ellipse: with the complex amplitudes ``X``, ``Y`` of its two in-plane
translations (the body's local axes, a right-handed pair turned by the body's orientation in
its frame), ``Im(X conj(Y))`` is ``1/(2 omega)`` times the signed area the centre sweeps per
unit time, positive counter-clockwise about ``z``: the sense of a positive input rotation. A
mode's roundness is ``R = 2 sum_b Im(X_b conj(Y_b)) / sum_b (|X_b|^2 + |Y_b|^2)`` over the bodies
with translations (1: every centre on a circle turning with the input, -1: against it, 0:
straight lines). ``whirl`` is ``forward`` for ``R > ROUND``, ``backward`` for ``R < -ROUND``,
``linear`` in between (the standing modes of a system at rest), and ``""`` for modes whose
translations carry less than ``TRANSLATION`` of the shape's norm (torsional modes). The orbits
are those of the coordinates as modelled: in the carrier frame for a planetary stage's bodies
(Lin & Parker's frame), in the ground for the housing and parallel stages.

**Logarithmic decrement** ``delta = 2 pi zeta / sqrt(1 - zeta^2)`` (the decay of successive
peaks of a free vibration, ``ln(x_k / x_(k+1))``); negative for an unstable mode; NaN for
``|zeta| >= 1`` (a real root: no oscillation, no successive peaks).
"""

from __future__ import annotations

import numpy as np

#: roundness above which a mode counts as whirling (below its negative, backward): damping
#: that is not proportional makes the standing modes of the 600 kW drivetrain at rest elliptic
#: up to R = 0.005; its gyroscopic pairs at 22 rpm have R = +-1
ROUND = 1e-2
#: share of the shape's squared norm on translations below which a mode has no whirl
TRANSLATION = 1e-2


def log_decrement(zeta) -> np.ndarray:
    """``2 pi zeta / sqrt(1 - zeta^2)`` elementwise; NaN where ``|zeta| >= 1``."""
    z = np.asarray(zeta, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        out = 2.0 * np.pi * z / np.sqrt(1.0 - z * z)
    return np.where(np.abs(z) >= 1.0, np.nan, out)


def damping_ratios(lam) -> np.ndarray:
    """``-Re(lambda) / |lambda|`` of eigenvalues ``lam``: 0 where ``lambda`` is 0, and where
    the ratio is below 1e-12 in magnitude (an undamped mode's eigenvalue has a real part of
    rounding, ~1e-16 of its magnitude), so that ``gm.modal`` and ``gm.campbell`` read an
    undamped mode's ratio as the same 0."""
    lam = np.asarray(lam)
    absl = np.abs(lam)
    with np.errstate(invalid="ignore", divide="ignore"):
        zeta = np.where(absl > 0, -lam.real / np.where(absl > 0, absl, 1.0), 0.0)
    return np.where(np.abs(zeta) < 1e-12, 0.0, zeta)


def rigid_undamped(zeta, types) -> np.ndarray:
    """``zeta`` with the damping ratio of every ``"rigid"`` mode (``types``, the same shape)
    set to 0: a rigid-body mode's eigenvalue is zero to rounding, and at speed the gyroscopic
    and centripetal terms split the pair into two real roundings ``+-eps``, whose ratio
    ``-Re/|lambda|`` would read as -1 and 1 (an unstable mode and a critically damped one)."""
    z = np.array(zeta, dtype=float)
    z[np.asarray(types) == "rigid"] = 0.0
    return z


def translation_pairs(geometry, dof_names: list[str]) -> np.ndarray:
    """``(k, 2)`` row indices of the (x, y) translations of every body of ``geometry`` (a
    :attr:`gearmodal.ModalResult.geometry` table) that has both among ``dof_names``."""
    index = {n: i for i, n in enumerate(dof_names)}
    pairs = [(index[x], index[y]) for x, y in zip(geometry.x_dof, geometry.y_dof, strict=True)
             if isinstance(x, str) and isinstance(y, str) and x in index and y in index]
    return np.array(pairs, dtype=np.int64).reshape(-1, 2)


def roundness(shapes: np.ndarray, pairs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(R, share)`` per mode of ``shapes`` (n_dofs, n_modes): the roundness (module
    docstring) and the translations' share of the shape's squared norm."""
    phi = np.asarray(shapes)
    total = (np.abs(phi) ** 2).sum(axis=0)
    if not len(pairs):
        zero = np.zeros(phi.shape[1])
        return zero, zero
    X, Y = phi[pairs[:, 0]], phi[pairs[:, 1]]
    trans = (np.abs(X) ** 2 + np.abs(Y) ** 2).sum(axis=0)
    area = np.imag(X * np.conj(Y)).sum(axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        r = np.where(trans > 0, 2.0 * area / np.where(trans > 0, trans, 1.0), 0.0)
        share = np.where(total > 0, trans / np.where(total > 0, total, 1.0), 0.0)
    return r, share


def whirl(shapes: np.ndarray, pairs: np.ndarray) -> np.ndarray:
    """``forward`` / ``backward`` / ``linear`` / ``""`` per mode (module docstring)."""
    r, share = roundness(shapes, pairs)
    out = np.where(r > ROUND, "forward", np.where(r < -ROUND, "backward", "linear"))
    return np.where(share < TRANSLATION, "", out).astype(object)
