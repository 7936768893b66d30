"""One call of an integration method: what every method reads, in one object (:class:`Stretch`).

The driver (:class:`~gearmodal.integrate.driver.Driver`) makes one per call of a method and
the methods (:func:`~gearmodal.integrate.exact.run_exact`,
:func:`~gearmodal.integrate.newmark.run_newmark`,
:func:`~gearmodal.integrate.scipy_ref.run_scipy`) read what they use of it; a method's own
options stay keywords beside it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from .peaks import PeakTracker
    from .system import PiecewiseLinearSystem


@dataclass(frozen=True, eq=False)
class Stretch:
    """``n_steps`` output steps of ``dt`` (s) of ``system`` from the state ``x0`` in the
    contact state ``s0``.

    ``F`` (n_steps + 1 rows) is the generalised force at the output times (linear in between);
    ``azimuth0`` the input azimuth at the start (rad); ``loads``: ``(knot_t, knot_u,
    harmonic_u, harmonic_nu, basis)``, loads on their own time structure added to ``F``
    (:func:`~gearmodal.integrate.loads.force_at`); ``peaks``: a
    :class:`~gearmodal.integrate.peaks.PeakTracker` for the exact peaks (``t0``: the run's
    time at the call's start, s). ``k_org``: the call continues a run at its output step
    ``k_org`` (``azimuth0`` and the loads' times then from the run's start); ``t_span``: the
    call's start and end times when they are not ``k dt`` (a stepper's re-basing grid).
    ``audits``: the run's energy audits (:mod:`~gearmodal.integrate.energy`, a dict a method
    keeps its :class:`~gearmodal.integrate.energy.EnergyAudit` in), so that a run advanced
    call by call is audited as one. :class:`~gearmodal.integrate.driver.Method` says what each
    method makes of them.
    """

    system: PiecewiseLinearSystem
    dt: float
    n_steps: int
    F: np.ndarray
    x0: np.ndarray
    s0: np.ndarray
    azimuth0: float = 0.0
    loads: tuple | None = None
    peaks: PeakTracker | None = None
    t0: float = 0.0
    k_org: int | None = None
    t_span: tuple | None = None
    audits: dict | None = None
