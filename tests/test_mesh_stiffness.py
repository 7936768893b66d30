"""Alternating mesh stiffness (single/double tooth-pair contact,
:mod:`gearmodal.model.mesh_stiffness`): the wave, its schedule, and the exact method's time
events against independent solutions."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.linalg as sla

import gearmodal as gm
from gearmodal.errors import ModelError
from gearmodal.model.mesh_stiffness import contact_ratio

RPM = 2 * math.pi / 60


def _pair(alternation=True, backlash=1e-4, damping=50.0, teeth=(20, 40)):
    p = gm.Gear(teeth[0], 0.004, math.radians(20), mass=1.0, inertia=1e-3)
    w = gm.Gear(teeth[1], 0.004, math.radians(20), mass=4.0, inertia=1.6e-2)
    return gm.gear_pair(p, w, mesh_stiffness=2e8, backlash=backlash, mesh_damping=damping,
                        mesh_alternation=alternation)


def test_contact_ratio_of_standard_spur_gears():
    """Textbook value for two standard 20-tooth spur gears at 20 deg: eps = 1.557; and the
    same from the path of contact measured on the line of action numerically."""
    g = gm.Gear(20, 0.01, math.radians(20), mass=1.0, inertia=1.0)
    assert contact_ratio(g, g, False) == pytest.approx(1.557, abs=2e-3)
    # independent: sample the line of action between the base tangent points; contact is where
    # the point lies inside both tip circles (pitch radii 0.1 m, tip 0.11 m)
    a = gm.Gear(17, 0.01, math.radians(20), mass=1.0, inertia=1.0)
    b = gm.Gear(53, 0.01, math.radians(20), mass=1.0, inertia=1.0)
    alpha = math.radians(20)
    cd = a.pitch_radius + b.pitch_radius
    t1 = a.base_radius * np.array([math.cos(alpha), math.sin(alpha)])  # base tangent point
    u = np.array([math.sin(alpha), -math.cos(alpha)])  # along the line, T1 -> pitch point
    length = cd * math.sin(alpha)  # |T1 T2|
    s = np.linspace(0.0, length, 2_000_001)
    P = t1[None, :] + s[:, None] * u[None, :]
    inside = ((np.hypot(P[:, 0], P[:, 1]) <= a.pitch_radius + 0.01)
              & (np.hypot(P[:, 0] - cd, P[:, 1]) <= b.pitch_radius + 0.01))
    path = inside.sum() * (s[1] - s[0])
    eps = path / (math.pi * 0.01 * math.cos(alpha))
    assert contact_ratio(a, b, False) == pytest.approx(eps, rel=1e-5)


def test_wave_mean_fraction_and_schedule():
    """(M1)-(M3): the mean over a mesh period is the given stiffness, the double-pair fraction
    is eps - 1, and the schedule's times are those of the mesh frequency z n."""
    pair = _pair({"contact_ratio": 1.6, "stiffness_ratio": 1.75, "phase": 0.25})
    v = pair.assemble().contacts.variation
    assert list(v.rows) == [0, 1]
    om = 600 * RPM  # the pinion (20 teeth): mesh frequency 200 Hz
    assert v.rate[0] * om == pytest.approx(200.0, rel=1e-12)
    psi = np.linspace(0.0, 2 * math.pi / 20, 200_001)[:-1]  # one mesh period
    k = v.stiffness(psi)[:, 0]
    assert k.mean() == pytest.approx(2e8, rel=1e-4)
    assert np.mean(k == v.k_double[0]) == pytest.approx(0.6, abs=1e-4)
    assert v.k_double[0] / v.k_single[0] == pytest.approx(1.75)
    t, rows, ks = v.schedule(0.0, om, 0.02)
    # phase 0.25: double from 0.75 to 1.35 periods, i.e. switches at (0.75 + n) / 200 s
    # (to double) and (0.35 + n) / 200 s (to single), each on both flanks
    up = np.sort(t[(rows == 0) & (ks == v.k_double[0])])
    down = np.sort(t[(rows == 0) & (ks == v.k_single[0])])
    np.testing.assert_allclose(up, (0.75 + np.arange(4)) / 200, rtol=0, atol=1e-15)
    np.testing.assert_allclose(down, (0.35 + np.arange(4)) / 200, rtol=0, atol=1e-15)
    assert np.all(np.diff(t) >= 0)
    # the schedule agrees with the wave just after each change
    after = v.stiffness(om * (t + 1e-9))
    np.testing.assert_array_equal(ks, after[np.arange(len(t)), rows])


