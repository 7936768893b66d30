"""ISO 6336 method B: the pitting and tooth-root safety factors of one gear pair.

The clauses cited are those of ISO 6336-1:2006 (load factors; the resonance method B of K_v,
method C of K_Hbeta, method B of K_Halpha and of the mesh stiffness), ISO 6336-2:2019 (surface
durability), ISO 6336-3:2019 (tooth bending, method B with the load at the outer point of
single pair contact) and ISO 1328-1:1995 (the tolerances of an accuracy grade). The geometry
follows ISO 21771: an internal gear has a negative tooth number and diameters, so one set of
formulas serves both kinds of pair.

The API takes SI units (m, N, Pa, rpm); inside, as in the standard, lengths are in mm,
deviations in um, stresses in N/mm^2 (MPa), mesh stiffness in N/(mm um).

What this implementation leaves at the standard's simple values, each stated where it is
used: solid gear bodies (C_R = 1, Y_B = 1), no deep teeth (Y_DT = 1), equal flank hardness
(Z_W = 1), size factor Z_X = 1 (ISO 6336-2's recommendation without test data), no
protuberance, tip relief ``tip_relief`` (C_a) only in K_v. An internal gear's tooth-root factors
are taken as a rack's with the ring's profile (z_n -> infinity, the 30 deg tangent): internal
teeth are thicker at the root than a rack's, so this is the conservative side of ISO 6336-3's
own internal-gear procedure.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import pandas as pd

from ..errors import ModelError

#: steel's density (kg/mm^3) for the reduced mass of solid gears (ISO 6336-1, 6.3.2)
STEEL_DENSITY = 7.83e-6
#: a rack's tooth number for an internal gear's root factors (see the module docstring)
RACK_TEETH = 1.0e5


@dataclass(frozen=True)
class GearSpec:
    """One gear of a pair as ISO 6336 needs it (SI units).

    ``teeth`` is the number of teeth (positive; ``internal`` marks a ring). ``profile_shift``
    is x of ISO 21771 (for an internal gear with the standard's sign convention of a negative
    tooth number), ``tip_alteration`` the change of the tip radius, m (negative: shortened).
    The basic rack: ``dedendum`` h_fP and ``root_radius`` rho_fP in modules (ISO 53 profile A:
    1.25 and 0.38). Material (ISO 6336-5, case-hardened steel MQ by default): ``sigma_Hlim``,
    ``sigma_Flim`` (Pa), ``youngs_modulus`` (Pa), ``poisson``. Surfaces: ``flank_Rz`` and
    ``root_Rz`` (m). ``reversed_bending``: the teeth are loaded on both flanks in turn (a
    planet or an idler; Y_M = 0.7).
    """

    teeth: int
    module: float
    pressure_angle: float
    helix_angle: float
    face_width: float
    profile_shift: float = 0.0
    tip_alteration: float = 0.0
    internal: bool = False
    dedendum: float = 1.25
    root_radius: float = 0.38
    sigma_Hlim: float = 1.5e9
    sigma_Flim: float = 5.0e8
    youngs_modulus: float = 206e9
    poisson: float = 0.3
    flank_Rz: float = 4.8e-6
    root_Rz: float = 10.0e-6
    reversed_bending: bool = False

    def __post_init__(self):
        for name, lo in (("teeth", 3), ("module", 0.0), ("face_width", 0.0),
                         ("sigma_Hlim", 0.0), ("sigma_Flim", 0.0), ("youngs_modulus", 0.0)):
            x = getattr(self, name)
            if not (isinstance(x, (int, float)) and math.isfinite(x) and x > lo):
                raise ModelError(f"gear.{name}", f"= {x!r}: must be a number > {lo}")
        if not 0.0 < self.pressure_angle < math.pi / 4:
            raise ModelError("gear.pressure_angle", f"= {self.pressure_angle!r} rad: must lie "
                             "in (0, pi/4)")
        if not abs(self.helix_angle) < math.pi / 4:
            raise ModelError("gear.helix_angle", f"= {self.helix_angle!r} rad: must lie in "
                             "(-pi/4, pi/4)")
        if not -1.5 <= self.profile_shift <= 1.5:
            raise ModelError("gear.profile_shift", f"= {self.profile_shift!r}: must lie in "
                             "[-1.5, 1.5] (a coefficient, not a length)")

    # -- geometry, ISO 21771 (mm; signed for an internal gear) -----------------------------
    @property
    def z(self) -> float:
        return -float(self.teeth) if self.internal else float(self.teeth)

    @property
    def m_n(self) -> float:
        return self.module * 1e3

    @property
    def beta(self) -> float:
        return abs(self.helix_angle)

    @property
    def alpha_t(self) -> float:
        """Transverse pressure angle (ISO 21771 eq. 7)."""
        return math.atan(math.tan(self.pressure_angle) / math.cos(self.beta))

    @property
    def d(self) -> float:
        """Reference diameter, mm (negative for an internal gear)."""
        return self.z * self.m_n / math.cos(self.beta)

    @property
    def d_b(self) -> float:
        return self.d * math.cos(self.alpha_t)

    @property
    def d_a(self) -> float:
        """Tip diameter: d + 2 m_n (1 + x + k), k the tip alteration in modules."""
        return self.d + 2.0 * self.m_n * (1.0 + self.profile_shift
                                          + self.tip_alteration * 1e3 / self.m_n)

    @property
    def d_f(self) -> float:
        """Root diameter: d - 2 (h_fP - x m_n)."""
        return self.d - 2.0 * self.m_n * (self.dedendum - self.profile_shift)


@dataclass
class PairRating:
    """The rating of one gear pair: ``pair`` (the factors common to both gears) and ``gears``
    (pinion first: each gear's stresses, factors and safety factors S_H, S_F)."""

    pair: dict
    gears: list = field(default_factory=list)

    def to_frame(self) -> pd.DataFrame:
        """One row per gear: the pair's factors beside each gear's own."""
        return pd.DataFrame([{**self.pair, **g} for g in self.gears])


def _inv(a: float) -> float:
    return math.tan(a) - a


def iso1328(grade: float, d: float, m_n: float, b: float) -> dict:
    """ISO 1328-1:1995 tolerances (um) of accuracy grade ``grade`` for a gear of reference
    diameter ``d``, module ``m_n`` and face width ``b`` (mm): single pitch f_pt (eq. 1), profile
    form f_falpha (eq. 6), helix slope f_Hbeta (eq. 10), without the standard's rounding."""
    s = 2.0 ** (0.5 * (grade - 5.0))
    d, b = abs(d), abs(b)
    return {"f_pt": (0.3 * (m_n + 0.4 * math.sqrt(d)) + 4.0) * s,
            "f_falpha": (2.5 * math.sqrt(m_n) + 0.17 * math.sqrt(d) + 0.5) * s,
            "f_Hbeta": (0.07 * math.sqrt(d) + 0.45 * math.sqrt(b) + 3.0) * s}


def life_factor_pitting(n_cycles: float, optimum: bool = False) -> float:
    """Z_NT of case-hardened steel (ISO 6336-2:2019, Table 2, line for Eh, IF): 1.6 up to
    1e5 cycles, (5e7/N)^0.0756 to 5e7, then 1.0 under optimum conditions or the reference line
    (5e7/N)^0.0307 to 0.85 at 1e10."""
    n = float(n_cycles)
    if n <= 1e5:
        return 1.6
    if n <= 5e7:
        return (5e7 / n) ** 0.0756
    if optimum:
        return 1.0
    return max((5e7 / n) ** 0.0307, (5e7 / 1e10) ** 0.0307)


def life_factor_bending(n_cycles: float, optimum: bool = False) -> float:
    """Y_NT of case-hardened steel (ISO 6336-3:2019, Table 3, line for Eh, IF): 2.5 up to 1e3
    cycles, (3e6/N)^0.115 to 3e6, then 1.0 under optimum conditions or (3e6/N)^0.02 to 0.85 at
    1e10."""
    n = float(n_cycles)
    if n <= 1e3:
        return 2.5
    if n <= 3e6:
        return (3e6 / n) ** 0.115
    if optimum:
        return 1.0
    return max((3e6 / n) ** 0.02, (3e6 / 1e10) ** 0.02)


def _lubrication(sigma_Hlim: float, nu40: float, v: float) -> tuple[float, float]:
    """Z_L and Z_v (ISO 6336-2:2019, 11.4, eqs. 33-36); sigma_Hlim in MPa, nu40 in mm^2/s, v
    the pitch line velocity in m/s."""
    if sigma_Hlim < 850.0:
        c_zl = 0.83
    elif sigma_Hlim <= 1200.0:
        c_zl = sigma_Hlim / 4375.0 + 0.6357
    else:
        c_zl = 0.91
    z_l = c_zl + 4.0 * (1.0 - c_zl) / (1.2 + 134.0 / nu40) ** 2
    c_zv = c_zl + 0.02
    z_v = c_zv + 2.0 * (1.0 - c_zv) / math.sqrt(0.8 + 32.0 / max(v, 1e-6))
    return z_l, z_v


def _roughness(sigma_Hlim: float, rz_mean: float, rho_red: float) -> float:
    """Z_R (ISO 6336-2:2019, 11.5, eqs. 37-40): R_z10 = R_z (10/rho_red)^(1/3) (um, mm)."""
    rz10 = rz_mean * (10.0 / rho_red) ** (1.0 / 3.0)
    if sigma_Hlim < 850.0:
        c = 0.15
    elif sigma_Hlim <= 1200.0:
        c = 0.32 - 0.0002 * sigma_Hlim
    else:
        c = 0.08
    return (3.0 / rz10) ** c


def _root_factors(g: GearSpec, eps_an: float, beta_b: float) -> dict:
    """Y_F, Y_S and the root geometry of one gear (ISO 6336-3:2019, 6.2, eqs. 10-26; the load
    at the outer point of single pair contact; an internal gear as a rack)."""
    m = g.m_n
    an = g.pressure_angle
    hfp, rfp = g.dedendum * m, g.root_radius * m
    x = g.profile_shift
    internal = g.internal
    zn = RACK_TEETH if internal else g.z / (math.cos(beta_b) ** 2 * math.cos(g.beta))
    E = math.pi / 4.0 * m - hfp * math.tan(an) - (1.0 - math.sin(an)) * rfp / math.cos(an)
    G = rfp / m - hfp / m + x
    H = 2.0 / zn * (math.pi / 2.0 - E / m) - math.pi / 3.0
    theta = math.pi / 6.0
    for _ in range(100):
        new = 2.0 * G / zn * math.tan(theta) - H
        if abs(new - theta) < 1e-14:
            theta = new
            break
        theta = new
    s_fn = m * (zn * math.sin(math.pi / 3.0 - theta)
                + math.sqrt(3.0) * (G / math.cos(theta) - rfp / m))
    rho_f = m * (rfp / m + 2.0 * G * G / (math.cos(theta) * (zn * math.cos(theta) ** 2
                                                              - 2.0 * G)))
    # the virtual gear's diameters (eqs. 19-21): its addendum that of the real gear
    addendum = abs(g.d_a - g.d) / 2.0 if internal else (g.d_a - g.d) / 2.0
    d_n = m * zn
    d_bn = d_n * math.cos(an)
    d_an = d_n + 2.0 * addendum
    p_bn = math.pi * m * math.cos(an)
    rad = math.sqrt(max((d_an / 2.0) ** 2 - (d_bn / 2.0) ** 2, 0.0)) - p_bn * (eps_an - 1.0)
    d_en = 2.0 * math.sqrt(rad * rad + (d_bn / 2.0) ** 2)
    a_en = math.acos(min(d_bn / d_en, 1.0))
    g_e = (0.5 * math.pi + 2.0 * math.tan(an) * x) / zn + _inv(an) - _inv(a_en)
    a_fen = a_en - g_e
    h_fe = 0.5 * m * ((math.cos(g_e) - math.sin(g_e) * math.tan(a_fen)) * d_en / m
                      - zn * math.cos(math.pi / 3.0 - theta) - G / math.cos(theta) + rfp / m)
    y_f = 6.0 * (h_fe / m) * math.cos(a_fen) / ((s_fn / m) ** 2 * math.cos(an))
    L = s_fn / h_fe
    q_s = s_fn / (2.0 * rho_f)
    y_s = (1.2 + 0.13 * L) * q_s ** (1.0 / (1.21 + 2.3 / L))
    return {"Y_F": y_f, "Y_S": y_s, "s_Fn_mm": s_fn, "h_Fe_mm": h_fe, "rho_F_mm": rho_f,
            "q_s": q_s}


def rate_pair(pinion: GearSpec, wheel: GearSpec, centre_distance: float, torque: float,
              speed_rpm: float, *, cycles: tuple[float, float], application_factor: float = 1.0,
              k_gamma: float = 1.0, accuracy_grade: float = 6.0,
              lubricant_viscosity_40: float = 320.0, tip_relief: float = 0.0,
              misalignment: float | None = None, reduced_mass: float | None = None,
              long_life: str = "reference", dynamic_factor: float | None = None) -> PairRating:
    """Pitting and tooth-root safety factors of a pair under a steady load (ISO 6336 method B).

    Parameters
    ----------
    pinion, wheel : the gears; the pinion is the gear with fewer teeth (never the ring).
    centre_distance : the operating centre distance, m (positive for either kind of pair).
    torque : the pinion's torque on this mesh, N m (a planetary sun's share of one planet).
    speed_rpm : the pinion's speed relative to the frame the gears' centres sit in (a
        planetary stage: relative to the carrier), rpm.
    cycles : each gear's tooth load cycles over the required life (pinion, wheel).
    application_factor : K_A. k_gamma : K_gamma, the planets' mesh load factor.
    accuracy_grade : ISO 1328-1:1995 grade Q of both gears.
    lubricant_viscosity_40 : nu_40, mm^2/s.
    tip_relief : C_a, m (in K_v's B_k).
    misalignment : F_betax, the initial equivalent misalignment, m; default the helix slope
        tolerance f_Hbeta of the grade (a face whose helix is corrected for the deflections,
        ISO 6336-1, 7.6, leaves the manufacturing deviation).
    reduced_mass : the pair's reduced mass per face width, kg/m (ISO 6336-1, 6.3.2); default
        that of solid steel gears (eq. 30).
    long_life : ``"reference"`` (the life factors' lines to 0.85 at 1e10 cycles) or
        ``"optimum"`` (1.0 beyond the knee).
    dynamic_factor : a K_v to use instead of the standard's (e.g. one a dynamic model gives).
    """
    if pinion.internal:
        raise ModelError("pinion", "is internal: the ring is always the wheel")
    if long_life not in ("reference", "optimum"):
        raise ModelError("long_life", f"= {long_life!r}: must be 'reference' or 'optimum'")
    for name, x in (("centre_distance", centre_distance), ("torque", torque),
                    ("application_factor", application_factor), ("k_gamma", k_gamma),
                    ("lubricant_viscosity_40", lubricant_viscosity_40)):
        if not (math.isfinite(x) and x > 0):
            raise ModelError(name, f"= {x!r}: must be a number > 0")
    if not 1 <= accuracy_grade <= 12:
        raise ModelError("accuracy_grade", f"= {accuracy_grade!r}: ISO 1328 grades are 1-12")
    if abs(pinion.module - wheel.module) > 1e-12 or abs(pinion.pressure_angle
                                                          - wheel.pressure_angle) > 1e-12:
        raise ModelError("wheel", "module and pressure angle must equal the pinion's")
    optimum = long_life == "optimum"
    g1, g2 = pinion, wheel
    z1, z2 = g1.z, g2.z
    m_n, a_n, beta = g1.m_n, g1.pressure_angle, g1.beta
    a_t = g1.alpha_t
    m_t = m_n / math.cos(beta)
    b = min(g1.face_width, g2.face_width) * 1e3
    sign = 1.0 if z2 > 0 else -1.0
    a_w = sign * centre_distance * 1e3  # ISO 21771: negative for an internal pair
    cos_awt = (g1.d_b + g2.d_b) / (2.0 * a_w)
    if not 0.0 < cos_awt < 1.0:
        raise ModelError("centre_distance", f"= {centre_distance!r} m: the base circles "
                         f"({g1.d_b:.1f}, {g2.d_b:.1f} mm) give no pressure angle")
    a_wt = math.acos(cos_awt)
    # the profile shifts must give that centre distance (ISO 21771 eq. 53)
    inv_x = _inv(a_t) + 2.0 * (g1.profile_shift + g2.profile_shift) * math.tan(a_n) / (z1 + z2)
    if abs(inv_x - _inv(a_wt)) > 2e-4:
        a_x = _solve_inv(inv_x)
        raise ModelError("profile_shift", f"x1 + x2 = {g1.profile_shift + g2.profile_shift:g} "
                         f"gives an operating pressure angle of {math.degrees(a_x):.2f} deg, "
                         f"the centre distance {centre_distance:g} m gives "
                         f"{math.degrees(a_wt):.2f} deg: give the gears' profile shifts")
    beta_b = math.asin(math.sin(beta) * math.cos(a_n))
    u = z2 / z1
    p_bt = math.pi * m_t * math.cos(a_t)
    ra1, rb1, ra2, rb2 = g1.d_a / 2, g1.d_b / 2, g2.d_a / 2, g2.d_b / 2
    rho1_e = math.sqrt(ra1 ** 2 - rb1 ** 2)          # the pinion's tip on the line of action
    rho2_a = math.sqrt(ra2 ** 2 - rb2 ** 2)          # the wheel's tip (from its base point)
    t1t2 = abs(a_w) * math.sin(a_wt)                 # base tangent length T1T2
    g_alpha = rho1_e + sign * (rho2_a - t1t2)         # length of the path of contact
    eps_a = g_alpha / p_bt                           # ISO 21771 eq. 71
    eps_b = b * math.sin(beta) / (math.pi * m_n)     # eq. 73
    eps_g = eps_a + eps_b
    if not 1.0 < eps_a < 3.0:
        raise ModelError("profile_shift", f"the transverse contact ratio is {eps_a:.3f}: the "
                         "tip diameters (profile shift, tip alteration) give no working mesh")
    eps_an = eps_a / math.cos(beta_b) ** 2

    # -- ISO 6336-2: the contact stress factors ------------------------------------------
    z_h = math.sqrt(2.0 * math.cos(beta_b) * math.cos(a_wt)
                    / (math.cos(a_t) ** 2 * math.sin(a_wt)))           # eq. 10
    e1, e2 = g1.youngs_modulus * 1e-6, g2.youngs_modulus * 1e-6
    z_e = math.sqrt(1.0 / (math.pi * ((1 - g1.poisson ** 2) / e1
                                      + (1 - g2.poisson ** 2) / e2)))   # eq. 11
    if eps_b == 0.0:
        z_eps = math.sqrt((4.0 - eps_a) / 3.0)                          # eq. 12
    elif eps_b < 1.0:
        z_eps = math.sqrt((4.0 - eps_a) / 3.0 * (1.0 - eps_b) + eps_b / eps_a)  # eq. 13
    else:
        z_eps = math.sqrt(1.0 / eps_a)                                  # eq. 14
    z_beta = 1.0 / math.sqrt(math.cos(beta))                            # eq. 15
    # single pair contact factors Z_B, Z_D (6.2, eqs. 6-9), from the curvature radii on the
    # line of action: rho1 from the pinion's base point, rho2 = T1T2 - rho1 (external) or
    # rho1 + T1T2 (internal)
    def rho2(r1):
        return t1t2 - r1 if sign > 0 else r1 + t1t2
    rho1_c = rb1 * math.tan(a_wt)
    rho1_b = rho1_e - p_bt
    rho1_a = rho1_e - eps_a * p_bt
    rho1_d = rho1_a + p_bt
    m1 = math.sqrt(rho1_c * rho2(rho1_c) / (rho1_b * rho2(rho1_b)))
    m2 = math.sqrt(rho1_c * rho2(rho1_c) / (rho1_d * rho2(rho1_d)))
    if eps_b >= 1.0:
        z_b = z_d = 1.0
    else:
        z_b = max(1.0, m1 - eps_b * (m1 - 1.0))
        z_d = max(1.0, m2 - eps_b * (m2 - 1.0))
    if sign < 0:
        z_d = 1.0  # internal gears (6.2)
    rho_red = rho1_c * rho2(rho1_c) / t1t2           # at the pitch point (either kind)

    # -- loads and ISO 6336-1's factors ----------------------------------------------------
    d1 = g1.d
    f_t = 2.0 * torque / (d1 * 1e-3)                    # N, at the reference circle
    k_a = application_factor
    w = f_t * k_a / b                                   # N/mm
    v = math.pi * d1 * 1e-3 * speed_rpm / 60.0          # m/s, pitch line
    tol1 = iso1328(accuracy_grade, g1.d, m_n, b)
    tol2 = iso1328(accuracy_grade, g2.d, m_n, b)
    f_pb = max(tol1["f_pt"], tol2["f_pt"]) * math.cos(a_t)
    f_fa = max(tol1["f_falpha"], tol2["f_falpha"])
    f_hb = max(tol1["f_Hbeta"], tol2["f_Hbeta"])
    # mesh stiffness, method B (9.3, eqs. 69-77); an internal gear's z_n2 as infinite
    zn1 = z1 / (math.cos(beta_b) ** 2 * math.cos(beta))
    inv_zn2 = 0.0 if sign < 0 else math.cos(beta_b) ** 2 * math.cos(beta) / z2
    x1, x2 = g1.profile_shift, g2.profile_shift
    q = (0.04723 + 0.15551 / zn1 + 0.25791 * inv_zn2 - 0.00635 * x1 - 0.11654 * x1 / zn1
         - 0.00193 * x2 - 0.24188 * x2 * inv_zn2 + 0.00529 * x1 ** 2 + 0.00182 * x2 ** 2)
    c_th = 1.0 / q
    c_b = (1.0 + 0.5 * (1.2 - g1.dedendum)) * (1.0 - 0.02 * (20.0 - math.degrees(a_n)))
    c1 = c_th * 0.8 * 1.0 * c_b * math.cos(beta)        # C_M = 0.8, C_R = 1 (solid)
    if w < 100.0:
        c1 *= w / 100.0
    c_ga = c1 * (0.75 * eps_a + 0.25)                   # eq. 77
    c_gb = 0.85 * c_ga
    # running-in of case-hardened steel (8.3.3, 7.6: y_alpha = 0.075 f_pb <= 3 um, y_beta =
    # 0.15 F_betax <= 6 um)
    y_a = min(0.075 * f_pb, 3.0)
    y_f = min(0.075 * f_fa, 3.0)
    # dynamic factor, method B (6.3.2)
    if reduced_mass is None:
        m_red = _solid_reduced_mass(g1, g2)
    else:
        m_red = reduced_mass * 1e-3                     # kg/m -> kg/mm
    n_e1 = 30000.0 / (math.pi * abs(z1)) * math.sqrt(c_ga / m_red)   # eq. 6
    n_ratio = abs(speed_rpm) / n_e1
    if dynamic_factor is None:
        k_v = _dynamic_factor(n_ratio, w, eps_g, c1, f_pb - y_a, f_fa - y_f, tip_relief * 1e6)
    else:
        k_v = float(dynamic_factor)
    # face load factor, method C (7.6, eqs. 41-42)
    f_bx = f_hb if misalignment is None else misalignment * 1e6
    f_by = f_bx - min(0.15 * f_bx, 6.0)
    f_m = f_t * k_a * k_gamma * k_v
    r = c_gb * f_by / (2.0 * f_m / b)
    k_hb = 1.0 + r if r <= 1.0 else math.sqrt(2.0 * c_gb * f_by / (f_m / b))
    h1, h2 = abs(g1.d_a - g1.d_f) / 2.0, abs(g2.d_a - g2.d_f) / 2.0
    bh = max(min(b / h1, b / h2), 3.0)
    n_f = bh ** 2 / (1.0 + bh + bh ** 2)                # eq. 45
    k_fb = k_hb ** n_f
    # transverse load factors, method B (8.3.2, eqs. 71-74)
    f_th = f_t * k_a * k_gamma * k_v * k_hb
    lim = c_ga * max(f_pb - y_a, 0.0) / (f_th / b)
    if eps_g <= 2.0:
        k_ha = eps_g / 2.0 * (0.9 + 0.4 * lim)
    else:
        k_ha = 0.9 + 0.4 * math.sqrt(2.0 * (eps_g - 1.0) / eps_g) * lim
    k_fa = min(max(k_ha, 1.0), eps_g / (0.25 * eps_a + 0.75))
    k_ha = min(max(k_ha, 1.0), eps_g / (eps_a * z_eps ** 2))

    # -- contact stress (ISO 6336-2, eqs. 1-3) -----------------------------------------------
    sigma_h0 = z_h * z_e * z_eps * z_beta * math.sqrt(f_t / (d1 * b) * (u + 1.0) / u)
    load = k_a * k_gamma * k_v * k_hb * k_ha
    pair = {"centre_distance_m": centre_distance, "torque_Nm": torque,
            "speed_rpm": speed_rpm, "F_t_N": f_t, "v_m_s": v, "u": abs(u),
            "alpha_wt_deg": math.degrees(a_wt), "eps_alpha": eps_a, "eps_beta": eps_b,
            "c_prime": c1, "c_gamma_alpha": c_ga, "n_E1_rpm": n_e1, "N_resonance": n_ratio,
            "K_A": k_a, "K_gamma": k_gamma, "K_v": k_v, "K_Hbeta": k_hb, "K_Fbeta": k_fb,
            "K_Halpha": k_ha, "K_Falpha": k_fa, "Z_H": z_h, "Z_E": z_e, "Z_eps": z_eps,
            "Z_beta": z_beta, "f_pb_um": f_pb, "F_betax_um": f_bx}
    rz = 0.5 * (g1.flank_Rz + g2.flank_Rz) * 1e6
    z_l, z_v = _lubrication(min(g1.sigma_Hlim, g2.sigma_Hlim) * 1e-6, lubricant_viscosity_40, v)
    z_r = _roughness(min(g1.sigma_Hlim, g2.sigma_Hlim) * 1e-6, rz, rho_red)
    y_beta = 1.0 - min(eps_b, 1.0) * min(math.degrees(beta), 30.0) / 120.0   # ISO 6336-3 eq. 27
    gears = []
    for g, z_bd, n_l in ((g1, z_b, cycles[0]), (g2, z_d, cycles[1])):
        sigma_h = z_bd * sigma_h0 * math.sqrt(load)
        z_nt = life_factor_pitting(n_l, optimum)
        sigma_hg = g.sigma_Hlim * 1e-6 * z_nt * z_l * z_v * z_r          # Z_W = Z_X = 1
        root = _root_factors(g, eps_an, beta_b)
        sigma_f0 = f_t / (b * m_n) * root["Y_F"] * root["Y_S"] * y_beta   # Y_B = Y_DT = 1
        sigma_f = sigma_f0 * k_a * k_gamma * k_v * k_fb * k_fa
        y_nt = life_factor_bending(n_l, optimum)
        chi = (1.0 + 2.0 * root["q_s"]) / 5.0              # ISO 6336-3 eq. 43: rho' 0.003 mm
        y_drel = (1.0 + math.sqrt(0.003 * chi)) / (1.0 + math.sqrt(0.003 * 1.2))
        rz_root = max(g.root_Rz * 1e6, 1.0)
        y_rrel = 1.674 - 0.529 * (rz_root + 1.0) ** 0.1                   # eq. 49
        y_x = 1.0 if m_n <= 5.0 else (1.05 - 0.01 * m_n if m_n < 25.0 else 0.8)  # Table 7
        y_m = 0.7 if g.reversed_bending else 1.0
        sigma_fg = g.sigma_Flim * 1e-6 * 2.0 * y_nt * y_drel * y_rrel * y_x * y_m  # Y_ST = 2
        gears.append({"teeth": g.teeth, "internal": g.internal, "x": g.profile_shift,
                      "d_mm": abs(g.d), "d_a_mm": abs(g.d_a), "cycles": n_l,
                      "Z_BD": z_bd, "Z_L": z_l, "Z_v": z_v, "Z_R": z_r, "Z_NT": z_nt,
                      "sigma_H_MPa": sigma_h, "sigma_HG_MPa": sigma_hg,
                      "S_H": sigma_hg / sigma_h, "Y_F": root["Y_F"], "Y_S": root["Y_S"],
                      "Y_beta": y_beta, "Y_NT": y_nt, "Y_deltarelT": y_drel,
                      "Y_RrelT": y_rrel, "Y_X": y_x, "Y_M": y_m,
                      "sigma_F_MPa": sigma_f, "sigma_FG_MPa": sigma_fg,
                      "S_F": sigma_fg / sigma_f})
    return PairRating(pair, gears)


def _solve_inv(target: float) -> float:
    """The angle whose involute is ``target`` (Newton from 0.5 rad)."""
    a = 0.5
    for _ in range(60):
        a -= (_inv(a) - target) / (math.tan(a) ** 2)
    return a


def _solid_reduced_mass(g1: GearSpec, g2: GearSpec) -> float:
    """Reduced mass per face width, kg/mm, of two solid steel gears (ISO 6336-1, eq. 30:
    m* = (pi/8) (d_m/d_b)^2 d_m^2 rho); an internal gear as infinitely heavy."""
    def m_star(g):
        dm = abs(g.d_a + g.d_f) / 2.0
        return math.pi / 8.0 * (dm / abs(g.d_b)) ** 2 * dm ** 2 * STEEL_DENSITY
    m1 = m_star(g1)
    if g2.internal:
        return m1
    m2 = m_star(g2)
    return m1 * m2 / (m1 + m2)


def _dynamic_factor(n: float, w: float, eps_g: float, c1: float, f_pb_eff: float,
                    f_f_eff: float, c_a: float) -> float:
    """K_v by method B (ISO 6336-1:2006, 6.3.2, Table 8): resonance ratio ``n``, load per face
    width ``w`` (F_t K_A / b, N/mm), deviations after running-in and tip relief in um."""
    b_p = c1 * max(f_pb_eff, 0.0) / w
    b_f = c1 * max(f_f_eff, 0.0) / w
    b_k = abs(1.0 - c1 * c_a / w)
    if eps_g <= 2.0:
        cv1, cv2, cv3, cv4, cv5, cv6 = 0.32, 0.34, 0.23, 0.90, 0.47, 0.47
    else:
        cv1, cv2 = 0.32, 0.57 / (eps_g - 0.3)
        cv3, cv4 = 0.096 / (eps_g - 1.56), (0.57 - 0.05 * eps_g) / (eps_g - 1.44)
        cv5, cv6 = 0.47, 0.12 / (eps_g - 1.74)
    if eps_g <= 1.5:
        cv7 = 0.75
    elif eps_g <= 2.5:
        cv7 = 0.125 * math.sin(math.pi * (eps_g - 2.0)) + 0.875
    else:
        cv7 = 1.0
    n_s = 0.5 + 0.35 * math.sqrt(w / 100.0) if w < 100.0 else 0.85
    if n <= n_s:                                        # subcritical (eq. 13)
        return n * (cv1 * b_p + cv2 * b_f + cv3 * b_k) + 1.0
    main = cv1 * b_p + cv2 * b_f + cv4 * b_k + 1.0      # main resonance (eq. 14)
    if n <= 1.15:
        return main
    sup = cv5 * b_p + cv6 * b_f + cv7                   # supercritical (eq. 15)
    if n >= 1.5:
        return sup
    return sup + (main - sup) * (1.5 - n) / 0.35        # intermediate (eq. 16)

