"""The elastic turbine's equations by assumed modes: tower, nacelle, shaft, hub, bending blades
(issue 56, DESIGN 2.5a).

Coordinates: ``tower_fa<i>``, ``tower_ss<i>`` (the tower's modes, :mod:`.bodies`); the
rotor's rotation, ``shaft_twist`` against the generator on the deck's torsional spring or
``rotor_azimuth`` when a gearbox model carries shaft and generator; ``generator_azimuth``
(``generator="free"``, on the low-speed side); ``nacelle_yaw`` (the nacelle turning on its yaw
bearing's spring, when one is given); the blades' modes, each blade's
(``blade<k>_flap1`` ...: :func:`parked_matrices`) or in multi-blade coordinates
(``flap1_collective``, ``flap1_cos``, ``flap1_sin`` ...: :func:`turning_matrices`), with
``q_k = q_collective + q_cos cos(psi_k) + q_sin sin(psi_k)`` for blade ``k`` at azimuth
``psi_k`` (Coleman's transformation, Bir 2008, NREL/CP-500-42553, eq. 2).

Kinematics (as ElastoDyn's): a point of the tower moves with its modes; a point fixed to the
tower top at ``r`` moves by ``u_T + theta x r`` with the top's displacement ``u_T`` and rotation
``theta = (-sum phi'_ss q_ss, sum phi'_fa q_fa, 0)``; a blade point at span ``s`` sits at
``apex + (r_h + s) e_r + u_flap e_f + u_edge e_e`` turning with the rotor about the shaft
axis ``e_s``. With every point's position ``r = r_0(t) + A(t) x + x^T B(t) x / 2`` the
Lagrangian's quadratic part gives (``m`` the point's mass; the total time derivative
``d/dt (m r_0' . r_2)`` dropped)

* ``M = sum m A^T A``                                                        (L1)
* ``G = 2 sum m A^T A'``                  (Coriolis and gyroscopic; skew)    (L2)
* ``K_cent = sum m A^T A'' + sum m r_0'' . B`` (per (rad/s)^2: spin softening and the
  steady rotation's geometric stiffness: the blades' centrifugal tension and the
  turning rotor's second-order motion with the tower top, which cancel the softening of
  a rigid rotation exactly)                                                   (L3)

plus each body's elastic stiffness and structural damping, the drivetrain's spring and
damper, the hub's and generator's axial inertia (mass, and gyroscopic
``-I_p Omega Theta^T [e_s]x Theta``), and gravity on the tower: it carries the weight above
it, ``-int N phi_i' phi_j' dz`` with ``N(z) = g (m_RNA + int_z^H mu)``, and a tilt of its top
lowers the rotor-nacelle assembly's centre by ``h theta^2 / 2``. In multi-blade coordinates the
turning rotor's matrices are constant in time for three equal blades (the products of the
azimuth harmonics sum to constants; :func:`turning_matrices` measures the rest); the blades'
structural damping, acting on their rotating-frame rates, adds ``Omega T^T C_b T'``
(``K_speed``).

Left out: the blades' own weight (it depends on their azimuth: a standing blade is softened,
a hanging one stiffened), the second-order gravity terms of the rotor-nacelle assembly's
horizontal offset, the steady deflection under the centrifugal load, tower torsion.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import ModelError
from .bodies import BeamModes, tail_integral
from .elastodyn import GRAVITY, StructureDeck

GENERATOR = ("locked", "free")
#: samples of the azimuth for the exact derivatives of the blades' kinematics (a
#: trigonometric polynomial of degree 2 in the azimuth; 9 samples are exact to degree 4)
_SAMPLES = 9


@dataclass(frozen=True)
class TurbineMatrices:
    """The linear elastic turbine at speed ``Omega`` (rad/s)::

        M x'' + (C + Omega G) x' + (K + Omega K_speed + Omega^2 K_cent) x = 0

    dof_names : the coordinates (module docstring). Units SI (kg, N/m, N m/rad ...).
    """

    dof_names: list[str]
    M: np.ndarray
    C: np.ndarray
    K: np.ndarray
    G: np.ndarray
    K_cent: np.ndarray
    K_speed: np.ndarray


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v)


def _cross_matrix(v: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


class _Frame:
    """The fixed part: coordinates, the tower, the tower top's motion, nacelle, hub,
    generator, drivetrain and the tower's gravity (module docstring)."""

    def __init__(self, deck: StructureDeck, blade: BeamModes, tower: BeamModes,
                 generator: str | None, gravity: float, blade_names: list[str],
                 yaw: tuple[float, float] | None = None):
        if generator is not None and generator not in GENERATOR:
            raise ModelError("generator", f"= {generator!r}: one of {', '.join(GENERATOR)}")
        names = [f"tower_{m}" for m in tower.names]
        if yaw is not None:
            names.append("nacelle_yaw")
        names.append("rotor_azimuth" if generator is None else "shaft_twist")
        if generator == "free":
            names.append("generator_azimuth")
        names += blade_names
        self.names = names
        n = len(names)
        self.ix = ix = {nm: i for i, nm in enumerate(names)}
        self.M, self.K, self.C = np.zeros((n, n)), np.zeros((n, n)), np.zeros((n, n))
        self.G, self.K_cent, self.K_speed = (np.zeros((n, n)) for _ in range(3))
        tw = slice(0, tower.n)
        self.M[tw, tw] += tower.mass_matrix()
        self.K[tw, tw] += tower.stiffness
        self.C[tw, tw] += tower.damping_matrix()
        # the tower top: displacement uT (3 x n) and small rotation theta (3 x n)
        self.uT = uT = np.zeros((3, n))
        self.theta = th = np.zeros((3, n))
        uT[0, tw], uT[1, tw] = tower.tip()[:, 0], tower.tip()[:, 1]
        th[0, tw], th[1, tw] = -tower.tip_slope()[:, 1], tower.tip_slope()[:, 0]
        if yaw is not None:  # the yaw bearing: the nacelle turns about the tower's axis
            j = ix["nacelle_yaw"]
            th[2, j] = 1.0
            self.K[j, j] += yaw[0]
            self.C[j, j] += yaw[1]
        # the nacelle: a point mass (ElastoDyn gives no inertia but the yaw's)
        rN = np.array(deck.nacelle_cm, dtype=float)
        JN = self.rigid(rN)
        self.M += deck.nacelle_mass * JN.T @ JN
        self.M += deck.nacelle_yaw_inertia * np.outer(th[2], th[2])
        self.es = es = deck.shaft_axis
        self.apex = apex = deck.apex
        self.rot = rot = np.zeros(n)  # the rotor's rotation about the shaft, per coordinate
        rot[ix["rotor_azimuth" if generator is None else "shaft_twist"]] = 1.0
        if generator == "free":
            rot[ix["generator_azimuth"]] = 1.0
        # the hub: a point mass at its centre, its inertia about the shaft; spinning at Omega
        hub_c = apex + deck.hub_cm * es
        JH = self.rigid(hub_c) + np.outer(np.cross(es, hub_c - apex), rot)
        self.M += deck.hub_mass * JH.T @ JH
        w_hub = es @ th + rot
        self.M += deck.hub_inertia * np.outer(w_hub, w_hub)
        gyro = -th.T @ _cross_matrix(es) @ th  # per unit polar inertia and spin rate
        self.G += deck.hub_inertia * gyro
        if generator is not None:
            # the generator: its inertia about the high-speed shaft, gear_ratio times faster
            w_gen = es @ th
            if generator == "free":
                w_gen = w_gen + deck.gear_ratio * np.eye(n)[ix["generator_azimuth"]]
            self.M += deck.generator_inertia * np.outer(w_gen, w_gen)
            self.G += deck.generator_inertia * deck.gear_ratio * gyro
            j = ix["shaft_twist"]
            self.K[j, j] += deck.shaft_stiffness
            self.C[j, j] += deck.shaft_damping
        if gravity:
            m_blade = float(np.sum(blade.weights * blade.mass))
            m_rna = deck.nacelle_mass + deck.hub_mass + deck.blades * m_blade
            if m_rna > 0:
                above = tail_integral(tower, tower.mass)  # the tower's weight above each section
                tension = -gravity * (m_rna + above)  # compression: negative
                self.K[tw, tw] += tower.slope_matrix(tension)
                h = (deck.nacelle_mass * rN[2]
                     + (deck.hub_mass + deck.blades * m_blade) * apex[2]) / m_rna
                self.K -= gravity * m_rna * h * (np.outer(th[0], th[0])
                                                 + np.outer(th[1], th[1]))
        # the blades' axes: blade 1 at azimuth 0 points up and turns towards ``side``
        self.up = _unit(np.array([0.0, 0.0, 1.0]) - es[2] * es)
        self.side = np.cross(es, self.up)
        self.cone = deck.precone
        self.radius = deck.hub_radius + blade.x
        self.wm = blade.weights * blade.mass

    def rigid(self, r: np.ndarray) -> np.ndarray:
        """(3 x n): the motion of a point fixed to the tower top at offset ``r``."""
        return self.uT + np.cross(self.theta.T, r).T

    def axes(self, psi: float):
        """``(e_rad, e_r, e_e, e_f)`` of a blade at azimuth ``psi``: radial in the rotor
        plane, along the coned span, edgewise (the direction of rotation), flapwise."""
        e_rad = math.cos(psi) * self.up + math.sin(psi) * self.side
        e_r = math.cos(self.cone) * e_rad + math.sin(self.cone) * self.es
        e_e = _unit(np.cross(self.es, e_r))
        return e_rad, e_r, e_e, np.cross(e_r, e_e)

    def blade_motion(self, psi: float, T: np.ndarray, blade: BeamModes) -> np.ndarray:
        """(3, n, n_s): the motion of a blade's points at azimuth ``psi`` per coordinate;
        ``T`` (n_modes x n) maps the coordinates to the blade's own modal coordinates."""
        _, e_r, e_e, e_f = self.axes(psi)
        A0 = self.rigid(self.apex)
        B1 = np.cross(self.theta.T, e_r).T + np.outer(np.cross(self.es, e_r), self.rot)
        E = A0[:, :, None] + B1[:, :, None] * self.radius[None, None, :]
        shape = (e_f[:, None, None] * blade.disp[None, :, 0, :]
                 + e_e[:, None, None] * blade.disp[None, :, 1, :])  # (3, modes, n_s)
        return E + np.einsum("ams,mn->ans", shape, T)

    def matrices(self) -> TurbineMatrices:
        # M and K are symmetric by construction (rounding aside); G and K_cent are skew and
        # symmetric only as sums over the three blades: kept as summed (tests check them)
        return TurbineMatrices(list(self.names), 0.5 * (self.M + self.M.T), self.C.copy(),
                               0.5 * (self.K + self.K.T), self.G.copy(), self.K_cent.copy(),
                               self.K_speed.copy())


