"""The energy audit of a reference method's run: how much energy the method made.

The piecewise-linear system's energy balance is known (DESIGN 3.3): with the mechanical energy

    E(x) = 1/2 v^T M v + 1/2 q^T K0(psi) q + sum_e 1/2 k_e max(p_e, 0)^2            (E1)

(kinetic, always-active springs with the centripetal and geometric terms, compressed contacts;
``p = W q - offset`` the penetrations), an exact solution satisfies

    E(x(t)) = E(x(0)) + W(t) - D(t) + P(t),                                       (E2)

``W = int F . v dt`` the work of the loads (the constant centrifugal force among them),
``D = int v^T C v dt >= 0`` the dissipation (gyroscopic terms do no work) and, on a turning
system, ``P = int dE/dpsi Omega dt`` the parametric work of the turning stiffness and contact
rows at fixed state. What a method's run ``x(t)`` makes of energy on its own is

    M(t) = E(x(t)) - E(x(0)) - W(t) + D(t) - P(t),                                 (E3)

0 for an exact solution, and what the run had to work with is

    B(t) = |E(x(0))| + int |F . v| dt + |P(t)| + D(t),                             (E4)

the initial state, everything the loads put in or took out, the parametric work and what the
damping took. A run with ``M > B`` has made more energy than all of that (Newmark's contact
switched a step late lets the bodies penetrate as if free, and its switches feed the stiff
contacts energy each time, growing without bound; scipy's contact located late lets them pass
into each other): it stops with a :class:`~gearmodal.SolveError` instead of returning a wrong
answer. ``max |M| / max B`` is the run's ``energy_error`` (its stats): 0 to rounding for an
exact solution, the method's own error otherwise.

The integrals are taken with the trapezoidal rule on the method's own steps, which Newmark's
average acceleration satisfies exactly between switches (its discrete energy balance), so the
audit adds no error of its own there.
"""

from __future__ import annotations

import numpy as np

from ..errors import SolveError

#: a run whose made energy M (E3) exceeds this multiple of its budget B (E4) has failed
MADE = 1.0


class EnergyAudit:
    """The balance (E2) of one run of ``system``, kept step by step from state ``x0`` at
    input azimuth ``azimuth0`` (rad).

    ``step(x1, azimuth1, F0, F1, C)`` takes one step to state ``x1`` with the generalised loads
    ``F0``, ``F1`` at its ends and the damping matrix ``C`` it was taken with; it raises
    :class:`~gearmodal.SolveError` (``method``, the time ``t`` of the step's end) when the
    energy it made (E3) exceeds ``MADE`` times its budget (E4)."""

    def __init__(self, system, x0: np.ndarray, azimuth0: float, method: str, hint: str):
        self.system, self.method, self.hint = system, method, hint
        self.n = system.n
        self.M = system.asm.M
        self.K0 = system.at(azimuth0)["K0"] if system.turning else system.K0
        self.x = np.array(x0, dtype=float)
        self.azimuth = float(azimuth0)
        self.E0 = self.energy(self.x, self.azimuth, self.K0)
        self.work = 0.0  # W of (E2)
        self.dissipated = 0.0  # D
        self.parametric = 0.0  # P
        self.supply = abs(self.E0)  # |E(0)| + int |F . v| dt
        self.worst = 0.0  # max |M| (E3)
        self.scale = self.supply  # max B (E4)

    def energy(self, x: np.ndarray, azimuth: float, K0: np.ndarray) -> float:
        """``E(x)`` of (E1) at input ``azimuth`` with the springs' matrix ``K0``, J."""
        n = self.n
        q, v = x[:n], x[n:]
        p = np.maximum(self.system.penetration(x, azimuth), 0.0)
        return float(0.5 * v @ self.M @ v + 0.5 * q @ K0 @ q + 0.5 * np.sum(self.system.k * p * p))

    def step(self, x1: np.ndarray, azimuth1: float, F0: np.ndarray, F1: np.ndarray,
             C: np.ndarray, t: float) -> None:
        """Account one step to state ``x1`` (see the class docstring)."""
        n = self.n
        x0 = self.x
        dq = x1[:n] - x0[:n]
        vm = 0.5 * (x0[n:] + x1[n:])
        dw = float(dq @ (0.5 * (F0 + F1)))
        self.work += dw
        self.supply += abs(dw)
        # h vm^T C vm, as dq = h vm (Newmark's average acceleration; the trapezoidal rule)
        self.dissipated += float(dq @ C @ vm)
        K1 = self.K0
        if self.system.turning:
            # the turning springs' and contact rows' change over the step, at its start state
            K1 = self.system.at(azimuth1)["K0"]
            dp = (self.energy(x0, azimuth1, K1)
                  - self.energy(x0, self.azimuth, self.K0))
            self.parametric += dp
        E1 = self.energy(x1, azimuth1, K1)
        made = E1 - self.E0 - self.work + self.dissipated - self.parametric  # (E3)
        budget = self.supply + abs(self.parametric) + self.dissipated  # (E4)
        if not np.isfinite(made) or made > MADE * budget:
            raise SolveError(
                "method", f"= {self.method!r}: the solution is wrong (diverging) by t = "
                f"{t:.6g} s: it made {made:.3g} J of energy, more than the {budget:.3g} J its "
                f"initial state and loads supplied and its damping took; {self.hint}")
        self.worst = max(self.worst, abs(made))
        self.scale = max(self.scale, budget)
        self.x, self.azimuth, self.K0 = np.array(x1, dtype=float), float(azimuth1), K1

    @property
    def error(self) -> float:
        """The relative balance error of the run so far (the module docstring)."""
        return self.worst / self.scale if self.scale > 0 else 0.0


def audit_rows(system, X: np.ndarray, S: np.ndarray, F: np.ndarray, dt: float,
               azimuth0: float, method: str, hint: str) -> EnergyAudit:
    """The audit (E3)-(E4) of a finished run's output rows ``X`` (contact states ``S``, load
    rows ``F`` of the force grid, output step ``dt``, input azimuth ``azimuth0`` at its
    start): a method that takes its own steps between output times (scipy) is checked on its
    rows, the work taken with the trapezoidal rule at ``dt`` (second order in ``dt``: on the
    double-contact scene's exact solution at 1e-4 s a balance error of 5e-4 of the supply,
    far from the factor ``MADE``). Raises as :meth:`EnergyAudit.step` does."""
    audit = EnergyAudit(system, X[0], azimuth0, method, hint)
    om = system.omega
    L0 = system.generalized_force(F[0], azimuth0)
    for k in range(1, len(X)):
        az = azimuth0 + om * k * dt
        L1 = system.generalized_force(F[k], az)
        C = (system.matrices(S[k - 1], frozen=system.at(az) if system.turning else None)[1])
        audit.step(X[k], az, L0, L1, C, k * dt)
        L0 = L1
    return audit
