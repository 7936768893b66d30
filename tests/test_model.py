"""Model API: names, builders, sign conventions, geometry."""

import math

import numpy as np
import pytest

import gearmodal as gm

DEG20 = math.radians(20)


def pair(dofs="torsional", **kw):
    return gm.examples.gear_pair(dofs, **kw)


def test_gear_base_radius_spur_and_helical():
    g = gm.Gear(21, 0.010, DEG20, mass=10.0, inertia=0.1)
    assert g.base_radius == pytest.approx(21 * 0.010 * math.cos(DEG20) / 2, rel=1e-15)
    h = gm.Gear(21, 0.010, DEG20, math.radians(7.5), mass=10.0, inertia=0.1)
    at = math.atan(math.tan(DEG20) / math.cos(math.radians(7.5)))
    assert h.transverse_pressure_angle == pytest.approx(at, rel=1e-15)
    assert h.base_radius == pytest.approx(21 * 0.010 / math.cos(math.radians(7.5)) / 2
                                          * math.cos(at), rel=1e-15)


def test_gear_pair_names_and_loads():
    m = pair()
    assert m.dof_names == ["pinion.theta", "wheel.theta"]
    assert m.load_names == ["pinion.torque", "wheel.torque", "gravity"]
    mp = pair("planar", bearing_stiffness=1e9)
    assert mp.dof_names == ["pinion.x", "pinion.y", "pinion.theta", "wheel.x", "wheel.y",
                            "wheel.theta"]
    assert "pinion.force_x" in mp.load_names


def test_gear_pair_torsional_matrices():
    """d_f = r_p theta_p + r_w theta_w: K = k [r_p^2, r_p r_w; r_p r_w, r_w^2] (front flank)."""
    m = pair()
    asm = m.assemble()
    rp, rw = m.bodies["pinion"].base_radius, m.bodies["wheel"].base_radius
    K = 2e8 * np.array([[rp * rp, rp * rw], [rp * rw, rw * rw]])
    np.testing.assert_allclose(asm.stiffness(), K, rtol=1e-13)
    np.testing.assert_allclose(asm.M, np.diag([1e-3, 1.6e-2]), rtol=1e-15)
    # back flank: mirrored, offset = backlash
    c = asm.contacts
    assert list(c.contact) == ["front", "back"]
    np.testing.assert_allclose(c.W[1], -c.W[0], rtol=1e-15)
    assert c.offset[1] == 1e-4


@pytest.mark.parametrize("dofs", ["torsional", "planar"])
def test_positive_pinion_torque_closes_front_flank(dofs):
    """Sign convention: q = 0 is front flanks touching; a positive torque on the driving gear
    closes its front flank. The balancing wheel torque is T r_w / r_p (also positive)."""
    m = pair(dofs, bearing_stiffness=1e9) if dofs != "torsional" else pair()
    asm = m.assemble()
    rp, rw = m.bodies["pinion"].base_radius, m.bodies["wheel"].base_radius
    T = 100.0
    f = asm.load_vector({"pinion.torque": T, "wheel.torque": T * rw / rp})
    q = np.linalg.lstsq(asm.stiffness(), f, rcond=None)[0]
    p = asm.penetration(q)
    front = np.array(asm.contacts.contact) == "front"
    assert p[front][0] > 0 and p[~front][0] < 0
    # mesh force = torque / base radius along the line of action
    assert 2e8 * p[front][0] == pytest.approx(T / rp, rel=1e-9)


def test_planetary_stage_positive_carrier_torque_closes_front_flanks():
    sun = gm.Gear(21, 0.010, DEG20, mass=50.0, inertia=0.5)
    planet = gm.Gear(39, 0.010, DEG20, mass=100.0, inertia=2.0)
    ring = gm.Gear(99, 0.010, DEG20, internal=True, mass=300.0, inertia=60.0)
    st = gm.planetary_stage(sun, planet, ring, n_planets=3, carrier_mass=500.0,
                            carrier_inertia=50.0, mesh_stiffness=1e9, backlash=3e-4,
                            planet_bearing=1e9, carrier_bearing=1e9,
                            sun_support={"stiffness": {"x": 1e7, "y": 1e7, "theta": 1e7}},
                            ring_support={"stiffness": {"x": 1e9, "y": 1e9, "theta": 1e10}})
    asm = st.assemble()
    q = np.linalg.solve(asm.stiffness(), asm.load_vector({"carrier.torque": 1e5}))
    p = asm.penetration(q)
    flank = np.array(asm.contacts.contact)
    assert np.all(p[flank == "front"] > 0)
    assert np.all(p[flank == "back"] < 0)
    # torque balance on the carrier: sum of tangential planet forces times radius
    assert st.bodies["sun"].speed_ratio == pytest.approx(1 + 99 / 21)
    assert st.bodies["planet1"].speed_ratio == pytest.approx(1 - 99 / 39)


def test_radial_approach_closes_both_flanks():
    """Double contact: pushing a planet radially into the ring compresses front and back."""
    lp = dict(mass={"carrier": 5.43, "ring": 2.35, "sun": 0.4, "planet": 0.66},
              inertia_over_r2={"carrier": 6.29, "ring": 3.0, "sun": 0.39, "planet": 0.61},
              bearing={"carrier": 1e8, "ring": 1e8, "sun": 1e8, "planet": 1e8},
              torsional={"carrier": 1e8, "ring": 1e9, "sun": 1e8},
              mesh={"sun_planet": 5e8, "ring_planet": 5e8})
    m = gm.lin_parker_stage(3, **lp, pressure_angle=math.radians(24.6), backlash=1e-5)
    asm = m.assemble()
    q = np.zeros(asm.n)
    q[asm.dof_names.index("planet1.zeta")] = 1e-4  # outward, towards the ring
    p = asm.penetration(q) + asm.contacts.offset  # deflections d
    c = asm.contacts
    d_front = p[c.index("ring_planet1", "front")]
    d_back = p[c.index("ring_planet1", "back")]
    assert d_front > 0 and d_back > 0
    assert d_front == pytest.approx(1e-4 * math.sin(math.radians(24.6)), rel=1e-12)
    assert d_back == pytest.approx(d_front, rel=1e-12)


def test_drivetrain_chains_ratios_and_names():
    m = gm.load("studies/models/600kw.toml")
    assert "stage1.planet1.zeta" in m.dof_names
    assert "housing.x" in m.dof_names
    assert m.gear_ratio == pytest.approx((1 + 99 / 21) * 82 / 23 * 88 / 22, rel=1e-12)
    assert m.bodies["generator"].speed_ratio == pytest.approx(m.gear_ratio)
    # every mesh's front flank is closed by positive rotor torque against a held generator
    asm = m.assemble()
    K = asm.stiffness() + 1e-9 * np.eye(asm.n)  # housing/rotor all supported except rotation
    gen = asm.dof_names.index("generator.theta")
    K[gen, gen] += 1e12  # hold the generator
    q = np.linalg.solve(K, asm.load_vector({"rotor.torque": 2e5}))
    p = asm.penetration(q)
    c = asm.contacts
    front, back = c.mask("mesh", "front"), c.mask("mesh", "back")
    assert np.all(p[front] > 0), np.array(c.element)[front][p[front] <= 0]
    assert np.all(p[back] < 0)
