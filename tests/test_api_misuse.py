"""The Python API checks what the files check (issue 40 item 1, in part): loads, callables,
Series, methods and their options refused with one error naming the argument, before the run."""

import json

import numpy as np
import pandas as pd
import pytest

import gearmodal as gm

PAIR = gm.load("studies/models/gear_pair.toml")


@pytest.mark.parametrize("loads, match", [
    ([1.0], r"^loads: expected \{load name: value\} \(a dict\), got list"),
    ({"pinion.torque": lambda t: None}, r"gave NoneType None at t = 0"),
    ({"pinion.torque": lambda t: np.ones(2)}, r"gave ndarray .* one number"),
    ({"pinion.torque": lambda: 1.0}, r"the callable must take the time in s"),
    ({"pinion.torque": pd.Series(["a", "b"], index=[0.0, 1.0])}, r"a Series of .* values"),
    ({"pinion.torque": pd.Series([1.0, 2.0], index=pd.to_datetime(["2026-01-01",
                                                                    "2026-01-02"]))},
     r"indexed by time in s, got an index of datetime64.*total_seconds"),
    ({"pinion.torque": pd.Series([1.0, 2.0], index=pd.to_timedelta([0, 1], unit="s"))},
     r"indexed by time in s, got an index of timedelta64"),
    # a NaN time compared False with its neighbours and passed the increasing-time check
    ({"pinion.torque": pd.Series([1.0, 2.0, 3.0], index=[0.0, np.nan, 1.0])},
     r"time index holds nan: every time must be a finite number of s"),
    ({"pinion.torque": gm.Harmonic(mean=0.0, amplitude=1.0, frequency_hz=1e300)},
     r"loads.pinion.torque.frequency_hz = 1e\+300: outside .* \[0, 1e\+08\] Hz"),
])
def test_bad_loads_are_named(loads, match):
    with pytest.raises(gm.ModelError, match=match):
        gm.simulate(PAIR, 1e-3, dt=1e-4, loads=loads)


@pytest.mark.parametrize("kw, match", [
    ({"method": ["exact"]}, r"^method = \['exact'\]: must be one of"),
    ({"max_events_per_step": None}, r"max_events_per_step = None: must be an integer"),
    ({"max_events_per_step": 1e9}, r"must be an integer in \[1, 1e\+06\]"),
    ({"method": "scipy", "rtol": "x"}, r"rtol = 'x': must be a number"),
    ({"method": "scipy", "rtol": 1e3}, r"rtol = 1000.0: must be a number in \[1e-13, 0.1\]"),
    ({"method": "scipy", "scipy_method": "Euler"}, r"scipy_method = 'Euler': must be one of"),
    ({"propagator": "exp"}, r"propagator = 'exp': must be one of 'taylor', 'expm'"),
    ({"method": "scipy", "atol": [1e-12, -1.0]}, r"atol = .*one per state component"),
])
def test_bad_methods_and_options_are_named(kw, match):
    with pytest.raises(gm.ModelError, match=match):
        gm.simulate(PAIR, 1e-3, dt=1e-4, v0={"pinion.theta": 1.0}, **kw)


def test_good_options_still_run():
    sim = gm.simulate(PAIR, 1e-3, dt=1e-4, v0={"pinion.theta": 1.0}, method="scipy",
                      rtol=1e-8, atol=1e-12, max_step=1e-5)
    assert len(sim.t) == 11
    # an absolute tolerance per state component, as solve_ivp takes it (the work-precision
    # benchmark's; refused while the option check took only numbers)
    n = 2 * len(PAIR.assemble().dof_names)
    per = gm.simulate(PAIR, 1e-3, dt=1e-4, v0={"pinion.theta": 1.0}, method="scipy",
                      rtol=1e-8, atol=np.full(n, 1e-12), max_step=1e-5)
    np.testing.assert_array_equal(per.q.to_numpy(), sim.q.to_numpy())
    f = pd.Series([0.0, 2.0], index=[0.0, 1e-3])
    sim = gm.simulate(PAIR, 1e-3, dt=1e-4, loads={"pinion.torque": f,
                                                   "wheel.torque": lambda t: -4.0 * t / 1e-3},
                      max_events_per_step=50)
    assert np.isfinite(sim.q.to_numpy()).all()


