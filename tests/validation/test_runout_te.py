"""Run-out and transmission error: offsets of the gap functions that turn at orders that are
not whole numbers of the input azimuth, integrated exactly (issue 21).

- **Transmission error on a gear pair**: the relative coordinate on the line of action is an
  undamped oscillator ``m_e x'' + k (x + delta(t)) = F`` (``1/m_e = r_p^2/J_p + r_w^2/J_w``) driven
  by ``delta = A cos(M Omega t)`` at the mesh order ``M`` (the pinion's teeth). From rest:
  ``x = F/k (1 - cos w_n t) - w_n^2 A / (w_n^2 - w^2) (cos w t - cos w_n t)``, the flank force
  ``k (x + delta)``; the exact method matches it in either sense of rotation.
- **Run-out of a wheel**: its mesh gap moves by the eccentricity projected on the line of
  action, a pure harmonic of the wheel's rotation order against the mesh, of amplitude ``e``.
- **Sun run-out in a planetary stage**: with a floating sun (three planets) statics leaves the
  mesh loads unchanged; with a supported sun they modulate at the sun's order against the
  carrier, ``z_ring / z_sun`` (4.714 for 21/99 teeth).
- **Against the time-varying reference**: the clearance stage with sun and ring run-out and a
  two-harmonic transmission error at +-600 rpm, exact against solve_ivp (DOP853).
"""

import math

import numpy as np
import pytest

import gearmodal as gm
from gearmodal.examples import planetary_stage


@pytest.mark.parametrize("sense", [1.0, -1.0])
def test_transmission_error_drives_the_mesh_oscillator_in_closed_form(sense):
    m = gm.examples.gear_pair()
    A = 2e-6
    m.meshes["mesh"].transmission_error = ((A, 0.0),)
    p, w = m.bodies["pinion"], m.bodies["wheel"]
    k = m.meshes["mesh"].stiffness
    me = 1.0 / (p.base_radius**2 / p.inertia + w.base_radius**2 / w.inertia)
    wn = math.sqrt(k / me)
    M = float(p.teeth)  # the pinion is the input (speed ratio 1)
    om = 0.5 * wn / M
    T = 200.0
    loads = gm.balance(m, {"pinion.torque": T}, on="wheel.torque")
    sim = gm.simulate(m, 0.003, dt=1e-5, speed_rpm=sense * om * 30 / math.pi, loads=loads)
    t = sim.forces.index.to_numpy()
    F, w_ = T / p.base_radius, M * om
    x = F / k * (1 - np.cos(wn * t)) - wn**2 * A / (wn**2 - w_**2) * (np.cos(w_ * t)
                                                                        - np.cos(wn * t))
    expected = k * (x + A * np.cos(w_ * t))
    assert np.abs(sim.forces["mesh.front"].to_numpy() - expected).max() < 1e-9 * F


def _fit(psi, y, order):
    """Least squares of ``y`` on (1, cos, sin) of ``order psi``: (amplitude, residual)."""
    X = np.column_stack([np.ones_like(psi), np.cos(order * psi), np.sin(order * psi)])
    c, *_ = np.linalg.lstsq(X, y, rcond=None)
    return math.hypot(c[1], c[2]), np.abs(X @ c - y).max()


def test_runout_moves_the_gap_at_the_wheels_rotation_order():
    m = gm.examples.gear_pair()
    e = 15e-6
    m.bodies["wheel"].runout = (e, 0.4)
    psi = np.linspace(0.0, 7.0, 23)
    front = m.assemble().contacts.index("mesh", "front")
    off = np.array([m.assemble(a).contacts.offset[front] for a in psi])
    amp, res = _fit(psi, off, m.bodies["wheel"].speed_ratio)  # -0.5: the wheel's order
    assert amp == pytest.approx(e, rel=1e-12)  # a spur pair's line of action: in the plane
    assert res < 1e-12 * e


def _sun_forces(m, psi_deg):
    loads = gm.balance(m, {"carrier.torque": 2e5}, on="sun.torque")
    out = []
    for a in psi_deg:
        c = gm.equilibrium(m.assemble(math.radians(a)), loads).contacts.set_index(
            ["element", "contact"]).force_N
        out.append([c[(f"sun_planet{i}", "front")] for i in (1, 2, 3)])
    return np.array(out)


def test_sun_runout_in_a_planetary_stage():
    angles = [0.0, 2 * math.pi / 3, 4 * math.pi / 3]
    ro = {"sun": (20e-6, 0.3)}
    psi = np.linspace(0.0, 100.0, 17)
    floating = dict(sun_support={"stiffness": {"x": 0.0, "y": 0.0}}, mesh_stiffness=1e8,
                    support=1e12,
                    ring_support={"stiffness": {"x": 1e12, "y": 1e12, "theta": 1e12}})
    ideal = _sun_forces(planetary_stage(angles=angles, **floating), psi)
    got = _sun_forces(planetary_stage(angles=angles, runout=ro, **floating), psi)
    np.testing.assert_allclose(got, ideal, rtol=1e-8)  # statics of the floating sun
    held = dict(floating, sun_support=1e12)
    m = planetary_stage(angles=angles, runout=ro, **held)
    f = _sun_forces(m, psi)
    order = m.bodies["ring"].teeth / m.bodies["sun"].teeth  # the sun against the carrier
    amp, res = _fit(np.radians(psi), f[:, 0], order)
    assert amp > 0.1 * 1e8 * 20e-6 and res < 1e-6 * amp


@pytest.mark.parametrize("rpm", [600.0, -600.0])
def test_runout_and_transmission_error_match_the_time_varying_reference(rpm):
    over = {"planetary_stage.carrier_bearing": 1e9,
            "planetary_stage.runout": {"sun": [5e-6, 30.0], "ring": [4e-6, 100.0]},
            "planetary_stage.transmission_error": [[1e-6, 0.0], [0.5e-6, 90.0]]}
    m = gm.load("studies/models/planetary_clearance.toml", overrides=over)
    assert sorted({round(h, 6) for h in m.assemble().contacts.waves.h}) == [
        1.0, round(99 / 21, 6), 99.0, 198.0]
    loads = {"carrier.torque": 2.6e5, "sun.torque": -2.6e5 / 5.714285714285714}
    kw = dict(dt=1e-4, speed_rpm=rpm, loads=loads)
    ex = gm.simulate(m, 0.01, **kw)
    sp = gm.simulate(m, 0.01, method="scipy", scipy_method="DOP853", rtol=1e-10, atol=1e-15,
                     **kw)
    assert len(ex.events) == len(sp.events)
    fa, fb = ex.forces.to_numpy(), sp.forces.to_numpy()
    assert np.abs(fa - fb).max() < 1e-6 * np.abs(fb).max()


def test_runout_and_transmission_error_are_validated_and_round_trip():
    with pytest.raises(gm.ModelError, match=r"runout\.planet"):
        planetary_stage(runout={"planet": (1e-6, 0.0)})
    with pytest.raises(gm.ModelError, match="transmission_error"):
        planetary_stage(transmission_error=[[1e-6]])
    with pytest.raises(gm.ModelError, match="runout"):
        gm.RigidBody(name="b", mass=1.0, inertia=1.0, runout=(-1e-6, 0.0))
    m = planetary_stage(runout={"sun": (1e-5, 0.2), "carrier": (2e-6, 1.0)},
                        transmission_error={"sun_planet": [(1e-6, 0.5)]})
    again = gm.loads(gm.dumps(m))
    for az in (0.0, 0.9):
        np.testing.assert_array_equal(again.assemble(az).contacts.offset,
                                      m.assemble(az).contacts.offset)
