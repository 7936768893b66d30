"""Streamed results (issue 34 item 4): a run given ``out=`` writes its rows to Parquet while it
goes and reads them back lazily; it is the same run as the one held in memory, saved results
load back exactly in either format, long tables split into parts, and the figures' decimated
view keeps every extreme."""

import gc
import json
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import gearmodal as gm
from gearmodal import result_io
from gearmodal.scene import load_scene
from gearmodal.turbine import DrivetrainResult, simulate_drivetrain

TURBINE = "studies/scenes/600kw_turbine_10ms.toml"
STAGE = "studies/scenes/planetary_double_contact.toml"


def close(a: pd.DataFrame, b: pd.DataFrame, rel: float = 1e-12):
    """Same labels; values equal to ``rel`` of the table's largest (the force rows of a chunk
    and of the whole run go through BLAS products blocked differently: rounding)."""
    assert list(a.columns) == list(b.columns)
    np.testing.assert_array_equal(a.index.to_numpy(), b.index.to_numpy())
    x, y = a.to_numpy(dtype=float), b.to_numpy(dtype=float)
    np.testing.assert_allclose(x, y, rtol=0, atol=rel * max(np.abs(x).max(), 1e-300))


@pytest.fixture(scope="module")
def clearance_runs(tmp_path_factory):
    """The clearance gearbox in the turbine (contact events, re-basings), 1 s: held in memory
    and streamed in row groups of 64 rows, two groups per part (so its tables are folders
    of parts, as an hour-long run's are)."""
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "studies"))
    from double_contact import CLEARANCE

    sc = load_scene(TURBINE, overrides={"scene.t_end": 1.0,
                                        "model.stages.0.carrier_bearing": CLEARANCE})
    kw = {**sc.drivetrain, "top_frequency_hz": 500.0}
    held = simulate_drivetrain(sc.turbine, sc.wind, sc.model, 1.0, dt=1e-3, **kw)
    out = tmp_path_factory.mktemp("streamed")
    mp = pytest.MonkeyPatch()
    mp.setattr(result_io, "GROUP_ROWS", 64)
    mp.setattr(result_io, "PART_GROUPS", 2)
    try:
        streamed = simulate_drivetrain(sc.turbine, sc.wind, sc.model, 1.0, dt=1e-3, out=out,
                                       **kw)
    finally:
        mp.undo()
    return held, streamed, out


def test_a_streamed_turbine_run_is_the_run_held_in_memory(clearance_runs):
    held, streamed, out = clearance_runs
    a, b = held.gearbox, streamed.gearbox
    assert b.stored == out and (out / "forces.parquet").is_dir()  # in parts
    # 1 001 rows in groups of at least 64 (a stretch's rows between re-basings), two per part
    assert len(list((out / "forces.parquet").glob("part-*.parquet"))) >= 3
    assert a.stats["n_events"] > 100 and a.stats["n_rebases"] >= 5
    for name in ("q", "v", "forces"):
        close(getattr(a, name), getattr(b, name))
    pd.testing.assert_frame_equal(a.contact_state, b.contact_state, check_column_type=False)
    pd.testing.assert_frame_equal(a.events, b.events, check_exact=True)
    pd.testing.assert_frame_equal(a.peak_bins, b.peak_bins, check_exact=True)
    pd.testing.assert_frame_equal(held.turbine.loads, streamed.turbine.loads, check_exact=True)
    np.testing.assert_array_equal(a.t, b.t)
    skip = {"cpu_s", "gearbox_s", "aero_s", "wind_s", "wind_setup_s", "realtime_ratio"}
    assert {k: v for k, v in a.stats.items() if k not in skip} \
        == {k: v for k, v in b.stats.items() if k not in skip}
    assert a.double_contact().equals(b.double_contact())
    close(a.load_sharing(), b.load_sharing())
    assert a.load_sharing().attrs["peak_factor"] == pytest.approx(
        b.load_sharing().attrs["peak_factor"], rel=1e-12)
    # and what was streamed loads back as it is (a second process's view of the folder)
    again = DrivetrainResult.load(out)
    pd.testing.assert_frame_equal(again.gearbox.forces, b.forces, check_exact=True)
    pd.testing.assert_frame_equal(again.turbine.loads, held.turbine.loads, check_exact=True)


def test_a_streamed_run_keeps_no_rows_and_no_stretch_systems(tmp_path):
    """The driver writes each call's rows to its sink and keeps none; of the stretches'
    systems (one per re-basing) it keeps the first and the current one."""
    from gearmodal.integrate import Driver, PiecewiseLinearSystem, Recorder

    sc = load_scene(STAGE)
    system = PiecewiseLinearSystem(sc.model.assemble(), 0.0)
    x = np.zeros(2 * system.n)
    s = system.penetration(x) > 0
    with_sink = Driver("exact", 1e-4, x, s, sink=Recorder(tmp_path, system, 1e-4))
    F = np.tile(system.f_const, (11, 1))
    for _ in range(4):
        with_sink.advance(PiecewiseLinearSystem(sc.model.assemble(), 0.0), 10, F)
    X, S, _ = with_sink.arrays()
    assert X is None and S is None
    kept = [sg[2] for sg in with_sink.segments if sg[2] is not None]
    assert len(with_sink.segments) == 4 and len(kept) == 2
    # nor does the exact method's registry of integrators keep the dropped ones alive (its
    # integrators hold their systems weakly): the recorder's, the first and the current
    gc.collect()
    live = [o for o in gc.get_objects() if isinstance(o, PiecewiseLinearSystem)]
    assert len(live) <= 3
    with_sink.sink.close()
    assert len(result_io.read_table(tmp_path, "q")) == 41  # every row went to the sink


