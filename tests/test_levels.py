"""Exact level changes and load integrals (gearmodal/integrate/turns.py, the kernel's
_level_segment and _load_integrals) and the load spectra and bearing lives computed from them
(gearmodal.fatigue.level_spectrum, equivalent_loads; issue 34 item 3)."""

import copy

import numpy as np
import pandas as pd
import pytest
from scipy.integrate import simpson

import gearmodal as gm
from gearmodal.fatigue import LEVELS, equivalent_loads, level_spectrum, load_duration

STAGE = "studies/scenes/planetary_double_contact.toml"
DENSE = 1e-6  # s, the reference rows' step


@pytest.fixture(scope="module")
def turning_runs():
    """The same stage with its carrier turning at 22 rpm (the input's speed never crosses zero,
    so the dense rows' Simpson rule is a reference to about 1e-12): at the scene's output step,
    five times it and every 1 us."""
    from gearmodal.scene import load_scene

    dt = load_scene(STAGE).dt
    over = {"scene.t_end": 0.005, "scene.speed_rpm": 22.0}
    runs = {x: load_scene(STAGE, overrides={**over, "scene.dt": x}).simulate()
            for x in (dt, 5 * dt, DENSE)}
    return dt, runs


@pytest.fixture(scope="module")
def stage_runs():
    """The shipped double-contact stage (5 ms of its rattle at speed, the carrier its input)
    at its output step, five times it and with rows every 1 us (the dense reference)."""
    from gearmodal.scene import load_scene

    dt = load_scene(STAGE).dt
    runs = {x: load_scene(STAGE, overrides={"scene.t_end": 0.005, "scene.dt": x}).simulate()
            for x in (dt, 5 * dt, DENSE)}
    return dt, runs


def flanks(res):
    return [c for c in res.force_columns() if c.endswith((".front", ".back"))]


def revolutions_of_rows(w, t):
    """The trapezoid rule on ``|w|`` (rev/s at the rows ``t``) with the zeros of its linear
    interpolant added as samples (exact for a speed linear between rows, through zero too)."""
    k = np.flatnonzero(w[:-1] * w[1:] < 0)
    tz = t[k] - w[k] * (t[k + 1] - t[k]) / (w[k + 1] - w[k])
    t, w = np.insert(t, k + 1, tz), np.insert(w, k + 1, 0.0)
    return np.trapezoid(np.abs(w), t)


def input_speed(res):
    """The carrier's absolute speed at the rows (rad/s): its reference speed plus its
    deflection's rate."""
    return res.settings["speed_rpm"] * np.pi / 30 + res.v["carrier.theta"].to_numpy()


def test_level_changes_do_not_depend_on_the_output_step(stage_runs):
    dt, runs = stage_runs
    a, b = runs[dt].level_changes, runs[5 * dt].level_changes
    assert len(a) > 100 and set(a.channel) >= set(flanks(runs[dt]))
    pd.testing.assert_frame_equal(a, b, check_exact=True)
    pa, pb = runs[dt].peak_bins, runs[5 * dt].peak_bins
    pd.testing.assert_frame_equal(pa, pb, check_exact=True)


def test_level_spectrum_against_the_dense_rows(stage_runs):
    """The largest flank force's time in each level bin against the 1 us rows' (each sample
    standing for its trapezoid share): they differ by at most a sample step at each entry to
    and exit from the bin (a crossing is placed to rounding, the rows to within a step); the
    exact spectrum is the same at the scene's output step and five times it, and its times add
    up to the span."""
    dt, runs = stage_runs
    dense = runs[DENSE]
    fl = flanks(dense)
    exact = level_spectrum(dense, fl)
    for x in (dt, 5 * dt):
        pd.testing.assert_frame_equal(level_spectrum(runs[x], fl), exact, check_exact=True)
    top = dense.forces[fl].max(axis=1).clip(LEVELS["tooth_force_N"][0],
                                             LEVELS["tooth_force_N"][-1])
    rows = load_duration(top, LEVELS["tooth_force_N"])
    # entries and exits of each bin: the changes of the largest's bin, from the dense rows
    k = np.clip(np.searchsorted(LEVELS["tooth_force_N"], top.to_numpy(), side="right") - 1,
                0, len(LEVELS["tooth_force_N"]) - 2)
    moves = np.flatnonzero(np.diff(k))
    crossings = np.bincount(k[moves], minlength=len(rows)) \
        + np.bincount(k[moves + 1], minlength=len(rows))
    assert (exact.time_s > 0).sum() > 10
    assert np.all(np.abs(exact.time_s - rows.time_s) <= (crossings + 1) * DENSE)


