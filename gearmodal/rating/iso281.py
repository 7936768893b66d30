"""ISO 281:2007 modified rating life of a rolling bearing.

    L10m = a1 a_ISO (C / P)^p  10^6 revolutions                                       (eq. 2)

``p`` = 3 for ball and 10/3 for roller bearings, ``a1`` the reliability factor (Table 12),
``a_ISO`` the life modification factor of Annex A (eqs. A.4-A.9: radial roller bearings,
A.10-A.15: radial ball bearings) from the contamination factor ``e_C`` (Table 13), the fatigue
load limit ``C_u`` and the viscosity ratio ``kappa = nu / nu_1`` of the lubricant's operating
viscosity to the rated viscosity ``nu_1`` (eq. A.3, from the pitch diameter and the speed).
The operating viscosity follows from nu_40 and nu_100 by ASTM D341's Walther line.
"""

from __future__ import annotations

import math

from ..errors import ModelError

#: a1 by reliability in percent (ISO 281:2007, Table 12)
RELIABILITY = {90: 1.0, 95: 0.64, 96: 0.55, 97: 0.47, 98: 0.37, 99: 0.25, 99.2: 0.22,
               99.4: 0.19, 99.6: 0.16, 99.8: 0.12, 99.9: 0.093, 99.92: 0.087, 99.94: 0.080,
               99.95: 0.077}
#: a_ISO's upper limit (ISO 281:2007, A.1)
A_ISO_MAX = 50.0


def rated_viscosity(pitch_diameter: float, speed_rpm: float) -> float:
    """nu_1, mm^2/s, the viscosity needed for adequate lubrication (ISO 281:2007, eq. A.3)
    of a bearing of pitch diameter ``pitch_diameter`` (m) at ``speed_rpm``."""
    dm = pitch_diameter * 1e3
    n = abs(speed_rpm)
    if dm <= 0 or n <= 0:
        raise ModelError("rated_viscosity", f"pitch diameter {pitch_diameter!r} m and speed "
                         f"{speed_rpm!r} rpm must be > 0")
    if n < 1000.0:
        return 45000.0 * n ** -0.83 * dm ** -0.5
    return 4500.0 * n ** -0.5 * dm ** -0.5


def operating_viscosity(nu40: float, nu100: float, temperature_C: float) -> float:
    """Kinematic viscosity, mm^2/s, at ``temperature_C`` of an oil of viscosities ``nu40`` and
    ``nu100`` (mm^2/s at 40 and 100 deg C), on the Walther line (ASTM D341):
    log log (nu + 0.7) = A - B log T."""
    if not nu40 > nu100 > 0:
        raise ModelError("lubricant_viscosity_100", f"= {nu100!r} mm^2/s: must be > 0 and "
                         f"below nu_40 = {nu40!r}")
    t1, t2, t = math.log10(313.15), math.log10(373.15), math.log10(temperature_C + 273.15)
    w1, w2 = (math.log10(math.log10(x + 0.7)) for x in (nu40, nu100))
    b = (w1 - w2) / (t2 - t1)
    w = w1 - b * (t - t1)
    return 10.0 ** (10.0 ** w) - 0.7


def a_iso(kappa: float, ec_cu_over_p: float, kind: str = "roller") -> float:
    """The life modification factor a_ISO (ISO 281:2007, A.5: eqs. A.4-A.15) of a radial
    ``kind`` ("roller" or "ball") bearing at viscosity ratio ``kappa`` and ``e_C C_u / P``;
    kappa is taken in [0.1, 4] (the standard's range) and a_ISO is at most 50."""
    if kind not in ("roller", "ball"):
        raise ModelError("kind", f"= {kind!r}: must be 'roller' or 'ball'")
    k = min(max(float(kappa), 0.1), 4.0)
    x = max(float(ec_cu_over_p), 0.0)
    if kind == "roller":
        c0, c1, expo, power = 1.5859, (1.3993 if k < 0.4 else 1.2348), 0.4, -9.185
    else:
        c0, c1, expo, power = 2.5671, (2.2649 if k < 0.4 else 1.9987), 0.83, -1.0 / 3.0
    e = 0.054381 if k < 0.4 else (0.19087 if k < 1.0 else 0.071739)
    inner = 1.0 - (c0 - c1 / k ** e) * x ** expo
    if inner <= 0.0:
        return A_ISO_MAX
    return min(0.1 * inner ** power, A_ISO_MAX)


def modified_life(C: float, P: float, speed_rpm: float, *, C_u: float, pitch_diameter: float,
                  kind: str = "roller", contamination: float = 0.5, viscosity: float,
                  reliability: float = 90) -> dict:
    """ISO 281 modified rating life (eq. 2) of a bearing of dynamic load rating ``C`` and
    fatigue load limit ``C_u`` (N) under the equivalent dynamic load ``P`` (N) at
    ``speed_rpm`` (the rings' relative speed), lubricated at operating ``viscosity`` (mm^2/s).

    Returns ``L10_Mrev`` (basic), ``L10m_Mrev`` and ``L10m_h`` (modified), ``a_ISO``,
    ``kappa``, ``nu1_mm2_s``, ``a1``.
    """
    for name, x in (("C", C), ("C_u", C_u), ("P", P)):
        if not (math.isfinite(x) and x > 0):
            raise ModelError(name, f"= {x!r} N: must be a number > 0")
    if not 0.0 < contamination <= 1.0:
        raise ModelError("contamination", f"= {contamination!r}: e_C lies in (0, 1] "
                         "(ISO 281, Table 13)")
    if reliability not in RELIABILITY:
        raise ModelError("reliability", f"= {reliability!r}: one of "
                         + ", ".join(map(str, RELIABILITY)) + " percent (ISO 281, Table 12)")
    p = 10.0 / 3.0 if kind == "roller" else 3.0
    nu1 = rated_viscosity(pitch_diameter, speed_rpm)
    kappa = viscosity / nu1
    a = a_iso(kappa, contamination * C_u / P, kind)
    a1 = RELIABILITY[reliability]
    l10 = (C / P) ** p
    l10m = a1 * a * l10
    return {"L10_Mrev": l10, "L10m_Mrev": l10m, "L10m_h": l10m * 1e6 / (60.0 * abs(speed_rpm)),
            "a_ISO": a, "kappa": kappa, "nu1_mm2_s": nu1, "a1": a1, "life_exponent": p}
