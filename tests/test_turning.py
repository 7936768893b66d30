"""Exact turning points (gearmodal/integrate/turns.py, the kernel's poly_turns) and the DELs
counted from them (issue 34 item 3)."""

import math

import numpy as np
import pandas as pd
import pytest

import gearmodal as gm
from gearmodal.fatigue import damage_equivalent_load, turning_dels
from gearmodal.integrate.taylor import DEPTH, poly_turns

STAGE = "studies/scenes/planetary_double_contact.toml"


def series(rng, n):
    """Scaled Taylor coefficients like a piece's: three modes of up to 8 rad over [0, 1]."""
    k = np.arange(n)
    fact = np.array([float(math.factorial(int(x))) for x in k])
    c = np.zeros(n)
    for _ in range(3):
        A, w, ph = rng.normal(), rng.uniform(0, 8), rng.uniform(0, 6.3)
        c += A * np.real(np.exp(1j * ph) * (1j * w) ** k / fact)
    c[0] += 3 * rng.normal()
    return c


def turns(c, te):
    n = len(c)
    taus = np.empty(2 * n)
    cnt = poly_turns(c, n, te, taus, np.zeros(n), np.zeros(n), np.empty((DEPTH + 5) * n),
                     np.empty((2, DEPTH + 1)))
    return taus[:cnt]


def test_poly_turns_finds_every_extremum_of_random_series():
    """Against the polynomial sampled 200 001 times on [0, te]: every interior extremum of
    the samples (a sign change of their differences) has an exact extremum within two sample
    steps, and each exact one is a sample extremum's (none missed, none invented), with a
    value at least the samples' there for a maximum (at most, a minimum) and above it by at
    most the sampling's own miss (curvature 8^2 times the amplitude, half a step squared over
    2: 1e-9). 500 series of 5 to 40 terms (a double root at a sample's resolution excepted:
    pairs of extrema closer than 4 steps)."""
    rng = np.random.default_rng(7)
    checked = 0
    for _ in range(500):
        n = int(rng.integers(5, 41))
        c = series(rng, n)
        te = rng.uniform(0.3, 1.0)
        tau = turns(c, te)
        assert np.all(np.diff(tau) > 0) and np.all((tau > 0) & (tau < te))
        x = np.linspace(0.0, te, 200_001)
        y = np.polynomial.polynomial.polyval(x, c)
        d = np.sign(np.diff(y))
        idx = np.flatnonzero(d[1:] * d[:-1] < 0) + 1  # sampled extrema
        step = x[1]
        if len(idx) > 1 and np.min(np.diff(idx)) < 4:
            continue
        if len(tau) > 1 and np.min(np.diff(tau)) < 4 * step:
            continue
        assert len(tau) == len(idx), (n, te)
        np.testing.assert_allclose(tau, x[idx], atol=2 * step)
        vt = np.polynomial.polynomial.polyval(tau, c)
        scale = np.abs(y).max()
        is_max = d[idx - 1] > 0
        assert np.all(np.where(is_max, vt - y[idx], y[idx] - vt) >= -1e-13 * scale)
        assert np.all(np.abs(vt - y[idx]) <= 1e-9 * scale + 1e-13)
        checked += 1
    assert checked > 400


def test_a_monotone_or_flat_piece_has_no_turning_point():
    assert len(turns(np.array([1.0, 2.0, 0.5, 0.1, 0.01]), 1.0)) == 0
    assert len(turns(np.array([5.0, 1e-16, -1e-16, 1e-16]), 1.0)) == 0  # rounding, not a turn
    assert len(turns(np.array([0.0, 0.0, 1.0]), 1.0)) == 0  # the minimum at 0: not interior
    np.testing.assert_allclose(turns(np.array([0.0, -1.0, 1.0]), 1.0), [0.5], rtol=1e-15)


@pytest.fixture(scope="module")
def stage_runs():
    """The shipped double-contact stage (5 ms of its rattle at speed) at its output step, half
    it and with rows every 1 us (the dense reference)."""
    from gearmodal.scene import load_scene

    dt = load_scene(STAGE).dt
    runs = {x: load_scene(STAGE, overrides={"scene.t_end": 0.005, "scene.dt": x}).simulate()
            for x in (dt, dt / 2, 1e-6)}
    return dt, runs


def test_turning_points_do_not_depend_on_the_output_step(stage_runs):
    dt, runs = stage_runs
    a, b = runs[dt].turning_points, runs[dt / 2].turning_points
    assert len(a) > 100
    pd.testing.assert_frame_equal(a, b, check_exact=True)


def test_turning_points_hold_every_extreme_of_the_dense_rows(stage_runs):
    """Each channel's exact turning points against its rows every 1 us: every row lies within
    the range of the turning points around it (no extremum missed), the largest and smallest
    turning point are the exact extremes (at or beyond the rows', a maximum by at most the
    rows' own miss between samples), and the DELs converge to the exact one as the rows get
    denser."""
    dt, runs = stage_runs
    dense = runs[1e-6]
    tp = dense.turning_points
    f = dense.forces
    for ch, part in tp.groupby("channel", sort=False):
        if ch.endswith(".radial"):
            el = ch[:-len(".radial")]
            y = np.hypot(f[f"{el}.x"], f[f"{el}.y"]).to_numpy()
        else:
            y = f[ch].to_numpy()
        v = part["force_N"].to_numpy()
        scale = max(np.abs(y).max(), 1.0)
        assert v.max() >= y.max() - 1e-12 * scale and v.min() <= y.min() + 1e-12 * scale
        # (a minimum can be far below the rows: a flank's damping force pulls, k p + c p' < 0,
        # in the last microseconds before it opens, which the rows rarely catch)
        assert v.max() - y.max() <= 1e-4 * scale
    m = 8.7
    exact = turning_dels(dense, (m,))
    flanks = [c for c in exact.index if c.endswith(".front") and "ring" in c]
    for ch in flanks:
        e = float(exact.loc[ch].iloc[0])
        dense_del = damage_equivalent_load(f[ch], m)
        coarse_del = damage_equivalent_load(runs[dt].forces[ch], m)
        assert e > 0
        # the 1 us rows within 1e-4 of the exact count; the scene's rows further off
        assert abs(dense_del - e) <= 1e-4 * e, ch
        assert abs(coarse_del - e) >= abs(dense_del - e), ch


def test_turning_dels_refuse_what_they_cannot_count(stage_runs):
    dt, runs = stage_runs
    res = runs[dt]
    with pytest.raises(gm.ModelError, match="m = 0.5"):
        turning_dels(res, (0.5,))
    with pytest.raises(gm.ModelError, match="not a force channel"):
        turning_dels(res, (3.0,), channels=["nope.front"])
    other = gm.simulate(pair(), 0.002, dt=1e-4, method="newmark")
    assert other.turning_points is None and turning_dels(other, (3.0,)) is None


def pair():
    p = gm.Gear(20, 0.004, math.radians(20), mass=1.0, inertia=1e-3)
    w = gm.Gear(40, 0.004, math.radians(20), mass=4.0, inertia=1.6e-2)
    return gm.gear_pair(p, w, mesh_stiffness=2e8, backlash=1e-4)