def test_a_streamed_simulate_is_the_run_held_in_memory_to_the_bit(tmp_path):
    """gm.simulate's run is one kernel call: its streamed tables are the held ones exactly."""
    sc = load_scene(STAGE, overrides={"scene.t_end": 0.02})
    held = sc.simulate()
    streamed = sc.simulate(out=tmp_path)
    assert len(held.events) > 10
    for name in ("q", "v", "forces", "contact_state", "events"):
        pd.testing.assert_frame_equal(getattr(held, name), getattr(streamed, name),
                                      check_exact=True, check_column_type=False)
    assert repr(streamed).endswith(f"stored in {str(tmp_path)!r})")
    with pytest.raises(gm.ModelError, match="method = 'auto'"):
        load_scene(STAGE, overrides={"scene.method": "auto"}).simulate(out=tmp_path / "a")


def test_saved_results_load_back_in_either_format_and_the_csv_layout_1(tmp_path):
    sim = load_scene(STAGE, overrides={"scene.t_end": 0.01}).simulate()
    sim.save(tmp_path / "pq")
    sim.save(tmp_path / "csv", format="csv")
    for d in ("pq", "csv"):
        back = gm.SimulationResult.load(tmp_path / d)
        for name in ("q", "v", "forces", "contact_state", "events", "peak_bins", "elements"):
            pd.testing.assert_frame_equal(getattr(sim, name), getattr(back, name),
                                          check_exact=True, check_dtype=False,
                                          check_column_type=False, check_index_type=False)
        np.testing.assert_array_equal(back.t, sim.t)
    # a directory saved by the CSV-only layout (version 1) still loads
    head = json.loads((tmp_path / "csv" / "result.json").read_text())
    head.pop("header_sha256")  # (layout 1 had no digest of its header)
    (tmp_path / "csv" / "result.json").write_text(json.dumps({**head, "version": 1}))
    old = gm.SimulationResult.load(tmp_path / "csv")
    pd.testing.assert_frame_equal(old.forces, sim.forces, check_exact=True)
    # a stored run saved elsewhere: its files copied, not read; to CSV: written
    stored = gm.SimulationResult.load(tmp_path / "pq")
    stored.save(tmp_path / "copy")
    assert stored.__dict__.get("_forces") is None
    stored.save(tmp_path / "copy", format="csv")  # the other format replaces it
    assert not (tmp_path / "copy" / "forces.parquet").exists()
    pd.testing.assert_frame_equal(gm.SimulationResult.load(tmp_path / "copy").forces,
                                  sim.forces, check_exact=True)
    (tmp_path / "pq" / "v.parquet").unlink()
    with pytest.raises(gm.ModelError, match=r"v\.parquet is missing \(it was saved\)"):
        gm.SimulationResult.load(tmp_path / "pq")
    with pytest.raises(gm.ModelError, match="format = 'xlsx'"):
        sim.save(tmp_path / "x", format="xlsx")


def test_the_figures_view_keeps_every_extreme(tmp_path):
    """A 200 000-row table with one-row spikes: the view has about VIEW_ROWS rows and every
    spike, each column's largest and smallest value, exactly."""
    rng = np.random.default_rng(1)
    n = 200_000
    t = np.arange(n) * 1e-3
    V = rng.normal(size=(n, 3))
    spikes = rng.choice(n, 30, replace=False)
    V[spikes, 0] = 50.0 + np.arange(30)
    V[spikes[:10], 2] = -40.0
    V[5, 1] = np.nan  # a gap (a load share where nothing is loaded)
    df = pd.DataFrame(V, index=pd.Index(t, name="time"), columns=["a", "b", "c"])
    w = result_io.TableWriter(tmp_path, "tab", ["a", "b", "c"])
    for k in range(0, n, 7_000):
        w.append(t[k:k + 7_000], V[k:k + 7_000])
    w.close()
    pd.testing.assert_frame_equal(result_io.read_table(tmp_path, "tab"), df, check_exact=True)
    view = result_io.decimated(tmp_path, "tab", ["a", "b", "c"], max_rows=6_000)
    assert len(view) <= 6_000 * 1.05
    assert set(t[spikes]) <= set(view.index)
    for c in "abc":
        assert view[c].max() == df[c].max() and view[c].min() == df[c].min()
    assert view.index.is_monotonic_increasing
    # a table in memory thins to the same view (the rows grouped as a stored table's)
    result_io.write_table(df, tmp_path, "tab2")
    pd.testing.assert_frame_equal(result_io.thin_frame(df, 6_000),
                                  result_io.decimated(tmp_path, "tab2", ["a", "b", "c"], 6_000),
                                  check_exact=True)
    every = result_io.decimated(tmp_path, "tab", ["b"], max_rows=None)
    pd.testing.assert_frame_equal(every, df[["b"]], check_exact=True)