def parked_matrices(deck: StructureDeck, blade: BeamModes, tower: BeamModes, *,
                    generator: str | None = "locked", azimuth: float = 0.0,
                    gravity: float = GRAVITY,
                    yaw: tuple[float, float] | None = None) -> TurbineMatrices:
    """The parked turbine in each blade's own coordinates (``blade<k>_<mode>``) with blade 1
    at ``azimuth`` (rad, 0: up). ``generator``: ``"locked"``, ``"free"`` (the deck's
    drivetrain) or None (``rotor_azimuth`` free: a gearbox model supplies the drivetrain).
    ``yaw``: ``(stiffness N m/rad, damping N m s/rad)`` of the yaw bearing, the coordinate
    ``nacelle_yaw`` (None: the nacelle held in yaw). The speed terms are zero (a parked
    rotor)."""
    nb = deck.blades
    bnames = [f"blade{k + 1}_{m}" for k in range(nb) for m in blade.names]
    f = _Frame(deck, blade, tower, generator, gravity, bnames, yaw)
    n = len(f.names)
    for k in range(nb):
        cols = [f.ix[f"blade{k + 1}_{m}"] for m in blade.names]
        T = np.zeros((blade.n, n))
        T[np.arange(blade.n), cols] = 1.0
        E = f.blade_motion(azimuth + 2.0 * math.pi * k / nb, T, blade)
        f.M += np.einsum("ias,ibs,s->ab", E, E, f.wm)
        f.K[np.ix_(cols, cols)] += blade.stiffness
        f.C[np.ix_(cols, cols)] += blade.damping_matrix()
    return f.matrices()


