"""Static equilibrium with unilateral contacts: closed forms, double contact, bad loads."""

import math

import numpy as np
import pytest

import gearmodal as gm

DEG20 = math.radians(20)


def pair(dofs):
    return gm.examples.gear_pair(dofs)


@pytest.mark.parametrize("dofs", ["torsional", "planar"])
@pytest.mark.parametrize("torque", [100.0, -100.0])
def test_gear_pair_flank_force_is_torque_over_base_radius(dofs, torque):
    m = pair(dofs)
    loads = gm.balance(m, {"pinion.torque": torque}, on="wheel.torque")
    rp, rw = m.bodies["pinion"].base_radius, m.bodies["wheel"].base_radius
    assert loads["wheel.torque"] == pytest.approx(torque * rw / rp, rel=1e-12)
    eq = gm.equilibrium(m, loads)
    c = eq.contacts.set_index("contact")
    loaded, free = ("front", "back") if torque > 0 else ("back", "front")
    assert c.loc[loaded, "active"] and not c.loc[free, "active"]
    assert c.loc[loaded, "force_N"] == pytest.approx(abs(torque) / rp, rel=1e-9)


def test_bearing_clearance_closes_under_load():
    """Dead band c then spring k: x = +-(c + |F|/k) exactly (DESIGN 2.3)."""
    m = gm.Model("block", input="body")
    m.add(gm.RigidBody(name="body", mass=3.0, inertia=1.0, dofs="planar"))
    k, c = 2e7, 5e-5
    m.add(gm.Bearing("b", "body", None, stiffness={"x": k, "y": k, "theta": 1e5},
                     clearance={"x": c}))
    for F in (1e3, -1e3):
        eq = gm.equilibrium(m, {"body.force_x": F})
        assert eq.q["body.x"] == pytest.approx(math.copysign(c + abs(F) / k, F), rel=1e-12)
        act = eq.contacts.set_index("contact")["active"]
        assert act["x+"] == (F > 0) and act["x-"] == (F < 0)


def stage(carrier_clearance):
    sun = gm.Gear(21, 0.010, DEG20, mass=80.0, inertia=0.45)
    planet = gm.Gear(39, 0.010, DEG20, mass=140.0, inertia=3.5)
    ring = gm.Gear(99, 0.010, DEG20, internal=True, mass=620.0, inertia=130.0)
    return gm.planetary_stage(
        sun, planet, ring, n_planets=3, carrier_mass=1000.0, carrier_inertia=110.0,
        mesh_stiffness=5e9, backlash=1e-4, planet_bearing=2e9,
        carrier_bearing={"stiffness": {"x": 1e9, "y": 1e9},
                         "clearance": {"x": carrier_clearance, "y": carrier_clearance}},
        sun_support={"stiffness": {"x": 1e7, "y": 1e7, "theta": 1e8}},
        ring_support={"stiffness": {"x": 1e10, "y": 1e10, "theta": 1e11}})


def test_rotor_weight_on_carrier_with_large_clearance_gives_double_contact():
    """The paper's mechanism: with a carrier-bearing clearance larger than the backlash, a
    radial load on the carrier is carried by planets wedged into the ring (double contact)."""
    loads = {"carrier.torque": 2e5, "carrier.force_y": -5e4}
    small = gm.equilibrium(stage(1e-6), loads)
    large = gm.equilibrium(stage(1e-3), loads)

    def doubles(eq):
        a = eq.contacts[eq.contacts.active & eq.contacts.element.str.contains("planet")]
        both = a.groupby("element").contact.nunique()
        return set(both[both == 2].index)

    assert doubles(small) == set()
    assert doubles(large)  # at least one mesh with both flanks in contact
    # equilibrium of the final contact state: K_s q = f + f_s (to rounding of 1e10 N/m terms)
    asm = stage(1e-3).assemble()
    q = large.q.to_numpy()
    r = asm.stiffness(large.state) @ q - asm.load_vector(loads) - asm.contact_force(large.state)
    assert np.abs(r).max() < 1e-8 * 2e5
    # complementarity: open contacts do not penetrate, closed ones push
    p = asm.penetration(q)
    assert np.all(p[~large.state] <= 1e-12) and np.all(p[large.state] > 0)


def test_unbalanced_loads_name_the_free_mode():
    with pytest.raises(gm.ModelError, match=r"loads: not in equilibrium.*pinion\.theta"):
        gm.equilibrium(pair("torsional"), {"pinion.torque": 100.0})


def test_600kw_loaded_modal_shares_load_equally():
    m = gm.load("studies/models/600kw.toml")
    loads = gm.balance(m, {"rotor.torque": 2.6e5}, on="generator.torque")
    assert loads["generator.torque"] == pytest.approx(-2.6e5 / m.gear_ratio, rel=1e-9)
    res = gm.modal(m, speed_rpm=22.1, loads=loads)
    c = res.equilibrium.contacts
    sp = c[c.element.str.contains("sun_planet") & c.active].force_N.to_numpy()
    assert len(sp) == 3 and np.ptp(sp) < 1e-6 * sp.mean()
    # the loaded state is the nominal one (every front flank engaged): same modes
    nominal = gm.modal(m, speed_rpm=22.1)
    np.testing.assert_allclose(res.frequencies_hz[1:], nominal.frequencies_hz[1:], rtol=1e-9)


def test_planet_free_to_turn_in_an_intermediate_state_still_converges():
    """The 600 kW gearbox with the paper's 'clearance' carrier bearing, accelerating under a
    small torque and a large shaft-end force: on the way to the solution the Newton iterate
    opens both flanks of planet 2, whose rotation nothing then resists while its own
    d'Alembert torque acts on it. The step must still aim at the contacts that have to close
    (this took more than 2000 iterations before; the solution satisfies equilibrium and
    complementarity in its final state)."""
    text = open("studies/models/600kw.toml", encoding="utf-8").read().replace(
        "carrier_bearing = 1.0e9", "carrier_bearing = { stiffness = { x = 1.0e8, y = 1.0e8 }, "
        "clearance = { x = 1.0e-3, y = 1.0e-3 } }")
    asm = gm.loads(text).assemble(math.pi / 2)
    r = gm.static.free_modes(asm)[:, 0]
    loads = {"rotor.torque": 28617.7, "stage1.carrier.force_x": -226.6,
             "stage1.carrier.force_y": 41991.6}
    Mr = asm.M @ r
    alpha = float(r @ asm.load_vector(loads)) / float(r @ Mr)
    asm.B = np.column_stack([asm.B, -Mr])
    asm.load_names = [*asm.load_names, "rigid_acceleration"]
    loads["rigid_acceleration"] = alpha
    eq = gm.equilibrium(asm, loads, 6.0, max_iter=30)
    q = eq.q.to_numpy()
    K = asm.stiffness(eq.state) + (6.0 * math.pi / 30) ** 2 * asm.K_cent
    f = asm.load_vector(loads) + (6.0 * math.pi / 30) ** 2 * asm.f_cent
    res = K @ q - f - asm.contact_force(eq.state)
    assert np.abs(res).max() < 1e-7 * np.abs(f).max()
    p = asm.penetration(q)
    assert np.all(p[~eq.state] <= 1e-12) and np.all(p[eq.state] > 0)
