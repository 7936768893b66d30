"""Fatigue loads (gearmodal.fatigue, issue 22 item 1) against closed forms: the rainflow count
of the ASTM E1049 textbook sequence, the DEL of a cosine, the LDD and LRD of a constant torque,
the ISO 281 rating life of a constant and of a two-level load."""

import numpy as np
import pandas as pd
import pytest

import gearmodal as gm
from gearmodal import fatigue


def test_rainflow_count_of_the_astm_textbook_sequence():
    """ASTM E1049-85, Fig. 6: ranges 3, 4, 6, 8, 9 with counts 0.5, 1.5, 0.5, 1.0, 0.5."""
    c = fatigue.rainflow_cycles([-2, 1, -3, 5, -1, 3, -4, 4, -2])
    got = c.groupby("range")["count"].sum().to_dict()
    assert got == {3.0: 0.5, 4.0: 1.5, 6.0: 0.5, 8.0: 1.0, 9.0: 0.5}


@pytest.mark.parametrize("m", [3.0, 8.7, 13.2])
def test_del_of_a_cosine(m):
    """n periods of A cos: n cycles of range 2A, so DEL = 2 A (n / n_ref)^(1/m) (F1)."""
    A, n, n_ref = 3.0e4, 50, 1e7
    t = np.linspace(0.0, n, 40 * n + 1)
    got = fatigue.damage_equivalent_load(A * np.cos(2 * np.pi * t), m, n_ref)
    assert got == pytest.approx(2 * A * (n / n_ref) ** (1 / m), rel=1e-6)


def test_ldd_and_lrd_of_a_constant_torque():
    T, rpm, d = 2.6e5, 22.0, 30.0
    load = pd.Series(np.full(301, T), index=np.linspace(0.0, d, 301))
    edges = [0.0, 1e5, 2e5, 3e5]
    ldd = fatigue.load_duration(load, edges)
    lrd = fatigue.load_revolutions(load, rpm, edges)
    np.testing.assert_allclose(ldd.time_s, [0.0, 0.0, d], rtol=1e-12)
    np.testing.assert_allclose(lrd.revolutions, [0.0, 0.0, rpm * d / 60.0], rtol=1e-12)


def test_rating_life_of_a_constant_and_a_two_level_load():
    C, p, rpm = 5e5, 10 / 3, 300.0
    t = np.linspace(0.0, 10.0, 1001)
    life = fatigue.rating_life(pd.Series(np.full(t.size, 1e5), index=t), rpm, C, p)
    assert life["l10_million_revolutions"] == pytest.approx((C / 1e5) ** p, rel=1e-12)
    assert life["l10_h"] == pytest.approx(1e6 * (C / 1e5) ** p / (60 * rpm), rel=1e-12)
    two = np.where(np.arange(t.size) < 500, 1e5, 2e5)[:-1]  # equal time at each level
    two = pd.Series(two, index=t[:-1])
    eq = fatigue.rating_life(two, rpm, C, p)["equivalent_load_N"]
    assert eq == pytest.approx(((1e5**p + 2e5**p) / 2) ** (1 / p), rel=1e-12)


def test_damage_equivalent_loads_of_a_run_and_bad_input():
    stage = gm.examples.planetary_stage(
        ring_support={"stiffness": {"x": 1e9, "y": 1e9, "theta": 1e9}})
    loads = gm.balance(stage, {"carrier.torque": 2e3}, on="sun.torque")
    sim = gm.simulate(stage, 0.02, dt=1e-4, loads=loads, speed_rpm=300.0)
    d = sim.damage_equivalent_loads()
    assert set(d.kind) == {"tooth_root", "tooth_flank", "bearing"} and d.exact.all()
    # the exact count is the flank's turning points' (its first row the run's start)
    row = d[(d.load == "sun_planet1.front") & (d.kind == "tooth_root")].iloc[0]
    tp = sim.turning_points
    seq = tp.force_N[tp.channel == "sun_planet1.front"]
    assert seq.index[0] == 0.0 and seq.iloc[0] == sim.forces["sun_planet1.front"].iloc[0]
    assert row.del_N == pytest.approx(fatigue.damage_equivalent_load(seq, 8.7), rel=1e-12)
    # without turning points the rows are counted, and say so
    rows = gm.simulate(stage, 0.02, dt=1e-4, loads=loads, speed_rpm=300.0,
                       turning_points=False)
    assert rows.turning_points is None
    dr = rows.damage_equivalent_loads()
    row = dr[(dr.load == "sun_planet1.front") & (dr.kind == "tooth_root")].iloc[0]
    assert not dr.exact.any() and row.del_N == pytest.approx(
        fatigue.damage_equivalent_load(sim.forces["sun_planet1.front"], 8.7), rel=1e-12)
    with pytest.raises(gm.ModelError, match="m"):
        fatigue.damage_equivalent_load([0.0, 1.0, 0.0], 0.5)
    with pytest.raises(gm.ModelError, match="C"):
        fatigue.rating_life(pd.Series([1.0, 2.0], index=[0.0, 1.0]), 10.0, -1.0)
    assert np.isfinite(d.del_N).all() and (d.del_N >= 0).all()


