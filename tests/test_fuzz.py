"""Unbreakable inputs (issue 24): malformed model files, scene files, wind and turbine tables and
command-line flags, generated over classes of faults (numbers, types, structure, semantics,
flags), each run through the CLI in-process. A case fails on a traceback or an internal error
(exit 3), a hang, an exit 0 for an input that must be refused, or a NaN/inf in what a run that
was accepted wrote. Every refusal must name the field it is about.
"""

from __future__ import annotations

import math
import signal
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from gearmodal.cli import main

ROOT = Path(__file__).resolve().parents[1]
PAIR = (ROOT / "studies" / "models" / "gear_pair.toml").read_text()
STAGE = (ROOT / "studies" / "models" / "planetary_clearance.toml").read_text()
TURBINE = (ROOT / "studies" / "turbines" / "600kw_turbine.toml").read_text()
SCENE = (ROOT / "studies" / "scenes" / "gear_rattle.toml").read_text().replace(
    "t_end = 0.1 ", "t_end = 0.005 ")
TURBINE_SCENE = (ROOT / "studies" / "scenes" / "600kw_turbine_10ms.toml").read_text()

REFUSE, EITHER = "refuse", "either"  # must be refused / may run if what it writes is finite


def _sub(text: str, old: str, new: str) -> str:
    assert old in text, old
    return text.replace(old, new, 1)


# -- the cases --------------------------------------------------------------------------------
def _number_cases():
    """Every numeric key of the gear pair's model file x bad numbers and bad types."""
    keys = [("mesh_stiffness = 2.0e8", "mesh_stiffness", False),
            ("backlash = 1.0e-4", "backlash", False),
            ("mesh_damping = 40.0", "mesh_damping", False),
            ("teeth = 20", "teeth", True), ("module = 0.004", "module", True),
            ("pressure_angle_deg = 20.0", "pressure_angle_deg", True),
            ("mass = 0.99", "mass", True), ("inertia = 2.0e-4", "inertia", True)]
    bad = [("nan", REFUSE), ("inf", REFUSE), ("-inf", REFUSE), ("-1.0", REFUSE),
           ("1e300", REFUSE), ('"1.0"', REFUSE), ("true", REFUSE), ("[1.0]", REFUSE),
           ("{ x = 1.0 }", REFUSE), ("1e-300", EITHER), ("0.0", EITHER)]
    for old, key, positive in keys:
        for value, expect in bad:
            if positive and value in ("0.0", "1e-300"):
                expect = REFUSE  # masses, inertias, modules, teeth, angles: > 0 and plausible
            yield (f"model-{key}={value}", "model", _sub(PAIR, old, f"{key} = {value}"), key,
                   expect)


def _structure_cases():
    yield "model-unknown-key", "model", PAIR + "\n[gear_pair.extra]\nx = 1\n", "extra", REFUSE
    yield ("model-misspelt-key", "model", _sub(PAIR, "mesh_damping", "mesh_dampign"),
           "mesh_dampign", REFUSE)
    yield ("model-missing-key", "model", _sub(PAIR, "mass = 0.99", ""), "mass", REFUSE)
    yield ("model-missing-table", "model", PAIR[:PAIR.index("[gear_pair.wheel]")], "wheel",
           REFUSE)
    yield ("model-table-as-number", "model", PAIR.replace("[gear_pair.wheel]",
                                                          "[gear_pair.whee]"), "whee", REFUSE)
    yield ("model-type", "model", _sub(PAIR, 'type = "gear_pair"', 'type = "gearpair"'),
           "model.type", REFUSE)
    yield ("model-type-number", "model", _sub(PAIR, 'type = "gear_pair"', "type = 5"),
           "model.type", REFUSE)
    yield ("model-dofs", "model", _sub(PAIR, 'dofs = "torsional"', 'dofs = "2d"'), "dofs",
           REFUSE)
    yield "model-syntax", "model", PAIR.replace("backlash = ", "backlash "), "syntax", REFUSE
    yield "model-empty", "model", "", "model", REFUSE
    yield ("model-deep", "model", "x = " + "[" * 5000 + "]" * 5000 + "\n", "nested", REFUSE)
    yield ("model-nul", "model", PAIR.replace('name = "gear_pair"', 'name = "a\\u0000b"'),
           "name", EITHER)
    yield "model-binary", "binary", None, "UTF-8", REFUSE
    yield "model-directory", "directory", None, "cannot read", REFUSE
    yield "scene-binary", "binary-scene", None, "UTF-8", REFUSE
    yield "scene-directory", "directory-scene", None, "cannot read", REFUSE
    yield ("scene-deep", "scene", "x = " + "[" * 5000 + "]" * 5000 + "\n", "nested", REFUSE)