def test_scipy_at_rest_on_a_flank_does_not_loop():
    """The gear pair at rest with its front flank at zero gap and no loads: solve_ivp's event
    is zero throughout, and the reference method restarted 1e-6 dt apart for ever (1 ms did
    not end in 20 s). The contact now rests until the next output time: a few restarts per
    step, no events; with a torque it closes as the exact method's does."""
    sim = gm.simulate(PAIR, 1e-3, dt=1e-4, method="scipy")
    assert len(sim.events) == 0 and sim.stats["nfev"] < 5000
    loads = {"pinion.torque": 1.0, "wheel.torque": -2.0}
    sp = gm.simulate(PAIR, 1e-3, dt=1e-4, method="scipy", loads=loads)
    ex = gm.simulate(PAIR, 1e-3, dt=1e-4, loads=loads)
    assert list(sp.events.contact) == list(ex.events.contact) == ["front"]
    np.testing.assert_allclose(sp.q.to_numpy(), ex.q.to_numpy(), rtol=0,
                               atol=1e-5 * np.abs(ex.q.to_numpy()).max())


def test_modal_campbell_balance_refuse_bad_loads_and_speeds():
    with pytest.raises(gm.ModelError, match=r"^speeds_rpm = '0:10:5': expected an array"):
        gm.campbell(PAIR, "0:10:5")
    with pytest.raises(gm.ModelError, match=r"loads\.pinion\.torque = nan: must be finite"):
        gm.modal(PAIR, loads={"pinion.torque": np.nan, "wheel.torque": 0.0})
    with pytest.raises(gm.ModelError, match=r"loads\.pinion\.torque = nan: must be finite"):
        gm.balance(PAIR, {"pinion.torque": float("nan")}, on="wheel.torque")
    with pytest.raises(gm.ModelError, match=r"loads\.pinion\.torque = 'x': expected a number"):
        gm.campbell(PAIR, [0.0, 10.0], loads={"pinion.torque": "x"})


def test_a_run_that_cannot_fit_in_memory_is_refused_up_front(monkeypatch):
    """Rows the machine cannot hold are refused before anything is allocated, saying how
    much and what to change (the available memory pinned at 1 GB: the test does not depend on
    the machine)."""
    from gearmodal.integrate import driver

    monkeypatch.setattr(driver, "available_memory", lambda: 1e9)
    with pytest.raises(gm.ModelError, match=r"would hold 10,000,001 output rows .* 1 GB "
                                            r"available: a longer dt"):
        gm.simulate(PAIR, 10.0, dt=1e-6)
    assert len(gm.simulate(PAIR, 1e-3, dt=1e-4).t) == 11


def test_dumps_writes_names_loads_reads():
    """Names with a character beyond the BMP, a tab, DEL, quotes and backslashes: gm.dumps
    writes TOML that gm.loads reads back to the same name (JSON's surrogate escapes were not
    TOML)."""
    m = gm.load("studies/models/gear_pair.toml")
    for name in ["pair \U0001F600", "tab\there", "del\x7fx", 'quote"b\\s', "ünïcode"]:
        m.name = name
        assert gm.loads(gm.dumps(m)).name == name


def test_a_planet_count_beyond_any_gearbox_is_refused():
    """10 000 planets allocated until memory ran out; a stage takes at most 32, from a file or
    from Python."""
    sun = gm.Gear(21, 0.01, np.radians(20), mass=80.0, inertia=0.45, name="sun")
    planet = gm.Gear(39, 0.01, np.radians(20), mass=140.0, inertia=3.6, name="planet")
    ring = gm.Gear(99, 0.01, np.radians(20), mass=620.0, inertia=190.0, name="ring",
                   internal=True)
    with pytest.raises(gm.ModelError, match=r"n_planets = 10000: must be an integer <= 32 "
                       r"\(wind-turbine gearboxes have 3 to 7\)"):
        gm.planetary_stage(sun, planet, ring, n_planets=10_000, carrier_mass=1000.0,
                           carrier_inertia=110.0, mesh_stiffness=1e9)
    stage = gm.planetary_stage(sun, planet, ring, n_planets=3, carrier_mass=1000.0,
                               carrier_inertia=110.0, mesh_stiffness=1e9)
    assert len(stage.groups["planets"]) == 3


