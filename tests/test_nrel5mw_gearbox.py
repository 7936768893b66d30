"""The 5 MW reference gearbox (studies/models/nrel5mw.toml) and the profile-shifted stages it
needs: operating pressure angles against the involute meshing equation of Nejad et al.'s
profile shifts, torque balance through stages whose ring is not sun + 2 planet, the drivetrain
torsion against ElastoDyn's two-mass drivetrain, and clear errors for a bad centre distance."""

import math

import numpy as np
import pytest
from scipy.optimize import brentq

import gearmodal as gm
from gearmodal.shipped import find

DEG20 = math.radians(20.0)


@pytest.fixture(scope="module")
def model():
    return gm.load(find("nrel5mw", "models"))


def inv(a: float) -> float:
    """The involute function, tan(a) - a."""
    return math.tan(a) - a


def meshing_angle(alpha_t: float, x_sum: float, z_sum: int) -> float:
    """The operating transverse pressure angle of an external pair with profile shifts x1 + x2
    meshing without backlash (ISO 21771): inv(a_w) = inv(a_t) + 2 tan(a_n) (x1 + x2) / (z1 + z2)."""
    target = inv(alpha_t) + 2.0 * math.tan(DEG20) * x_sum / z_sum
    return brentq(lambda a: inv(a) - target, 1e-3, 1.2)


@pytest.mark.parametrize("stage, mesh, alpha_t, x_sum, z_sum, a", [
    # Nejad et al. 2016, Table V: profile shifts sun + planet and the centre distances
    ("stage1", "sun_planet1", DEG20, 0.617 + 0.802, 19 + 17, 0.863),
    ("stage2", "sun_planet1", DEG20, 0.389 + 0.504, 18 + 36, 0.584),
    ("stage3", "mesh", math.atan(math.tan(DEG20) / math.cos(math.radians(10.0))),
     0.480 + 0.669, 24 + 95, 0.861),
])
def test_the_operating_pressure_angle_is_the_profile_shifts(model, stage, mesh, alpha_t, x_sum,
                                                            z_sum, a):
    """The angle gearmodal takes from the centre distance (cos a_w = (r_b1 + r_b2) / a) is the
    one the table's profile shifts give, to what the centre distance's rounding to whole
    millimetres allows: d(a_w) = cot(a_w) da / a with da = 0.5 mm."""
    got = model.meshes[f"{stage}.{mesh}"].pressure_angle
    want = meshing_angle(alpha_t, x_sum, z_sum)
    assert got == pytest.approx(want, abs=0.5e-3 / (a * math.tan(want)))


def test_ratio_and_planet_positions_follow_the_table(model):
    """Ratio (1 + 56/19)(1 + 93/18)(95/24) = 96.35 (Nejad et al.: 1:3.947, 1:6.167, 1:3.958);
    the planets sit on the table's centre distances, the pinion at 0.861 m from its wheel."""
    assert abs(model.gear_ratio) == pytest.approx((1 + 56 / 19) * (1 + 93 / 18) * 95 / 24,
                                                  rel=1e-14)
    for stage, a in (("stage1", 0.863), ("stage2", 0.584)):
        for n in (1, 2, 3):
            assert np.hypot(*model.bodies[f"{stage}.planet{n}"].position[:2]) == \
                pytest.approx(a, rel=1e-14)
    g, p = (np.array(model.bodies[f"stage3.{b}"].position[:2]) for b in ("gear", "pinion"))
    assert np.hypot(*(p - g)) == pytest.approx(0.861, rel=1e-14)


def test_rated_torque_passes_the_stages_in_equal_shares(model):
    """At the rated rotor torque every planet carries a third, and each mesh force is its
    torque over its base radius, whatever the operating angle: stage 1's sun takes
    T / (1 + z_r/z_s) and each sun-planet flank T_sun / (3 r_b,sun); a planet's two flanks
    balance (r_b,planet F_sp = r_b,planet F_rp); the helical parallel stage's flank force, in
    the normal plane, T_gear / (r_b,gear cos(beta_b))."""
    T = 4.18e6  # N m: 5 MW / (12.1 rpm) / 0.944 efficiency, the rated rotor torque
    loads = gm.balance(model, {"rotor.torque": T}, on="generator.torque")
    eq = gm.equilibrium(model, loads)
    f = eq.contacts.set_index(["element", "contact"])["force_N"]
    rb = {k: model.bodies[k].base_radius for k in ("stage1.sun", "stage2.sun", "stage3.gear")}
    t_sun1 = T / (1 + 56 / 19)
    t_sun2 = t_sun1 / (1 + 93 / 18)
    for n in (1, 2, 3):
        assert f[(f"stage1.sun_planet{n}", "front")] == pytest.approx(
            t_sun1 / (3 * rb["stage1.sun"]), rel=1e-6)
        assert f[(f"stage1.ring_planet{n}", "front")] == pytest.approx(
            f[(f"stage1.sun_planet{n}", "front")], rel=1e-6)
        assert f[(f"stage2.sun_planet{n}", "front")] == pytest.approx(
            t_sun2 / (3 * rb["stage2.sun"]), rel=1e-6)
    beta_b = model.bodies["stage3.gear"].base_helix_angle
    assert f[("stage3.mesh", "front")] == pytest.approx(
        t_sun2 / (rb["stage3.gear"] * math.cos(beta_b)), rel=1e-6)
    assert not any(f[(e, "back")] for e in model.meshes)