def _semantic_cases():
    """Models that parse but cannot be built: planets that overlap or cannot be assembled,
    helix hands that cannot mesh, teeth that do not add up."""
    for n in (8, 24):
        yield (f"stage-{n}-planets", "model", _sub(STAGE, "n_planets = 3", f"n_planets = {n}"),
               "n_planets", REFUSE)
    for angles in ("[0, 0, 0]", "[0, 10, 20]", "[0, 100, 200]", "[0.0, 120.0]"):
        yield (f"stage-angles-{angles}", "model",
               _sub(STAGE, "n_planets = 3", f"n_planets = 3\nplanet_angles_deg = {angles}"),
               "planet_angles_deg", REFUSE)
    yield ("stage-angles-ok", "model",
           _sub(STAGE, "n_planets = 3", "n_planets = 3\nplanet_angles_deg = [0, 117, 243]"),
           "", EITHER)
    yield ("stage-sun-planet-same-hand", "model", STAGE.replace("helix_angle_deg = -7.5",
                                                               "helix_angle_deg = 7.5"),
           "helix_angle", REFUSE)
    yield ("stage-ring-planet-opposite-hands", "model", _sub(
        STAGE, "helix_angle_deg = -7.5", "helix_angle_deg = 7.5"), "helix_angle", REFUSE)
    yield ("stage-ring-teeth", "model", _sub(STAGE, "teeth = 99", "teeth = 98"), "ring.teeth",
           REFUSE)
    yield ("pair-helix-same-hand", "model", PAIR.replace(
        "pressure_angle_deg = 20.0", "pressure_angle_deg = 20.0\nhelix_angle_deg = 10.0"),
        "helix_angle", REFUSE)
    yield ("pair-module-mm", "model", PAIR.replace("module = 0.004", "module = 4.0"), "module",
           REFUSE)


