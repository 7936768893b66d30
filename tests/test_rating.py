"""The rating of a whole model (gearmodal.rating.gearbox) and its inputs, report and command."""

import math
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest

import gearmodal as gm
from gearmodal.cli import main

NREL = "studies/models/nrel5mw.toml"
#: the steady run's input torque, N m
STEADY = 1.5e6


@pytest.fixture(scope="module")
def nrel():
    return gm.load(NREL)


@pytest.fixture(scope="module")
def rated(nrel):
    return gm.rate(nrel, gravity=False)


def test_every_gear_of_the_three_stages_is_rated(rated):
    g = rated.gears
    assert set(g.gear) == {"stage1.sun", "stage1.planet", "stage1.ring", "stage2.sun",
                           "stage2.planet", "stage2.ring", "stage3.gear", "stage3.pinion"}
    assert len(g) == 10  # a planet in its sun mesh and in its ring mesh
    assert np.all((g.S_H > 0.3) & (g.S_H < 10) & (g.S_F > 0.3) & (g.S_F < 10))


def test_the_loads_are_the_torque_through_the_stages(nrel, rated):
    """The pinion torque of each mesh is the input torque through the stage ratios: the sun's
    torque shared by three planets (no gravity: equal sharing, the model's K_gamma 1)."""
    g = rated.gears.set_index(["mesh", "member"])
    t = 4.18e6
    sun1 = t / (1 + 56 / 19)
    # stage 1's sun-planet pinion is the planet (17 < 19 teeth): its torque is the sun's share
    # times the planet's over the sun's base radius
    r = nrel.bodies
    tp = sun1 / 3 * r["stage1.planet1"].base_radius / r["stage1.sun"].base_radius
    assert g.loc[("stage1.sun_planet", "pinion"), "torque_Nm"] == pytest.approx(tp, rel=1e-6)
    sun2 = sun1 / (1 + 93 / 18)
    assert g.loc[("stage2.sun_planet", "pinion"), "torque_Nm"] == pytest.approx(sun2 / 3,
                                                                                 rel=1e-6)
    pinion3 = sun2 * 24 / 95
    assert g.loc[("stage3.mesh", "pinion"), "torque_Nm"] == pytest.approx(pinion3, rel=1e-6)
    assert np.allclose(rated.gears.K_gamma_model, 1.0, atol=1e-6)
    # IEC 61400-4's K_gamma for three planets on the planetary meshes, 1 on the parallel one
    assert set(g.loc["stage1.sun_planet", "K_gamma"]) == {1.1}
    assert set(g.loc["stage3.mesh", "K_gamma"]) == {1.0}


def test_cycles_follow_the_kinematics(nrel, rated):
    """A sun meets its three planets once each per revolution against the carrier; a planet
    one mesh per revolution of its own; over 20 years at 12.1 rpm."""
    g = rated.gears.set_index(["mesh", "gear"])
    minutes = 175200.0 * 60.0
    sun = nrel.bodies["stage1.sun"].speed_ratio - 1.0
    assert g.loc[("stage1.sun_planet", "stage1.sun"), "cycles"] == pytest.approx(
        abs(sun) * 12.1 * minutes * 3, rel=1e-12)
    planet = nrel.bodies["stage1.planet1"].speed_ratio - 1.0
    assert g.loc[("stage1.sun_planet", "stage1.planet"), "cycles"] == pytest.approx(
        abs(planet) * 12.1 * minutes, rel=1e-12)
    assert abs(planet) == pytest.approx(56 / 17, rel=1e-12)
    assert g.loc[("stage1.ring_planet", "stage1.planet"), "Y_M"] == 0.7
    assert g.loc[("stage1.sun_planet", "stage1.sun"), "Y_M"] == 1.0


