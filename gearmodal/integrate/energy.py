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

    B(t) = |E(x(0))| + int |F . v| dt + |P(t)|,                                    (E4)

the initial state, everything the loads put in or took out and the parametric work. A run with
``M > B`` has made more energy than all of that, whatever its damping took away since
(Newmark's contact switched a step late lets the bodies penetrate as if free, and its switches
feed the stiff contacts energy each time, growing without bound; scipy's contact located late
lets them pass into each other): it stops with a :class:`~gearmodal.SolveError` instead of
returning a wrong answer. ``max |M| / max (B + D)`` is the run's ``energy_error`` (its stats):
0 to rounding for an exact solution, the method's own error otherwise. A run advanced call by
call (a stepper, a turbine) keeps one audit from call to call while its system and state
continue; a new system (a re-basing) starts a new one.

The integrals are taken with the trapezoidal rule on the method's own steps, which Newmark's
average acceleration satisfies exactly between switches on a system that does not turn (its
discrete energy balance), so the audit adds no error of its own there (on a turning system the
step's matrices change with the azimuth, an O(dt) residual). Limits: the energy counts the
contacts at their mean stiffness (an alternating mesh is not audited: Newmark refuses it, and
scipy's run with one is not audited) and leaves the round clearances' springs out (a scipy run
with one is not audited); scipy, audited on its output rows, is audited only where the rows
resolve its loads (at least 8 rows per period of a harmonic load, and knots no closer than the
output step), since it follows them between rows.
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

    @classmethod
    def of(cls, stretch, method: str, hint: str) -> EnergyAudit:
        """The audit a call ``stretch`` continues (its ``audits``: the same system, from the
        state and azimuth the last call ended at), else a new one, kept there for the next."""
        box = stretch.audits
        a = None if box is None else box.get(method)
        if (a is None or a.system is not stretch.system
                or not np.array_equal(a.x, stretch.x0)
                or abs(a.azimuth - stretch.azimuth0) > 1e-9 * max(1.0, abs(a.azimuth))):
            a = cls(stretch.system, stretch.x0, stretch.azimuth0, method, hint)
            if box is not None:
                box[method] = a
        a.hint = hint
        return a

    def __init__(self, system, x0: np.ndarray, azimuth0: float, method: str, hint: str):
        self.system, self.method, self.hint = system, method, hint
        self.n = system.n
        self.M = system.asm.M
        self.K0 = system.at(azimuth0)["K0"] if system.turning else system.K0
        self.x = np.array(x0, dtype=float)
        self.azimuth = float(azimuth0)
        self.E0 = self.energy(self.x, self.azimuth, self.K0)
        self.E_last = self.E0  # E of the state reached
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
             C: np.ndarray, t: float, K1: np.ndarray | None = None) -> None:
        """Account one step to state ``x1`` (see the class docstring); ``K1``: the springs'
        matrix at ``azimuth1`` of a turning system, where the caller has it."""
        n = self.n
        x0 = self.x
        dq = x1[:n] - x0[:n]
        vm = 0.5 * (x0[n:] + x1[n:])
        dw = float(dq @ (0.5 * (F0 + F1)))
        self.work += dw
        self.supply += abs(dw)
        # h vm^T C vm, as dq = h vm (Newmark's average acceleration; the trapezoidal rule)
        self.dissipated += float(dq @ C @ vm)
        if self.system.turning:
            # the turning springs' and contact rows' change over the step, at its start state
            # (E(x0) at the step's start is the last step's E1: E does not depend on the state)
            K1 = self.system.at(azimuth1)["K0"] if K1 is None else K1
            self.parametric += self.energy(x0, azimuth1, K1) - self.E_last
        else:
            K1 = self.K0
        E1 = self.energy(x1, azimuth1, K1)
        made = E1 - self.E0 - self.work + self.dissipated - self.parametric  # (E3)
        budget = self.supply + abs(self.parametric)  # (E4)
        if not np.isfinite(made) or made > MADE * budget:
            raise SolveError(
                "method", f"= {self.method!r}: the solution is wrong (diverging) by t = "
                f"{t:.6g} s: it made {made:.3g} J of energy, more than the {budget:.3g} J its "
                f"initial state and loads supplied; {self.hint}")
        self.worst = max(self.worst, abs(made))
        self.scale = max(self.scale, budget + self.dissipated)
        self.x, self.azimuth, self.K0 = np.array(x1, dtype=float), float(azimuth1), K1
        self.E_last = E1

    @property
    def error(self) -> float:
        """The relative balance error of the run so far (the module docstring)."""
        return self.worst / self.scale if self.scale > 0 else 0.0


def resolved(loads, dt: float) -> bool:
    """Whether output rows ``dt`` apart resolve ``loads`` (:class:`Stretch`'s ``loads``): at
    least 8 rows per period of every harmonic and knots no closer than ``dt``."""
    if loads is None:
        return True
    knot_t, _, _, harmonic_nu = loads[:4]
    nu = np.asarray(harmonic_nu, dtype=float)
    if nu.size and float(np.max(np.abs(nu))) * dt > 2 * np.pi / 8:
        return False
    kt = np.asarray(knot_t, dtype=float)
    return not (kt.size > 1 and float(np.min(np.diff(kt))) < dt * (1 - 1e-9))


def audit_rows(stretch, X: np.ndarray, S: np.ndarray, F: np.ndarray, method: str,
               hint: str) -> EnergyAudit | None:
    """The audit (E3)-(E4) of a call's output rows ``X`` (contact states ``S``, load rows
    ``F``) of ``stretch`` (:class:`~gearmodal.integrate.stretch.Stretch`: its system, ``dt``,
    ``azimuth0``, ``t0``, its run's audits): a method that takes its own steps between output
    times (scipy) is checked on its rows, the work taken with the trapezoidal rule at ``dt``
    (second order in ``dt``: on the double-contact scene's exact solution at 1e-4 s a balance
    error of 5e-4 of the budget, far from ``MADE``). ``None`` where the rows cannot audit the
    run (the module docstring's limits). Raises as :meth:`EnergyAudit.step` does."""
    system, dt = stretch.system, stretch.dt
    if (not resolved(stretch.loads, dt) or system.alternating
            or system.asm.round is not None):
        return None
    audit = EnergyAudit.of(stretch, method, hint)
    om, azimuth0 = system.omega, stretch.azimuth0
    L0 = system.generalized_force(F[0], azimuth0)
    damping: dict = {}
    for k in range(1, len(X)):
        az = azimuth0 + om * k * dt
        L1 = system.generalized_force(F[k], az)
        if system.turning:
            C = system.matrices(S[k - 1], frozen=system.at(az))[1]
        else:  # one damping matrix per contact state
            key = S[k - 1].tobytes()
            if key not in damping:
                damping[key] = system.matrices(S[k - 1])[1]
            C = damping[key]
        audit.step(X[k], az, L0, L1, C, stretch.t0 + k * dt)
        L0 = L1
    return audit