def _scene_cases():
    model = str(ROOT / "studies" / "models" / "gear_pair.toml")
    base = SCENE.replace('"../models/gear_pair.toml"', f'"{model}"')
    bad = [("t_end = 0.005", "t_end = 0.01\ndt_ = 1", "dt_"),
           ("dt = 1e-4", "dt = 1.0", "scene.dt"), ("dt = 1e-4", "dt = 1e300", "dt"),
           ("dt = 1e-4", "dt = 0.0", "dt"), ("dt = 1e-4", "dt = nan", "dt"),
           ("dt = 1e-4", "dt = 1e-13", "dt"), ("t_end = 0.005", "t_end = 1e300", "t_end"),
           ("t_end = 0.005", "t_end = -1.0", "t_end"), ("t_end = 0.005", 't_end = "1"', "t_end"),
           ('method = "exact"', 'method = "fast"', "method"),
           ('method = "exact"', "method = 1", "method"),
           ('method = "exact"', 'method = "exact"\ntolerance = 0.1', "tolerance"),
           ('method = "exact"', 'method = "exact"\nspeed_rpm = 1e300', "speed_rpm"),
           ('method = "exact"', 'method = "exact"\nspeed_rpm = -5.0', "speed_rpm"),
           ("[loads]", "loads = 5\n[q0_]", "loads"), ("[loads]", "[loads]\n[q0]\n", "q0"),
           ('"wheel.torque" = "balance"', '"wheel.torque" = "balance"\n[q0]\n'
            '"pinion.theta" = 1e300', "q0"),
           ('"wheel.torque" = "balance"', '"wheel.torque" = "balance"\n[q0]\n'
            '"pinion.theta" = "x"', "q0"),
           ('"wheel.torque" = "balance"', '"wheel.torque" = "balance"\n[v0]\n'
            '"pinion.nothing" = 1.0', "v0"),
           ('"wheel.torque" = "balance"', '"wheel.torque" = "balance"\n[options]\n'
            "warp_drive = 1", "warp_drive"),
           ('"wheel.torque" = "balance"', '"wheel.torque" = "balance"\noptions = "fast"',
            "options"),
           ("mean = 1.0", "mean = nan", "mean"), ("mean = 1.0", "mean = 1e300", "loads"),
           ("frequency_hz = 60.0", "frequency_hz = -60.0", "frequency_hz"),
           ("mean = 1.0", 'mean = "one"', "mean"),
           ('"wheel.torque" = "balance"', '"wheel.torque" = "balance"\n"x.torque" = 1.0',
            "x.torque"),
           ('"pinion.torque" = {', '"pinion.torque" = "balance"\n"q" = {', "balance"),
           (f'"{model}"', '"no_such_model.toml"', "no_such_model"),
           (f'"{model}"', '"a\\u0000b.toml"', "model"), (f'"{model}"', '""', "model"),
           (f'"{model}"', "5", "model"), ("[scene]", "[scenes]", "scenes")]
    for old, new, field in bad:
        yield f"scene-{new.splitlines()[-1][:30]}", "scene", _sub(base, old, new), field, REFUSE
    yield "scene-ok", "scene", base, "", EITHER


def _turbine_scene_cases():
    models = str(ROOT / "studies" / "models")
    turbines = str(ROOT / "studies" / "turbines")
    base = TURBINE_SCENE.replace('"../models/', f'"{models}/').replace(
        '"../turbines/', f'"{turbines}/').replace("t_end = 30.0", "t_end = 0.02")
    bad = [("turbulence_intensity = 0.12", 'turbulence_intensity = "high"',
            "turbulence_intensity"),
           ("turbulence_intensity = 0.12", "turbulence_intensity = 5.0", "turbulence_intensity"),
           ("seed = 1", 'seed = "one"', "seed"), ("seed = 1", "seed = 1.5", "seed"),
           ("seed = 1", "seed = -1", "seed"), ("[wind]", "[wind]\ngrid_points = 1e9",
                                               "grid_points"),
           ("[wind]", "[wind]\ngust = 1", "gust"),
           ("mean_speed = 10.0", "mean_speed = nan", "mean_speed"),
           ("aero_dt = 0.02", "aero_dt = 0.0", "aero_dt"),
           ("aero_dt = 0.02", "aero_dt = 0.0015", "aero_dt"),
           ("connected = false", 'connected = "false"', "connected"),
           ("connected = false", "connected = 0", "connected"),
           ('aero_hold = "interpolate"', 'aero_hold = "freeze"', "aero_hold"),
           ("rotor_speed0_rpm = 6.0", "rotor_speed0_rpm = -6.0", "rotor_speed0_rpm"),
           ("rotor_speed0_rpm = 6.0", "rotor_speed0_rpm = 1e300", "rotor_speed0_rpm"),
           ("[turbine]", "[turbine]\nrefreeze_deg = 0.1", "refreeze_deg"),
           ("[turbine]", "[turbine]\n[loads]\n", "loads")]
    for old, new, field in bad:
        yield (f"turbine-scene-{new.splitlines()[-1][:40]}", "scene", _sub(base, old, new),
               field, REFUSE)


