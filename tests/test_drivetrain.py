"""The turbine and the gearbox in one run (gm.turbine.simulate_drivetrain), its scene and CLI."""

import math

import numpy as np
import pandas as pd
import pytest

import gearmodal as gm
from gearmodal.cli import main
from gearmodal.scene import load_scene
from gearmodal.turbine import simulate_drivetrain, simulate_turbine

TURBINE = "studies/turbines/600kw_turbine.toml"
GEARBOX = "studies/models/600kw.toml"


@pytest.fixture(scope="module")
def parts():
    return gm.turbine.load_turbine(TURBINE), gm.load(GEARBOX)


@pytest.fixture(scope="module")
def cut_in_run(parts):
    """Laminar 10 m/s from 20 rpm: the generator cuts in about a second later."""
    tb, gb = parts
    wind = gm.turbine.Wind(mean_speed=10.0)
    coupled = simulate_drivetrain(tb, wind, gb, 3.0, rotor_speed0_rpm=20.0, gravity=False)
    rigid = simulate_turbine(tb, wind, 3.0, rotor_speed0_rpm=20.0)
    return coupled, rigid


def test_coupled_turbine_matches_the_rigid_turbine(cut_in_run):
    """The gearbox model's drivetrain inertia (5.028e5 kg m^2) is the rigid turbine's (5.03e5):
    before cut-in the rotor speeds agree; the generator cuts in at the same time; afterwards the
    flexible main shaft lets the rotor swing against the grid-held generator (a ~1.7 Hz mode the
    rigid model cannot have, decaying within ~2 s) and the mean power agrees."""
    coupled, rigid = cut_in_run
    assert coupled.cut_in_time is not None and rigid.cut_in_time is not None
    assert coupled.cut_in_time == pytest.approx(rigid.cut_in_time, abs=0.05)
    a = coupled.turbine.loads
    b = rigid.loads.reindex(a.index)
    before = a.index < rigid.cut_in_time - 0.05
    assert np.abs(a["rotor_speed_rpm"] - b["rotor_speed_rpm"])[before].max() < 0.01  # rpm
    late = a.index > 2.0
    pa, pb = a["power_W"][late].mean(), b["power_W"][late].mean()
    assert pa == pytest.approx(pb, rel=0.05)
    assert 250e3 < pa < 400e3  # ~320 kW at 10 m/s, the 600 kW stall turbine's class


def test_gearbox_carries_the_rotor_loads(cut_in_run):
    """Quasi-static balance after cut-in: the shaft-end force on the carrier splits between
    the shaft's own bending support to ground (k_sb = 1e7 N/m) and the carrier bearing (1e9)
    in series with the housing's suspension (2e7): the carrier bearing carries
    k_eff / (k_eff + k_sb) = 66 % of it, k_eff = 1 / (1/1e9 + 1/2e7) (600kw.toml)."""
    coupled, _ = cut_in_run
    f = coupled.gearbox.forces
    ld = coupled.turbine.loads
    lz = ld["rear_force_z_N"][ld.index > 2.0].mean()
    fy = f["stage1.carrier_bearing.y"][f.index > 2.0].mean()  # gearbox y = shaft z
    k_eff = 1.0 / (1.0 / 1e9 + 1.0 / 2e7)
    assert abs(fy) == pytest.approx(abs(lz) * k_eff / (k_eff + 1e7), rel=0.05)
    assert np.isfinite(f.to_numpy()).all()


def test_gravity_puts_the_gearbox_weight_on_its_ground_supports(parts, cut_in_run):
    """With gravity on (the default) the ground supports of the gearbox (the shaft's bending
    support and the housing's suspension) carry, on average after cut-in, the weight of every
    body that moves vertically (all but the torsional rotor and generator) on top of the
    rotor loads: the same run without gravity, minus g times that mass (within 2 %: the
    mean over 1 s of a drivetrain still swinging)."""
    tb, gb = parts
    off, _ = cut_in_run
    on = simulate_drivetrain(tb, gm.turbine.Wind(mean_speed=10.0), gb, 3.0,
                             rotor_speed0_rpm=20.0)
    assert on.gearbox.settings["gravity_mps2"] == pytest.approx(9.80665)
    mass = sum(b.mass for b in gb.bodies.values() if b.dofs != "torsional")

    def ground(run):
        f = run.gearbox.forces
        late = f.index > 2.0
        return (f["shaft_bending.y"] + f["suspension.y"])[late].mean()

    assert ground(on) - ground(off) == pytest.approx(-9.80665 * mass, rel=0.02)


