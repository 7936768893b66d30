"""Quasi-steady blade-element momentum (BEM) aerodynamics of a rigid rotor (DESIGN 2.5).

Per blade element (radius ``r``, chord ``c``, twist ``beta``), with the local wind ``U`` normal
to the rotor and ``v_t`` in the plane along the blade's direction of motion:

    W^2 = (U (1 - a))^2 + (Omega r (1 + a') - v_t)^2
    phi = atan2(U (1 - a), Omega r (1 + a') - v_t)
    alpha = phi - beta - pitch,   Cn = cl cos(phi) + cd sin(phi),   Ct = cl sin(phi) - cd cos(phi)
    a = 1 / (4 F sin^2(phi) / (sigma Cn) + 1),   a' = 1 / (4 F sin(phi) cos(phi) / (sigma Ct) - 1)

with solidity ``sigma = B c / (2 pi r)`` and Prandtl's tip and hub loss ``F``; above ``a_c = 0.2``
the axial induction follows Glauert's correction in Spera's form (M. O. L. Hansen, "Aerodynamics
of Wind Turbines", 2nd ed., Earthscan 2008, ch. 6, eqs. 6.35-6.38 and 6.40), or, with
``Rotor(correction="buhl")``, Buhl's above a = 0.4 (M. L. Buhl, "A New Empirical Relationship
between Thrust Coefficient and Induction Factor for the Turbulent Windmill State",
NREL/TP-500-36834, 2005; as AeroDyn and CCBlade). Quasi-steady: the
inductions are solved to convergence at every aerodynamic update: each element's flow angle
is the root of the one-equation residual ``sin(phi) U_t - cos(phi) U_x`` (S. A. Ning, "A simple
solution method for the blade element momentum equations with guaranteed convergence", Wind
Energy 17, 2014), found by secant and bracketed regula falsi steps next to the previous
update's angle; where no root is found there, the inductions are iterated (relaxed, to
``tol``) as a fallback. Forces per unit length ``0.5 rho W^2 c (Cn, Ct)``.

Coned blades (``precone`` ``c``, ElastoDyn's sign: negative leans the blades upwind), as CCBlade
(S. A. Ning, "CCBlade documentation", NREL 2013, sec. 2; the blade-element kinematics of AeroDyn):
an element at span ``r`` (along the blade, from the rotor centre) turns on the radius
``r cos(c)`` and sits ``r sin(c)`` downwind of the rotor centre; it takes the wind normal to its
coned span, ``U = u_x cos(c) - u_r sin(c)`` (:meth:`Turbine.blade_wind`), turns at
``Omega r cos(c)``, and its normal force acts along ``e_n = cos(c) e_x - sin(c) e_r``; the
solidity and Prandtl's losses take the span ``r``.

Hub loads (the shaft's nonrotating axes at the rotor centre: ``x`` along the shaft downwind,
``z`` up normal to it; without shaft tilt the axes of :mod:`.wind`): thrust ``Fx``, driving
torque ``Q`` (about the shaft, positive in the direction of rotation), in-plane shear ``Fy``,
``Fz`` (with the rotor's weight, ``-m g cos(tilt)``), tilt ``My`` and yaw ``Mz`` moments, the
sums ``F = sum f``, ``M = sum p x f`` over the elements' forces ``f = f_n e_n + f_t e_t`` at
their positions ``p``. The thrust is aerodynamic: the weight's component along a tilted shaft,
``m g sin(tilt)``, is left to the main bearing, and the weight acts at the rotor centre: the
coned blades' centre of mass upwind of it (0.96 m on the 5 MW) and its tilt moment are left
out. Blade ``b`` is at azimuth ``psi + 2 pi b / B``
(0 = up); its element sits at ``y = -r cos(c) sin(psi_b)``, ``z = r cos(c) cos(psi_b)`` and
moves along ``e_t = (0, -cos(psi_b), -sin(psi_b))``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numba
import numpy as np

from ..errors import ModelError
from .airfoil import Airfoil

LOAD_COLUMNS = ["thrust_N", "torque_Nm", "shear_y_N", "shear_z_N", "tilt_Nm", "yaw_Nm"]
#: the high-induction corrections (:class:`Rotor`)
CORRECTIONS = ("spera", "buhl")
#: the largest precone a rotor takes (rad: 30 deg)
MAX_CONE = math.radians(30.0)


@dataclass
class Rotor:
    """A rigid three-bladed (or ``blades``-bladed) rotor.

    radius, hub_radius : m. r, chord : m at the element centres. twist : rad (local pitch of
    the chord to the rotor plane). pitch : rad (fixed: stall regulation; a pitch-regulated
    turbine gives it per call of :meth:`loads`). airfoil : polar of every element, or
    ``airfoils`` with ``airfoil_id`` (per element, an index into ``airfoils``): a blade of
    several sections. mass : kg (its weight acts on the hub). rho : air density, kg/m^3.
    correction : the high-induction correction, ``"spera"`` (Glauert's in Spera's form above
    a = 0.2, Hansen eq. 6.38: the 600 kW turbine's) or ``"buhl"`` (Buhl's above a = 0.4, as
    AeroDyn and CCBlade: a rotor read from an OpenFAST deck). precone : rad, the blades' cone
    angle out of the rotor plane (ElastoDyn's sign: negative leans them upwind; module
    docstring); ``r``, ``radius`` and ``hub_radius`` are spans along the coned blade.
    """

    radius: float
    hub_radius: float
    r: np.ndarray
    chord: np.ndarray
    twist: np.ndarray
    blades: int = 3
    pitch: float = 0.0
    airfoil: Airfoil = field(default_factory=Airfoil.viterna)
    mass: float = 0.0
    rho: float = 1.225
    airfoils: list | None = None
    airfoil_id: np.ndarray | None = None
    correction: str = "spera"
    gravity: float = 9.81
    tol: float = 1e-8
    max_iter: int = 200
    precone: float = 0.0

    def __post_init__(self):
        self.r = np.asarray(self.r, dtype=float)
        self.chord = np.asarray(self.chord, dtype=float)
        self.twist = np.asarray(self.twist, dtype=float)
        n = len(self.r)
        if self.correction not in CORRECTIONS:
            raise ModelError("rotor.correction", f"= {self.correction!r}: one of "
                             + ", ".join(map(repr, CORRECTIONS)))
        if n < 2 or self.chord.shape != (n,) or self.twist.shape != (n,):
            raise ModelError("rotor.r", "r, chord and twist need the same length >= 2")
        if not (0 <= self.hub_radius < self.r.min() and self.r.max() < self.radius):
            raise ModelError("rotor.r", f"element radii must lie in ({self.hub_radius}, "
                             f"{self.radius}) m")
        if np.any(np.diff(self.r) <= 0) or np.any(self.chord <= 0):
            raise ModelError("rotor.r", "radii must increase and chords be > 0")
        if not (isinstance(self.precone, (int, float)) and abs(self.precone) <= MAX_CONE):
            raise ModelError("rotor.precone", f"= {self.precone!r} rad: must be a number in "
                             f"[-{MAX_CONE:.4f}, {MAX_CONE:.4f}] (30 deg)")
        self.precone = float(self.precone)
        #: each element's radius of rotation and downwind offset (module docstring)
        self.r_turn = self.r * math.cos(self.precone)
        self.r_axial = self.r * math.sin(self.precone)
        # the polars on one grid of angles, a row each, and each element's row: the union of
        # the polars' own angles, so that interpolating on it is each polar's own (exact)
        foils = list(self.airfoils) if self.airfoils else [self.airfoil]
        ids = (np.zeros(n, dtype=np.int64) if self.airfoil_id is None
               else np.asarray(self.airfoil_id, dtype=np.int64))
        if ids.shape != (n,) or ids.min() < 0 or ids.max() >= len(foils):
            raise ModelError("rotor.airfoil_id", f"needs one index per element into the "
                             f"{len(foils)} airfoils")
        if len(foils) == 1:
            grid = foils[0].alpha
        else:
            grid = np.unique(np.concatenate([f.alpha for f in foils]))
        self._polars = (np.ascontiguousarray(grid, dtype=float),
                        np.array([np.interp(grid, f.alpha, f.cl) for f in foils]),
                        np.array([np.interp(grid, f.alpha, f.cd) for f in foils]), ids)
        edges = np.concatenate([[self.hub_radius], 0.5 * (self.r[1:] + self.r[:-1]),
                                [self.radius]])
        self.dr = np.diff(edges)
        self._a = np.zeros((self.blades, n))
        self._ap = np.zeros((self.blades, n))

    def __getstate__(self):
        """Pickle without the induction factors of the last call (a warm start that every run
        resets), so that a pickled (or fingerprinted) rotor is the same before and after a
        run."""
        state = {**self.__dict__, "_a": np.zeros_like(self._a), "_ap": np.zeros_like(self._ap)}
        state.pop("_pos", None)
        return state

    def positions(self, psi: float):
        """Element positions ``(y, z)`` in the rotor plane relative to the hub, each
        (blades, n) (the downwind offsets are ``r_axial``), and the blade azimuths
        (read-only: the last azimuth's are kept, asked for twice a step)."""
        last = self.__dict__.get("_pos")
        if last is not None and last[0] == psi:
            return last[1]
        psib = psi + 2 * math.pi * np.arange(self.blades) / self.blades
        y = -np.sin(psib)[:, None] * self.r_turn[None, :]
        z = np.cos(psib)[:, None] * self.r_turn[None, :]
        for a in (y, z, psib):
            a.flags.writeable = False
        self._pos = (psi, (y, z, psib))
        return y, z, psib

    def loads(self, omega: float, psi: float, wind_u: np.ndarray, wind_vt: np.ndarray,
              reset: bool = False, pitch: float | None = None, tilt: float = 0.0) -> dict:
        """Hub loads (``LOAD_COLUMNS``, SI; module docstring) at rotor speed ``omega`` (rad/s)
        and azimuth ``psi`` (rad) for the wind normal to the coned blades ``wind_u`` and in
        plane along the blade motion ``wind_vt`` (m/s, each (blades, n)); ``pitch``: the
        blades' pitch (rad; default the rotor's); ``tilt``: the shaft's tilt (rad, the rotor
        end up), which turns the rotor's weight in the shaft's axes."""
        a = np.zeros_like(wind_u) if reset else self._a
        ap = np.zeros_like(wind_u) if reset else self._ap
        pa, pcl, pcd, pid = self._polars
        fn, ft, a, ap = _bem(np.ascontiguousarray(wind_u, dtype=float),
                             np.ascontiguousarray(wind_vt, dtype=float), float(omega), self.r,
                             self.r_turn, self.chord,
                             self.twist + (self.pitch if pitch is None else float(pitch)),
                             self.dr, self.blades, self.radius, self.hub_radius, pa, pcl, pcd,
                             pid, a.copy(), ap.copy(), self.rho, self.tol, self.max_iter,
                             CORRECTIONS.index(self.correction))
        self._a, self._ap = a, ap
        y, z, psib = self.positions(psi)
        cc, sc = math.cos(self.precone), math.sin(self.precone)
        sp, cp = np.sin(psib)[:, None], np.cos(psib)[:, None]
        # f = fn (cos c e_x - sin c e_r) + ft e_t, e_r = (0, -sin, cos), e_t = (0, -cos, -sin)
        fx = fn * cc
        fy = fn * sc * sp - ft * cp
        fz = -fn * sc * cp - ft * sp
        x = np.broadcast_to(self.r_axial[None, :], fn.shape)
        return {
            "thrust_N": float(fx.sum()),
            "torque_Nm": float((ft * self.r_turn[None, :]).sum()),  # = sum (y fz - z fy)
            "shear_y_N": float(fy.sum()),
            "shear_z_N": float(fz.sum()) - self.mass * self.gravity * math.cos(tilt),
            "tilt_Nm": float((z * fx - x * fz).sum()),
            "yaw_Nm": float((x * fy - y * fx).sum()),
        }

    def power_coefficient(self, wind_speed: float, omega: float,
                          pitch: float | None = None) -> tuple[float, float]:
        """``(Cp, Ct)`` in uniform wind along the shaft (no shear, tilt, turbulence or tower),
        at ``pitch`` (rad; default the rotor's), on the swept area ``pi (R cos(c))^2`` (as
        CCBlade; :meth:`Turbine.power_coefficient` for the turbine's tilt and shear)."""
        u = np.full((self.blades, len(self.r)), float(wind_speed) * math.cos(self.precone))
        ld = self.loads(omega, 0.0, u, np.zeros_like(u), reset=True, pitch=pitch)
        return self.coefficients(ld, wind_speed, omega)

    def coefficients(self, loads: dict, wind_speed: float, omega: float) -> tuple[float, float]:
        """``(Cp, Ct)`` of hub ``loads`` at ``wind_speed`` (m/s) and rotor speed ``omega``
        (rad/s) on the swept area ``pi (R cos(c))^2``."""
        area = math.pi * (self.radius * math.cos(self.precone))**2
        q = 0.5 * self.rho * area * wind_speed**2
        return loads["torque_Nm"] * omega / (q * wind_speed), loads["thrust_N"] / q


@numba.njit(cache=True)
def _polar(al, pa, pcl, pcd):
    """``(cl, cd)`` at angle ``al`` on the polar grid ``pa`` (increasing): np.interp of both
    with one search, held at the ends."""
    n = pa.shape[0]
    if al <= pa[0]:
        return pcl[0], pcd[0]
    if al >= pa[n - 1]:
        return pcl[n - 1], pcd[n - 1]
    lo, hi = 0, n - 1  # pa[lo] <= al < pa[hi]
    while hi - lo > 1:
        mid = (lo + hi) >> 1
        if pa[mid] <= al:
            lo = mid
        else:
            hi = mid
    w = (al - pa[lo]) / (pa[hi] - pa[lo])
    return pcl[lo] + w * (pcl[hi] - pcl[lo]), pcd[lo] + w * (pcd[hi] - pcd[lo])


@numba.njit(cache=True)
def _inductions(phi, theta, sigma, B, R, ri, rh, pa, pcl, pcd, corr=0):
    """The inductions ``(a, a')`` that flow angle ``phi`` implies at an element (module
    docstring: Prandtl's losses, the high-induction correction ``corr``: 0 Glauert's in
    Spera's form, 1 Buhl's; the same limits as the iteration)."""
    ac = 0.2
    al = (phi - theta + math.pi) % (2.0 * math.pi) - math.pi
    cl, cd = _polar(al, pa, pcl, pcd)
    sp, cp = math.sin(phi), math.cos(phi)
    cn = cl * cp + cd * sp
    ct = cl * sp - cd * cp
    s = max(abs(sp), 1e-6)
    f_tip = B * (R - ri) / (2.0 * ri * s)
    f_hub = B * (ri - rh) / (2.0 * max(rh, 1e-3) * s)
    F = (4.0 / math.pi**2) * math.acos(math.exp(-f_tip)) * math.acos(math.exp(-f_hub))
    F = max(F, 1e-4)
    scn = sigma * cn
    K = 4.0 * F * sp * sp / (scn if abs(scn) > 1e-12 else 1e-12)
    an = 1.0 / (K + 1.0)
    if corr == 1:
        if an > 0.4:  # Buhl's correction (NREL/TP-500-36834, 2005; as AeroDyn and CCBlade)
            k = 1.0 / K
            g1 = 2.0 * F * k - (10.0 / 9.0 - F)
            g2 = max(2.0 * F * k - F * (4.0 / 3.0 - F), 0.0)
            g3 = 2.0 * F * k - (25.0 / 9.0 - 2.0 * F)
            an = ((g1 - math.sqrt(g2)) / g3 if abs(g3) > 1e-6
                  else 1.0 - 0.5 / max(math.sqrt(g2), 1e-12))
    elif an > ac:  # Glauert correction, Spera's form (Hansen eq. 6.38)
        d = (K * (1.0 - 2.0 * ac) + 2.0) ** 2 + 4.0 * (K * ac * ac - 1.0)
        an = 0.5 * (2.0 + K * (1.0 - 2.0 * ac) - math.sqrt(max(d, 0.0)))
    sct = sigma * ct
    den = 4.0 * F * sp * cp / (sct if abs(sct) > 1e-12 else 1e-12)
    apn = 1.0 / (den - 1.0) if abs(den - 1.0) > 1e-12 else 0.5
    if not math.isfinite(an):
        an = 0.0
    if not math.isfinite(apn):
        apn = 0.0
    return min(max(an, -0.5), 0.95), min(max(apn, -0.5), 0.5)


@numba.njit(cache=True)
def _residual(phi, u, wr, vt, theta, sigma, B, R, ri, rh, pa, pcl, pcd, corr=0):
    """``sin(phi) U_t - cos(phi) U_x`` with the inductions ``phi`` implies: zero exactly at
    the BEM solution (``tan(phi) = U_x / U_t``; Ning 2014's one-equation form)."""
    a, ap = _inductions(phi, theta, sigma, B, R, ri, rh, pa, pcl, pcd, corr)
    return math.sin(phi) * (wr * (1.0 + ap) - vt) - math.cos(phi) * u * (1.0 - a)


@numba.njit(cache=True)
def _solve_phi(phi0, u, wr, vt, theta, sigma, B, R, ri, rh, pa, pcl, pcd, corr=0):
    """The flow angle near ``phi0`` where :func:`_residual` vanishes: secant steps, kept
    inside a bracket once the residual has changed sign (Illinois rule); NaN when no root
    is found within 60 evaluations (the caller then iterates the inductions instead)."""
    x0 = phi0
    f0 = _residual(x0, u, wr, vt, theta, sigma, B, R, ri, rh, pa, pcl, pcd, corr)
    if f0 == 0.0:
        return x0
    x1 = x0 + (1e-3 if f0 < 0.0 else -1e-3) * (1.0 if math.cos(x0) > 0.0 else -1.0)
    f1 = _residual(x1, u, wr, vt, theta, sigma, B, R, ri, rh, pa, pcl, pcd, corr)
    lo = hi = np.nan
    flo = fhi = 0.0
    for _ in range(60):
        if f1 == 0.0:
            return x1
        if not math.isfinite(lo) and f0 * f1 < 0.0:  # a bracket: the residual changes sign
            lo, flo, hi, fhi = x0, f0, x1, f1
        if math.isfinite(lo):
            # regula falsi on the bracket (Illinois: halve the stale end's value)
            x2 = hi - fhi * (hi - lo) / (fhi - flo)
            f2 = _residual(x2, u, wr, vt, theta, sigma, B, R, ri, rh, pa, pcl, pcd, corr)
            if abs(x2 - hi) <= 1e-13 * (1.0 + abs(x2)) or f2 == 0.0:
                return x2
            if f2 * fhi < 0.0:
                lo, flo = hi, fhi
            else:
                flo *= 0.5
            hi, fhi = x2, f2
            if abs(hi - lo) <= 1e-13 * (1.0 + abs(hi)):
                return hi
            continue
        if f1 == f0:
            return np.nan
        x2 = x1 - f1 * (x1 - x0) / (f1 - f0)
        if abs(x2 - x1) > 0.2:  # a secant step that leaves the neighbourhood: a small one
            x2 = x1 + math.copysign(0.2, x2 - x1)
        x0, f0 = x1, f1
        x1 = x2
        f1 = _residual(x1, u, wr, vt, theta, sigma, B, R, ri, rh, pa, pcl, pcd, corr)
        if abs(x1 - x0) <= 1e-13 * (1.0 + abs(x1)):
            return x1
    return np.nan


@numba.njit(cache=True)
def _bem(U, vt, omega, r, rt, chord, theta, dr, B, R, rh, pa, PCL, PCD, pid, a, ap, rho, tol,
         max_iter, corr=0):
    """Element-by-element BEM solution (module docstring); returns per element the normal and
    tangential forces (N, over the element's width) and the inductions. Each element's flow
    angle is the root of the one-equation residual (:func:`_solve_phi`) next to the previous
    update's; where none is found, the inductions are iterated (relaxed) as before. The polars
    are rows of ``PCL``, ``PCD`` on the angles ``pa``, element ``i``'s the row ``pid[i]``.
    ``r``: the elements' spans (solidity, losses); ``rt``: their radii of rotation."""
    nb, n = U.shape
    fn = np.empty((nb, n))
    ft = np.empty((nb, n))
    for b in range(nb):
        for i in range(n):
            ri = r[i]
            wr = omega * rt[i]
            pcl, pcd = PCL[pid[i]], PCD[pid[i]]
            sigma = B * chord[i] / (2.0 * math.pi * ri)
            u = max(U[b, i], 1e-3)
            ai, api = a[b, i], ap[b, i]
            phi0 = math.atan2(u * (1.0 - ai), wr * (1.0 + api) - vt[b, i])
            phi = _solve_phi(phi0, u, wr, vt[b, i], theta[i], sigma, B, R, ri, rh,
                             pa, pcl, pcd, corr)
            if math.isfinite(phi):
                ai, api = _inductions(phi, theta[i], sigma, B, R, ri, rh, pa, pcl, pcd, corr)
            else:
                for _ in range(max_iter):
                    ux = u * (1.0 - ai)
                    ut = wr * (1.0 + api) - vt[b, i]
                    an, apn = _inductions(math.atan2(ux, ut), theta[i], sigma, B, R, ri, rh,
                                          pa, pcl, pcd, corr)
                    change = max(abs(an - ai), abs(apn - api))
                    ai += 0.5 * (an - ai)
                    api += 0.5 * (apn - api)
                    if change < tol:
                        break
            a[b, i], ap[b, i] = ai, api
            ux = u * (1.0 - ai)
            ut = wr * (1.0 + api) - vt[b, i]
            phi = math.atan2(ux, ut)
            al = (phi - theta[i] + math.pi) % (2.0 * math.pi) - math.pi
            cl, cd = _polar(al, pa, pcl, pcd)
            q = 0.5 * rho * (ux * ux + ut * ut) * chord[i] * dr[i]
            fn[b, i] = q * (cl * math.cos(phi) + cd * math.sin(phi))
            ft[b, i] = q * (cl * math.sin(phi) - cd * math.cos(phi))
    return fn, ft, a, ap