def _turbine_file_cases():
    models = str(ROOT / "studies" / "models")
    bad = [("gear_ratio = 81.491", "gear_ratio = -81.0", "gear_ratio"),
           ("gear_ratio = 81.491", "gear_ratio_ = 81.0", "gear_ratio"),
           ("radius = 21.7", 'radius = "big"', "radius"), ("blades = 3", "blades = 0", "blades"),
           ("rated_slip = 0.02", "rated_slip = 2.0", "rated_slip"),
           ("[blade]", "[blades]", "blade"), ("stall_deg = 12.0", "stall_deg = 45.0",
                                              "stall_deg"),
           ("hub_height = 40.0", "hub_height = nan", "hub_height")]
    for old, new, field in bad:
        text = _sub(TURBINE, old, new)
        scene = TURBINE_SCENE.replace('"../models/', f'"{models}/').replace(
            '"../turbines/600kw_turbine.toml"', '"turbine.toml"')
        yield f"turbine-file-{new[:24]}", ("turbine", text, scene), None, field, REFUSE


def _flag_cases():
    model = str(ROOT / "studies" / "models" / "gear_pair.toml")
    for cmd in ("modal", "campbell"):
        for load in ("pinion.torque=nan", "pinion.torque=inf", "pinion.torque=x",
                     "nothing.torque=1", "pinion.torque", "pinion.torque=1e300"):
            yield (f"flag-{cmd}-load-{load}", "argv", [cmd, model, "--load", load], "load",
                   REFUSE)
    for speeds in ("0:10:100000000", "0:1e300:3", "", "5", "0:10:1", "a:b:c", "10:0:5",
                   "0:nan:5"):
        yield (f"flag-speeds-{speeds}", "argv", ["campbell", model, "--speeds", speeds],
               "speeds", REFUSE)
    yield "flag-out-empty", "argv", ["modal", model, "--out", ""], "out", REFUSE
    yield "flag-out-file", "argv-outfile", ["modal", model], "out", REFUSE
    yield "flag-no-model", "argv", ["modal", "no_such.toml"], "no_such", REFUSE
    yield "flag-speed-neg", "argv", ["modal", model, "--speed", "-5"], "speed", REFUSE
    # issue 62's command-line cases
    yield "flag-study-out-file", "argv-outfile", ["study", "power-curve"], "out", REFUSE
    yield ("flag-study-out-under-file", "argv-underfile", ["study", "power-curve"], "out",
           REFUSE)
    yield ("flag-fmu-out-under-file", "argv-underfile-fmu", ["fmu", model], "out", REFUSE)
    yield ("flag-fmu-drive-stiffness-alone", "argv",
           ["fmu", model, "--drive-stiffness", "2e3"], "drive-stiffness", REFUSE)
    yield ("flag-fmu-rebase-dt-fixed", "argv", ["fmu", model, "--rebase-dt", "0.01"],
           "rebase-dt", REFUSE)
    yield "flag-speed-huge", "argv", ["modal", model, "--speed", "1e300"], "speed", REFUSE


CASES = [*_number_cases(), *_structure_cases(), *_semantic_cases(), *_scene_cases(),
         *_turbine_scene_cases(), *_turbine_file_cases(), *_flag_cases()]


def test_there_are_enough_cases_of_every_class():
    assert len(CASES) >= 150
    kinds = {c[1] if isinstance(c[1], str) else c[1][0] for c in CASES}
    assert {"model", "scene", "turbine", "argv", "binary", "directory", "binary-scene"} <= kinds


# -- running one --------------------------------------------------------------------------------
class _Hang(Exception):
    pass


def _alarm(signum, frame):
    raise _Hang