def test_multirate_aero_step_error_is_small(parts):
    """Aerodynamics every 20 ms (interpolated) against every gearbox step (2 ms): the tooth
    forces agree to 2 % on the grid at rated speed (measured 1.0 %, 0.9 kN of 90 kN)."""
    tb, gb = parts
    wind = gm.turbine.Wind(mean_speed=10.0)
    kw = dict(rotor_speed0_rpm=22.3, connected=True, dt=2e-3)
    fine = simulate_drivetrain(tb, wind, gb, 0.6, aero_dt=2e-3, **kw)
    coarse = simulate_drivetrain(tb, wind, gb, 0.6, aero_dt=0.02, **kw)
    col = "stage1.sun_planet1.front"
    a, b = fine.gearbox.forces[col], coarse.gearbox.forces[col]
    assert np.abs(a - b).max() < 0.02 * a.abs().max()
    assert a.iloc[0] > 0.5 * a.max()  # the run starts loaded (accelerating equilibrium)


def test_bad_input_names_the_field(parts):
    tb, gb = parts
    wind = gm.turbine.Wind(mean_speed=10.0)
    with pytest.raises(gm.ModelError, match="aero_dt"):
        simulate_drivetrain(tb, wind, gb, 0.1, dt=2e-3, aero_dt=0.003)
    with pytest.raises(gm.ModelError, match="aero_hold"):
        simulate_drivetrain(tb, wind, gb, 0.1, aero_hold="cubic")
    pair = gm.load("studies/models/gear_pair.toml")
    with pytest.raises(gm.ModelError, match="rotor"):
        simulate_drivetrain(tb, wind, pair, 0.1)
    geared = gb.copy()
    geared.bodies["rotor"].speed_ratio = 2.0
    with pytest.raises(gm.ModelError, match="rotor.speed_ratio"):
        simulate_drivetrain(tb, wind, geared, 0.1)


def test_turbine_scene_cli_writes_loads_events_forces_figures(tmp_path):
    rc = main(["simulate", "studies/scenes/600kw_turbine_10ms.toml", "--out",
               str(tmp_path), "--t-end", "0.2", "--quiet"])
    assert rc == 0
    for name in ("turbine_loads.parquet", "events.parquet", "forces.parquet", "q.parquet",
                 "drivetrain.png", "turbine.png", "forces.png", "stats.json"):
        assert (tmp_path / name).exists(), name
    loads = pd.read_parquet(tmp_path / "turbine_loads.parquet").set_index("time")
    assert len(loads) == 10 and loads["torque_Nm"].gt(0).all()  # 0.2 s at 20 ms, driving
    scene = load_scene("studies/scenes/600kw_turbine_10ms.toml")
    assert scene.wind.turbulence_intensity == pytest.approx(0.12)
    assert scene.drivetrain["aero_dt"] == pytest.approx(0.02)


