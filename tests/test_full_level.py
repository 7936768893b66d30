"""The full DOF level: gyroscopic tilt of a spinning wheel, helical axial mesh forces, and the
fidelity ladder's most detailed DOF rung on the 600 kW drivetrain (with the clear error when a
support leaves a tilt free)."""

import math

import numpy as np
import pytest

import gearmodal as gm
from gearmodal.errors import ModelError


def test_spinning_wheel_tilt_whirl_closed_form():
    """A wheel spinning at Omega on isotropic tilt springs k_t: the whirl frequencies solve
    Id w^2 -+ Ip Omega w - k_t = 0 (forward and backward whirl, classical rotor dynamics)."""
    Ip, Id, kt = 2.0, 1.2, 3e5
    m = gm.Model("disk", input="disk")
    m.add(gm.RigidBody(name="disk", mass=50.0, inertia=Ip, inertia_diametral=Id, dofs="full",
                       speed_ratio=1.0))
    m.add(gm.Bearing("support", "disk", None,
                     stiffness={"x": 1e9, "y": 1e9, "z": 1e9, "rx": kt, "ry": kt,
                                "theta": 1e4}))
    rpm = 3000.0
    om = rpm * 2 * math.pi / 60
    res = gm.modal(m, speed_rpm=rpm)
    w = res.frequencies_hz * 2 * math.pi
    disc = math.sqrt((Ip * om) ** 2 + 4 * Id * kt)
    forward = (Ip * om + disc) / (2 * Id)
    backward = (-Ip * om + disc) / (2 * Id)
    for expected in (forward, backward):
        assert np.min(np.abs(w - expected)) < 1e-9 * expected
    # at rest both tilt modes sit at sqrt(kt / Id)
    w0 = gm.modal(m).frequencies_hz * 2 * math.pi
    assert np.sum(np.abs(w0 - math.sqrt(kt / Id)) < 1e-9 * math.sqrt(kt / Id)) == 2


@pytest.mark.parametrize("helix_deg", [0.0, 7.5, 15.0])
def test_helical_mesh_axial_force(helix_deg):
    """The flank normal is cos(beta_b) n_t - s sin(beta_b) z: a torque T on the pinion gives
    the axial force T tan(beta_b) / r_b on its bearing (zero for spur gears)."""
    beta = math.radians(helix_deg)
    kz = 1e9
    sup = {"stiffness": {"x": 1e9, "y": 1e9, "z": kz, "rx": 1e7, "ry": 1e7}}
    m = gm.examples.gear_pair("full", helix_angle=beta, bearing_stiffness=sup)
    p = m.bodies["pinion"]
    T = 100.0
    eq = gm.equilibrium(m, gm.balance(m, {"pinion.torque": T}, on="wheel.torque"))
    axial = abs(kz * eq.q["pinion.z"])
    assert axial == pytest.approx(T * math.tan(p.base_helix_angle) / p.base_radius,
                                  rel=1e-6, abs=1e-9)
    flank = eq.contacts.set_index("contact").loc["front"]
    assert flank.force_N == pytest.approx(T / (p.base_radius * math.cos(p.base_helix_angle)),
                                          rel=1e-6)


def test_levels_mix_and_matrices_stay_symmetric():
    m = gm.load("studies/models/600kw.toml")
    m.set_dofs("full", [b for b in m.bodies if b.startswith("stage1.")])
    asm = m.assemble()
    assert "stage1.planet1.rx" in asm.dof_names
    for mat in (asm.M, asm.K, asm.stiffness(), asm.K_cent):
        np.testing.assert_allclose(mat, mat.T, atol=1e-9 * np.abs(mat).max())
    np.testing.assert_allclose(asm.G, -asm.G.T, atol=1e-12 * np.abs(asm.G).max())
    assert np.all(np.linalg.eigvalsh(asm.M) > 0)


SCENE = "studies/scenes/600kw_turbine_10ms.toml"
FULL = {f"model.stages.{i}.dofs": "full" for i in range(3)}


def _frequencies(asm):
    lam = np.linalg.eigvals(np.linalg.solve(asm.M, asm.stiffness())).real
    return np.sort(np.sqrt(np.abs(lam))) / (2 * math.pi)


def test_spur_stage_full_contains_the_planar_modes():
    """With spur gears (no helix) the flank normals lie in the plane and the contact points at
    mid face width, so the out-of-plane motions (z, rx, ry) decouple: every planar frequency
    is also a frequency of the full stage, and the full stage adds one per new DOF."""
    gears = gm.examples.planetary_gears(face_width=0.2)
    support = {"stiffness": {"x": 1e9, "y": 1e9, "z": 5e8, "rx": 2e7, "ry": 2e7,
                             "theta": 1e9}}
    f = {}
    for level in ("planar", "full"):
        stage = gm.examples.planetary_stage(level, support, gears=gears,
                                            angles=(0.0, 2 * math.pi / 3, 4 * math.pi / 3))
        f[level] = _frequencies(stage.assemble())
    assert len(f["full"]) == 2 * len(f["planar"])
    # each planar frequency has a full one within rounding of the eigen solver (the
    # frequencies span 10 Hz - 5 kHz; 1e-8 relative is well above eigvals' ~1e-12)
    near = np.abs(f["full"][None, :] / f["planar"][:, None] - 1).min(axis=1)
    assert near.max() < 1e-8


def test_600kw_full_has_one_free_motion_and_runs():
    """The 600 kW model file gives every support an axial and a tilt stiffness, so at the full
    level only the drivetrain rotation is free; a short turbine run applies the shaft-end
    force on the carrier and stays finite."""
    from gearmodal.scene import load_scene
    from gearmodal.static import free_modes

    sc = load_scene(SCENE, {"scene.t_end": 0.2, **FULL})
    asm = sc.model.assemble()
    assert asm.n == 65
    assert free_modes(asm).shape[1] == 1
    res = sc.simulate()
    assert "not modelled" not in res.gearbox.settings.get("shaft_end_force", "")
    assert np.all(np.isfinite(res.gearbox.forces.to_numpy()))


def test_free_tilt_at_full_is_named():
    """A planet bearing given as a number has no tilt stiffness: at the full level the planets'
    tilts are free and the turbine run refuses with the DOFs named."""
    from gearmodal.scene import load_scene

    sc = load_scene(SCENE, {"scene.t_end": 0.01, **FULL,
                            "model.stages.0.planet_bearing": 2.0e9})
    with pytest.raises(ModelError, match=r"nothing resists .*stage1\.planet1\.r[xy].*"
                                         r"tilts rx/ry need a stiffness table"):
        sc.simulate()