def _run(kind, payload, tmp: Path) -> list[str]:
    out = tmp / "out"
    if kind == "model":
        f = tmp / "m.toml"
        f.write_text(payload)
        return ["modal", str(f), "--out", str(out)]
    if kind == "binary":
        f = tmp / "m.toml"
        f.write_bytes(bytes(range(256)) * 4)
        return ["modal", str(f), "--out", str(out)]
    if kind == "directory":
        return ["modal", str(tmp), "--out", str(out)]
    if kind == "binary-scene":
        f = tmp / "s.toml"
        f.write_bytes(bytes(range(256)) * 4)
        return ["simulate", str(f), "--out", str(out)]
    if kind == "directory-scene":
        return ["simulate", str(tmp), "--out", str(out)]
    if kind == "scene":
        f = tmp / "s.toml"
        f.write_text(payload)
        return ["simulate", str(f), "--out", str(out)]
    if isinstance(kind, tuple):  # a turbine file and a scene that uses it
        _, turbine, scene = kind
        (tmp / "turbine.toml").write_text(turbine)
        (tmp / "s.toml").write_text(scene)
        return ["simulate", str(tmp / "s.toml"), "--out", str(out)]
    if kind == "argv-outfile":
        (tmp / "taken").write_text("x")
        return [*payload, "--out", str(tmp / "taken")]
    if kind in ("argv-underfile", "argv-underfile-fmu"):
        (tmp / "taken").write_text("x")
        leaf = "x.fmu" if kind.endswith("fmu") else "run"
        return [*payload, "--out", str(tmp / "taken" / leaf)]
    argv = list(payload)
    if "--out" not in argv:
        argv += ["--out", str(out)]
    return argv


@pytest.mark.parametrize("case", CASES, ids=[c[0] for c in CASES])
def test_malformed_input_is_refused_by_name_or_runs_clean(case, tmp_path, capsys):
    name, kind, payload, field, expect = case
    argv = _run(kind, payload, tmp_path)
    old = signal.signal(signal.SIGALRM, _alarm)
    signal.alarm(120)  # a hang, not a slow case: each takes well under a second
    try:
        code = main(argv)
    except SystemExit as e:  # argparse refusing a flag: status 2 and a usage line
        code = e.code
    except _Hang:
        pytest.fail(f"{name}: hung")
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)
    err = capsys.readouterr().err
    assert "Traceback" not in err and code != 3, f"{name}: internal error: {err}"
    if expect == REFUSE:
        assert code == 2, f"{name}: accepted (exit {code}) what must be refused"
        # progress bars (tqdm, at the edges) may have started before a late check
        lines = [ln for ln in err.replace("\r", "\n").splitlines()
                 if ln.strip() and "%|" not in ln]
        # one line naming the field (argparse puts its usage lines before it for a flag)
        assert field.lower() in lines[-1].lower(), f"{name}: the error does not name " \
            f"{field!r}: {err}"
        assert lines[-1].startswith("gearmodal"), f"{name}: {err}"
        assert all(ln.startswith(("usage", " ", "gearmodal")) for ln in lines), \
            f"{name}: more than the error: {err}"
    else:
        assert code in (0, 2), f"{name}: exit {code}"
        if code == 0:
            for csv in (tmp_path / "out").rglob("*.csv"):
                df = pd.read_csv(csv)
                num = df.select_dtypes(include=[np.number]).to_numpy(dtype=float)
                assert np.all(np.isfinite(num[~np.isnan(num)])) and not (
                    np.isnan(num).any() and csv.name not in _NAN_ALLOWED), (name, csv.name)


#: tables that mark undefined values with NaN on purpose (shares of an unloaded stage, the
#: event log's episode peak on rows that do not end an episode)
_NAN_ALLOWED = {"load_sharing.csv", "crossings.csv", "modes.csv", "double_contact.csv",
                "elements.csv", "geometry.csv", "events.csv"}