def test_operating_pressure_angles_are_the_models(nrel, rated):
    """The profile shifts of the [rating] table give each mesh the operating pressure angle
    the model's centre distances give (the ring's x with ISO 21771's sign)."""
    g = rated.gears.drop_duplicates("mesh").set_index("mesh")
    for mesh in ("stage1.sun_planet1", "stage1.ring_planet1", "stage2.ring_planet1",
                 "stage3.mesh"):
        group = mesh.rstrip("123") if mesh != "stage3.mesh" else mesh
        want = math.degrees(nrel.meshes[mesh].pressure_angle)
        assert g.loc[group, "alpha_wt_deg"] == pytest.approx(want, abs=0.01)


def test_bearings_carry_the_mesh_forces(nrel):
    r = gm.rate(nrel)
    b = r.bearings.set_index("bearing")
    assert len(b) == 10 and np.all(np.isfinite(b.L10m_h) & (b.L10m_h > 0))
    # a planet's bearing (no gravity): the sun's and the ring's mesh forces F on it, each on
    # its line of action at its operating pressure angle to the tangent, inward and outward
    flat = gm.rate(nrel, gravity=False)
    g = flat.gears.set_index(["mesh", "member"])
    f = g.loc[("stage1.sun_planet", "pinion"), "torque_Nm"] / nrel.bodies[
        "stage1.planet1"].base_radius
    a1 = nrel.meshes["stage1.sun_planet1"].pressure_angle
    a2 = nrel.meshes["stage1.ring_planet1"].pressure_angle
    want = f * math.hypot(math.cos(a1) + math.cos(a2), math.sin(a1) - math.sin(a2))
    loads = flat.bearings.set_index("bearing").loc[
        [f"stage1.planet{i}_bearing" for i in (1, 2, 3)], "radial_load_N"]
    # (plus the planet's centrifugal force at 12.1 rpm, m w^2 r_c = 0.95 kN, mostly across the
    # resultant: 6e-5 of it)
    assert np.allclose(loads, want, rtol=2e-4)
    # gravity moves each planet's share (the carrier's azimuth 0), not the mean much
    assert b.loc[[f"stage1.planet{i}_bearing" for i in (1, 2, 3)],
                 "radial_load_N"].mean() == pytest.approx(want, rel=0.01)
    # the planet bearing turns at the planet's speed against the carrier
    assert b.loc["stage1.planet1_bearing", "speed_rpm"] == pytest.approx(12.1 * 56 / 17)


def test_the_rating_table_round_trips_and_leaves_the_identity(nrel, tmp_path):
    again = gm.loads(gm.dumps(nrel))
    assert again.rating == nrel.rating
    assert gm.dumps(nrel, rating=False) == gm.dumps(gm.loads(gm.dumps(nrel, rating=False)),
                                                     rating=False)
    assert "[rating]" not in gm.dumps(nrel, rating=False)


@pytest.mark.parametrize("extra, field", [
    ("[rating]\nlife = 3\n", "rating.life"),
    ("[rating]\nk_gamma = 0.5\n", "rating.k_gamma"),
    ("[rating.gears.nope]\nprofile_shift = 0.1\n", "rating.gears.nope"),
    ("[rating.bearings.\"x*\"]\nC = 1e6\n", "rating.bearings.x*"),
    ("[rating.bearings.bearing_b]\npitch_diameter = 0.1\n", "rating.bearings.bearing_b.C"),
    ("[rating.gears.pinion]\nprofile_shift = 4\n", "rating.gears.pinion.profile_shift"),
])
def test_bad_rating_data_is_refused_by_name(extra, field):
    text = open("studies/models/gear_pair.toml").read() + "\n" + extra
    with pytest.raises(gm.ModelError) as e:
        gm.loads(text)
    assert e.value.field == field


def test_a_model_without_its_data_says_what_is_missing():
    m = gm.load("studies/models/600kw.toml")
    with pytest.raises(gm.ModelError, match="input_torque"):
        gm.rate(m)
    r = gm.rate(m, 2.6e5)
    assert len(r.gears) == 8 and r.bearings.empty
    with pytest.raises(gm.ModelError, match="rated_speed_rpm"):
        gm.rate(gm.load("studies/models/gear_pair.toml"), 100.0)
    with pytest.raises(gm.ModelError, match="face_width"):
        gm.rate(gm.load("studies/models/gear_pair.toml"), 100.0, speed_rpm=1000.0)