MBC = ("collective", "cos", "sin")


def turning_matrices(deck: StructureDeck, blade: BeamModes, tower: BeamModes, *,
                     generator: str | None = "locked", azimuth: float = 0.0,
                     gravity: float = GRAVITY,
                     yaw: tuple[float, float] | None = None) -> TurbineMatrices:
    """The turbine in multi-blade coordinates with its speed terms (module docstring,
    (L1)-(L3)), blade 1 at ``azimuth``: constant in time for three equal blades (the test
    compares azimuths). Three blades only."""
    nb = deck.blades
    if nb != 3:
        raise ModelError("deck.NumBl", f"= {nb}: multi-blade coordinates here are for three "
                         "blades")
    bnames = [f"{m}_{c}" for m in blade.names for c in MBC]
    f = _Frame(deck, blade, tower, generator, gravity, bnames, yaw)
    n = len(f.names)
    cols = np.array([[f.ix[f"{m}_{c}"] for c in MBC] for m in blade.names])  # (modes, 3)
    K_b, C_b = blade.stiffness, blade.damping_matrix()
    # the centrifugal tension per (rad/s)^2: N(s) = cos(cone)^2 int_s^L m (r_h + s') ds'
    tension = math.cos(f.cone) ** 2 * tail_integral(blade, blade.mass * f.radius)
    K_tension = blade.slope_matrix(tension)
    j = np.arange(_SAMPLES)
    phase = 2.0 * math.pi * j / _SAMPLES
    harm = np.arange(1, (_SAMPLES - 1) // 2 + 1)
    d1 = 2.0 / _SAMPLES * (harm[None, :] * np.sin(np.outer(phase, harm))).sum(axis=1)
    d2 = -2.0 / _SAMPLES * (harm[None, :] ** 2 * np.cos(np.outer(phase, harm))).sum(axis=1)
    es, th, rho = f.es, f.theta, f.rot
    for k in range(nb):
        psi_k = azimuth + 2.0 * math.pi * k / nb

        def T_at(psi):
            T = np.zeros((blade.n, n))
            T[np.arange(blade.n), cols[:, 0]] = 1.0
            T[np.arange(blade.n), cols[:, 1]] = math.cos(psi)
            T[np.arange(blade.n), cols[:, 2]] = math.sin(psi)
            return T

        T0 = T_at(psi_k)
        dT = np.zeros_like(T0)  # d T / d psi
        dT[np.arange(blade.n), cols[:, 1]] = -math.sin(psi_k)
        dT[np.arange(blade.n), cols[:, 2]] = math.cos(psi_k)
        samples = np.stack([f.blade_motion(psi_k + p, T_at(psi_k + p), blade) for p in phase])
        E0 = samples[0]
        E1 = np.tensordot(d1, samples, axes=1)  # d E / d psi, exact
        E2 = np.tensordot(d2, samples, axes=1)
        f.M += np.einsum("ias,ibs,s->ab", E0, E0, f.wm)                          # (L1)
        f.G += 2.0 * np.einsum("ias,ibs,s->ab", E0, E1, f.wm)                    # (L2)
        f.K_cent += np.einsum("ias,ibs,s->ab", E0, E2, f.wm)                     # (L3)
        # (L3), r_0'' . B: the points' centripetal acceleration per (rad/s)^2 times mass
        e_rad, e_r, _, _ = f.axes(psi_k)
        c0 = e_r[:, None] * f.radius[None, :]                  # (3, n_s) from the apex
        w = -(f.wm * f.radius * math.cos(f.cone))[None, :] * e_rad[:, None]
        d = f.apex[:, None] + c0
        # the tower top's rotation, twice: theta x (theta x d) / 2
        S = 0.5 * (d @ w.T + w @ d.T) - np.sum(d * w) * np.eye(3)
        f.K_cent += th.T @ S @ th
        # the tower top's rotation with the rotor's and the blades' motion: theta x v
        C1 = E0 - (f.rigid(f.apex)[:, :, None]
                   + (np.cross(th.T, e_r).T[:, :, None]
                      + np.outer(np.cross(es, e_r), rho)[:, :, None]) * f.radius)
        V1 = np.cross(es, c0.T).T[:, None, :] * rho[None, :, None] + C1   # (3, n, n_s)
        X = np.cross(V1, w[:, None, :], axis=0).sum(axis=2)                # sum v x w
        P = th.T @ X
        f.K_cent += P + P.T
        # the rotor's rotation with the blades' motion: theta_r e_s x c_1
        y = np.einsum("is,ias->a", np.cross(w.T, es).T, C1)
        f.K_cent += np.outer(rho, y) + np.outer(y, rho)
        # the rotor's rotation twice: theta_r^2 e_s x (e_s x c_0) / 2
        f.K_cent += np.outer(rho, rho) * float(np.sum((es @ c0) * (es @ w) - np.sum(c0 * w,
                                                                                   axis=0)))
        # the blades' shortening along the span under their centrifugal tension
        f.K_cent += T0.T @ K_tension @ T0
        f.K += T0.T @ K_b @ T0
        f.C += T0.T @ C_b @ T0
        f.K_speed += T0.T @ C_b @ dT
    return f.matrices()
