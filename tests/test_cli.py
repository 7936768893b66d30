"""The command line: the Campbell report of the 600 kW example, and clean input errors."""

import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest

from gearmodal.cli import main

MODEL = "studies/models/600kw.toml"


@pytest.mark.slow
def test_campbell_report_600kw(tmp_path):
    out = tmp_path / "r"
    assert main(["campbell", MODEL, "--out", str(out), "--speeds", "0:27:28", "--quiet"]) == 0
    for f in ("campbell.csv", "crossings.csv", "modes.csv", "campbell.png",
              "campbell_low.png", "report.html", "mode_01.png"):
        assert (out / f).exists(), f
    camp = pd.read_csv(out / "campbell.csv")
    assert list(camp.columns[:5]) == ["speed_rpm", "mode", "frequency_hz", "damping_ratio",
                                      "mode_type"]
    modes = pd.read_csv(out / "modes.csv")
    # the paper's gearbox-housing translation modes near 10 Hz (section 2), labelled housing
    housing = modes[(modes.frequency_hz > 8) & (modes.frequency_hz < 12)]
    assert len(housing) == 2 and set(housing.mode_type) == {"housing"}
    html = (out / "report.html").read_text()
    assert "Gearbox housing modes" in html and "data:image/png;base64," in html


def test_bad_model_file_gives_one_line_error(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text(open(MODEL).read().replace("teeth = 99", "teeth = 98"))
    r = subprocess.run([sys.executable, "-m", "gearmodal.cli", "campbell", str(bad), "--out",
                        str(tmp_path / "o")], capture_output=True, text=True)
    assert r.returncode == 2
    assert "Traceback" not in r.stderr
    assert "ring.teeth = 98" in r.stderr and "21 + 2 * 39 = 99" in r.stderr
    r = subprocess.run([sys.executable, "-m", "gearmodal.cli", "modal", str(tmp_path / "no.toml"),
                        "--out", str(tmp_path / "o")], capture_output=True, text=True)
    assert r.returncode == 2 and "Traceback" not in r.stderr


def test_simulate_scene_writes_events_forces_and_figures(tmp_path):
    from gearmodal.result_io import read_csv

    out = tmp_path / "dc"
    assert main(["simulate", "studies/scenes/planetary_double_contact.toml", "--out", str(out),
                 "--t-end", "0.05"]) == 0
    for f in ("events.parquet", "forces.parquet", "forces.png", "double_contact.csv",
              "load_sharing.parquet", "settings.json"):
        assert (out / f).exists(), f
    ev = pd.read_parquet(out / "events.parquet")
    assert list(ev.columns) == ["time", "element", "contact", "state_before", "state_after",
                                "gap_rate", "force_after", "peak_force_N", "peak_time"]
    ends = ev[ev.state_after == "open"]
    assert ends.peak_force_N.notna().all() and ev[ev.state_after == "closed"].peak_time.isna().all()
    assert (ev.contact == "back").any()  # the clearance lets the back flanks touch
    dc = pd.read_csv(out / "double_contact.csv")
    assert len(dc) and (dc.duration > 0).all()
    # the tables streamed while the run went are the run's: the same as CSV written after it
    csv = tmp_path / "csv"
    assert main(["simulate", "studies/scenes/planetary_double_contact.toml", "--out", str(csv),
                 "--t-end", "0.05", "--format", "csv"]) == 0
    pd.testing.assert_frame_equal(pd.read_csv(csv / "events.csv"), ev, check_exact=True,
                                  check_dtype=False)
    f_csv = read_csv(csv / "forces.csv", index_col="time")
    f_pq = pd.read_parquet(out / "forces.parquet").set_index("time")
    pd.testing.assert_frame_equal(f_csv, f_pq, check_exact=True)
    ls_csv = read_csv(csv / "load_sharing.csv", index_col="time")
    pd.testing.assert_frame_equal(ls_csv, pd.read_parquet(out / "load_sharing.parquet")
                                  .set_index("time"), check_exact=True)


def test_bad_scene_is_one_line_error(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text('[scene]\nmodel = "x.toml"\nt_end = -1\ndt = 1e-4\n')
    r = subprocess.run([sys.executable, "-m", "gearmodal.cli", "simulate", str(bad), "--out",
                        str(tmp_path / "o")], capture_output=True, text=True)
    assert r.returncode == 2 and "Traceback" not in r.stderr and "x.toml" in r.stderr


def test_bad_flags_and_scene_values_are_refused_by_name(tmp_path, capsys):
    """Flags and scene values that used to crash, hang or be misread (issue "Unbreakable
    inputs"): a non-finite load, a sweep of 1e8 speeds or to 1e300 rpm, an empty --speeds,
    a step longer than the run, 'connected = "false"' (a string that read as true)."""
    out = str(tmp_path / "o")
    for flags, field in ((["--load", "pinion.torque=nan"], "--load"),
                         (["--load", "pinion.torque=inf"], "--load"),
                         (["--speeds", "0:10:100000000"], "--speeds"),
                         (["--speeds", "0:1e300:3"], "--speeds"),
                         (["--speeds", ""], "--speeds")):
        assert main(["campbell", "studies/models/gear_pair.toml", "--out", out, *flags]) == 2
        assert field in capsys.readouterr().err
    scene = tmp_path / "s.toml"
    model = str(Path(MODEL).resolve().parent / "gear_pair.toml")
    scene.write_text(f'[scene]\nmodel = "{model}"\nt_end = 0.01\ndt = 1.0\n')
    assert main(["simulate", str(scene), "--out", out]) == 2
    assert "scene.dt" in capsys.readouterr().err
    turb = tmp_path / "t.toml"
    text = open("studies/scenes/600kw_turbine_10ms.toml").read()
    text = text.replace('"../models/', '"' + str(Path("studies/models").resolve()) + "/")
    text = text.replace('"../turbines/', '"' + str(Path("studies/turbines").resolve()) + "/")
    text = text.replace("connected = false", 'connected = "false"')
    turb.write_text(text)
    assert main(["simulate", str(turb), "--out", out]) == 2
    assert "turbine.connected" in capsys.readouterr().err


def test_version(capsys):
    import gearmodal as gm

    with pytest.raises(SystemExit) as e:
        main(["--version"])
    assert e.value.code == 0 and capsys.readouterr().out.strip() == f"gearmodal {gm.__version__}"


def test_shipped_examples_are_found_by_name(tmp_path, monkeypatch, capsys):
    """An installed gearmodal runs its examples without the source tree: a model or scene
    given by name is the shipped one (gearmodal.library, pyproject.toml's package-dir)."""
    monkeypatch.chdir(tmp_path)  # no studies/ folder here
    assert main(["info", "600kw"]) == 0
    assert "600kw: 13 bodies" in capsys.readouterr().out
    assert main(["info", "no_such_model"]) == 2
    assert "no_such_model" in capsys.readouterr().err


def test_python_dash_m_runs_the_command_line():
    """``python -m gearmodal`` is the command line (docs-figures runs each figure's command
    so, in a fresh process)."""
    import subprocess
    import sys

    import gearmodal as gm

    out = subprocess.run([sys.executable, "-m", "gearmodal", "--version"], capture_output=True,
                         text=True, check=True).stdout
    assert out.strip() == f"gearmodal {gm.__version__}"


@pytest.mark.parametrize("argv, message", [
    (["docs-figures", "--out", "{f}"], "is a file, not a folder"),
    (["study", "power-curve", "--out", "{f}"], "is a file, not a folder"),
    (["study", "power-curve", "--out", "{f}/sub"], "is a file, not a folder"),
    (["fmu", "studies/models/gear_pair.toml", "--out", "{f}/x.fmu"], "is a file, not a folder"),
    (["fmu", "studies/models/gear_pair.toml", "--out", "{d}.fmu"], "is a folder"),
])
def test_a_file_where_a_folder_goes_is_one_line(tmp_path, capsys, argv, message):
    """Issue 62: an output folder that is a file, or under one, and an FMU path that is a
    folder: exit 2 with gearmodal's one-line message, before anything is computed."""
    f = tmp_path / "f"
    f.write_text("x")
    (tmp_path / "d.fmu").mkdir()
    argv = [a.format(f=f, d=tmp_path / "d") for a in argv]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("gearmodal: error: --out") and message in err
    assert err.count("\n") == 1, err