def test_counting_on_the_turning_points_gives_the_same_cycles():
    """The count (fatigue._count, the three-point loop in numba) reads only the series'
    turning points (fatigue._reversals): on random walks with plateaus it gives exactly the
    cycles of the rainflow package, the reference, on every sample, in the same order."""
    import rainflow

    from gearmodal.fatigue import rainflow_cycles

    rng = np.random.default_rng(0)
    for _ in range(50):
        x = np.round(rng.standard_normal(rng.integers(3, 400)).cumsum(), 1)
        full = [(r, m, c) for r, m, c, _, _ in rainflow.extract_cycles(x)]
        np.testing.assert_allclose(rainflow_cycles(x).to_numpy(), np.array(full), rtol=0,
                                   atol=0)


def test_a_streamed_count_is_the_whole_count():
    """RainflowStream (chunks, only the residue kept) gives the cycles of the whole load:
    the ASTM sequence fed a point at a time, and 300 random loads with plateaus cut at random
    (a chunk of one point first) give the DELs of the whole series to 1e-12."""
    astm = [-2, 1, -3, 5, -1, 3, -4, 4, -2]
    st = fatigue.RainflowStream([1.0])
    for x in astm:
        st.feed([x])
    # m = 1: DEL * n_ref = sum of count * range = 3/2 + 4*3/2 + 6/2 + 8 + 9/2
    assert st.damage_equivalent_load(1.0, n_ref=1.0) == pytest.approx(23.0, rel=1e-15)
    rng = np.random.default_rng(0)
    for _ in range(300):
        n = int(rng.integers(2, 3000))
        x = np.round(np.cumsum(rng.normal(size=n)) + (rng.random(n) < 0.1) * 5, 1)
        x[rng.random(n) < 0.05] = x[0]
        st = fatigue.RainflowStream([3.0, 8.7])
        cuts = np.sort(np.concatenate([[1, 1], rng.integers(0, n, rng.integers(0, 20))]))
        for part in np.split(x, cuts):
            st.feed(part)
        for m in (3.0, 8.7):
            whole = fatigue.damage_equivalent_load(x, m)
            assert st.damage_equivalent_load(m) == pytest.approx(whole, rel=1e-12)
    with pytest.raises(gm.ModelError, match="two finite values"):
        one = fatigue.RainflowStream([3.0])
        one.feed([1.0])
        one.close()


def test_the_upper_percentile_of_chunks_is_numpys():
    """UpperPercentile keeps the largest values alone (1 % and two for the 99th) and gives
    np.percentile of all of them to the bit: random sizes, scales, ties, chunkings and
    percentiles, the ends included."""
    from gearmodal.fatigue import UpperPercentile

    rng = np.random.default_rng(7)
    for trial in range(400):
        n = int(rng.integers(1, 2500))
        x = rng.standard_normal(n) * 10 ** rng.uniform(-3, 6)
        if trial % 5 == 0:
            x = np.round(x, 1)  # ties
        for q in (99.0, 95.0, 50.0, 0.0, 100.0):
            p = UpperPercentile(n, q)
            for part in np.array_split(x, int(rng.integers(1, 12))):
                p.push(part)
            assert p.value() == np.percentile(x, q)
            assert p.top.size <= n - int((n - 1) * q / 100.0) + 1