def test_load_integrals_against_the_dense_rows(turning_runs):
    """Every planet bearing's ``int F^p dN`` over the carrier's revolutions (its own speed,
    every piece's series) against Simpson's rule on the 1 us rows: equal to 1e-9 (Simpson's
    error on these rows is about 1e-12); the input's revolutions likewise, and the equivalent
    loads follow from them."""
    dt, runs = turning_runs
    dense = runs[DENSE]
    f, t = dense.forces, dense.forces.index.to_numpy()
    n = np.abs(input_speed(dense)) / (2 * np.pi)  # rev/s
    bins = dense.peak_bins.set_index("channel")
    bearings = dense.elements_of("planet_bearing")
    assert bearings
    for b in bearings:
        F = np.hypot(f[f"{b}.x"], f[f"{b}.y"]).to_numpy()
        row = bins.loc[f"{b}.radial"]
        for p, col in ((3.0, "int_F3_dN"), (10 / 3, "int_F10_3_dN")):
            assert row[col] == pytest.approx(simpson(F ** p * n, x=t), rel=1e-9)
        assert row["input_revolutions"] == pytest.approx(simpson(n, x=t), rel=1e-9)
    peq = equivalent_loads(dense, 10 / 3)
    for b in bearings:
        F = np.hypot(f[f"{b}.x"], f[f"{b}.y"]).to_numpy()
        ref = (simpson(F ** (10 / 3) * n, x=t) / simpson(n, x=t)) ** 0.3
        assert peq.loc[f"{b}.radial", "equivalent_load_N"] == pytest.approx(ref, rel=1e-9)
    pd.testing.assert_frame_equal(equivalent_loads(runs[dt], 10 / 3),
                                  equivalent_loads(runs[5 * dt], 10 / 3), check_exact=True)


def test_level_revolutions_are_the_inputs(turning_runs, stage_runs):
    """The revolution distribution's bins add up to the input's revolutions over the span (the
    mark at the run's end), as the 1 us rows' speed integrates: Simpson's rule at 22 rpm; at
    standstill, where the carrier swings through zero speed, the trapezoid rule on the rows
    split where their speed changes sign (its error: the speed's curvature, about 0.7 rad/s at
    a kilohertz of rattle, times the step squared over 12, 7e-6 of the total; the revolutions
    taken as |A(te)| per piece, without the zeros, were 3 % short)."""
    for runs, tol in ((turning_runs[1], 1e-9), (stage_runs[1], 2e-5)):
        dense = runs[DENSE]
        b = dense.elements_of("planet_bearing")[0]
        spec = level_spectrum(dense, [f"{b}.radial"])
        w = input_speed(dense) / (2 * np.pi)
        t = dense.forces.index.to_numpy()
        ref = simpson(w, x=t) if np.all(w > 0) else revolutions_of_rows(w, t)
        assert spec.revolutions.sum() == pytest.approx(ref, rel=tol)
        # the mark at the run's end (the series' antiderivative between the speed's zeros)
        # against the peak bins' quadrature of the same speed (Gauss-Legendre)
        marks = dense.level_changes.query("channel == 'input'")
        assert marks.index[-1] == pytest.approx(0.005, rel=1e-12)
        pb = dense.peak_bins
        quad = pb[pb.channel == f"{b}.radial"].input_revolutions.sum()
        assert marks["input_revolutions"].iloc[-1] == pytest.approx(quad, rel=1e-12)


def test_level_tables_survive_save_and_load(stage_runs, tmp_path):
    dt, runs = stage_runs
    res = runs[dt]
    res.save(tmp_path / "r")
    back = gm.SimulationResult.load(tmp_path / "r")
    pd.testing.assert_frame_equal(back.level_changes, res.level_changes, check_exact=True,
                                  check_dtype=False, check_index_type=False)
    fl = flanks(res)
    pd.testing.assert_frame_equal(level_spectrum(back, fl), level_spectrum(res, fl),
                                  check_exact=True)
    pd.testing.assert_frame_equal(equivalent_loads(back, 3.0), equivalent_loads(res, 3.0),
                                  check_exact=True)


def test_level_spectrum_of_a_stored_run_in_constant_memory(stage_runs, tmp_path, monkeypatch):
    """A stored run is swept a row group at a time: in row groups of 64 rows (82 of them) the
    spectrum is the in-memory run's to the bit and the sweep's peak allocation stays below
    half the table's size (the whole-table sweep took 2.6 times it); a table whose rows are
    not in time order (each channel's are: as runs wrote them before the table was sorted)
    is swept whole, to the same spectrum."""
    import tracemalloc

    from gearmodal import result_io

    dt, runs = stage_runs
    res = runs[dt]
    lc = res.level_changes
    assert lc.index.is_monotonic_increasing
    monkeypatch.setattr(result_io, "GROUP_ROWS", 64)
    res.save(tmp_path / "r")
    back = gm.SimulationResult.load(tmp_path / "r")
    assert sum(1 for _ in back.level_chunks()) > 50
    fl = flanks(res)
    spans = ((0.0, None), (0.001, 0.004), (0.0012345, 0.0043))
    for t_from, t_to in spans:
        pd.testing.assert_frame_equal(level_spectrum(back, fl, t_from=t_from, t_to=t_to),
                                      level_spectrum(res, fl, t_from=t_from, t_to=t_to),
                                      check_exact=True)
    tracemalloc.start()
    level_spectrum(back, fl)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert peak < 0.5 * lc.memory_usage(deep=True).sum()
    old = lc.reset_index().sort_values(["channel", "time"], kind="stable").set_index("time")
    assert not old.index.is_monotonic_increasing
    legacy = copy.copy(res)
    legacy.level_changes = old
    for t_from, t_to in spans:
        a = level_spectrum(legacy, fl, t_from=t_from, t_to=t_to)
        b = level_spectrum(res, fl, t_from=t_from, t_to=t_to)
        np.testing.assert_allclose(a.to_numpy(), b.to_numpy(), rtol=1e-12, atol=1e-18)


