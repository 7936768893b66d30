"""The turbine side: polars, BEM, generator, start-up with cut-in, shaft-end loads."""

import math

import numpy as np
import pytest

import gearmodal as gm
from gearmodal.turbine import Airfoil, InductionGenerator, Wind, load_turbine, simulate_turbine

TOML = "studies/turbines/600kw_turbine.toml"


def test_viterna_polar_is_continuous_and_reaches_the_flat_plate():
    af = Airfoil.viterna(stall_deg=12.0, aspect_ratio=12.0)
    a = np.radians(np.linspace(-179, 179, 20001))
    cl, cd = af.coefficients(a)
    assert np.abs(np.diff(cl)).max() < 0.01 and np.abs(np.diff(cd)).max() < 0.01
    cdmax = 1.11 + 0.018 * 12
    assert af.coefficients(math.pi / 2)[1] == pytest.approx(cdmax, rel=1e-3)
    assert af.coefficients(math.radians(5))[0] == pytest.approx(6.2 * math.radians(7.6),
                                                                rel=1e-3)


def test_bem_inductions_satisfy_momentum_balance():
    """Converged inductions below a_c satisfy blade-element = momentum:
    a / (1 - a) = sigma Cn / (4 F sin^2 phi) (Hansen eq. 6.23), to the solver tolerance."""
    rot = load_turbine(TOML).rotor
    omega = 22.3 * math.pi / 30
    u = np.full((3, len(rot.r)), 9.0)
    rot.loads(omega, 0.0, u, 0 * u, reset=True)
    a, ap = rot._a, rot._ap
    r = rot.r[None, :]
    phi = np.arctan2(9.0 * (1 - a), omega * r * (1 + ap))
    cl, cd = rot.airfoil.coefficients(phi - rot.twist[None, :] - rot.pitch)
    cn = cl * np.cos(phi) + cd * np.sin(phi)
    sigma = 3 * rot.chord[None, :] / (2 * math.pi * r)
    s = np.abs(np.sin(phi))
    F = (4 / math.pi**2) * np.arccos(np.exp(-3 * (rot.radius - r) / (2 * r * s))) \
        * np.arccos(np.exp(-3 * (r - rot.hub_radius) / (2 * rot.hub_radius * s)))
    low = a < 0.19
    assert low.sum() > 10
    lhs = (a / (1 - a))[low]
    rhs = (sigma * cn / (4 * F * np.sin(phi) ** 2))[low]
    np.testing.assert_allclose(lhs, rhs, rtol=1e-5)


def test_power_curve_is_a_plausible_stall_curve():
    """Against the class's published curves (Bonus 600 kW: ~0.44 peak Cp, ~600 kW at 15-16 m/s,
    flat in stall): peak Cp 0.38-0.45 and below Betz, 10 m/s 280-380 kW, 16 m/s 550-650 kW."""
    rot = load_turbine(TOML).rotor
    om = 22.3 * math.pi / 30
    cps = {u: rot.power_coefficient(u, om)[0] for u in (6, 8, 10, 16)}
    area = math.pi * rot.radius**2
    power = {u: cp * 0.5 * 1.225 * area * u**3 for u, cp in cps.items()}
    assert 0.38 < max(cps.values()) < min(0.45, 16 / 27)
    assert 280e3 < power[10] < 380e3
    assert 550e3 < power[16] < 650e3


def test_generator_slip_torque_curve():
    g = InductionGenerator(rated_power=600e3, sync_speed_rpm=1800, rated_slip=0.02,
                           pullout_ratio=2.5)
    ws = g.omega_sync
    assert g.torque(ws) == 0.0
    assert g.torque(ws * 1.02) == pytest.approx(600e3 / (ws * 1.02), rel=1e-12)
    assert g.torque(ws * (1 + g.pullout_slip)) == pytest.approx(g.pullout_torque, rel=1e-12)
    assert g.torque(ws * 0.99) < 0  # motoring below synchronous speed
    with pytest.raises(gm.ModelError, match="rated_slip"):
        InductionGenerator(rated_slip=0.5)


