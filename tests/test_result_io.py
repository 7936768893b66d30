"""Results load back (issue 20): SimulationResult, ModalResult and CampbellResult read what
their save() wrote, every table and number exactly; a directory of an older layout or of
another kind is refused naming it."""

import json

import numpy as np
import pandas as pd
import pytest

import gearmodal as gm
from gearmodal.scene import load_scene

STAGE = "studies/scenes/planetary_double_contact.toml"


def _same_frame(a, b):
    pd.testing.assert_frame_equal(a, b, check_exact=True)


@pytest.fixture(scope="module")
def sim():
    """4 ms of the double-contact stage: events on both flanks, planets, a clearance."""
    return load_scene(STAGE, {"scene.t_end": 0.004}).simulate()


def test_a_simulation_loads_back_exactly(sim, tmp_path):
    sim.save(tmp_path)
    again = gm.SimulationResult.load(tmp_path)
    assert len(sim.events) > 0
    for name in ("q", "v", "forces", "events", "contact_state", "elements"):
        _same_frame(getattr(sim, name), getattr(again, name))
    assert np.array_equal(sim.t, again.t)
    assert again.initial_state == sim.initial_state and again.stats == sim.stats
    assert again.settings == json.loads(json.dumps(sim.settings, default=str))
    # the analyses run on the loaded result as on the original (the structure came back)
    _same_frame(sim.double_contact(), again.double_contact())
    _same_frame(sim.load_sharing(), again.load_sharing())


def test_a_coupled_simulation_keeps_its_constraint_forces(tmp_path):
    pair = gm.examples.gear_pair()
    lock = gm.Joint("lock", "pair.wheel", None, directions=("theta",))
    both = gm.Coupled([gm.ModelSystem(pair, "pair")], [lock])
    res = gm.simulate(both, 0.002, dt=1e-4, loads={"pair.pinion.torque": 5.0}, method="scipy")
    assert res.constraint_forces is not None
    res.save(tmp_path)
    again = gm.SimulationResult.load(tmp_path)
    _same_frame(res.constraint_forces, again.constraint_forces)
    _same_frame(res.constraint_residual, again.constraint_residual)
    _same_frame(res.forces, again.forces)


def test_modal_and_campbell_results_load_back_exactly(tmp_path):
    pair = gm.examples.gear_pair()
    loads = gm.balance(pair, {"pinion.torque": -50.0}, on="wheel.torque")
    res = gm.modal(pair, loads=loads)  # the back flank's state, kept
    res.save(tmp_path / "modal")
    again = gm.ModalResult.load(tmp_path / "modal")
    assert np.array_equal(res.shapes, again.shapes)
    assert np.array_equal(res.frequencies_hz, again.frequencies_hz)
    assert np.array_equal(res.damping_ratios, again.damping_ratios)
    assert np.array_equal(res.contact_state, again.contact_state)
    assert (res.mode_types, res.dof_names, res.speed_rpm, res.model_name) == \
        (again.mode_types, again.dof_names, again.speed_rpm, again.model_name)
    _same_frame(res.to_frame(), again.to_frame())
    _same_frame(res.kinetic_energy, again.kinetic_energy)
    _same_frame(res.strain_energy, again.strain_energy)
    camp = gm.campbell(gm.load("studies/models/600kw.toml"), np.linspace(0.0, 25.0, 6))
    camp.save(tmp_path / "campbell")
    back = gm.CampbellResult.load(tmp_path / "campbell")
    for get in (lambda c: c.to_frame(), lambda c: c.crossings(), lambda c: c.veerings()):
        _same_frame(get(camp), get(back))
    assert all(np.array_equal(a, b) for a, b in zip(camp.macs, back.macs, strict=True))
    assert (back.orders, back.speed_range_rpm) == (camp.orders, camp.speed_range_rpm)


def test_an_older_or_foreign_directory_is_refused_by_name(sim, tmp_path):
    with pytest.raises(gm.ModelError, match="no such result directory"):
        gm.SimulationResult.load(tmp_path / "nothing")
    sim.save(tmp_path / "run")
    head = json.loads((tmp_path / "run" / "result.json").read_text())
    with pytest.raises(gm.ModelError, match="holds a 'SimulationResult', not a ModalResult"):
        gm.ModalResult.load(tmp_path / "run")
    (tmp_path / "run" / "result.json").write_text(json.dumps({**head, "version": 0}))
    with pytest.raises(gm.ModelError, match=r"^directory = .*older gearmodal"):
        gm.SimulationResult.load(tmp_path / "run")
    (tmp_path / "run" / "result.json").unlink()  # what a save before this version left
    with pytest.raises(gm.ModelError, match=r"no result\.json; .*older gearmodal"):
        gm.SimulationResult.load(tmp_path / "run")


