"""Induction generator: slip-torque curve and cut-in (DESIGN 2.5).

Kloss's formula for the steady torque of an induction machine (e.g. A. E. Fitzgerald, C.
Kingsley and S. D. Umans, "Electric Machinery", 6th ed., McGraw-Hill 2003, ch. 6, the torque-slip
curve with the stator resistance neglected)::

    T(s) = 2 T_k / (s / s_k + s_k / s),   s = (omega - omega_sync) / omega_sync

here with generator slip ``s > 0`` above synchronous speed and ``T`` the braking torque on the
generator shaft (N m). ``T_k`` is the pull-out torque; ``s_k`` follows from the rated point
``T(s_rated) = P_rated / omega_rated``. The generator is connected (cut in) the first time its
speed reaches synchronous speed and stays connected; before that it carries no torque, as in
the paper's start-up.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..errors import ModelError


@dataclass
class InductionGenerator:
    """rated_power : W (electrical ~ mechanical here). sync_speed_rpm : generator rpm.
    rated_slip : slip at rated power (0.01-0.03 typical). pullout_ratio : T_k / T_rated."""

    rated_power: float = 600e3
    sync_speed_rpm: float = 1800.0
    rated_slip: float = 0.02
    pullout_ratio: float = 2.5

    def __post_init__(self):
        for label, val, lo, hi in (("rated_power", self.rated_power, 1.0, 1e9),
                                   ("sync_speed_rpm", self.sync_speed_rpm, 1.0, 1e5),
                                   ("rated_slip", self.rated_slip, 1e-4, 0.2),
                                   ("pullout_ratio", self.pullout_ratio, 1.05, 10.0)):
            if not (lo <= val <= hi):
                raise ModelError(f"generator.{label}", f"= {val!r}: must be in [{lo}, {hi}]")
        self.omega_sync = self.sync_speed_rpm * math.pi / 30
        omega_r = self.omega_sync * (1 + self.rated_slip)
        self.rated_torque = self.rated_power / omega_r
        self.pullout_torque = self.pullout_ratio * self.rated_torque
        # T_r = 2 T_k / (s_r/s_k + s_k/s_r) -> s_k^2 - 2 p s_r s_k + s_r^2 = 0, p = T_k/T_r;
        # the root above s_r is the stable branch's pull-out slip
        p, sr = self.pullout_ratio, self.rated_slip
        self.pullout_slip = sr * (p + math.sqrt(p * p - 1))

    def slip(self, omega: float) -> float:
        """Slip at generator speed ``omega`` (rad/s), positive when generating."""
        return (omega - self.omega_sync) / self.omega_sync

    def tangent(self, omega: float) -> tuple[float, float]:
        """``(T, dT/domega)`` at ``omega`` (rad/s): the braking torque (N m) and its slope
        (N m s/rad), from the Kloss curve in the module docstring."""
        s = self.slip(omega)
        sk, tk = self.pullout_slip, self.pullout_torque
        if s == 0.0:
            return 0.0, 2 * tk / (sk * self.omega_sync)
        den = s / sk + sk / s
        return 2 * tk / den, -2 * tk * (1 / sk - sk / s**2) / den**2 / self.omega_sync

    def torque(self, omega: float) -> float:
        """Braking torque (N m) on the generator shaft at ``omega`` (rad/s), connected."""
        s = self.slip(omega)
        if s == 0.0:
            return 0.0
        sk = self.pullout_slip
        return 2 * self.pullout_torque / (s / sk + sk / s)