def _damage(path, n=256):
    """Garbage bytes in the middle of a file, its size unchanged."""
    import os

    b = bytearray(path.read_bytes())
    mid = len(b) // 2
    b[mid:mid + n] = os.urandom(n)
    path.write_bytes(bytes(b))


def test_a_damaged_saved_table_is_refused_naming_it(tmp_path):
    """Every page carries a CRC the reader checks: 256 garbage bytes inside a saved forces
    table are an error naming the file, never data (33 values changed silently before)."""
    from gearmodal.scene import load_scene

    sim = load_scene("studies/scenes/planetary_double_contact.toml",
                     {"scene.t_end": 0.05}).simulate()
    sim.save(tmp_path)
    _damage(tmp_path / "forces.parquet")
    with pytest.raises(gm.ModelError, match=r"forces\.parquet was damaged or changed"):
        gm.SimulationResult.load(tmp_path)  # its SHA-256
    # a result saved before the checksums: the pages' CRCs still refuse it when read
    head = json.loads((tmp_path / "result.json").read_text())
    del head["sha256"], head["header_sha256"]
    head["version"] = 1  # the layout before the checksums
    (tmp_path / "result.json").write_text(json.dumps(head))
    back = gm.SimulationResult.load(tmp_path)
    with pytest.raises(gm.ModelError, match=r"forces\.parquet is unreadable"):
        _ = back.forces
    with pytest.raises(gm.ModelError, match=r"forces\.parquet is unreadable"):
        list(back.force_chunks())
    pd.testing.assert_frame_equal(back.q, sim.q, check_exact=True)  # the others read


def test_a_damaged_stored_case_is_computed_again(tmp_path):
    scene = "studies/scenes/planetary_double_contact.toml"
    grid = {"scene.t_end": [0.002, 0.003]}
    first = gm.sweep(scene, grid, store=tmp_path, progress=False, max_workers=1)
    cid = first.case_id.iloc[0]
    _damage(tmp_path / "cases" / cid / "row.parquet", n=64)
    with pytest.warns(UserWarning, match=rf"stored case {cid} is damaged"):
        again = gm.sweep(scene, grid, store=tmp_path, progress=False, max_workers=1)
    assert list(again.cached) == [False, True]
    pd.testing.assert_series_equal(again.n_events, first.n_events)
    # a case folder without its row file, a case's checksums unreadable: computed again
    (tmp_path / "cases" / cid / "row.parquet").unlink()
    with pytest.warns(UserWarning, match=rf"stored case {cid} has no row.parquet"):
        again = gm.sweep(scene, grid, store=tmp_path, progress=False, max_workers=1)
    assert list(again.cached) == [False, True]
    (tmp_path / "cases" / cid / "sha256.json").write_text("{")
    with pytest.warns(UserWarning, match=rf"stored case {cid} is damaged"):
        again = gm.sweep(scene, grid, store=tmp_path, progress=False, max_workers=1)
    pd.testing.assert_series_equal(again.n_events, first.n_events)
    # the store's own file damaged: which scene its cases belong to is unknown: refused
    meta = tmp_path / "sweep.json"
    meta.write_bytes(meta.read_bytes()[:40])
    with pytest.raises(gm.StoreError, match="sweep.json is unreadable .* use a new store"):
        gm.sweep(scene, grid, store=tmp_path, progress=False, max_workers=1)


def _truncate(path, frac=0.5):
    b = path.read_bytes()
    path.write_bytes(b[:int(len(b) * frac)])


def _drop_rows(path, n=50):
    lines = path.read_text().splitlines(True)
    path.write_text("".join(lines[:-n]))


def _edit_cell(path):
    lines = path.read_text().splitlines(True)
    cells = lines[5].split(",")
    cells[1] = "maybe"
    lines[5] = ",".join(cells)
    path.write_text("".join(lines))