def test_a_turbine_run_loads_back_exactly(tmp_path):
    from gearmodal.summary import summarize
    from gearmodal.turbine import DrivetrainResult

    run = load_scene("studies/scenes/600kw_turbine_10ms.toml", {"scene.t_end": 0.04}).simulate()
    run.save(tmp_path)
    again = DrivetrainResult.load(tmp_path)
    _same_frame(run.turbine.loads, again.turbine.loads)
    for name in ("q", "v", "forces", "events", "contact_state", "elements"):
        _same_frame(getattr(run.gearbox, name), getattr(again.gearbox, name))
    assert (again.stats, again.cut_in_time) == (run.stats, run.cut_in_time)
    assert summarize(again) == summarize(run)


def test_a_sweep_keeps_whole_results_when_asked(tmp_path):
    from gearmodal.studies import load_result
    from gearmodal.summary import summarize

    rows = gm.sweep(STAGE, {"scene.t_end": [0.002, 0.003]}, store=tmp_path, progress=False,
                    max_workers=1, keep_results=True)
    for cid in rows.case_id:
        res = load_result(tmp_path, cid)
        row = rows.set_index("case_id").loc[cid]
        assert summarize(res)["n_events"] == row["n_events"]
        assert res.t[-1] == pytest.approx(row["scene.t_end"], abs=1e-12)
    assert not list(tmp_path.glob("cases/.res-*"))  # moved into the cases, none left over
    with pytest.raises(gm.ModelError, match="keep_results = True needs a store"):
        gm.sweep(STAGE, {"scene.t_end": [0.002]}, keep_results=True, progress=False)
    plain = gm.sweep(STAGE, {"scene.t_end": [0.002]}, store=tmp_path / "plain", progress=False,
                     max_workers=1)
    with pytest.raises(gm.ModelError, match="keep_results=True"):
        load_result(tmp_path / "plain", plain.case_id.iloc[0])


def test_the_fidelity_ladder_returns_the_stored_rung_without_running_it(tmp_path,
                                                                        monkeypatch):
    import gearmodal.auto as auto

    sc = load_scene(STAGE, {"scene.t_end": 0.004})
    first = gm.choose_fidelity(sc, 0.05, store=tmp_path)
    assert first.met
    kept = sorted(p.name for p in tmp_path.iterdir() if p.is_dir())
    assert f"rung{first.rung}" in kept and len(kept) <= 3

    def no_run(*a, **k):
        raise AssertionError("a stored rung was run again")

    monkeypatch.setattr(auto, "one_run", no_run)  # what runs a rung
    again = gm.choose_fidelity(sc, 0.05, store=tmp_path)
    assert again.table.cached.all() and again.rung == first.rung
    _same_frame(again.result.forces, first.result.forces)
    _same_frame(again.result.events, first.result.events)


@pytest.mark.parametrize("kind, key, value", [
    ("modal", "dof_names", 5), ("modal", "mode_types", None), ("campbell", "extra", "x"),
    ("campbell", "orders", [1]), ("campbell", "speed_range_rpm", 1.5),
    ("simulation", "initial_state", 5), ("simulation", "span", True),
    ("simulation", "sha256", [1])])
def test_a_result_json_edited_to_a_wrong_type_is_named(tmp_path, kind, key, value):
    """A saved result whose result.json field was edited to another type: a ModelError naming
    the directory (issue 62), not the TypeError or AttributeError it trips."""
    import json

    from gearmodal.campbell import CampbellResult
    from gearmodal.integrate.result import SimulationResult
    from gearmodal.modal import ModalResult

    m = gm.load("studies/models/gear_pair.toml")
    d = tmp_path / kind
    res = {"modal": lambda: gm.modal(m), "campbell": lambda: gm.campbell(m, [0.0, 100.0]),
           "simulation": lambda: gm.simulate(m, 1e-3, dt=1e-4)}[kind]()
    res.save(d)
    head = json.loads((d / "result.json").read_text())
    head[key] = value
    (d / "result.json").write_text(json.dumps(head))
    load = {"modal": ModalResult, "campbell": CampbellResult,
            "simulation": SimulationResult}[kind].load
    with pytest.raises(gm.ModelError, match=r"directory = .*damaged"):
        load(d)
