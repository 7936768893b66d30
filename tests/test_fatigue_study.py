"""The design-load-case set (studies/fatigue.py, ``gearmodal study fatigue``): the IEC
normal turbulence model (D1), the Rayleigh hours (D2), the lifetime sums (D3) against closed
forms, and a shortened set through the CLI."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

import gearmodal as gm
from gearmodal.cli import _study_module, main
from gearmodal.fatigue import WOEHLER, drivetrain_fatigue
from gearmodal.turbine import simulate_drivetrain

fatigue = _study_module("fatigue", None)


def test_ntm_turbulence_intensity_and_rayleigh_hours():
    """(D1): IEC 61400-1's sigma_1 = I_ref (0.75 V + 5.6): 18.0 % at 15 m/s in category A
    (the standard's tabulated value), 14 % x (0.75 + 5.6 / V) in B. (D2): bins from 0 to far
    beyond cut-out hold the whole design life; the class II mean speed 8.5 m/s."""
    assert fatigue.turbulence_intensity(15.0, "A") == pytest.approx(0.16 * 16.85 / 15.0)
    assert fatigue.turbulence_intensity(15.0, "A") == pytest.approx(0.1797, abs=5e-5)
    v = np.arange(1.0, 101.0, 2.0)  # bins [0, 2], [2, 4], ... [98, 100]
    h = fatigue.bin_hours(v, "II")
    assert h.sum() == pytest.approx(20 * 8766.0, rel=1e-12)
    # the mean of the Rayleigh distribution (bin centres: within a bin width squared / 12)
    assert np.sum(h * v) / h.sum() == pytest.approx(8.5, abs=0.05)


def test_lifetime_sums_against_a_hand_calculation():
    """(D3) on two bins with two seeds each, made-up runs: the lifetime DEL is the m-th root
    of the damage per second of each run, averaged over its bin's seeds, times the bin's
    seconds; L10h from the revolution-weighted P_eq; spectra summed with the same weights."""
    runs = pd.DataFrame({
        "variant": ["a"] * 4, "wind_speed_mps": [6.0, 6.0, 12.0, 12.0], "seed": [1, 2, 1, 2],
        "duration_s": [100.0, 100.0, 50.0, 50.0],
        "del_tooth_N": [1e3, 2e3, 3e3, 5e3], "del_planet_bearing_N": [10.0, 20.0, 30.0, 40.0],
        "del_rotor_torque_Nm": [1.0, 1.0, 1.0, 1.0],
        "planet_bearing_revolutions": [100.0, 120.0, 60.0, 80.0],
        "planet_bearing_peq_N": [1e5, 1.2e5, 2e5, 3e5]})
    spec = pd.DataFrame({"quantity": ["x"], "level_low": [0.0], "level_high": [1.0],
                         "time_s": [10.0], "revolutions": [3.0]})
    life, s = fatigue.lifetime(runs, {i: spec for i in range(4)}, "II")
    h6, h12 = fatigue.bin_hours([6.0, 12.0], "II")
    w = np.array([h6 / 2 / 100, h6 / 2 / 100, h12 / 2 / 50, h12 / 2 / 50]) * 3600
    m = WOEHLER["tooth_root"]
    expect = np.sum(w * runs.del_tooth_N.to_numpy() ** m) ** (1 / m)
    assert life.loc["a", "del_tooth_N"] == pytest.approx(expect, rel=1e-12)
    p = WOEHLER["bearing"]
    n = runs.planet_bearing_revolutions.to_numpy()
    peq = (np.sum(w * n * runs.planet_bearing_peq_N.to_numpy() ** p) / np.sum(w * n)) ** (1 / p)
    assert life.loc["a", "planet_bearing_peq_N"] == pytest.approx(peq, rel=1e-12)
    l10h = (fatigue.BEARING_C / peq) ** p * 1e6 / (np.sum(w * n) / (h6 + h12))
    assert life.loc["a", "l10_planet_bearing_h"] == pytest.approx(l10h, rel=1e-12)
    assert s.hours.iloc[0] == pytest.approx(np.sum(w) * 10.0 / 3600.0, rel=1e-12)
    assert s.revolutions.iloc[0] == pytest.approx(np.sum(w) * 3.0, rel=1e-12)


def test_run_fatigue_of_a_constant_load_state():
    """A steady run (no turbulence, on the grid): the rotor torque's LRD puts all the rotor's
    revolutions (speed x time / 60) in the bins it visits, the 99th percentile lies below the
    peak, and L10 follows ISO 281 from the bearing's P_eq and revolutions."""
    tb = gm.turbine.load_turbine("studies/turbines/600kw_turbine.toml")
    gb = gm.load("studies/models/600kw.toml")
    res = simulate_drivetrain(tb, gm.turbine.Wind(mean_speed=11.0), gb, 1.5,
                              rotor_speed0_rpm=22.1, connected=True, top_frequency_hz=500.0)
    row = drivetrain_fatigue(res, bearing_C=2e6, planet_spin=99 / 39, t_skip=0.5)
    sp = row["tables"]["spectra"]
    tq = sp[sp.quantity == "rotor_torque_Nm"]
    speed = res.turbine.loads.rotor_speed_rpm[res.turbine.loads.index >= 0.5].mean()
    assert tq.revolutions.sum() == pytest.approx(speed * row["duration_s"] / 60, rel=5e-3)
    assert tq.time_s.sum() == pytest.approx(row["duration_s"], rel=1e-12)
    assert row["p99_tooth_force_N"] <= row["max_front_force_N"]
    l10h = (2e6 / row["planet_bearing_peq_N"]) ** (10 / 3) * 1e6 / (
        row["planet_bearing_revolutions"] / row["duration_s"] * 3600)
    assert row["l10_planet_bearing_h"] == pytest.approx(l10h, rel=1e-9)
    with pytest.raises(gm.ModelError, match="planet_spin"):
        drivetrain_fatigue(res, bearing_C=2e6, planet_spin=0.0, t_skip=0.5)
    with pytest.raises(gm.ModelError, match="t_skip"):
        drivetrain_fatigue(res, bearing_C=2e6, planet_spin=2.5, t_skip=10.0)
    with pytest.raises(gm.ModelError, match="bearing_C"):  # the exact path checks it too
        drivetrain_fatigue(res, bearing_C=-2e6, planet_spin=2.5, t_skip=0.5)


@pytest.mark.slow
def test_study_fatigue_shortened(tmp_path):
    """The quick set shortened to 16 s runs: both gearboxes on the same seeds, the columns
    the issue names, a lifetime table with the clearance/reference ratio, a report; the
    clearance gearbox's tooth DEL above the reference's (double contact), the rotor torque's
    the same to 2 % (the gearboxes differ inside, not in the aerodynamics)."""
    out = tmp_path / "fat"
    assert main(["study", "fatigue", "--quick", "--duration", "16", "--out", str(out),
                 "--quiet"]) == 0
    s = pd.read_csv(out / "summary.csv")
    for col in ("variant", "wind_speed_mps", "seed", "del_tooth_N", "del_planet_bearing_N",
                "l10_planet_bearing_h"):
        assert col in s and s[col].notna().all()
    assert sorted(set(zip(s.variant, s.wind_speed_mps, s.seed, strict=True))) == sorted(
        (v, w, 1) for v in ("reference", "clearance") for w in (6.0, 12.0, 18.0))
    life = pd.read_csv(out / "lifetime.csv", index_col="variant")
    assert list(life.index) == ["reference", "clearance", "clearance / reference"]
    assert life.loc["clearance", "del_tooth_N"] > life.loc["reference", "del_tooth_N"]
    assert life.loc["clearance / reference", "del_rotor_torque_Nm"] == pytest.approx(1, abs=0.02)
    assert (out / "report.html").exists() and (out / "fatigue.png").stat().st_size > 10_000
    assert math.isfinite(life.loc["reference", "l10_planet_bearing_h"])


def test_lifetime_ratios_over_the_seeds_against_a_hand_calculation():
    """Two gearboxes on three seeds, made-up runs in two bins: the interval's ratio is the
    geometric mean of the per-seed lifetime ratios (each seed's (D3) alone), its bounds the
    Student-t interval (C1) of their logarithms; the pooled ratio is lifetime()'s."""
    from scipy import stats

    rows = []
    rng = np.random.default_rng(3)
    for variant, f in (("reference", 1.0), ("clearance", 1.4)):
        for v in (6.0, 12.0):
            for sd in (1, 2, 3):
                rows.append({"variant": variant, "wind_speed_mps": v, "seed": sd,
                             "duration_s": 100.0,
                             "del_tooth_N": f * v * 100 * (1 + 0.1 * rng.normal()),
                             "del_planet_bearing_N": f * v * 10 * (1 + 0.1 * rng.normal()),
                             "del_rotor_torque_Nm": v, "planet_bearing_revolutions": 50.0,
                             "planet_bearing_peq_N": 1e5 * f})
    runs = pd.DataFrame(rows)
    spec = pd.DataFrame({"quantity": ["x"], "level_low": [0.0], "level_high": [1.0],
                         "time_s": [10.0], "revolutions": [3.0]})
    spectra = {i: spec for i in runs.index}
    r = fatigue.lifetime_ratios(runs, spectra, "II")
    per = []
    for sd in (1, 2, 3):
        g = runs[runs.seed == sd]
        life, _ = fatigue.lifetime(g, {i: spec for i in g.index}, "II")
        per.append(np.log(life.loc["clearance", "del_tooth_N"]
                          / life.loc["reference", "del_tooth_N"]))
    d = np.array(per)
    half = stats.t.ppf(0.975, 2) * d.std(ddof=1) / math.sqrt(3)
    row = r.loc["del_tooth_N"]
    assert row.ratio == pytest.approx(math.exp(d.mean()), rel=1e-12)
    assert (row.low, row.high) == pytest.approx((math.exp(d.mean() - half),
                                                 math.exp(d.mean() + half)), rel=1e-12)
    pooled, _ = fatigue.lifetime(runs, spectra, "II")
    assert row.pooled == pytest.approx(pooled.loc["clearance", "del_tooth_N"]
                                       / pooled.loc["reference", "del_tooth_N"], rel=1e-12)
    assert r.loc["planet_bearing_peq_N", "ratio"] == pytest.approx(1.4, rel=1e-12)
    assert row.n == 3 and bool(row.differs)


@pytest.mark.slow
def test_study_fatigue_on_a_dask_local_cluster(tmp_path):
    """The set on the sweep's executors: a Dask LocalCluster (two worker processes) runs a
    shortened set with two paired seeds, the same rows as the local process pool's to 1e-12
    (the same runs: the result does not depend on where a case runs), and writes the
    lifetime ratios with their intervals over the seeds."""
    distributed = pytest.importorskip("distributed", reason="the dask extra (CI installs it)")
    kw = dict(quick=True, duration=16.0, seeds=2, progress=False)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        fatigue.run(tmp_path / "dask", executor=client.get_executor(), **kw)
    fatigue.run(tmp_path / "local", max_workers=1, **kw)
    a = pd.read_csv(tmp_path / "dask" / "summary.csv")
    b = pd.read_csv(tmp_path / "local" / "summary.csv")
    assert len(a) == 12 and sorted(a.seed.unique()) == [1, 2]
    num = [c for c in a.columns if c != "variant" and c != "cpu_s"
           and pd.api.types.is_numeric_dtype(a[c])]
    np.testing.assert_allclose(a[num].to_numpy(), b[num].to_numpy(), rtol=1e-12)
    r = pd.read_csv(tmp_path / "dask" / "lifetime_ratios.csv", index_col="quantity")
    assert list(r.index) == list(fatigue.RATIOS)
    assert (r.n == 2).all() and np.isfinite(r[["low", "high"]].to_numpy()).all()
    # the clearance's rattle raises the tooth DEL on both seeds; the rotor torque's the same
    assert r.loc["del_tooth_N", "ratio"] > 1.05
    assert r.loc["del_rotor_torque_Nm", "ratio"] == pytest.approx(1.0, abs=0.02)


def test_the_first_stage_rated_under_the_lifetime_tooth_force_spectrum():
    """The lifetime LRD of the largest tooth force rates the first stage's gears (ISO 6336-6,
    gearmodal.rating.rate_spectrum): a spectrum on one level rates as the steady load at that
    level's upper force over the same cycles (K_A = K_gamma = K_v = 1), gear by gear; a stronger
    spectrum rates lower; a table without that spectrum rates nothing (NaN)."""
    from gearmodal.rating import rate, rate_spectrum

    edges = np.linspace(0.0, 4e5, 81)
    revs = np.zeros(80)
    revs[20] = 4e7  # 20 years of a rotor at ~22 rpm, all at 100-105 kN
    base = pd.DataFrame({"variant": "a", "quantity": "tooth_force_N", "level_low": edges[:-1],
                         "level_high": edges[1:], "hours": 1.0, "revolutions": revs})
    one = fatigue.ratings(base, 175200.0)
    model = fatigue._rated_model()
    per_gear = rate_spectrum(model, base, meshes=list(fatigue.RATED), hours=175200.0)
    assert one["S_H_stage1"] == pytest.approx(per_gear.S_H_spectrum.min(), rel=1e-12)
    # the steady load of 105 kN on every first-stage flank: the rotor torque that puts it on
    # each of the three sun-planet meshes (F the normal force, its transverse part
    # F cos(beta_b)), T = F cos(beta_b) N r_b,sun (1 + z_ring / z_sun)
    sun, ring = model.bodies["stage1.sun"], model.bodies["stage1.ring"]
    torque = (105e3 * math.cos(sun.base_helix_angle) * 3 * sun.base_radius
              * (1 + ring.teeth / sun.teeth))
    rpm = 4e7 / (175200.0 * 60.0)
    steady = rate(model, torque, speed_rpm=rpm, life_h=175200.0, application_factor=1.0,
                  k_gamma=1.0, dynamic_factor=1.0, gravity=False).gears
    steady = steady[steady["mesh"].isin(fatigue.RATED)]
    assert np.allclose(per_gear.S_H_spectrum, steady.S_H, rtol=1e-6)
    assert np.allclose(per_gear.S_F_spectrum, steady.S_F, rtol=1e-6)
    stronger = base.assign(level_low=base.level_low * 1.25, level_high=base.level_high * 1.25)
    two = fatigue.ratings(stronger, 175200.0)
    assert two["S_H_stage1"] < one["S_H_stage1"] and two["S_F_stage1"] < one["S_F_stage1"]
    assert 1.0 < one["S_H_stage1"] < 10.0 and 1.0 < one["S_F_stage1"] < 10.0
    nothing = fatigue.ratings(base.assign(quantity="x"), 175200.0)
    assert all(math.isnan(v) for v in nothing.values())
