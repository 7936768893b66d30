"""Stall-capable airfoil polars (DESIGN 2.5).

Pre-stall: the linear lift of thin-airfoil theory with the section's measured slope and zero-lift
angle, drag ``cd0 + k (alpha - alpha0)^2``. Post-stall, up to 90 degrees: Viterna and Corrigan's
flat-plate extrapolation,

    CD = B1 sin^2(a) + B2 cos(a),        CL = A1 sin(2a) + A2 cos^2(a) / sin(a),
    B1 = CDmax = 1.11 + 0.018 AR,  A1 = B1 / 2,
    B2 = (CDs - CDmax sin^2(as)) / cos(as),  A2 = (CLs - CDmax sin(as) cos(as)) sin(as) / cos^2(as),

continuous with the pre-stall polar at the stall angle ``as`` (L. A. Viterna and R. D. Corrigan,
"Fixed pitch rotor performance of large horizontal axis wind turbines", DOE/NASA Workshop on
Large Horizontal Axis Wind Turbines, NASA CP-2230, 1982, pp. 69-85; the method of NREL's
AirfoilPrep). Beyond 90 degrees and for negative angles the flat plate ``CL = CDmax sin(2a)/2``,
``CD = CDmax sin^2(a)`` is used, blended from the negative stall angle.

The default section is the NACA 63-415 of the Danish 600 kW blades (LM 19 family): lift slope
6.2 /rad, zero-lift angle -2.6 deg, CLmax 1.25 at 12 deg with a rough leading edge, cd0 0.008
(I. H. Abbott and A. E. von Doenhoff, "Theory of Wing Sections", Dover 1959, appendix IV, read
off the plots at Re = 3e6 with standard roughness: an estimate).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import ModelError


@dataclass
class Airfoil:
    """A polar ``(alpha [rad], cl, cd)`` on a grid over [-pi, pi]; :meth:`coefficients`
    interpolates it."""

    alpha: np.ndarray
    cl: np.ndarray
    cd: np.ndarray
    name: str = "airfoil"

    def coefficients(self, alpha: np.ndarray):
        """``(cl, cd)`` at angles of attack ``alpha`` (rad, any range: wrapped to [-pi, pi))."""
        a = np.mod(np.asarray(alpha) + math.pi, 2 * math.pi) - math.pi
        return np.interp(a, self.alpha, self.cl), np.interp(a, self.alpha, self.cd)

    @classmethod
    def viterna(cls, lift_slope: float = 6.2, alpha0_deg: float = -2.6,
                stall_deg: float = 12.0, cd0: float = 0.008, k_drag: float = 0.6,
                aspect_ratio: float = 12.0, name: str = "NACA 63-415 (Viterna)",
                n: int = 721) -> Airfoil:
        """Polar from pre-stall data and Viterna-Corrigan post-stall (module docstring).

        lift_slope : 1/rad. alpha0_deg, stall_deg : zero-lift and stall angles, deg.
        cd0, k_drag : pre-stall drag ``cd0 + k_drag (alpha - alpha0)^2`` (alpha in rad).
        aspect_ratio : blade length / mean chord (sets CDmax = 1.11 + 0.018 AR, capped at
        AR = 50 as in the source).
        """
        for label, val, lo, hi in (("lift_slope", lift_slope, 1.0, 8.0),
                                   ("stall_deg", stall_deg, 4.0, 30.0),
                                   ("aspect_ratio", aspect_ratio, 1.0, 1e3),
                                   ("cd0", cd0, 0.0, 0.1)):
            if not (lo <= val <= hi):
                raise ModelError(f"airfoil.{label}", f"= {val!r}: must be in [{lo}, {hi}]")
        a0, as_ = math.radians(alpha0_deg), math.radians(stall_deg)
        cdmax = 1.11 + 0.018 * min(aspect_ratio, 50.0)
        cls_ = lift_slope * (as_ - a0)
        cds = cd0 + k_drag * (as_ - a0) ** 2
        B1, A1 = cdmax, cdmax / 2
        B2 = (cds - cdmax * math.sin(as_) ** 2) / math.cos(as_)
        A2 = (cls_ - cdmax * math.sin(as_) * math.cos(as_)) * math.sin(as_) / math.cos(as_) ** 2
        alpha = np.linspace(-math.pi, math.pi, n)
        cl = np.empty(n)
        cd = np.empty(n)
        neg_stall = a0 - (as_ - a0)  # symmetric about the zero-lift angle
        for i, a in enumerate(alpha):
            if neg_stall <= a <= as_:
                cl[i] = lift_slope * (a - a0)
                cd[i] = cd0 + k_drag * (a - a0) ** 2
            elif as_ < a <= math.pi / 2:
                cd[i] = B1 * math.sin(a) ** 2 + B2 * math.cos(a)
                cl[i] = A1 * math.sin(2 * a) + A2 * math.cos(a) ** 2 / math.sin(a)
            else:  # flat plate, blended in over 10 degrees after the negative stall
                plate_cl = 0.5 * cdmax * math.sin(2 * a)
                plate_cd = cdmax * math.sin(a) ** 2
                if neg_stall - math.radians(10) < a < neg_stall:
                    w = (neg_stall - a) / math.radians(10)
                    cl[i] = (1 - w) * lift_slope * (neg_stall - a0) + w * plate_cl
                    cd[i] = ((1 - w) * (cd0 + k_drag * (neg_stall - a0) ** 2)
                             + w * max(plate_cd, cd0))
                else:
                    cl[i] = plate_cl
                    cd[i] = max(plate_cd, cd0)
        return cls(alpha=alpha, cl=cl, cd=cd, name=name)
