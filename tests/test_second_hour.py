"""A new user's second hour (issue 38): a GRC-like planetary stage (21/39/99 teeth, the NREL
GRC 750 kW gearbox's first stage) written from the docs starts from its static equilibrium in
a scene; ``q0`` takes an equilibrium's Series; radians typed into degree keys are caught with
a hint; a builder's error names the key and unit the file used."""

import re
from pathlib import Path

import numpy as np
import pytest

import gearmodal as gm
from gearmodal.scene import load_scene

ROOT = Path(__file__).resolve().parents[1]
MODEL = (ROOT / "studies/models/planetary_clearance.toml").read_text().replace(
    "carrier_bearing = { stiffness = { x = 1.0e8, y = 1.0e8 }, clearance = { x = 1.0e-3, "
    "y = 1.0e-3 } }", "carrier_bearing = 1.0e8")

SCENE = """
[scene]
model = "grc.toml"
t_end = 0.05
dt = 1e-4
{start}

[loads]
"carrier.torque" = 2.0e5
"carrier.force_y" = -2.0e4
"sun.torque" = "balance"
"""


def write(tmp_path, start: str) -> Path:
    (tmp_path / "grc.toml").write_text(MODEL)
    p = tmp_path / f"scene_{start or 'none'}.toml"
    p.write_text(SCENE.format(start=f'start = "{start}"' if start else ""))
    return p