def _interval_expm(pair, loads, om, t_grid, q0):
    """Independent solution of an always-closed front flank with the stiffness switched at
    the wave's changes: Van Loan's augmented exponential per interval (constant load)."""
    asm = pair.assemble()
    c = asm.contacts
    v = c.variation
    w, cd = c.W[0], c.damping[0]
    n = asm.n
    Minv = np.linalg.inv(asm.M)
    F = asm.load_vector(loads)
    t_sw = v.schedule(0.0, om, t_grid[-1])[0]
    knots = np.unique(np.concatenate([t_grid, t_sw]))
    x = np.concatenate([q0, np.zeros(n)])
    out = [x]
    for a, b in zip(knots[:-1], knots[1:], strict=True):
        k = v.stiffness(om * a)[0, 0] if a not in t_sw else v.stiffness(om * a + 1e-12)[0, 0]
        A = np.zeros((2 * n + 1, 2 * n + 1))
        A[:n, n:2 * n] = np.eye(n)
        A[n:2 * n, :n] = -Minv @ (k * np.outer(w, w))
        A[n:2 * n, n:2 * n] = -Minv @ (cd * np.outer(w, w))
        A[n:2 * n, -1] = Minv @ F
        x = (sla.expm(A * (b - a)) @ np.append(x, 1.0))[:-1]
        if np.any(np.isclose(b, t_grid, rtol=0, atol=1e-15)):
            out.append(x)
    return np.array(out)


def test_exact_follows_the_wave_as_interval_exponentials():
    """Preloaded pair (front flank closed throughout): the exact method's time events give the
    solution of the piecewise-constant stiffness to near rounding."""
    pair = _pair({"contact_ratio": 1.6, "phase": 0.3}, backlash=1e-3, damping=200.0)
    loads = {"pinion.torque": 20.0, "wheel.torque": 40.0}  # balanced through the mesh
    om = 300 * RPM  # 100 Hz mesh frequency: 10 periods, 20 switches per flank
    # start with the front flank compressed (it stays closed: no event but the closing)
    sim = gm.simulate(pair, 0.1, dt=2.5e-3, loads=loads, speed_rpm=300.0,
                      q0={"pinion.theta": 1e-5})
    assert sim.contact_state["mesh:front"].all()
    ref = _interval_expm(pair, loads, om, sim.t, np.array([1e-5, 0.0]))
    asm = pair.assemble()
    p_ref = ref[:, :2] @ asm.contacts.W[0]
    p = sim.q.to_numpy() @ asm.contacts.W[0]
    # measured 1e-13 relative (the constant-stiffness run is 77 % off)
    assert np.abs(p - p_ref).max() <= 1e-11 * np.abs(p_ref).max()
    # the forces use the stiffness at each output time
    k = asm.contacts.variation.stiffness(om * sim.t)[:, 0]
    f = k * p + 200.0 * (sim.v.to_numpy() @ asm.contacts.W[0])
    np.testing.assert_allclose(sim.forces["mesh.front"].to_numpy(), f, rtol=1e-12,
                               atol=1e-9 * np.abs(f).max())


def test_rattle_driven_by_the_wave_matches_tight_scipy():
    """The stiffness jump to double contact kicks the flank open: a rattle of short impacts.
    The exact method against DOP853 at rtol 1e-12 restarting at every change (and a step
    limit, since scipy misses a dip shorter than its step): same events (77), times to 1e-10 s
    (measured 2e-13 s), forces to 1e-6 of the peak (measured 2e-9)."""
    pair = _pair(True)
    loads = {"pinion.torque": 20.0, "wheel.torque": 40.0}  # balanced through the mesh
    ex = gm.simulate(pair, 0.02, dt=1e-4, loads=loads, speed_rpm=600.0)
    sp = gm.simulate(pair, 0.02, dt=1e-4, loads=loads, speed_rpm=600.0, method="scipy",
                     scipy_method="DOP853", rtol=1e-12, atol=1e-15, max_step=1e-5)
    e1, e2 = ex.events, sp.events
    assert len(e1) > 40  # the constant-stiffness pair closes once and stays closed
    assert len(gm.simulate(_pair(None), 0.02, dt=1e-4, loads=loads,
                           speed_rpm=600.0).events) == 1
    assert list(e1.state_after) == list(e2.state_after)
    np.testing.assert_allclose(e1.time, e2.time, rtol=0, atol=1e-10)
    f1, f2 = ex.forces["mesh.front"].to_numpy(), sp.forces["mesh.front"].to_numpy()
    assert np.abs(f1 - f2).max() <= 1e-6 * np.abs(f1).max()


