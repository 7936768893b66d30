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