def test_load_file_scene(tmp_path):
    """A scene driven by an OpenFAST text file: the channels become the loads (SI)."""
    t = np.arange(101) * 0.01
    torque = 20.0 + 5.0 * np.sin(2 * math.pi * 3 * t)  # kN m
    rows = "\n".join(f"{a:.6e}\t{b:.6e}" for a, b in zip(t, torque, strict=True))
    (tmp_path / "run.out").write_text("OpenFAST\n\nDescription\n\n\n\nTime\tRotTorq\n"
                                      f"(s)\t(kN-m)\n{rows}\n")
    (tmp_path / "scene.toml").write_text(
        '[scene]\nmodel = "%s"\nt_end = 0.2\ndt = 1e-4\n'
        '[load_file]\npath = "run.out"\n[load_file.mapping]\n'
        '"pinion.torque" = ["RotTorq", 1e-3]\n[loads]\n"wheel.torque" = "balance"\n'
        % (gm.__file__.rsplit("/", 2)[0] + "/studies/models/gear_pair.toml"))
    sc = load_scene(tmp_path / "scene.toml")
    assert sc.loads["pinion.torque"].iloc[0] == pytest.approx(20.0)  # 20 kN m x 1e-3
    # balance: the wheel's torque makes the mean load do no work on the free rotation
    mean = sc.loads["pinion.torque"].mean()
    assert abs(sc.loads["wheel.torque"]) == pytest.approx(2.0 * mean, rel=1e-9)  # 40 / 20 teeth
    assert sc.loads["wheel.torque"] == pytest.approx(
        gm.balance(sc.model, {"pinion.torque": mean}, on="wheel.torque")["wheel.torque"])
    sim = sc.simulate()
    ref = gm.simulate(sc.model, 0.2, dt=1e-4, loads={
        "pinion.torque": pd.Series([float(f"{x:.6e}") for x in torque], index=t),
        "wheel.torque": sc.loads["wheel.torque"]})  # the file's 7 digits
    np.testing.assert_allclose(sim.q.to_numpy(), ref.q.to_numpy(), rtol=0,
                               atol=1e-9 * np.abs(ref.q.to_numpy()).max())
    (tmp_path / "bad.toml").write_text((tmp_path / "scene.toml").read_text().replace(
        '"RotTorq"', '"NoSuchChannel"'))
    with pytest.raises(gm.ModelError, match="NoSuchChannel"):
        load_scene(tmp_path / "bad.toml")


def test_exact_and_scipy_agree_on_the_turning_drivetrain(parts):
    """The same coupled run (aerodynamic loads, the shaft-end force turning onto the carrier,
    the carrier bearing turning against the housing) by the exact method and by solve_ivp on
    the time-varying equations: tooth and carrier-bearing forces agree to scipy's tolerance."""
    tb, gb = parts
    wind = gm.turbine.Wind(mean_speed=10.0)
    kw = dict(rotor_speed0_rpm=22.3, connected=True, dt=1e-3, aero_dt=0.01)
    cols = ["stage1.ring_planet1.front", "stage1.carrier_bearing.x", "stage1.carrier_bearing.y"]
    a = simulate_drivetrain(tb, wind, gb, 0.04, **kw).gearbox.forces[cols].to_numpy()
    b = simulate_drivetrain(tb, wind, gb, 0.04, method="scipy", scipy_method="DOP853",
                            rtol=1e-10, atol=1e-14, **kw).gearbox.forces[cols].to_numpy()
    scale = np.abs(a).max(axis=0)
    assert np.all(scale > 1e3)
    assert np.all(np.abs(a - b).max(axis=0) < 1e-6 * scale)


def test_the_generator_torque_does_not_depend_on_the_re_basing(parts):
    """The generator's slip torque is taken at the generator's own speed at every aerodynamic
    step (its tangent's constant part), the slope at the last re-basing: over 2 s the default
    re-basing (1 % speed drift) and one at every aerodynamic step give the generator torque and
    gearbox forces to within 1e-3 and 6e-4 of their size (measured 1.1e-4 and 3.1e-4; a
    tangent kept from one re-basing to the next, as before, was 4.8e-3 and 8.4e-4 off)."""
    tb, gb = parts
    wind = gm.turbine.Wind(mean_speed=10.0, turbulence_intensity=0.12, seed=2, duration=3.0)
    kw = dict(rotor_speed0_rpm=22.3, connected=True, dt=1e-3)
    a = simulate_drivetrain(tb, wind, gb, 2.0, **kw)
    b = simulate_drivetrain(tb, wind, gb, 2.0, rebase_speed=1e-6, rebase_angle=1e-6, **kw)
    assert b.stats["n_rebases"] >= 99 > 10 * a.stats["n_rebases"]
    ga, gb_ = (r.turbine.loads["generator_torque_Nm"].to_numpy() for r in (a, b))
    assert np.abs(ga - gb_).max() < 1e-3 * np.abs(ga).max()
    cols = ["stage1.carrier_bearing.x", "stage1.ring_planet1.front", "stage1.sun_planet1.front"]
    fa, fb = (r.gearbox.forces[cols].to_numpy() for r in (a, b))
    assert np.abs(fa - fb).max() < 6e-4 * np.abs(fa).max()