def test_what_the_exact_statistics_cannot_give(stage_runs):
    dt, runs = stage_runs
    res = runs[dt]
    assert equivalent_loads(res, 2.5) is None  # an exponent the run has no integral of
    assert equivalent_loads(res, 3.0, t_from=0.0015) is None  # off the peak bins' grid
    with pytest.raises(gm.ModelError, match="no level changes of that channel"):
        level_spectrum(res, ["nope.front"])
    off = gm.scene.load_scene(STAGE, overrides={"scene.t_end": 0.001}).model
    plain = gm.simulate(off, 0.001, dt=dt, speed_rpm=600.0, turning_points=False)
    assert plain.level_changes is None and level_spectrum(plain, flanks(plain)) is None
    assert equivalent_loads(plain, 3.0) is None


def test_turbine_fatigue_row_does_not_depend_on_the_output_step():
    """The clearance gearbox in the turbine, 2 s counted from 1 s: ``drivetrain_fatigue`` at
    output steps of 1 and 4 ms gives the same DELs, planet-bearing P_eq, life and revolutions
    and the same tooth and bearing spectra, to the bit (all from the exact solution: the
    99th percentiles alone are of the rows)."""
    import sys
    from pathlib import Path

    from gearmodal.fatigue import drivetrain_fatigue
    from gearmodal.scene import load_scene
    from gearmodal.turbine import simulate_drivetrain

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "studies"))
    from double_contact import CLEARANCE

    sc = load_scene("studies/scenes/600kw_turbine_10ms.toml",
                    overrides={"model.stages.0.carrier_bearing": CLEARANCE})
    kw = {**sc.drivetrain, "top_frequency_hz": 500.0}
    rows = {}
    for dt in (1e-3, 4e-3):
        res = simulate_drivetrain(sc.turbine, sc.wind, sc.model, 3.0, dt=dt, **kw)
        rows[dt] = drivetrain_fatigue(res, bearing_C=2e6, planet_spin=99 / 39, t_skip=1.0)
    a, b = rows[1e-3], rows[4e-3]
    assert a["life_exact"] and a["dels_exact"]
    for key in ("del_tooth_N", "del_tooth_flank_N", "del_planet_bearing_N",
                "l10_planet_bearing_h", "planet_bearing_peq_N", "planet_bearing_revolutions",
                "max_front_force_N", "duration_s", "del_rotor_torque_Nm"):
        assert a[key] == b[key], key
    pd.testing.assert_frame_equal(a["tables"]["spectra"], b["tables"]["spectra"],
                                  check_exact=True)


def test_a_bearing_spectrum_keeps_its_own_levels(stage_runs):
    """A planet bearing's spectrum is on the bearing levels, also over a stretch where its
    force stays in the first bin (whose low edge, 0, the tooth levels share); flank and
    bearing channels are not mixed, and a span past the run's end is refused."""
    dt, runs = stage_runs
    res = runs[dt]
    b = f"{res.elements_of('planet_bearing')[0]}.radial"
    for t_to in (None, 5e-5):
        spec = level_spectrum(res, [b], t_to=t_to)
        np.testing.assert_array_equal(spec.level_high, LEVELS["planet_bearing_force_N"][1:])
    with pytest.raises(gm.ModelError, match="one kind of channel"):
        level_spectrum(res, [b, flanks(res)[0]])
    with pytest.raises(gm.ModelError, match="t_to"):
        level_spectrum(res, [b], t_to=1.0)


def test_the_end_mark_is_at_the_run_end_when_every_force_is_flat():
    """A gear pair rattling at rest, its flanks open (flat) at the end: the mark of the input's
    revolutions is at the run's end (the last change of a flank's value was earlier), and it
    holds the input's revolutions there: against the trapezoid rule on rows every 1 us split
    where the speed changes sign (as above: 2e-5)."""
    from gearmodal.scene import load_scene

    sc = load_scene("studies/scenes/gear_rattle.toml")
    res = gm.simulate(sc.model, 0.0995, dt=DENSE, loads=sc.loads, method="exact")
    marks = res.level_changes.query("channel == 'input'")
    assert marks.index[-1] == pytest.approx(0.0995, rel=1e-12)
    fl = flanks(res)
    last_change = max(res.turning_points[res.turning_points.channel == c].index.max()
                      for c in fl)
    assert last_change < 0.0995 - 1e-4  # the flanks stayed flat to the end
    ref = revolutions_of_rows(res.v[sc.model.input + ".theta"].to_numpy() / (2 * np.pi),
                              res.v.index.to_numpy())
    assert marks.input_revolutions.iloc[-1] == pytest.approx(ref, rel=2e-5)
    assert level_spectrum(res, fl).revolutions.sum() == pytest.approx(ref, rel=2e-5)
