"""Static equilibrium under load with unilateral contacts (DESIGN 3.1).

The contact state of a loaded gearbox follows from its equilibrium: which flanks touch, which
bearing clearances are closed. With every contact a compression-only spring with an offset, the
equilibrium minimises the convex, piecewise-quadratic energy

    Pi(q) = 1/2 q^T K q - f^T q + sum_e 1/2 k_e max(0, W_e q - offset_e)^2

(``K`` the always-active stiffness plus ``Omega^2 K_cent``, ``f = B u + Omega^2 f_cent``). It is
found by a semismooth Newton method with an exact line search on ``Pi``: the Newton matrix
is the stiffness of the current contact state, so the method stops exactly when the state no
longer changes (finite termination for this piecewise-quadratic problem).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd
import scipy.linalg as sla

from .assembly import Assembly, as_assembly, reduction
from .errors import ModelError, unknown

RPM = 2.0 * np.pi / 60.0


@dataclass
class Equilibrium:
    """A static equilibrium: displacements ``q`` (Series by DOF name), the contact ``state``
    (booleans, one per contact), and ``contacts``: a DataFrame with ``element``, ``contact``,
    ``active``, ``penetration_m`` and ``force_N`` (N, or N m for rotational directions)."""

    q: pd.Series
    state: np.ndarray
    contacts: pd.DataFrame
    iterations: int


def free_modes(asm: Assembly, K: np.ndarray | None = None, rtol: float = 1e-9) -> np.ndarray:
    """Columns spanning the DOF motions that no spring resists (rigid-body modes) when all
    contacts are engaged: the null space of ``K + sum_e k_e W_e^T W_e``."""
    c = asm.contacts
    H = (asm.K if K is None else K) + (c.W.T * c.stiffness) @ c.W
    # scale by the mass so that the tolerance is relative to the system's own frequencies
    d = 1.0 / np.sqrt(np.diag(asm.M))
    Hs = H * d[:, None] * d[None, :]
    w, v = np.linalg.eigh(Hs)
    tol = rtol * max(float(np.max(np.abs(w))), 1e-300)
    return d[:, None] * v[:, np.abs(w) <= tol]


def _line_search(r: np.ndarray, Kd: np.ndarray, p: np.ndarray, w: np.ndarray, k: np.ndarray,
                 d: np.ndarray) -> float:
    """Exact minimiser ``t > 0`` of the energy ``Pi(q + t d)`` along a descent direction ``d``.

    ``Pi`` is convex and piecewise quadratic in ``t``: its derivative
    ``d^T r + t d^T K d + sum_e k_e w_e max(0, p_e + t w_e)`` (``r = K q - f``, ``p`` the
    penetrations, ``w = W d``) is piecewise linear and non-decreasing, with kinks where a
    contact opens or closes (``t = -p_e / w_e``). The root is found interval by interval."""
    dKd = float(d @ Kd)
    a0 = float(d @ r)
    kinks = np.unique(np.concatenate([[0.0], -p[w != 0] / w[w != 0]]))
    kinks = kinks[kinks >= 0.0]

    def slope(t):  # derivative and its rate on the interval that starts at t (right limits)
        on = (p + t * w > 0) | ((p + t * w == 0) & (w > 0))
        return a0 + t * dKd + float(np.sum(k[on] * w[on] * (p[on] + t * w[on]))), \
            dKd + float(np.sum(k[on] * w[on] ** 2))

    for j, t0 in enumerate(kinks):
        d0, rate = slope(t0)
        if d0 >= 0.0:  # at t = 0: not a descent direction (rounding at convergence): stay
            return float(t0)
        t_end = kinks[j + 1] if j + 1 < len(kinks) else np.inf
        if rate > 0.0 and t0 - d0 / rate <= t_end:
            return float(t0 - d0 / rate)
    raise ModelError("loads", "no static equilibrium: the energy decreases without bound along "
                     "a motion nothing resists")


def _describe(asm: Assembly, mode: np.ndarray) -> str:
    j = np.argsort(-np.abs(mode))[:6]
    ref = mode[j[0]]
    return ", ".join(f"{asm.dof_names[i]} {mode[i] / ref:+.4g}" for i in j if abs(mode[i]) >
                     1e-9 * abs(ref))


def balance(model, loads: dict, on: str) -> dict:
    """Return ``loads`` with load ``on`` set so that the loads do no work on the model's free
    rigid-body mode (e.g. the generator torque that balances a rotor torque).

    ``model`` is a :class:`gearmodal.Model` or an :class:`Assembly`.
    """
    asm, _ = as_assembly(model)
    modes = free_modes(asm)
    if modes.shape[1] != 1:
        raise ModelError("balance", f"needs exactly one free mode, the model has "
                         f"{modes.shape[1]}")
    if on not in asm.load_names:
        raise ModelError(f"loads.{on}", unknown("load", on, asm.load_names))
    rest = {k: v for k, v in loads.items() if k != on}
    phi = modes[:, 0]
    work = phi @ asm.load_vector(rest)
    unit = phi @ asm.B[:, asm.load_names.index(on)]
    if abs(unit) < 1e-12 * np.abs(phi).max():
        raise ModelError(f"loads.{on}", "does no work on the free mode; it cannot balance")
    return {**rest, on: float(-work / unit)}


def equilibrium(model, loads: dict | None = None, speed_rpm: float = 0.0, *,
                state=None, max_iter: int = 200, rtol: float = 1e-12) -> Equilibrium:
    """Static equilibrium of ``model`` (a Model or an Assembly) under ``loads``
    (``{load name: value}``, N or N m) at input speed ``speed_rpm`` (centrifugal forces and
    centripetal softening included).

    Raises :class:`ModelError` when the loads do work on a free rigid-body mode (they are not
    balanced; see :func:`balance`) or when no equilibrium is found within ``max_iter`` steps.
    """
    full, _ = as_assembly(model)
    full.require_piecewise_linear("gm.equilibrium")
    asm, N = reduction(full)
    om = float(speed_rpm) * RPM
    K = asm.K + om**2 * asm.K_cent + om * asm.K_speed
    f = asm.load_vector(loads) + om**2 * asm.f_cent
    c = asm.contacts
    W, k, off = c.W, c.stiffness, c.offset
    # rigid-body modes are a property of the springs, not of the speed (Lin & Parker's
    # centripetal term only softens them slightly), so they are taken without K_cent
    modes = free_modes(asm)
    fscale = max(float(np.abs(f).max()), 1e-300)
    if modes.shape[1]:
        # loads must do no work on motions that nothing resists
        P, _ = np.linalg.qr(modes)
        net = P.T @ f
        if np.abs(net).max() > 1e-9 * np.linalg.norm(f):
            j = int(np.argmax(np.abs(net)))
            # a load of this model that works on the mode and is not given: the one to
            # balance on (a torque first)
            work = np.abs(P[:, j] @ asm.B)
            given = set(loads or {})
            free = [n for k, n in enumerate(asm.load_names)
                    if work[k] > 1e-9 * max(work.max(), 1e-300) and n not in given]
            free.sort(key=lambda n: not n.endswith(".torque"))
            how = f"with gm.balance(model, loads, on={free[0]!r})" if free else \
                "with gm.balance(model, loads, on=<one of the loads given>)"
            raise ModelError("loads", "not in equilibrium: they do net work on a free "
                             f"rigid-body mode ({_describe(asm, P[:, j])}); balance them, e.g. "
                             f"{how}, or add a support")
    q = np.zeros(asm.n)

    # Work in the space orthogonal to the free modes (basis Q): the minimum-norm solution, no
    # drift along motions nothing resists. The first Newton matrix is that of the given
    # (default: nominal) state, afterwards that of the contacts active at the iterate; where it
    # cannot resist the residual (a contact still open in the loaded direction, a planet with
    # all flanks open) a weak share of the open contacts' stiffness is added, and the exact
    # line search goes as far along that step as the contacts allow.
    Q = (np.linalg.qr(modes, mode="complete")[0][:, modes.shape[1]:] if modes.shape[1]
         else np.eye(asm.n))
    s = asm.state(state)
    Hr_all = Q.T @ (K + (W.T * k) @ W) @ Q
    iterations = 0
    for _ in range(max_iter):
        iterations += 1
        p = W @ q - off
        g = Q.T @ (K @ q - f + W.T @ (k * np.maximum(p, 0.0)))
        Hr = Q.T @ (K + (W[s].T * k[s]) @ W[s]) @ Q
        dr, *_ = sla.lstsq(Hr, -g, lapack_driver="gelsy")
        if np.linalg.norm(Hr @ dr + g) > 1e-8 * max(np.linalg.norm(g), 1e-300):
            # the state's stiffness cannot resist the residual (e.g. a planet whose flanks are
            # all open turns freely): a weak share of the open contacts' stiffness points the
            # step at the contacts that must close; the line search goes as far as they allow
            Hreg = Hr + 1e-6 * (Q.T @ (W[~s].T * k[~s]) @ W[~s] @ Q)
            try:
                dr = np.linalg.solve(Hreg, -g)
            except np.linalg.LinAlgError:  # nothing resists even then: all contacts engaged
                dr = np.linalg.solve(Hr_all, -g)
        step = Q @ dr
        t = _line_search(K @ q - f, K @ step, p, W @ step, k, step)
        q = q + t * step
        p = W @ q - off
        tol = rtol * max(np.abs(W @ q).max(initial=0.0), np.abs(off).max(initial=0.0), 1e-300)
        new = p > tol
        g = Q.T @ (K @ q - f + W.T @ (k * np.maximum(p, 0.0)))
        done = np.array_equal(new, s) and np.abs(g).max() <= 1e-9 * fscale
        s = new
        if done:
            break
    else:
        raise ModelError("loads", f"no static equilibrium found in {max_iter} Newton steps")
    p = W @ q - off
    force = np.where(s, k * p, 0.0)
    df = pd.DataFrame({"element": c.element, "contact": c.contact, "active": s,
                       "penetration_m": p, "force_N": force})
    if N is not None:  # coupled: back to the original coordinates
        q = full.expand(q)
    return Equilibrium(q=pd.Series(q, index=full.dof_names), state=s, contacts=df,
                       iterations=iterations)