def test_re_basing_does_not_kick_the_floating_carrier(parts):
    """The reference rotation re-based every few steps (speed tolerance 1e-4, angle 1e-5 rad)
    against the default (1 %, 5e-4 rad): the carrier floating in its 1 mm clearance sees the
    same forces, because the reference azimuth stays continuous and no turning gap jumps (a
    re-basing that moved the rigid rotation into the azimuth at once kicked it into a rattle:
    hundreds of kN on the planet bearings). No contact is switched by a re-basing."""
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "studies"))
    from double_contact import CLEARANCE

    tb, _ = parts
    gb = gm.load(GEARBOX, overrides={"stages.0.carrier_bearing": CLEARANCE})
    wind = gm.turbine.Wind(mean_speed=10.0, turbulence_intensity=0.12, seed=2, duration=2.0)
    kw = dict(rotor_speed0_rpm=22.3, connected=True, dt=1e-3)
    a = simulate_drivetrain(tb, wind, gb, 1.0, **kw)
    b = simulate_drivetrain(tb, wind, gb, 1.0, rebase_speed=1e-4, rebase_angle=1e-5, **kw)
    assert b.stats["n_rebases"] > 5 * max(a.stats["n_rebases"], 1)
    assert a.stats.get("rebase_switches", 0) == b.stats.get("rebase_switches", 0) == 0
    cols = ["stage1.carrier_bearing.x", "stage1.carrier_bearing.y", "stage1.ring_planet1.front"]
    fa, fb = a.gearbox.forces[cols].to_numpy(), b.gearbox.forces[cols].to_numpy()
    # the reference speed enters the speed terms and the generator tangent: a small change
    assert np.abs(fa - fb).max() < 0.02 * np.abs(fa).max()


def test_reference_methods_run_the_turbine_through_re_basings(parts):
    """Newmark on the coupled turbine with a re-basing every aerodynamic step (the driver hands
    it each stretch; a re-based system built for it has no Taylor bound to pass on, which once
    failed): it runs and agrees with the exact method over 0.1 s."""
    tb, gb = parts
    wind = gm.turbine.Wind(mean_speed=10.0)
    kw = dict(rotor_speed0_rpm=22.3, connected=True, dt=1e-3, aero_dt=0.01, rebase_speed=1e-6)
    col = "stage1.ring_planet1.front"
    ex = simulate_drivetrain(tb, wind, gb, 0.1, **kw)
    nm = simulate_drivetrain(tb, wind, gb, 0.1, method="newmark", **kw)
    assert nm.stats["n_rebases"] >= 5
    a, b = ex.gearbox.forces[col].to_numpy(), nm.gearbox.forces[col].to_numpy()
    # Newmark at 1 ms against the exact solution: second order (measured 2.3 %)
    assert np.abs(a - b).max() < 0.05 * np.abs(a).max()


def test_a_diverging_method_is_named_not_an_overflow():
    """Newmark on the clearance gearbox (the carrier floating in 1 mm) diverges within half a
    second (its contact switches at step ends feed the rattle; RESULTS, stability map): the
    run stops with an error naming the method and the time, not an OverflowError from the
    generator's slip a step later. The exact method runs the same scene (the studies)."""
    import tomllib
    from pathlib import Path

    clearance = tomllib.loads(Path("studies/models/planetary_clearance.toml").read_text(
        encoding="utf-8"))["planetary_stage"]["carrier_bearing"]
    sc = load_scene("studies/scenes/600kw_turbine_10ms.toml",
                    overrides={"scene.t_end": 1.0, "scene.method": "newmark",
                               "model.stages.0.carrier_bearing": clearance})
    with pytest.raises(gm.SolveError, match=r"method.*'newmark'.*diverg.*t = 0\.\d+ s"):
        with np.errstate(all="ignore"):
            sc.simulate()