def test_the_cases_cover_the_issues_examples():
    ids = {c[0] for c in CASES}
    for must in ("flag-modal-load-pinion.torque=nan", "flag-speeds-0:10:100000000",
                 "stage-8-planets", "stage-24-planets", "stage-angles-[0, 0, 0]",
                 "stage-angles-[0, 10, 20]", "model-teeth=1e300", "model-mass=1e-300",
                 "model-mesh_damping=1e300", "model-mesh_stiffness=1e300", "model-deep",
                 "flag-out-file", "flag-out-empty", "scene-binary", "scene-directory",
                 "scene-dt = 1.0", "scene-dt = 1e300", "scene-t_end = 1e300", "scene-[q0_]",
                 "scene-options = \"fast\"", "scene-warp_drive = 1",
                 "turbine-scene-connected = \"false\"", "turbine-scene-aero_dt = 0.0",
                 "turbine-scene-grid_points = 1e9", "turbine-scene-seed = \"one\"",
                 "turbine-scene-turbulence_intensity = \"high\""):
        assert must in ids, must
    assert math.isfinite(len(ids))


# -- issue 62: the co-simulation side's entries, misused through the Python API ---------------
def _stepper(**kw):
    import gearmodal as gm

    return gm.Stepper(gm.load(ROOT / "studies" / "models" / "gear_pair.toml"), dt=1e-4,
                      loads={"pinion.torque": 1.0}, **kw)


def _campbell_orders():
    import gearmodal as gm

    gm.campbell(gm.load(ROOT / "studies" / "models" / "gear_pair.toml"), [0.0, 100.0],
                orders={"x": "a"})


def _nan_load_index():
    import gearmodal as gm

    gm.simulate(gm.load(ROOT / "studies" / "models" / "gear_pair.toml"), 0.01, dt=1e-4,
                loads={"pinion.torque": pd.Series([1.0, 2.0, 3.0], index=[0.0, np.nan, 0.01])})


def _law_raises():
    import gearmodal as gm

    def law(w):
        raise ValueError("slip out of the table")

    _stepper(speed_torque=gm.SpeedTorque("wheel.theta", law))


def _edited_result(tmp: Path):
    import json

    import gearmodal as gm

    r = gm.simulate(gm.load(ROOT / "studies" / "models" / "gear_pair.toml"), 0.002, dt=1e-4)
    r.save(tmp / "run")
    meta = json.loads((tmp / "run" / "result.json").read_text())
    meta["initial_state"] = [1, 2]  # a wrong type (once an AttributeError)
    (tmp / "run" / "result.json").write_text(json.dumps(meta))
    gm.SimulationResult.load(tmp / "run")


API_CASES = [
    ("stepper-loads-a-list", lambda tmp: _stepper().advance(0.001, [1.0, 2.0]), "loads"),
    ("stepper-advance-1e9-s", lambda tmp: _stepper().advance(1e9), "t"),
    ("stepper-advance-1e6-s-recorded", lambda tmp: _stepper(record=True).advance(1e6), "t"),
    ("stepper-advance-nan", lambda tmp: _stepper().advance(float("nan")), "t"),
    ("stepper-load-nan", lambda tmp: _stepper().advance(0.001, {"pinion.torque": np.nan}),
     "pinion.torque"),
    ("stepper-reserve-passed", lambda tmp: (st := _stepper(), st.advance(0.002),
                                            st.reserve(0.001)), "t_end"),
    ("stepper-law-raises", lambda tmp: _law_raises(), "speed_torque"),
    ("campbell-orders-text", lambda tmp: _campbell_orders(), "orders"),
    ("load-index-nan", lambda tmp: _nan_load_index(), "pinion.torque"),
    ("result-json-edited", _edited_result, "result.json"),
]


@pytest.mark.parametrize("case", API_CASES, ids=[c[0] for c in API_CASES])
def test_cosimulation_misuse_is_refused_by_name(case, tmp_path):
    """Issue 62's cases of the Python API (the FMU's are in test_fmu.py, ROSCO's and the
    5 MW deck's in test_rosco.py and test_nrel5mw.py: they need their extras): a gearmodal
    error naming the field, never another exception, never accepted."""
    import gearmodal as gm

    name, call, field = case
    with pytest.raises(gm.GearmodalError) as e:
        call(tmp_path)
    assert field.lower() in str(e.value).lower(), f"{name}: {e.value}"