def test_planet_mesh_phases_and_rates():
    """Parker & Lin's phasing: planet n's ring mesh leads by z_r psi_n / 2 pi, its sun mesh
    lags by z_s psi_n / 2 pi (periods); every mesh of the stage runs z_r periods per carrier
    revolution."""
    angles = [math.radians(a) for a in (0.0, 117.0, 243.0)]  # unequal, assemblable
    st = gm.examples.planetary_stage(angles=angles, planet_bearing=2e9, sun_support=1e7,
                                     ring_support=None, mesh_alternation=True)
    asm = st.assemble()
    c, v = asm.contacts, asm.contacts.variation
    assert len(v) == 12
    np.testing.assert_allclose(v.rate * 2 * math.pi, 99.0, rtol=1e-12)
    for row, ph in zip(v.rows, v.phase, strict=True):
        el = c.element[row]
        n = int(el[-1])
        want = (99 if el.startswith("ring") else -21) * angles[n - 1] / (2 * math.pi)
        assert ph == pytest.approx(want, abs=1e-12)
    eps = 1 + v.double
    assert np.all((eps > 1) & (eps < 2))


def test_errors_name_the_field():
    with pytest.raises(ModelError, match="contact_ratio"):
        _pair({"contact_ratio": 2.3})
    with pytest.raises(ModelError, match="stiffness_ratio"):
        _pair({"stiffness_ratio": 0.5})
    with pytest.raises(ModelError, match="mesh_alternation.bogus"):
        _pair({"bogus": 1})
    pair = _pair(True)
    with pytest.raises(ModelError, match="newmark"):
        gm.simulate(pair, 0.001, dt=1e-4, method="newmark", speed_rpm=600.0)
    with pytest.raises(ModelError, match="expm"):
        gm.simulate(pair, 0.001, dt=1e-4, propagator="expm", speed_rpm=600.0)
    lp = gm.lin_parker_stage(3, {"carrier": 5.43, "ring": 2.35, "sun": 0.4, "planet": 0.66},
                             {"carrier": 6.29, "ring": 3.0, "sun": 0.39, "planet": 0.61},
                             {"carrier": 1e8, "ring": 1e8, "sun": 1e8, "planet": 1e8},
                             {"carrier": 0.0, "ring": 1e9, "sun": 0.0},
                             {"sun_planet": 5e8, "ring_planet": 5e8}, math.radians(24.6))
    lp.meshes["sun_planet1"].alternation = True
    with pytest.raises(ModelError, match="tooth counts"):
        lp.assemble()


def test_toml_key():
    """``mesh_alternation`` in a model file reaches the meshes."""
    text = """
[model]
type = "gear_pair"
[gear_pair]
mesh_stiffness = 2e8
backlash = 1e-4
mesh_alternation = { contact_ratio = 1.5, stiffness_ratio = 2.0 }
[gear_pair.pinion]
teeth = 20
module = 0.004
pressure_angle_deg = 20
mass = 1.0
inertia = 1e-3
[gear_pair.wheel]
teeth = 40
module = 0.004
pressure_angle_deg = 20
mass = 4.0
inertia = 1.6e-2
"""
    m = gm.loads(text)
    mesh = m.meshes["mesh"]
    assert mesh.alternation and mesh.contact_ratio == 1.5 and mesh.stiffness_ratio == 2.0


def test_backward_rotation_starts_in_the_interval_it_enters():
    """Turning backwards from a boundary (phase 0 at -600 rpm) runs the single-pair interval
    first, as the forward run whose phase starts at the same boundary from the other side
    (phase eps - 1 at +600 rpm): the torsional pair has no speed terms, so the two are the
    same run."""
    loads = {"pinion.torque": 20.0, "wheel.torque": 40.0}
    back = gm.simulate(_pair({"contact_ratio": 1.6}), 0.02, dt=1e-4, loads=loads,
                       speed_rpm=-600.0)
    fwd = gm.simulate(_pair({"contact_ratio": 1.6, "phase": 0.6}), 0.02, dt=1e-4, loads=loads,
                      speed_rpm=600.0)
    assert len(back.events) == len(fwd.events)
    # (the last sample, t = 0.02 s, is a switching instant, where the two runs' rounding of
    # the phase picks either side: left out)
    f1, f2 = back.forces["mesh.front"].to_numpy()[:-1], fwd.forces["mesh.front"].to_numpy()[:-1]
    assert np.abs(f1 - f2).max() <= 1e-9 * np.abs(f2).max()
    # starting in the double-pair interval instead is a different run
    dbl = gm.simulate(_pair({"contact_ratio": 1.6}), 0.02, dt=1e-4, loads=loads,
                      speed_rpm=600.0).forces["mesh.front"].to_numpy()[:-1]
    assert np.abs(dbl - f2).max() > 0.05 * np.abs(f2).max()


def test_a_mesh_without_frequency_is_refused():
    """Gears that do not turn against their frame have no mesh frequency."""
    pair = _pair(True)
    for b in pair.bodies.values():
        b.speed_ratio = 0.0
    with pytest.raises(ModelError, match="no frequency"):
        pair.assemble()
