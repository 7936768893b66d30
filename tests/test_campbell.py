"""Campbell diagrams: MAC tracking through a crossing and a veering, orders, crossings."""

import math

import numpy as np
import pytest

import gearmodal as gm
from gearmodal.campbell import campbell

W_A, W_B = 100.0, 160.0  # rad/s, translational natural frequencies at rest


def two_bodies(coupling=0.0):
    """Two masses on isotropic supports in a frame turning with the input: in the rotating
    frame body A has omega_A +- Omega, body B omega_B +- Omega; A+ meets B- at Omega = 30 rad/s."""
    m = gm.Model("two", input="a")
    m.add(gm.Frame("rot", 1.0))
    for name, w in (("a", W_A), ("b", W_B)):
        m.add(gm.RigidBody(name=name, mass=1.0, inertia=1.0, dofs="planar", frame="rot",
                           speed_ratio=1.0))
        m.add(gm.Bearing(f"{name}_support", name, None,
                         stiffness={"x": w * w, "y": w * w, "theta": 1e8}))
    if coupling:
        # an anisotropic link: an isotropic one conserves the whirl sense and cannot couple
        # forward whirl of A with backward whirl of B
        m.add(gm.Bearing("link", "a", "b", stiffness={"x": coupling}))
    return m


SPEEDS = np.linspace(0.0, 60.0, 121) * 60 / (2 * math.pi)  # Omega 0..60 rad/s in rpm


def test_tracking_follows_modes_through_a_crossing():
    camp = campbell(two_bodies(), SPEEDS, orders={"1P": 1.0})
    om = SPEEDS * 2 * math.pi / 60
    f = camp.frequencies_hz * 2 * math.pi
    # every tracked branch is one of omega_{A,B} +- Omega over the whole sweep: sorting would
    # swap A+ and B- at Omega = 30 rad/s and produce kinks
    expected = [W_A - om, W_A + om, W_B - om, W_B + om]
    matched = 0
    for j in range(camp.n_modes):
        if f[:, j].max() > 1000:
            continue  # torsional modes at 1e4 rad/s
        err = [np.max(np.abs(f[:, j] - e)) for e in expected]
        assert min(err) < 1e-6 * W_B, f"branch {j} is not a straight line"
        matched += 1
    assert matched == 4
    assert camp.veerings().empty


def test_veering_is_flagged_and_branches_do_not_cross():
    camp = campbell(two_bodies(coupling=60.0), SPEEDS, orders={"1P": 1.0})
    v = camp.veerings()
    assert len(v) >= 1
    row = v.iloc[0]
    om_v = row.speed_rpm * 2 * math.pi / 60
    assert om_v == pytest.approx(30.0, abs=2.0)
    a, b = int(row.mode_a), int(row.mode_b)
    gap = camp.frequencies_hz[:, b] - camp.frequencies_hz[:, a]
    assert np.all(gap > 0) or np.all(gap < 0)
    assert camp.veering[:, a].any() and camp.veering[:, b].any()
    assert len(camp.macs) == len(SPEEDS) - 1


def test_order_crossings_and_frame(tmp_path):
    camp = campbell(two_bodies(), SPEEDS, orders={"1P": 1.0, "2P": 2.0})
    df = camp.to_frame()
    assert list(df.columns[:5]) == ["speed_rpm", "mode", "frequency_hz", "damping_ratio",
                                    "mode_type"]
    cr = camp.crossings("2P")
    # the 2P line, 2 Omega (rad/s), meets the backward branches W - Omega at Omega = W / 3;
    # W + Omega only beyond the sweep. Linear interpolation between grid points of straight
    # lines is exact up to rounding.
    om = np.array([W_A, W_B]) / 3
    assert len(cr) == 2
    np.testing.assert_allclose(cr.speed_rpm, om * 60 / (2 * math.pi), rtol=1e-9)
    np.testing.assert_allclose(cr.frequency_hz, 2 * om / (2 * math.pi), rtol=1e-9)
    camp.save(tmp_path)
    assert (tmp_path / "campbell.csv").exists() and (tmp_path / "crossings.csv").exists()
    fig = camp.plot()
    assert fig.axes


def test_loaded_campbell_uses_the_equilibrium_contact_state():
    """Reversed torque loads the back flanks: the loaded sweep follows that state (the mesh
    mode of a pair is the same on either flank, while the open-flank state has none)."""
    pair = gm.examples.gear_pair()
    loads = gm.balance(pair, {"pinion.torque": -50.0}, on="wheel.torque")
    camp = campbell(pair, [0.0, 100.0, 200.0], orders={"1P": 1.0}, loads=loads)
    st = camp.extra["states"]
    assert st.shape == (3, 2) and not st[:, 0].any() and st[:, 1].all()  # back flank closed
    nominal = campbell(pair, [0.0, 100.0, 200.0], orders={"1P": 1.0})
    np.testing.assert_allclose(camp.frequencies_hz[:, 1], nominal.frequencies_hz[:, 1],
                               rtol=1e-12)


@pytest.mark.parametrize("orders, match", [({"x": "a"}, r"orders\.x = 'a': an order"),
                                           ({"x": -1.0}, r"orders\.x = -1\.0: must be"),
                                           ([1, 2], r"orders = \[1, 2\]: a mapping")])
def test_bad_orders_are_named(orders, match):
    m = gm.load("studies/models/gear_pair.toml")
    with pytest.raises(gm.ModelError, match=match):
        gm.campbell(m, [0.0, 100.0], orders=orders)