def test_start_up_cut_in_and_operation_at_10_m_per_s():
    """The paper's start-up: from low rotor speed with the generator cut out, cut-in near 12 s
    (here 10-14 s from 6 rpm), then operation near synchronous speed with plausible power."""
    tb = load_turbine(TOML)
    run = simulate_turbine(tb, Wind(mean_speed=10.0, hub_height=tb.hub_height), 30.0)
    assert 10.0 < run.cut_in_time < 14.0
    op = run.loads.loc[20:]
    assert op.generator_connected.all()
    sync_rotor = 1800 / tb.gear_ratio
    assert np.all((op.rotor_speed_rpm > sync_rotor) & (op.rotor_speed_rpm < 1.03 * sync_rotor))
    assert 250e3 < op.power_W.mean() < 400e3  # rated 600 kW at ~16 m/s; 10 m/s about half
    # 3P tower-shadow dip visible in the thrust
    assert op.thrust_N.std() > 0


def test_rear_force_of_an_overhung_rotor_by_statics():
    """No wind, rotor at rest: the rear bearing (gearbox) carries x_f W / (x_r - x_f) upward
    (an overhung weight lifts the shaft end)."""
    tb = load_turbine(TOML)
    run = simulate_turbine(tb, Wind(mean_speed=0.0, tower_radius=0.0), 0.1,
                           rotor_speed0_rpm=0.0)
    W = tb.rotor.mass * 9.81
    expect = tb.front_bearing * W / (tb.rear_bearing - tb.front_bearing)
    assert run.loads.rear_force_z_N.iloc[0] == pytest.approx(expect, rel=1e-3)


