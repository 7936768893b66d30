"""A scene's work-precision table (gearmodal.precision, ``gearmodal fidelity``): every method
and setting, CPU time and errors against the exact method, written as it goes and resumed."""

import json
import math

import pytest

import gearmodal as gm
import gearmodal.precision as fid
from gearmodal.cli import main
from gearmodal.scene import load_scene, settings

RATTLE = "studies/scenes/gear_rattle.toml"


@pytest.fixture(scope="module")
def table(tmp_path_factory):
    out = tmp_path_factory.mktemp("fidelity")
    sc = load_scene(RATTLE, overrides=settings(["t_end=0.02"]))
    return gm.fidelity(sc, out=out), out, sc


def test_the_table_measures_every_setting_against_exact(table):
    ft, _, _ = table
    t = ft.to_frame().set_index("setting")
    assert list(t.index) == [label for label, _ in fid.settings_of(ft_scene(table))]
    assert t.loc["exact (reference)", "status"] == "reference"
    # rounding-level start: the same events, peaks within 1e-9 (measured 3e-13)
    floor = t.loc["exact, start perturbed (floor)"]
    assert floor.status == "floor" and floor.events_error == 0 and floor.peak_error < 1e-9
    # the exact method's output step places the rows only: the same exact peaks and events
    coarse = t.loc["exact, output dt x4"]
    assert coarse.status == "ok" and coarse.peak_error == 0 and coarse.events_error == 0
    # Newmark at the scene's 1e-4 s (omega dt = 3.9 on the mesh) stops, naming the setting
    nm = t.loc["newmark dt 0.0001 s"]
    assert nm.status == "stopped" and "reduce dt" in nm.note
    for _, r in t.iterrows():
        assert r.cpu_s > 0
        assert (r.status in ("stopped", "refused")) == math.isnan(r.peak_error)
    rec = ft.recommend(0.01)
    assert rec is not None and rec.method == "exact" and rec.status != "floor"


def ft_scene(table):
    return table[2]


def test_the_table_is_saved_and_resumed(table, monkeypatch):
    ft, out, sc = table
    ft.save(out)
    meta = json.loads((out / "fidelity.json").read_text())
    assert meta["recommended"] == ft.recommend().setting and meta["target"] == 0.01
    assert (out / "fidelity.png").stat().st_size > 0
    # a second call on the same scene and folder runs nothing: every row is in the folder

    def refuse(*a, **k):
        raise AssertionError("ran a setting that was stored")

    monkeypatch.setattr(fid, "_run_one", refuse)
    again = gm.fidelity(sc, out=out)
    assert again.to_frame().drop(columns="cpu_s").equals(ft.to_frame().drop(columns="cpu_s"))
    # the scene's own method does not make it another scene; its t_end does
    same = load_scene(RATTLE, overrides=settings(["t_end=0.02", "method=newmark"]))
    assert gm.fidelity(same, out=out).to_frame().setting.tolist() == ft.to_frame().setting.tolist()
    other = load_scene(RATTLE, overrides=settings(["t_end=0.01"]))
    with pytest.raises(gm.StoreError, match="another scene"):
        gm.fidelity(other, out=out)


def test_a_row_cut_by_a_stop_runs_again(table, tmp_path, monkeypatch):
    ft, out, sc = table
    rows = (out / "fidelity.jsonl").read_text().splitlines(keepends=True)
    cut = tmp_path / "cut"
    cut.mkdir()
    (cut / "fidelity.jsonl").write_text("".join(rows[:-1]) + rows[-1][:40])
    ran = []
    real = fid._run_one

    def counting(scene, label, changes):
        ran.append(label)
        return real(scene, label, changes)

    monkeypatch.setattr(fid, "_run_one", counting)
    again = gm.fidelity(sc, out=cut)
    assert ran == [ft.to_frame().setting.iloc[-1]]  # only the cut row
    assert len(again.to_frame()) == len(ft.to_frame())


@pytest.mark.parametrize("target", [0.0, -1.0, math.nan, "1%"])
def test_a_bad_target_is_refused(target):
    sc = load_scene(RATTLE, overrides=settings(["t_end=0.001"]))
    with pytest.raises(gm.ModelError, match="target"):
        gm.fidelity(sc, target=target)


def test_the_command_line_takes_a_percentage(tmp_path, capsys):
    assert main(["fidelity", RATTLE, "--out", str(tmp_path / "x"), "--target", "fast"]) == 2
    assert "--target" in capsys.readouterr().err