@pytest.mark.parametrize("name, damage", [
    ("q.csv", _truncate), ("forces.csv", _drop_rows), ("contact_state.csv", _edit_cell),
    ("events.csv", lambda p: p.write_text(p.read_text().replace("closed", "clsoed", 1))),
    ("settings.json", _truncate), ("q.csv", lambda p: p.write_text("")),
    ("turning_points.csv", _truncate),
])
def test_a_damaged_or_edited_saved_csv_is_named_not_loaded(tmp_path, name, damage):
    """A CSV has no checksum of its own: a truncated table, 50 rows missing, an edited cell or
    event state, a truncated settings.json, an emptied table loaded as different data (or as
    a raw pandas/json error) before; the header's SHA-256 of every file names it now."""
    sim = gm.simulate(PAIR, 0.01, dt=1e-4, v0={"pinion.theta": 1.0})
    sim.save(tmp_path, format="csv")
    gm.SimulationResult.load(tmp_path)  # intact: loads
    damage(tmp_path / name)
    with pytest.raises(gm.ModelError, match=rf"{name.replace('.', '[.]')} was damaged or "
                       "changed after it was saved"):
        gm.SimulationResult.load(tmp_path)


def test_a_save_over_an_earlier_result_is_atomic(tmp_path, monkeypatch):
    """A save that fails half-way (a full disk) leaves the earlier result there, loading as it
    was, and nothing beside it; a save that completes replaces it whole."""
    import gearmodal.integrate.result as R

    first = gm.simulate(PAIR, 0.01, dt=1e-4, v0={"pinion.theta": 1.0})
    first.save(tmp_path / "run")
    second = gm.simulate(PAIR, 0.02, dt=1e-4, v0={"pinion.theta": 2.0})
    calls = {"n": 0}
    write = R.write_table

    def full_disk(*a, **k):
        calls["n"] += 1
        if calls["n"] == 3:
            raise OSError(28, "No space left on device")
        return write(*a, **k)

    monkeypatch.setattr(R, "write_table", full_disk)
    with pytest.raises(OSError, match="No space left"):
        second.save(tmp_path / "run")
    monkeypatch.undo()
    back = gm.SimulationResult.load(tmp_path / "run")
    pd.testing.assert_frame_equal(back.q, first.q, check_exact=True)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]
    second.save(tmp_path / "run", format="csv")
    back = gm.SimulationResult.load(tmp_path / "run")
    pd.testing.assert_frame_equal(back.q, second.q, check_exact=True)
    assert not list((tmp_path / "run").glob("*.parquet"))  # replaced whole


def test_a_failed_solve_is_not_bad_input(tmp_path, capsys):
    """Errors by kind: a solve that fails on valid input (more contact events in one step than
    allowed) is a SolveError, not a ModelError (a caller can tell them apart), with its own
    CLI exit status (4); bad input stays ModelError (2)."""
    import math
    from pathlib import Path

    from gearmodal.cli import main

    p = gm.Gear(20, 0.004, math.radians(20), mass=1.0, inertia=1e-3)
    w = gm.Gear(40, 0.004, math.radians(20), mass=4.0, inertia=1.6e-2)
    pair = gm.gear_pair(p, w, mesh_stiffness=2e8, backlash=1e-6)
    with pytest.raises(gm.SolveError, match="max_events_per_step") as err:
        gm.simulate(pair, 0.01, dt=1e-2, v0={"pinion.theta": 5.0}, max_events_per_step=1)
    assert not isinstance(err.value, gm.ModelError)
    assert isinstance(err.value, gm.GearmodalError) and err.value.field == "max_events_per_step"
    with pytest.raises(gm.ModelError) as bad:
        gm.simulate(pair, -1.0, dt=1e-4)
    assert not isinstance(bad.value, gm.SolveError)
    scene = tmp_path / "s.toml"
    scene.write_text('[scene]\nmodel = "' + str(Path("studies/models/gear_pair.toml").resolve())
                     + '"\nt_end = 0.01\ndt = 0.01\n[options]\nmax_events_per_step = 1\n'
                     '[v0]\n"pinion.theta" = 5.0\n')
    assert main(["simulate", str(scene), "--out", str(tmp_path / "o"), "--quiet"]) == 4
    assert "the solve failed: max_events_per_step" in capsys.readouterr().err