def test_a_coned_rotor_on_a_tilted_shaft():
    """The rotor's geometry (gearmodal/turbine/rotor.py, Turbine.blade_wind) by closed forms:
    without cone and tilt the wind at the elements is the field's own, bit for bit; a shaft
    tilted by tau sees a horizontal wind U as U cos(tau) along it and U sin(tau) in the
    rotor plane; a cone c takes U cos(c) of a wind along the shaft; equal blades in a
    uniform wind cancel their in-plane forces and moments whatever the cone; a tilted shaft
    carries the rotor's weight m g cos(tau) in plane and changes nothing else; a cone beyond
    30 deg is refused by name."""
    import dataclasses

    tb = load_turbine(TOML)
    U, psi = 9.0, 0.37
    wind = Wind(mean_speed=U, hub_height=tb.hub_height, shear_exponent=0.0, tower_radius=0.0)
    sheared = Wind(mean_speed=U, hub_height=tb.hub_height, shear_exponent=0.2,
                   turbulence_intensity=0.1, duration=5.0, grid_points=4)
    y, z, psib = tb.rotor.positions(psi)
    vel = sheared.velocity(1.0, y, z + tb.hub_height)
    u, vt = tb.blade_wind(sheared, 1.0, psi)
    np.testing.assert_array_equal(u, vel[0])
    np.testing.assert_array_equal(vt, -vel[1] * np.cos(psib)[:, None]
                                  - vel[2] * np.sin(psib)[:, None])
    tau, c = math.radians(5.0), math.radians(-4.0)
    tilted = dataclasses.replace(tb, tilt_deg=5.0)
    u, vt = tilted.blade_wind(wind, 0.0, psi)
    np.testing.assert_allclose(u, U * math.cos(tau), rtol=1e-12)
    np.testing.assert_allclose(vt, np.broadcast_to(-U * math.sin(tau) * np.sin(psib)[:, None],
                                                   vt.shape), rtol=1e-12)
    coned = dataclasses.replace(tb, rotor=dataclasses.replace(tb.rotor, precone=c))
    u, vt = coned.blade_wind(wind, 0.0, psi)
    np.testing.assert_allclose(u, U * math.cos(c), rtol=1e-12)
    np.testing.assert_allclose(vt, 0.0, atol=1e-12)
    om = 2.3
    ld = coned.rotor.loads(om, psi, u, vt, reset=True)
    weight = coned.rotor.mass * coned.rotor.gravity
    scale = ld["thrust_N"]
    assert scale > 0
    for key, value in (("shear_y_N", 0.0), ("shear_z_N", -weight), ("tilt_Nm", 0.0),
                       ("yaw_Nm", 0.0)):
        assert abs(ld[key] - value) < 1e-9 * scale * (tb.rotor.radius if "Nm" in key else 1)
    level = coned.rotor.loads(om, psi, u, vt, reset=True, tilt=tau)
    assert level["shear_z_N"] - ld["shear_z_N"] == pytest.approx(weight * (1 - math.cos(tau)),
                                                                 rel=1e-9)
    assert {k: v for k, v in level.items() if k != "shear_z_N"} == \
        {k: v for k, v in ld.items() if k != "shear_z_N"}
    with pytest.raises(gm.ModelError, match=r"rotor\.precone = 0\.6 rad: must be a number in"):
        dataclasses.replace(tb.rotor, precone=0.6)
    # the tilt's in-plane wind meets the descending blades (the -y side) head on: more thrust
    # there, a positive yaw moment; none without tilt
    ld0 = tb.hub_loads(wind, 0.0, om, 0.0, reset=True)
    ld1 = tilted.hub_loads(wind, 0.0, om, 0.0, reset=True)
    assert abs(ld0["yaw_Nm"]) < 1e-9 * ld0["thrust_N"] * tb.rotor.radius
    assert ld1["yaw_Nm"] > 1e-3 * ld1["thrust_N"] * tb.rotor.radius
    # the plane rotor's loads are the element forces' plain sums, bit for bit
    from gearmodal.turbine import rotor as rotor_mod

    rot = tb.rotor
    u, vt = tb.blade_wind(sheared, 1.0, psi)
    pa, pcl, pcd, pid = rot._polars
    n = u.shape
    fn, ft, _, _ = rotor_mod._bem(u, vt, om, rot.r, rot.r_turn, rot.chord, rot.twist + rot.pitch,
                                  rot.dr, rot.blades, rot.radius, rot.hub_radius, pa, pcl, pcd,
                                  pid, np.zeros(n), np.zeros(n), rot.rho, rot.tol, rot.max_iter,
                                  rotor_mod.CORRECTIONS.index(rot.correction))
    got = rot.loads(om, psi, u, vt, reset=True)
    yy, zz, pb = rot.positions(psi)
    assert got["thrust_N"] == float(fn.sum())
    assert got["torque_Nm"] == float((ft * rot.r[None, :]).sum())
    assert got["tilt_Nm"] == float((zz * fn).sum())
    assert got["yaw_Nm"] == float((-yy * fn).sum())
    assert got["shear_y_N"] == float((ft * -np.cos(pb)[:, None]).sum())
    # the shadow at the rotor plane's own distance is the default one, bit for bit
    shadowed = Wind(mean_speed=U, hub_height=tb.hub_height, shear_exponent=0.0, tower_radius=1.5,
                    tower_distance=3.0)
    z_low = tb.hub_height - np.linspace(1.0, 20.0, 7)
    y_low = np.linspace(-2.0, 2.0, 7)
    np.testing.assert_array_equal(shadowed.velocity(0.0, y_low, z_low),
                                  shadowed.velocity(0.0, y_low, z_low, np.full(7, 3.0)))
    far = shadowed.velocity(0.0, y_low, z_low, np.full(7, 9.0))[0]
    a2, x = 1.5**2, 9.0
    np.testing.assert_allclose(far, U * (1 - a2 * (x * x - y_low**2) / (x * x + y_low**2)**2),
                               rtol=1e-12)


