"""Scene.dumps and the identity of a run (issue 20): a scene written with its model loads back
to the same scene; its identity is the canonical text of its inputs (not a pickle), so it
survives comments, moves and library versions and changes with any value; stores of an older
layout are refused by name."""

import json
import shutil
from pathlib import Path

import pytest

import gearmodal as gm
from gearmodal.scene import load_scene

ROOT = Path(__file__).resolve().parents[1]
SCENES = sorted((ROOT / "studies" / "scenes").glob("*.toml"))


@pytest.mark.parametrize("path", SCENES, ids=[p.stem for p in SCENES])
def test_a_dumped_scene_and_model_load_back_to_the_same_scene(path, tmp_path):
    sc = load_scene(path)
    gm.dump(sc.model, tmp_path / "model.toml")
    (tmp_path / "scene.toml").write_text(sc.dumps("model.toml"))
    again = load_scene(tmp_path / "scene.toml")
    assert again.dumps("model.toml") == sc.dumps("model.toml")
    assert again.identity() == sc.identity()
    for attr in ("t_end", "dt", "method", "speed_rpm", "loads", "q0", "v0", "options",
                 "drivetrain"):
        assert getattr(again, attr) == getattr(sc, attr), attr


def test_identity_ignores_comments_and_place_and_follows_values(tmp_path):
    src = ROOT / "studies" / "scenes" / "gear_rattle.toml"
    base = load_scene(src).identity()
    moved = tmp_path / "elsewhere"
    moved.mkdir()
    text = src.read_text().replace('"../models/', f'"{ROOT}/studies/models/')
    (moved / "s.toml").write_text("# a comment\n" + text)
    assert load_scene(moved / "s.toml").identity() == base
    assert load_scene(src, {"scene.t_end": 0.05}).identity() != base
    assert load_scene(src, {"model.gear_pair.backlash": 2e-4}).identity() != base


def test_stores_of_an_older_layout_are_refused_by_name(tmp_path):
    scene = ROOT / "studies" / "scenes" / "planetary_double_contact.toml"
    store = tmp_path / "sweep"
    gm.sweep(scene, {"scene.t_end": [0.002]}, store=store, progress=False, max_workers=1)
    meta = json.loads((store / "sweep.json").read_text())
    meta.pop("format")
    (store / "sweep.json").write_text(json.dumps(meta))
    with pytest.raises(gm.StoreError, match=r"^store = .*older gearmodal"):
        gm.sweep(scene, {"scene.t_end": [0.002]}, store=store, progress=False)
    sc = load_scene(scene, {"scene.t_end": 0.002})
    rungs = tmp_path / "rungs"
    rungs.mkdir()
    (rungs / "auto_store.json").write_text(json.dumps({"scene_sha256": "x", "coarsest": 4.0}))
    with pytest.raises(gm.StoreError, match=r"^store = .*older gearmodal"):
        gm.choose_fidelity(sc, 0.05, store=rungs)
    shutil.rmtree(rungs)


def test_a_scene_with_a_function_load_cannot_be_written():
    sc = load_scene(ROOT / "studies" / "scenes" / "gear_rattle.toml")
    sc.loads = {"pinion.torque": lambda t: 1.0}
    with pytest.raises(gm.ModelError, match=r"^loads\.pinion\.torque: a load given as function"):
        sc.dumps()