def test_the_cli_streams_a_turbine_run_and_writes_csv_when_asked(tmp_path):
    from gearmodal.cli import main

    assert main(["simulate", TURBINE, "--out", str(tmp_path / "pq"), "--t-end", "0.1",
                 "--quiet"]) == 0
    assert main(["simulate", TURBINE, "--out", str(tmp_path / "csv"), "--t-end", "0.1",
                 "--quiet", "--format", "csv"]) == 0
    for name in ("forces", "q", "turbine_loads", "load_sharing", "events"):
        assert (tmp_path / "pq" / f"{name}.parquet").exists(), name
        assert (tmp_path / "csv" / f"{name}.csv").exists(), name
    a = DrivetrainResult.load(tmp_path / "pq")
    b = DrivetrainResult.load(tmp_path / "csv")
    close(a.gearbox.forces, b.gearbox.forces)
    pd.testing.assert_frame_equal(a.turbine.loads, b.turbine.loads, check_exact=True)


def test_the_fatigue_row_of_a_stored_run_is_the_held_runs(clearance_runs):
    """drivetrain_fatigue reads a stored run a row group at a time (the flank forces counted
    as they stream): the same row as from the run held in memory, and its tooth DEL is the
    whole series' count."""
    from gearmodal.fatigue import damage_equivalent_load, drivetrain_fatigue

    held, _, out = clearance_runs
    streamed = DrivetrainResult.load(out)
    a = drivetrain_fatigue(held, bearing_C=2e6, planet_spin=2.5, t_skip=0.2)
    b = drivetrain_fatigue(streamed, bearing_C=2e6, planet_spin=2.5, t_skip=0.2)
    assert streamed.gearbox.__dict__.get("_forces") is None  # never read whole
    for key, val in a.items():
        if key != "tables":
            assert b[key] == pytest.approx(val, rel=1e-12, abs=1e-9), key
    close(a["tables"]["spectra"].drop(columns="quantity"),
          b["tables"]["spectra"].drop(columns="quantity"))
    # the DELs count the exact turning points (streamed from the stored table), and the
    # count of each flank's whole sequence held in memory is the same
    assert a["dels_exact"] and b["dels_exact"]
    tp = held.gearbox.turning_points
    pd.testing.assert_frame_equal(tp, streamed.gearbox.turning_points, check_exact=True)
    f = held.gearbox.forces
    flanks = [c for c in f.columns if c.startswith("stage1.") and c.endswith((".front",
                                                                              ".back"))]
    row = f[f.index >= 0.2].iloc[0]
    after = {c: tp.force_N[(tp.channel == c) & (tp.index > row.name)] for c in flanks}
    whole = max(damage_equivalent_load(np.concatenate([[row[c]], after[c]]), 8.7)
                for c in flanks if len(after[c]))  # (a back flank that never closes: none)
    assert a["del_tooth_N"] == pytest.approx(whole, rel=1e-12)
    # and the count of the 1 ms rows misses some of it (the rows' DEL is below)
    rows = max(damage_equivalent_load(f[f.index >= 0.2][c], 8.7) for c in flanks)
    assert rows < a["del_tooth_N"]


def test_a_coarser_output_step_is_a_plain_option(tmp_path, capsys):
    """``--output-dt`` only places the rows: the event log and the exact peaks are the same
    to the bit at twice the scene's step, the rows shared are the same, the table smaller."""
    from gearmodal.cli import main

    runs = {}
    for name, extra in (("base", []), ("coarse", ["--output-dt", "2e-4"])):
        assert main(["simulate", STAGE, "--out", str(tmp_path / name), "--t-end", "0.02",
                     *extra]) == 0
        runs[name] = gm.SimulationResult.load(tmp_path / name)
    a, b = runs["base"], runs["coarse"]
    assert len(b.t) == (len(a.t) - 1) // 2 + 1
    pd.testing.assert_frame_equal(a.events, b.events, check_exact=True)
    pd.testing.assert_frame_equal(a.peak_bins, b.peak_bins, check_exact=True)
    pd.testing.assert_frame_equal(a.forces.iloc[::2], b.forces, check_exact=True)
    assert (tmp_path / "coarse" / "forces.parquet").stat().st_size \
        < (tmp_path / "base" / "forces.parquet").stat().st_size
    assert main(["simulate", STAGE, "--out", str(tmp_path / "x"), "--output-dt", "0"]) == 2
    assert "--output-dt = 0.0: must be > 0 s" in capsys.readouterr().err