def test_a_run_in_openfasts_channels_and_units():
    """``TurbineResult.openfast``: OpenFAST's channel names, each with its unit in
    ``attrs["units"]`` and the value converted to it (rpm, deg, kN-m, kW, N, N-m); GenSpeed
    the rotor's times the gear ratio; GenPwr the shaft power times the efficiency (the
    electrical power, as ServoDyn's GenEff makes it). The loads frame names its units too,
    and a bad gear ratio or efficiency is refused by name."""
    tb = load_turbine(TOML)
    run = simulate_turbine(tb, Wind(mean_speed=10.0, tower_radius=0.0), 0.5,
                           rotor_speed0_rpm=27.0, connected=True)
    frame = run.to_frame()
    assert frame.attrs["units"]["power_W"] == "W"
    assert set(frame.attrs["units"]) == set(frame.columns)
    of = run.openfast(gear_ratio=tb.gear_ratio, efficiency=0.95)
    assert list(of.columns) == ["RotSpeed", "Azimuth", "BldPitch1", "GenTq", "RtAeroFxh",
                                "RtAeroMxh", "GenSpeed", "GenPwr"]
    assert of.index.name == "Time" and of.attrs["units"] == {
        "Time": "s", "RotSpeed": "rpm", "Azimuth": "deg", "BldPitch1": "deg", "GenTq": "kN-m",
        "RtAeroFxh": "N", "RtAeroMxh": "N-m", "GenSpeed": "rpm", "GenPwr": "kW"}
    d = run.loads
    np.testing.assert_array_equal(of.index.to_numpy(), d.index.to_numpy())
    np.testing.assert_array_equal(of.RotSpeed, d.rotor_speed_rpm)
    np.testing.assert_allclose(of.GenSpeed, d.rotor_speed_rpm * tb.gear_ratio, rtol=1e-15)
    np.testing.assert_allclose(of.GenTq, d.generator_torque_Nm / 1e3, rtol=1e-15)
    np.testing.assert_allclose(of.GenPwr, d.power_W * 0.95 / 1e3, rtol=1e-15)
    np.testing.assert_array_equal(of.RtAeroMxh, d.torque_Nm)
    assert of.GenPwr.iloc[-1] > 100.0  # kW: the generator connected and producing
    for kw, name in (({"gear_ratio": 0.0}, "gear_ratio"), ({"gear_ratio": 50.0,
                                                           "efficiency": 1.2}, "efficiency")):
        with pytest.raises(gm.ModelError, match=rf"^{name} = "):
            run.openfast(**kw)


def test_turbulence_is_seeded_and_sampled():
    kw = dict(mean_speed=10.0, hub_height=40.0, turbulence_intensity=0.12, duration=20.0,
              dt=0.2, grid_points=4)
    from gearmodal.turbine import wind as wind_mod

    a, b, c = Wind(seed=1, **kw), Wind(seed=1, **kw), Wind(seed=2, **kw)
    y, z = np.array([0.0, 10.0]), np.array([40.0, 50.0])
    va = np.array([a.velocity(t, y, z)[0] for t in np.arange(0, 20, 0.2)])
    wind_mod._BOXES.clear()  # generated again, not read from the process's cache
    vb = np.array([b.velocity(t, y, z)[0] for t in np.arange(0, 20, 0.2)])
    assert b._turbulence()[3] is not a._turbulence()[3]
    vc = np.array([c.velocity(t, y, z)[0] for t in np.arange(0, 20, 0.2)])
    np.testing.assert_array_equal(va, vb)
    assert np.abs(va - vc).max() > 0.1
    # at the grid nodes the box has the standard deviations asked (u, v, w = 1, 0.8, 0.5 of
    # TI U; a 20 s record of a Kaimal process, time scale ~30 s, holds ~90 % of it); between
    # nodes bilinear interpolation averages partly coherent signals and lowers it
    _, gy, gz, box = a._turbulence()
    for comp, share in ((0, 1.0), (1, 0.8), (2, 0.5)):
        ratio = box[:, comp].std(axis=0).mean() / (share * 0.12 * 10.0)
        assert 0.8 < ratio < 1.1
    node = a.velocity(4.0, np.array([gy[1]]), np.array([gz[2]]))
    assert node[0, 0] == pytest.approx(10.0 * (gz[2] / 40.0) ** 0.2 + box[20, 0, 1, 2],
                                       rel=1e-12)
    with pytest.raises(gm.ModelError, match="turbulence_intensity"):
        Wind(turbulence_intensity=2.0)