def test_k_gamma_choices(nrel, rated):
    model = gm.rate(nrel, k_gamma="model", gravity=False).gears
    assert np.allclose(model.K_gamma, model.K_gamma_model)
    planetary = rated.gears["mesh"].str.contains("planet").to_numpy()
    # the equilibrium shares equally (K_gamma 1) where IEC 61400-4 assumes 1.1
    assert np.all(model.S_H.to_numpy()[planetary] > rated.gears.S_H.to_numpy()[planetary])
    assert np.allclose(model.S_H.to_numpy()[~planetary], rated.gears.S_H.to_numpy()[~planetary])


def test_report_and_command(tmp_path, capsys):
    assert main(["rate", NREL, "--out", str(tmp_path / "r")]) == 0
    out = capsys.readouterr().out
    assert "rated 10 gears and 10 bearings" in out
    g = pd.read_csv(tmp_path / "r" / "gears.csv", comment="#")
    b = pd.read_csv(tmp_path / "r" / "bearings.csv", comment="#")
    assert {"S_H", "S_F", "sigma_H_MPa"} <= set(g.columns) and "L10m_h" in b.columns
    assert (tmp_path / "r" / "index.html").read_text().count("<table") == 2
    assert (tmp_path / "r" / "rating.png").stat().st_size > 10_000
    r = subprocess.run([sys.executable, "-m", "gearmodal.cli", "rate",
                        "studies/models/600kw.toml", "--out", str(tmp_path / "s")],
                       capture_output=True, text=True)
    assert r.returncode == 2 and "rating.input_torque" in r.stderr
    assert main(["rate", NREL, "--out", str(tmp_path / "t"), "--k-gamma", "x"]) == 2


@pytest.fixture(scope="module")
def steady_run(nrel):
    """2 s of the 5 MW gearbox at 1.5 MN m (its first stage's flanks at 316 kN, under the
    level table's 400 kN) and its rated speed from the static equilibrium (no gravity): every
    flank force constant within a bin of the run's level table."""
    loads = gm.balance(nrel, {"rotor.torque": STEADY}, on="generator.torque")
    q0 = gm.equilibrium(nrel, loads, speed_rpm=12.1).q
    return gm.simulate(nrel, t_end=2.0, dt=1e-3, loads=loads, speed_rpm=12.1, q0=q0)


def test_a_steady_spectrum_rates_as_the_steady_load(nrel, steady_run):
    """Under a constant load the spectrum's equivalent safety factors are the steady rating's
    with the same factors (K_A = K_gamma = K_v = 1) at the same cycles, within the bin: the
    spectrum takes a bin's upper edge (at most 5 kN above a 100-316 kN force: its square root
    for S_H, itself for S_F); the planet bearings' lives from the exact equivalent load are
    the steady ones."""
    r = gm.rate(nrel, STEADY, result=steady_run, gravity=False)
    steady = gm.rate(nrel, STEADY, application_factor=1.0, k_gamma=1.0, dynamic_factor=1.0,
                     gravity=False)
    sp = r.spectrum.set_index(["mesh", "member"])
    st = steady.gears.set_index(["mesh", "member"])
    assert set(sp.flank) == {"front"}  # no back flank touches at a steady torque
    # the run's peaks over the steady rating's forces (the same torque): no dynamics to add
    assert np.allclose(sp.peak_over_steady, 1.0, atol=2e-3)
    assert np.allclose(sp.life_cycles, st.loc[sp.index, "cycles"], rtol=1e-3)
    ratio_h = (sp.S_H_spectrum / st.loc[sp.index, "S_H"]).to_numpy()
    ratio_f = (sp.S_F_spectrum / st.loc[sp.index, "S_F"]).to_numpy()
    # the bin's upper edge over the force: the stress's share of it (K_Hbeta, K_Halpha move a
    # little with the load: 1e-3)
    edge = (np.floor(sp.peak_force_N / 5e3) + 1) * 5e3
    share = (sp.peak_force_N / edge).to_numpy()
    assert np.all((ratio_h > np.sqrt(share) - 1e-3) & (ratio_h < 1.0 + 1e-6))
    assert np.all((ratio_f > share - 1e-3) & (ratio_f < 1.0 + 1e-6))
    b = r.bearings.set_index("bearing")
    planets = [f"stage{s}.planet{i}_bearing" for s in (1, 2) for i in (1, 2, 3)]
    assert np.allclose(b.loc[planets, "L10m_h_spectrum"], b.loc[planets, "L10m_h"], rtol=1e-4)
    assert b.drop(planets).L10m_h_spectrum.isna().all()  # their forces are not tracked


