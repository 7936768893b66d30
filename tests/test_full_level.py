"""The full DOF level: gyroscopic tilt of a spinning wheel and helical axial mesh forces."""

import math

import numpy as np
import pytest

import gearmodal as gm


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
    p = gm.Gear(20, 0.004, math.radians(20), beta, mass=1.0, inertia=1e-3)
    w = gm.Gear(40, 0.004, math.radians(20), -beta, mass=4.0, inertia=1.6e-2)
    kz = 1e9
    sup = {"stiffness": {"x": 1e9, "y": 1e9, "z": kz, "rx": 1e7, "ry": 1e7}}
    m = gm.gear_pair(p, w, mesh_stiffness=2e8, backlash=1e-4, dofs="full",
                     bearing_stiffness=sup)
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