def test_turbulence_box_does_not_depend_on_the_blas_threads(monkeypatch):
    """The scene's box (30 s, 10 m/s, TI 0.12, seed 1) is the same to the bit whatever the
    BLAS thread count the user runs with: made with two threads, PyConTurb's products rounded
    differently (3.6e-15 m/s), and the clearance gearbox's rattle turned that into a
    different run (146.8 against 144.0 kN tooth peak on the 500 Hz rung). PyConTurb runs with
    one BLAS thread even when the user allows two (checked directly too: on a one-core
    machine two threads may not round differently)."""
    from threadpoolctl import threadpool_info, threadpool_limits

    from gearmodal.turbine import wind as wind_mod

    seen = []
    kaimal_box = wind_mod.kaimal_box

    def spy(*args, **kwargs):
        seen.append(max(p["num_threads"] for p in threadpool_info()
                        if p["user_api"] == "blas"))
        return kaimal_box(*args, **kwargs)

    monkeypatch.setattr(wind_mod, "kaimal_box", spy)
    kw = dict(mean_speed=10.0, turbulence_intensity=0.12, seed=1, duration=30.0)
    boxes = []
    for threads in (1, 2):
        with threadpool_limits(threads, user_api="blas"):
            wind_mod._BOXES.clear()
            boxes.append(Wind(**kw)._turbulence()[3])
    np.testing.assert_array_equal(boxes[0], boxes[1])
    assert seen == [1, 1]


def test_turbulence_box_is_pyconturbs_to_the_bit(monkeypatch):
    """wind.kaimal_box (gearmodal's own Veers generator: phases and coherence a chunk of
    frequencies at a time, each column's inverse FFT straight into the box) is PyConTurb's
    gen_turb, frequency by frequency, to the bit: odd and even step counts, any chunk size
    (one, uneven, all at once), two grids."""
    pytest.importorskip("pyconturb", reason="the reference generator: pip install "
                        "'gearmodal[wind]' (installed in CI)")
    from pyconturb import gen_spat_grid, gen_turb
    from pyconturb.sig_models import constant_sig
    from pyconturb.wind_profiles import constant_profile

    from gearmodal.turbine import wind as wind_mod

    # 600 s at 0.1 s on 7 x 7 points: 48 frequencies per 8 MiB, all of a short box's
    assert wind_mod.coherence_chunk(6001, 147) == 48
    assert wind_mod.coherence_chunk(101, 48) == 51
    for ny, hub in ((4, 40.0), (3, 80.0)):  # hub heights below and above 60 m (Lambda_1)
        y = np.linspace(-20, 20, ny)
        z = hub + np.linspace(-20, 20, ny)
        spat = gen_spat_grid(y, z)
        sig = [1.2, 0.96, 0.6]
        for nt in (101, 100):
            ref = gen_turb(spat, T=nt * 0.2, nt=nt, seed=3, u_ref=10.0, z_ref=hub,
                           wsp_func=constant_profile, sig_func=constant_sig, sig_vals=sig,
                           comps=[0, 1, 2], nf_chunk=1).to_numpy()
            ref = ref.reshape(nt, ny, ny, 3).transpose(0, 3, 1, 2)
            for chunk in (1, 16, 51):
                monkeypatch.setattr(wind_mod, "coherence_chunk", lambda nt, n, c=chunk: c)
                box = wind_mod.kaimal_box(y, z, nt, 0.2, 3, 10.0, sig)
                np.testing.assert_array_equal(box, ref)


def test_turbine_loads_drive_the_gearbox():
    """The turbine's shaft loads (rotor torque, generator torque, shaft-end force) drive the
    600 kW drivetrain in operation: the carrier bearing then carries the shaft-end force."""
    tb = load_turbine(TOML)
    run = simulate_turbine(tb, Wind(mean_speed=10.0, hub_height=tb.hub_height), 0.4,
                           rotor_speed0_rpm=22.3, connected=True)
    loads = run.gearbox_loads()
    m = gm.load("studies/models/600kw.toml")
    sim = gm.simulate(m, 0.4, dt=1e-3, loads=loads, speed_rpm=22.3)
    assert np.all(np.isfinite(sim.q.to_numpy()))
    # quasi-static vertical balance of the carrier after the start transient: the carrier
    # bearing and the main-shaft bending support carry the shaft-end force (measured: 0.9 %)
    late = sim.forces.loc[0.2:]
    carried = (late["stage1.carrier_bearing.y"] + late["shaft_bending.y"]).mean()
    applied = run.loads.loc[0.2:, "rear_force_z_N"].mean()
    assert applied > 1e4
    assert carried == pytest.approx(applied, rel=0.05)