def test_a_clipped_spectrum_is_refused(nrel):
    """At the rated 4.18 MN m the first stage's flanks carry 880 kN, beyond the run's level
    table (400 kN): the spectrum would be clipped, so the rating refuses it by name."""
    loads = gm.balance(nrel, {"rotor.torque": 4.18e6}, on="generator.torque")
    q0 = gm.equilibrium(nrel, loads, speed_rpm=12.1).q
    sim = gm.simulate(nrel, t_end=0.2, dt=1e-3, loads=loads, speed_rpm=12.1, q0=q0)
    with pytest.raises(gm.ModelError, match="clipped"):
        gm.rate(nrel, result=sim)


def test_a_run_of_another_model_is_refused(nrel):
    pair = gm.load("studies/models/gear_pair.toml")
    sim = gm.simulate(pair, t_end=0.01, dt=1e-3, loads={"pinion.torque": 10.0,
                                                        "wheel.torque": -20.0})
    with pytest.raises(gm.ModelError, match="another model"):
        gm.rate(nrel, result=sim)


def test_a_run_rated_from_the_command_line(nrel, steady_run, tmp_path, capsys):
    steady_run.save(tmp_path / "run")
    assert main(["rate", NREL, "--out", str(tmp_path / "r"), "--run",
                 str(tmp_path / "run"), "--torque", str(STEADY)]) == 0
    assert "under the run's load spectrum" in capsys.readouterr().out
    sp = pd.read_csv(tmp_path / "r" / "spectrum.csv", comment="#")
    assert len(sp) == 10 and np.all(sp.S_H_spectrum > 1.0)


def test_a_fatigue_studys_output_is_rated(tmp_path, capsys):
    """`gearmodal rate STUDY_DIR`: the recorded 600 kW fatigue study's lifetime spectra rate
    the first stage per gearbox; double contact's clearance lowers every safety factor."""
    import json
    import shutil

    study = tmp_path / "fatigue"
    study.mkdir()
    shutil.copy("studies/results/fatigue/spectra.csv", study / "spectra.csv")
    (study / "study.json").write_text(json.dumps(
        {"study": "fatigue", "scene": "studies/scenes/600kw_turbine_10ms.toml"}))
    assert main(["rate", str(study), "--out", str(tmp_path / "r")]) == 0
    assert "clearance: lowest S_H" in capsys.readouterr().out
    t = pd.read_csv(tmp_path / "r" / "ratings.csv", comment="#")
    assert set(t.variant) == {"reference", "clearance"} and set(t["mesh"]) == {
        "stage1.sun_planet", "stage1.ring_planet"}
    ref = t[t.variant == "reference"].set_index(["mesh", "member"])
    cl = t[t.variant == "clearance"].set_index(["mesh", "member"])
    assert np.all(cl.S_H_spectrum < ref.S_H_spectrum) and np.all(cl.S_F_spectrum
                                                                 < ref.S_F_spectrum)
    (study / "study.json").write_text(json.dumps({"scene": "nowhere.toml"}))
    assert main(["rate", str(study), "--out", str(tmp_path / "s")]) == 2