def test_exact_solution_does_not_depend_on_the_output_step():
    """The exact method's output step only places the output rows: a run at half the step
    takes the same pieces and switches the same contacts at the same times, so the shared
    rows hold the same state to the bit. The clearance gearbox's rattle is chaotic (a
    rounding-level change grows to kN within a second of start-up: benchmarks/RESULTS.md), so
    anything that moves the solution with ``dt`` shows here: a tie window in units of ``dt``
    (parted the runs at 1.6 s) and loads interpolated as ``(t + tau) - t`` (at 8.1 s)."""
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "studies"))
    from double_contact import CLEARANCE

    sc = load_scene("studies/scenes/600kw_turbine_10ms.toml",
                    overrides={"scene.t_end": 9.0, "model.stages.0.carrier_bearing": CLEARANCE})
    kw = {**sc.drivetrain, "top_frequency_hz": 500.0}
    a = simulate_drivetrain(sc.turbine, sc.wind, sc.model, sc.t_end, dt=1e-3, **kw)
    b = simulate_drivetrain(sc.turbine, sc.wind, sc.model, sc.t_end, dt=5e-4, **kw)
    assert len(a.gearbox.events) > 1000  # the carrier rattles in its clearance
    pd.testing.assert_frame_equal(a.gearbox.events, b.gearbox.events, check_exact=True)
    np.testing.assert_array_equal(a.gearbox.q.to_numpy(), b.gearbox.q.to_numpy()[::2])
    np.testing.assert_array_equal(a.gearbox.v.to_numpy(), b.gearbox.v.to_numpy()[::2])
    assert a.gearbox.stats["pieces"] == b.gearbox.stats["pieces"]
    # the exact peaks (found across the run's 450 kernel calls and its re-basings): the same
    # at both steps, and never below a sample
    pd.testing.assert_frame_equal(a.gearbox.peak_bins, b.gearbox.peak_bins, check_exact=True)
    # and the exact turning points, so the DELs counted from them
    pd.testing.assert_frame_equal(a.gearbox.turning_points, b.gearbox.turning_points,
                                  check_exact=True)
    for sim in (a.gearbox, b.gearbox):
        pk = sim.peaks()
        flanks = [c for c in pk.index if c.endswith((".front", ".back"))]
        assert pk.loc[flanks, "exact"].all()
        assert (pk.loc[flanks, "peak_force_N"] >= sim.forces[flanks].max()).all()


@pytest.mark.parametrize("t_end, start, min_rebases", [
    (10.0, {}, 100),  # the scene's start-up from 6 rpm: the generator off the grid
    (3.0, {"connected": True, "rotor_speed0_rpm": 22.3}, 5)])  # on the grid: its slip torque