def test_bem_solution_satisfies_its_equations():
    """Every element's inductions solve the BEM equations (Hansen ch. 6): the flow angle
    they give implies the same inductions again, to 1e-12, from a cold start and from the
    previous update's (the one-equation root of rotor._solve_phi), in sheared, turbulent
    inflow from cut-in to cut-out."""
    from gearmodal.turbine import rotor as R

    rot = gm.turbine.load_turbine("studies/turbines/600kw_turbine.toml").rotor
    rng = np.random.default_rng(3)
    om = 22.3 * 2 * np.pi / 60
    th = rot.twist + rot.pitch
    for V in (4.0, 8.0, 12.0, 18.0, 25.0):
        U = V * (1 + 0.15 * rng.standard_normal((rot.blades, len(rot.r))))
        vt = 0.5 * rng.standard_normal(U.shape)
        for reset in (True, False):
            rot.loads(om, 0.2, U, vt, reset=reset)
            for b in range(rot.blades):
                for i, ri in enumerate(rot.r):
                    a, ap = rot._a[b, i], rot._ap[b, i]
                    u = max(U[b, i], 1e-3)
                    phi = np.arctan2(u * (1 - a), om * ri * (1 + ap) - vt[b, i])
                    sigma = rot.blades * rot.chord[i] / (2 * np.pi * ri)
                    a2, ap2 = R._inductions(phi, th[i], sigma, rot.blades, rot.radius, ri,
                                            rot.hub_radius, rot.airfoil.alpha, rot.airfoil.cl,
                                            rot.airfoil.cd)
                    assert abs(a2 - a) < 1e-12 and abs(ap2 - ap) < 1e-12, (V, b, i)


def test_polar_lookup_is_numpys_interpolation():
    """The BEM's polar lookup (one search for lift and drag) is np.interp of each, held at the
    grid's ends, at random angles, grid points and beyond the grid."""
    from gearmodal.turbine.rotor import _polar

    af = Airfoil.viterna()
    rng = np.random.default_rng(4)
    angles = np.concatenate([rng.uniform(-3.3, 3.3, 2000), af.alpha[::37], [-4.0, 4.0]])
    for a in angles:
        cl, cd = _polar(a, af.alpha, af.cl, af.cd)
        assert cl == pytest.approx(np.interp(a, af.alpha, af.cl), rel=1e-14, abs=1e-15)
        assert cd == pytest.approx(np.interp(a, af.alpha, af.cd), rel=1e-14, abs=1e-15)


def test_turbulence_boxes_are_kept_per_process_by_their_parameters():
    """A wind with the same turbulence parameters reads the box generated before (read-only);
    shear and tower do not enter the box, a new seed or intensity makes a new one."""
    from gearmodal.turbine import wind as wind_mod

    kw = dict(mean_speed=10.0, hub_height=40.0, turbulence_intensity=0.12, duration=8.0,
              dt=0.2, grid_points=3, seed=11)
    wind_mod._BOXES.clear()
    first = Wind(**kw)._turbulence()[3]
    assert not first.flags.writeable
    assert Wind(**{**kw, "shear_exponent": 0.1, "tower_radius": 0.0})._turbulence()[3] is first
    other = Wind(**{**kw, "seed": 12})._turbulence()[3]
    assert other is not first and np.abs(other - first).max() > 0.1
    assert Wind(**{**kw, "turbulence_intensity": 0.06})._turbulence()[3] is not first
    for seed in range(20, 20 + wind_mod.BOX_CACHE + 1):  # the oldest is dropped
        Wind(**{**kw, "seed": seed})._turbulence()
    assert len(wind_mod._BOXES) == wind_mod.BOX_CACHE
    assert Wind(**kw)._turbulence()[3] is not first