def test_the_drivetrain_is_as_stiff_as_elastodyns(model):
    """The main shaft is set so that the rotor, the generator held, turns against ElastoDyn's
    DTTorSpr (8.67637e8 N m/rad) through shaft, stages and torque arms: the static stiffness
    of that whole path, to 0.1 % (the shaft's stiffness is given to four digits)."""
    asm = model.assemble()
    K, names = asm.stiffness(), asm.dof_names
    keep = [i for i, n in enumerate(names) if n != "generator.theta"]
    f = np.zeros(len(keep))
    r = keep.index(names.index("rotor.theta"))
    f[r] = 1.0
    assert 1.0 / np.linalg.solve(K[np.ix_(keep, keep)], f)[r] == pytest.approx(8.67637e8,
                                                                              rel=1e-3)


def test_drivetrain_torsion_is_the_two_mass_one(model):
    """The first drivetrain torsion at 0 rpm is the two-mass drivetrain
    sqrt(K (1/J_rotor + 1/J_gen)) / 2 pi with DTTorSpr and, on the generator side, the
    generator and every wheel at its speed ratio (the rigid rotation's kinetic energy less the
    rotor's: 5.48e6 kg m^2, against GenIner x 97^2 = 5.03e6): 2.14 Hz, to 1 % (the wheels sit
    along the shaft line, not all at its end); it stays there to 13 rpm."""
    from gearmodal.turbine.drivetrain import rigid_rotation

    asm = model.assemble()
    v = rigid_rotation(asm)
    J = model.bodies["rotor"].inertia
    j_gen = float(v @ asm.M @ v) - J
    want = math.sqrt(8.67637e8 * (1 / J + 1 / j_gen)) / (2 * math.pi)
    c = gm.campbell(model, np.linspace(0.0, 13.0, 3), n_modes=6)
    df = c.to_frame()
    elastic = df[(df.mode_type == "torsional") & (df.frequency_hz > 0.5)]
    tors = elastic.groupby("speed_rpm").frequency_hz.min()
    assert tors.iloc[0] == pytest.approx(want, rel=1e-2)
    assert np.ptp(tors.to_numpy()) < 1e-3 * want


def stage(**kw):
    def g(z, internal=False):
        return gm.Gear(teeth=z, module=0.045, pressure_angle=DEG20, face_width=0.491,
                       internal=internal, mass=500.0, inertia=50.0)
    return gm.planetary_stage(g(19), g(17), g(56, True), carrier_mass=7900.0,
                              carrier_inertia=4800.0, mesh_stiffness=1e10, **kw)


def test_a_ring_that_is_not_sun_plus_two_planets_asks_for_the_centre_distance():
    with pytest.raises(gm.ModelError, match=r"ring\.teeth.*19 \+ 2 \* 17 = 53.*centre_dist"):
        stage()


@pytest.mark.parametrize("a", [863.0, 0.80, 0.0])
def test_a_centre_distance_outside_the_gears_range_names_its_range(a):
    """In millimetres by mistake, below the ring-planet base circles (0.8246 m), or zero."""
    with pytest.raises(gm.ModelError, match=r"centre_distance"):
        stage(centre_distance=a)


def test_an_alternating_mesh_on_shifted_gears_needs_its_contact_ratio():
    with pytest.raises(gm.ModelError, match=r"mesh_alternation\.contact_ratio.*profile shift"):
        stage(centre_distance=0.863, mesh_alternation=True)
    m = stage(centre_distance=0.863, mesh_alternation={"contact_ratio": 1.4})
    assert m.meshes["sun_planet1"].contact_ratio == 1.4


def test_the_file_names_a_bad_centre_distance_by_its_path():
    text = find("nrel5mw", "models").read_text().replace("centre_distance = 0.863",
                                                          "centre_distance = 863.0")
    with pytest.raises(gm.ModelError, match=r"stages\[0\]\.centre_distance = 863"):
        gm.loads(text)