def test_turbine_run_does_not_depend_on_how_the_gearbox_is_called(t_end, start, min_rebases):
    """The coupled run is a loop over the public stepping API (gm.Stepper): the same turbine
    run with each aerodynamic step's gearbox call chopped at random output steps (the loads
    given on the same lines at the cuts) is the run of one call per step, to rounding. A cut
    is a knot of the loads inside a piece: the loads there are rounded once more (1e-16),
    which the 600 kW drivetrain's linear dynamics carry at that size; the reference re-bases,
    and the generator's slip torque is taken anew, on the aerodynamic grid, so where the
    calls end does not move them (the torque taken at every call's start instead: 2e-5 of
    the forces)."""
    import time

    from gearmodal.turbine.drivetrain import couple

    sc = load_scene("studies/scenes/600kw_turbine_10ms.toml")
    sc.drivetrain.update(start)
    one = simulate_drivetrain(sc.turbine, sc.wind, sc.model, t_end, dt=sc.dt, **sc.drivetrain)
    c = couple(sc.turbine, sc.wind, sc.model, t_end, dt=sc.dt, **sc.drivetrain)
    st, plant, step = c.stepper, c.plant, c.first
    assert step.hold == "ramp"  # the scene's loads interpolate across a step
    m = round(c.aero_dt / sc.dt)
    rng = np.random.default_rng(2026)
    last, n_calls = dict(step.now), 0
    for k in range(1, c.n_aero + 1):
        for j in sorted(rng.choice(np.arange(1, m), size=rng.integers(0, 4), replace=False)):
            f = j / m
            st.advance(((k - 1) * m + j) * sc.dt,
                       {name: last[name] + f * (val - last[name])
                        for name, val in step.loads.items()})
            n_calls += 1
        y = st.advance(k * c.aero_dt, step.loads)
        last = step.loads
        if k < c.n_aero:
            step = plant.step(k, *y.values())
            if plant.switched:
                st.set_speed_torque(plant.generator())
    chopped = c.result(time.process_time())
    assert n_calls > c.n_aero  # more calls than aerodynamic steps
    assert chopped.gearbox.stats["n_rebases"] == one.gearbox.stats["n_rebases"] > min_rebases
    # to rounding of the state: the propagator's pieces end at the cuts, so each stretch is
    # summed in other pieces (each to ~1e-14). Displacements within 1e-12 of the largest
    # (measured 1.3e-13), velocities within 1e-12 of the fastest wheel's speed, the scale the
    # state's velocities are rounded at (re-expressed against the reference speed: measured
    # 1e-13), forces (stiffness times deflection) within 1e-10 of the largest (measured 5e-12)
    gen = one.turbine.loads["rotor_speed_rpm"].max() * 2 * math.pi / 60 \
        * abs(sc.model.bodies["generator"].speed_ratio)
    for name, scale, tol in (("q", None, 1e-12), ("v", gen, 1e-12), ("forces", None, 1e-10)):
        a = getattr(one.gearbox, name).to_numpy()
        b = getattr(chopped.gearbox, name).to_numpy()
        assert np.abs(a - b).max() < tol * (scale or np.abs(a).max()), name
    la, lb = one.turbine.loads.to_numpy(float), chopped.turbine.loads.to_numpy(float)
    assert (np.abs(la - lb).max(axis=0) / (np.abs(la).max(axis=0) + 1e-300)).max() < 1e-12


def test_the_low_speed_shafts_torque_in_openfasts_channels(parts, cut_in_run):
    """``DrivetrainResult.openfast``: the turbine's OpenFAST channels and ``LSShftTq`` (kN-m),
    the main shaft element's torque. Against the rotor's own balance (independent of the
    gearbox's forces): the shaft carries the aerodynamic torque less what accelerates the
    rotor, ``T_shaft = T_aero - J_rotor d(omega)/dt``, on the turbine's rows after cut-in."""
    tb, gb = parts
    coupled, _ = cut_in_run
    of = coupled.openfast(gear_ratio=tb.gear_ratio)
    assert of.attrs["units"]["LSShftTq"] == "kN-m" and "GenPwr" in of
    late = of[of.index > coupled.cut_in_time + 0.5]
    t = late.index.to_numpy()
    omega = late.RotSpeed.to_numpy() * math.pi / 30.0
    j_rotor = gb.bodies["rotor"].inertia
    balance = late.RtAeroMxh.to_numpy() - j_rotor * np.gradient(omega, t)
    shaft = late.LSShftTq.to_numpy() * 1e3
    assert np.mean(shaft) > 0  # the rotor drives the gearbox
    assert np.mean(shaft) == pytest.approx(np.mean(balance), rel=0.01)
    assert np.abs(shaft - balance).max() < 0.05 * np.abs(balance).max()
    with pytest.raises(gm.ModelError, match="^shaft = 'nope'"):
        coupled.openfast(gear_ratio=tb.gear_ratio, shaft="nope")