def test_a_scene_starts_from_its_static_equilibrium(tmp_path):
    """From rest the carrier torque is a step: the stage rings through its torsion modes (the
    sun-planet force swings by tens of percent). From equilibrium it stays there: the mesh
    force holds its static value to 1e-9 over the run (a free rotation, balanced, does not
    accelerate)."""
    assert "carrier_bearing = 1.0e8" in MODEL
    rest = load_scene(write(tmp_path, "")).simulate()
    eq_scene = load_scene(write(tmp_path, "equilibrium"))
    assert eq_scene.start == "equilibrium" and eq_scene.q0 == {}
    eq = eq_scene.simulate()
    f_rest = rest.forces["sun_planet1.front"]
    f_eq = eq.forces["sun_planet1.front"]
    static = f_eq.iloc[0]
    assert static > 1e3
    assert np.abs(f_eq - static).max() <= 1e-9 * static
    assert np.abs(f_rest - static).max() >= 0.1 * static  # the step rings
    assert len(eq.events) == 0
    # the scene writes back what it read; q0 with start = "equilibrium" is refused
    again = load_scene(write(tmp_path, "equilibrium"))
    assert 'start = "equilibrium"' in again.dumps("grc.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text(SCENE.format(start='start = "equilibrium"') + '\n[q0]\n"sun.x" = 1e-6\n')
    with pytest.raises(gm.ModelError, match=r"scene\.start.*remove \[q0\]"):
        load_scene(bad)


def test_q0_takes_the_equilibrium_series():
    sc = load_scene("studies/scenes/planetary_double_contact.toml")
    loads = {k: getattr(x, "mean", x) for k, x in sc.loads.items()}
    eq = gm.equilibrium(sc.model, loads)
    a = gm.simulate(sc.model, 0.002, dt=1e-4, loads=loads, q0=eq.q)
    b = gm.simulate(sc.model, 0.002, dt=1e-4, loads=loads, q0=dict(eq.q))
    np.testing.assert_array_equal(a.q.to_numpy(), b.q.to_numpy())
    with pytest.raises(gm.ModelError, match=r"q0: expected \{DOF name: value\}"):
        gm.simulate(sc.model, 0.002, dt=1e-4, q0=[0.0, 1.0])


@pytest.mark.parametrize("key, value, hint", [
    ("pressure_angle_deg = 20.0", "pressure_angle_deg = 0.349", "pressure_angle_deg = 20"),
    ("helix_angle_deg = 7.5", "helix_angle_deg = 0.131", "helix_angle_deg = 7.506")])
def test_radians_in_a_degree_key_are_caught(tmp_path, key, value, hint):
    p = tmp_path / "m.toml"
    p.write_text(MODEL.replace(key, value, 1))
    with pytest.raises(gm.ModelError, match=re.escape(f"if {value.split('= ')[1]} is in "
                                                      f"radians, give {hint}")):
        gm.load(p)


def test_a_builders_error_names_the_key_the_file_used(tmp_path):
    """The planet given the sun's helix hand: the error names ``helix_angle_deg`` (the key in
    the file) and the angles in degrees too."""
    p = tmp_path / "m.toml"
    text = MODEL.replace("helix_angle_deg = -7.5", "helix_angle_deg = 7.5", 1)
    p.write_text(text)
    with pytest.raises(gm.ModelError, match=r"planet\.helix_angle_deg = 0\.1309 rad \(7\.5 "
                                            r"deg\) against sun's 0\.1309 rad \(7\.5 deg\)"):
        gm.load(p)


def test_info_lists_the_loads_and_a_mistyped_name_gets_a_suggestion(capsys):
    from gearmodal.cli import main

    assert main(["info", "studies/models/gear_pair.toml"]) == 0
    out = capsys.readouterr().out
    assert "loads (3; the names [loads] takes, N or N m):" in out
    assert "  pinion.torque" in out and "  wheel.torque" in out
    m = gm.load("studies/models/gear_pair.toml")
    with pytest.raises(gm.ModelError, match=r"no such load \(did you mean 'pinion\.torque'"):
        gm.simulate(m, 1e-3, dt=1e-4, loads={"pinion.torqe": 1.0})
    with pytest.raises(gm.ModelError, match=r"no such DOF \(did you mean 'wheel\.theta'"):
        gm.simulate(m, 1e-3, dt=1e-4, v0={"wheel.theat": 1.0})


def test_an_unbalanced_modal_names_a_load_the_model_has():
    """The hint names a load of this model that works on the free rotation and was not
    given (the gear pair's wheel torque), not the drivetrain's generator torque."""
    m = gm.load("studies/models/gear_pair.toml")
    with pytest.raises(gm.ModelError, match=r"gm\.balance\(model, loads, on='wheel\.torque'\)"):
        gm.modal(m, loads={"pinion.torque": 10.0})
    bal = gm.balance(m, {"pinion.torque": 10.0}, on="wheel.torque")
    assert gm.modal(m, loads=bal) is not None


def test_campbell_order_labels_do_not_cover_each_other():
    """The 600 kW drivetrain's order lines: 3P and the stage-1 planet pass (the same order)
    share one label; no two labels' boxes overlap, none covers the legend, all lie in the
    plot; in the interactive diagram a log decrement of 0 is yellow, not orange-red."""
    import importlib

    cm = importlib.import_module("gearmodal.campbell")  # gm.campbell is the function

    orders = {"1P": 1.0, "3P": 3.0, "stage1 mesh": 99.0, "2x stage1 mesh": 198.0,
              "stage2 mesh": 468.6, "2x stage2 mesh": 937.1, "stage3 mesh": 1792.8,
              "2x stage3 mesh": 3585.6, "stage1 planet pass": 3.0}
    legend = (0.0, 9.0, 45.0, 60.0)
    at = cm.order_labels(orders, list(orders), 30.0, 60.0, (legend,))
    assert "3P = stage1 planet pass" in at and len(at) == 8
    h = 0.04 * 60.0
    boxes = []
    for text, (x, y, ha) in at.items():
        w = 0.0105 * 30.0 * len(text)
        boxes.append((x - w, x, y, y + h) if ha == "right" else (x, x + w, y, y + h))
        assert 0.0 <= boxes[-1][0] and boxes[-1][1] <= 30.0 and 0.0 <= y <= 60.0, text
    for i, a in enumerate(boxes + [legend]):
        for b in boxes[i + 1:]:
            assert not (a[0] < b[1] and b[0] < a[1] and a[2] < b[3] and b[2] < a[3])
    stops = dict((round(p, 6), c) for p, c in cm.LOG_DEC_COLOURS)
    zero = -cm.LOG_DEC_SCALE[1] / 5
    assert stops[round((0.0 - zero) / (cm.LOG_DEC_SCALE[1] - zero), 6)] == "#ffffbf"


def test_radians_in_other_degree_keys_are_caught_too():
    """A component file's gear (``pressure_angle_deg``) and a Lin & Parker stage's per-mesh
    pressure angles in degrees get the same hint; radians under the plain key stay exact."""
    from gearmodal.model.components import Gear
    from gearmodal.model.file_schema import PER_MESH_ANGLE

    gear = {"name": "g", "teeth": 20, "module": 0.01, "pressure_angle_deg": 0.349,
            "mass": 1.0, "inertia": 1.0}
    with pytest.raises(gm.ModelError, match=r"give pressure_angle_deg = 20"):
        Gear.SCHEMA.read("bodies.g", gear)
    rad = {**{k: x for k, x in gear.items() if k != "pressure_angle_deg"},
           "pressure_angle": 0.349}
    assert Gear.SCHEMA.read("bodies.g", rad)["pressure_angle"] == 0.349
    with pytest.raises(gm.ModelError, match=r"sun_planet = 0\.349 deg: .* give 20"):
        PER_MESH_ANGLE.read("lin_parker_stage.pressure_angle_deg",
                            {"sun_planet": 0.349, "ring_planet": 20.0})


def test_an_unwritable_output_folder_is_one_line_before_any_computing(tmp_path, capsys,
                                                                      monkeypatch):
    """``--out`` under a file (not a folder), and a write that fails mid-run (a full disk,
    simulated): one line naming the folder or the file and the cause, exit status 2, not an
    internal error. (Root writes into read-only folders, so CI cannot test those directly.)"""
    from gearmodal.cli import main

    (tmp_path / "file").write_text("x")
    assert main(["simulate", "studies/scenes/gear_rattle.toml", "--out",
                 str(tmp_path / "file" / "run")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--out = " in err and "cannot write there" in err
    import errno

    import gearmodal.result_io as rio

    def full(*a, **k):
        raise OSError(errno.ENOSPC, "No space left on device", str(tmp_path / "x.parquet"))

    monkeypatch.setattr(rio, "write_table", full)
    monkeypatch.setattr("gearmodal.integrate.result.write_table", full)
    assert main(["simulate", "studies/scenes/gear_rattle.toml", "--out", str(tmp_path / "r"),
                 "--t-end", "0.01", "--format", "csv"]) == 2
    err = capsys.readouterr().err
    assert "cannot write" in err and "No space left on device" in err
    assert "internal error" not in err
