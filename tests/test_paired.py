"""Effects over paired seeds with confidence intervals (gearmodal.paired, (C1), (C2)) and the
studies that report them."""

import math

import numpy as np
import pandas as pd
import pytest
from scipy import stats

import gearmodal as gm
from gearmodal.cli import main
from gearmodal.paired import paired_ratio


def test_a_constant_factor_is_found_exactly_with_a_zero_width_interval():
    b = np.array([3.0, 7.0, 11.0, 2.0])
    r = paired_ratio(1.25 * b, b)
    assert r["ratio"] == pytest.approx(1.25, rel=1e-14)
    assert r["low"] == pytest.approx(1.25, rel=1e-14) and r["high"] == pytest.approx(1.25)
    assert r["differs"] and r["n"] == 4 and r["seeds_needed"] == 2


def test_interval_is_the_t_interval_of_the_mean_log_ratio():
    """(C1) against scipy's own t-interval of the log ratios; (C2): with that spread the
    interval excludes 1 from seeds_needed seeds on, not one seed earlier."""
    rng = np.random.default_rng(7)
    b = rng.uniform(1.0, 2.0, 8)
    a = b * np.exp(0.1 + 0.15 * rng.standard_normal(8))
    d = np.log(a / b)
    lo, hi = stats.t.interval(0.95, 7, loc=d.mean(), scale=stats.sem(d))
    r = paired_ratio(a, b)
    assert r["low"] == pytest.approx(math.exp(lo), rel=1e-12)
    assert r["high"] == pytest.approx(math.exp(hi), rel=1e-12)
    assert r["differs"] == (lo > 0 or hi < 0)
    k = r["seeds_needed"]
    sd, m = d.std(ddof=1), abs(d.mean())
    assert stats.t.ppf(0.975, k - 1) * sd / math.sqrt(k) < m
    assert stats.t.ppf(0.975, k - 2) * sd / math.sqrt(k - 1) >= m


def test_one_seed_and_zero_loads_give_no_interval_and_bad_input_is_named():
    r = paired_ratio([2.0], [1.0])
    assert r["ratio"] == 2.0 and math.isnan(r["low"]) and not r["differs"]
    r = paired_ratio([1.0, 0.0], [1.0, 1.0])  # no back-flank force in one run: no ratio
    assert math.isnan(r["ratio"]) and not r["differs"]
    with pytest.raises(gm.ModelError, match="paired_ratio"):
        paired_ratio([1.0, 2.0], [1.0])
    with pytest.raises(gm.ModelError, match="level"):
        paired_ratio([1.0, 2.0], [1.0, 2.0], level=1.5)


def test_study_double_contact_over_paired_seeds(tmp_path):
    """Shortened to 0.6 s on two seeds: every case on every seed, the means, the effects with
    intervals (the clearance's tooth DEL above the reference's on both seeds: the interval's
    ratio above 1), and the claims judged on them in the report."""
    out = tmp_path / "dcs"
    assert main(["study", "double-contact", "--duration", "0.6", "--seeds", "2", "--seed", "3",
                 "--out", str(out), "--quiet"]) == 0
    runs = pd.read_csv(out / "runs.csv")
    assert sorted(zip(runs.case, runs.seed, strict=True)) == sorted(
        (c, s) for c in ("reference", "clearance", "clearance_rot60") for s in (3, 4))
    eff = pd.read_csv(out / "effects.csv")
    row = eff[(eff.effect == "clearance / reference") & (eff.quantity == "del_tooth_N")].iloc[0]
    a = runs[runs.case == "clearance"].sort_values("seed").del_tooth_N.to_numpy()
    b = runs[runs.case == "reference"].sort_values("seed").del_tooth_N.to_numpy()
    assert row.ratio == pytest.approx(math.exp(np.mean(np.log(a / b))), rel=1e-12)
    assert row.ratio > 1 and row.n == 2
    s = pd.read_csv(out / "summary.csv", index_col="case")
    assert s.loc["clearance", "del_tooth_N"] == pytest.approx(a.mean(), rel=1e-12)
    html = __import__("html").unescape((out / "report.html").read_text())
    assert "The paper's claims on the intervals" in html and html.count("<li><b>") == 8
