"""Whirl direction and logarithmic decrement (issue 23), against closed forms.

- A rigid body on an isotropic support, described in a frame turning at ``Omega``: in the
  ground its modes are circles at ``w_n`` in either sense; in the turning frame the one turning
  with the frame appears at ``w_n - Omega`` (forward), the other at ``w_n + Omega`` (backward),
  both exactly circular (roundness +-1).
- The logarithmic decrement of a damped mode is the log of the ratio of successive peaks of its
  free vibration, measured here on the exact method's trajectory.
"""

import math

import numpy as np
import pytest

import gearmodal as gm
from gearmodal.whirl import log_decrement, roundness, translation_pairs

MASS, K = 2.0, 2e5


def _body(c: float = 0.0, frame_ratio: float = 1.0) -> gm.Model:
    m = gm.Model("body", input="body")
    m.add(gm.Frame("rot", frame_ratio))
    m.add(gm.RigidBody(name="body", mass=MASS, inertia=1.0, dofs="planar", frame="rot",
                       speed_ratio=frame_ratio))
    m.add(gm.Bearing("support", "body", None, stiffness={"x": K, "y": K, "theta": 1e4},
                     damping={"x": c, "y": c} if c else {}))
    return m


@pytest.mark.parametrize("rpm", [300.0, 900.0])
def test_isotropic_support_seen_from_a_turning_frame_splits_forward_and_backward(rpm):
    res = gm.modal(_body(), rpm)
    wn, om = math.sqrt(K / MASS), rpm * math.pi / 30
    df = res.to_frame()
    trans = df[df.whirl != ""].sort_values("frequency_hz")
    np.testing.assert_allclose(trans.frequency_hz, [(wn - om) / (2 * math.pi),
                                                    (wn + om) / (2 * math.pi)], rtol=1e-9)
    assert list(trans.whirl) == ["forward", "backward"]
    r, _ = roundness(res.shapes, translation_pairs(res.geometry, res.dof_names))
    np.testing.assert_allclose(np.sort(r[trans.index]), [-1.0, 1.0], atol=1e-9)
    camp = gm.campbell(_body(), [0.0, rpm])
    last = camp.to_frame().query(f"speed_rpm == {rpm}")
    assert sorted(last.whirl[last.whirl != ""]) == ["backward", "forward"]
    still = gm.modal(_body(), 0.0).to_frame()  # at rest: standing (straight-line) orbits
    assert set(still.whirl) <= {"linear", ""}


def test_log_decrement_is_the_decay_of_successive_peaks():
    c = 40.0
    m = _body(c, frame_ratio=0.0)
    res = gm.modal(m, 0.0)
    df = res.to_frame()
    mode = df[df.whirl != ""].iloc[0]
    zeta = c / (2 * math.sqrt(K * MASS))
    assert mode.damping_ratio == pytest.approx(zeta, rel=1e-9)
    assert mode.log_dec == pytest.approx(2 * math.pi * zeta / math.sqrt(1 - zeta**2), rel=1e-9)
    sim = gm.simulate(m, 0.2, dt=2e-6, q0={"body.x": 1e-3})
    x = sim.q["body.x"].to_numpy()
    peaks = np.flatnonzero((x[1:-1] > x[:-2]) & (x[1:-1] >= x[2:])) + 1
    # the peaks on the 2 us grid, each refined by the parabola through its neighbours
    a, b, cc = x[peaks - 1], x[peaks], x[peaks + 1]
    top = b + (a - cc) ** 2 / (8 * (2 * b - a - cc))
    measured = np.log(top[:-1] / top[1:])
    np.testing.assert_allclose(measured, mode.log_dec, rtol=1e-4)
    assert math.isnan(log_decrement(1.0)) and log_decrement(-0.1) < 0
