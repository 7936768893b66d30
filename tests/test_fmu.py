"""`gearmodal fmu`: the gearbox as an FMI 2.0 co-simulation FMU, run by fmpy (a client nobody
here wrote) and compared with the stepping API it wraps."""

import importlib
import os
import subprocess
import sys

import numpy as np
import pytest

import gearmodal as gm
from gearmodal.cli import main


def _need(module: str):
    """The fmu extra's modules: CI installs them (GEARMODAL_CI: missing is a failure), else
    the test skips saying how to get them."""
    if os.environ.get("GEARMODAL_CI"):
        return importlib.import_module(module)
    return pytest.importorskip(module, reason="the fmu extra: pip install -e '.[fmu]' (CI "
                                              "installs it)")


fmpy = _need("fmpy")
_need("pythonfmu")
from fmpy.validation import validate_fmu  # noqa: E402

H = 1e-3  # communication step, s
N = 50  # steps

#: fmpy's run in a process of its own: pythonfmu 0.7's loader crashes a process that makes a
#: second instance after the first was freed (PythonFMU issues 213, 228), and now and then at
#: the process's exit, in its library's destructor (issue 229: about 1 exit in 30 here); the
#: result saved, the process leaves without running the destructors (os._exit)
_RUN = """
import os, sys, numpy as np, fmpy
fmu, out, stop, inp, starts = sys.argv[1:6]
kw = dict(stop_time=float(stop), output_interval=float(sys.argv[6]),
          start_values=eval(starts), start_time=float(sys.argv[7]))
if inp != "-":
    kw["input"] = np.load(inp)
np.save(out, fmpy.simulate_fmu(fmu, **kw))
sys.stdout.flush()
os._exit(0)
"""


def simulate(fmu, stop_time, signal=None, start_values=None, interval=H, start_time=0.0):
    """``fmpy.simulate_fmu`` of ``fmu`` in a fresh process (:data:`_RUN`): its result."""
    d = os.path.dirname(str(fmu))
    inp = "-"
    if signal is not None:
        inp = os.path.join(d, "input.npy")
        np.save(inp, signal)
    out = os.path.join(d, "output.npy")
    r = subprocess.run([sys.executable, "-c", _RUN, str(fmu), out, repr(stop_time), inp,
                        repr(start_values or {}), repr(interval), repr(start_time)],
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr[-2000:]
    return np.load(out)


def _compare(fmu, model, signal, stepper_kw, start_values=None):
    """fmpy's run of ``fmu`` against the stepper advanced as an FMI master does (inputs
    sampled from ``signal`` at each step's start, held): the largest difference of every
    output, relative to its own largest value (floor: 1e-9 of the largest value of its kind,
    so that a force that is zero up to rounding is not compared on its rounding). The signal
    has a row at every communication point, where fmpy's interpolation and numpy's both give
    the row's value to the bit: these gearboxes rattle and are chaotic, so that inputs one
    rounding apart (the two interpolations between rows) part after some 30 steps."""
    md = fmpy.read_model_description(fmu)
    outs = [v.name for v in md.modelVariables if v.causality == "output"]
    res = simulate(fmu, N * H, signal, start_values)
    names = [n for n in signal.dtype.names if n != "time"]
    # the master sets the inputs at the start before initialisation ends: the stepper
    # starts from them
    u0 = {n: float(signal[n][0]) for n in names}
    if "drive" in stepper_kw:
        stepper_kw = {**stepper_kw, "drive": gm.Drive(
            stepper_kw["drive"].dof, stepper_kw["drive"].stiffness,
            stepper_kw["drive"].damping, angle0=u0.pop("drive.angle"),
            speed0=u0.pop("drive.speed"))}
    st = gm.Stepper(model, outputs=outs, **{**stepper_kw, "loads": u0})
    ref = [st.values()]
    for k in range(N):
        u = {n: float(np.interp(k * H, signal["time"], signal[n])) for n in names}
        drive = {}
        if "drive.angle" in u:
            drive = {"drive_angle": u.pop("drive.angle"), "drive_speed": u.pop("drive.speed")}
        ref.append(st.advance((k + 1) * H, u, hold="hold", **drive))
    a = np.array([[res[n][i] for n in outs] for i in range(N + 1)])
    b = np.array([[r[n] for n in outs] for r in ref])
    kind = np.array([0 if "." in n and n.rsplit(".", 1)[-1] in ("theta", "velocity", "x", "y")
                     and n.split(".")[0] in {d.split(".")[0] for d in st.asm.dof_names}
                     else 1 for n in outs])
    scale = np.abs(b).max(axis=0)
    for k in (0, 1):
        if np.any(kind == k):
            scale[kind == k] = np.maximum(scale[kind == k], 1e-9 * scale[kind == k].max())
    assert np.all(np.isfinite(a))
    return np.abs(a - b).max(axis=0) / np.maximum(scale, 1e-300), outs


def test_gear_pair_with_drive(tmp_path):
    """The gear pair driven through a spring from the host's shaft (angle, speed in; the
    drive's torque out), a wheel torque as a load input: fmpy validates it and runs it to
    the stepper's own outputs within 1e-9."""
    fmu = tmp_path / "pair.fmu"
    assert main(["fmu", "studies/models/gear_pair.toml", "--out", str(fmu), "--drive",
                 "pinion.theta", "--drive-stiffness", "2e3", "--drive-damping", "0.5",
                 "--input", "wheel.torque"]) == 0
    assert validate_fmu(str(fmu)) == []
    t = np.arange(N + 1) * H  # a row at every communication point (see _compare)
    w = 50.0 + 400.0 * t
    sig = np.array(list(zip(t, -20.0 + 50 * t, w * t, w, strict=True)),
                   dtype=[("time", float), ("wheel.torque", float), ("drive.angle", float),
                          ("drive.speed", float)])
    model = gm.load("studies/models/gear_pair.toml")
    err, outs = _compare(str(fmu), model, sig, dict(
        dt=1e-4, drive=gm.Drive("pinion.theta", 2e3, 0.5)))
    assert "drive.torque" in outs and "mesh.front" in outs
    assert err.max() <= 1e-9, dict(zip(outs, err, strict=True))


def test_clearance_stage_at_speed(tmp_path):
    """The clearance planetary stage with its default inputs (carrier and sun torques) at
    600 rpm (a parameter set by the master): validated, and fmpy's run is the stepper's."""
    fmu = tmp_path / "stage.fmu"
    assert main(["fmu", "studies/models/planetary_clearance.toml", "--out", str(fmu)]) == 0
    assert validate_fmu(str(fmu)) == []
    md = fmpy.read_model_description(str(fmu))
    ins = [v.name for v in md.modelVariables if v.causality == "input"]
    assert ins == ["carrier.torque", "sun.torque"]
    t = np.arange(N + 1) * H
    tc = 2e5 * (1 + np.sin(60 * t))
    sig = np.array(list(zip(t, tc, -tc / (1 + 99 / 21), strict=True)),
                   dtype=[("time", float), ("carrier.torque", float), ("sun.torque", float)])
    model = gm.load("studies/models/planetary_clearance.toml")
    err, outs = _compare(str(fmu), model, sig, dict(
        dt=1e-4, speed_rpm=600.0),
        start_values={"speed_rpm": 600.0})
    assert len(outs) > 20
    assert err.max() <= 1e-9, dict(zip(outs, err, strict=True))


def test_result_dir_parameter(tmp_path):
    """result_dir: the gearbox's own result streams there and is whole at the end."""
    fmu = tmp_path / "pair.fmu"
    assert main(["fmu", "studies/models/gear_pair.toml", "--out", str(fmu)]) == 0
    out = tmp_path / "result"
    res = simulate(fmu, 0.02, start_values={"result_dir": str(out), "pinion.torque": 2.0})
    back = gm.SimulationResult.load(out)
    assert back.q.index[-1] == pytest.approx(0.02)
    assert back.q["pinion.theta"].iloc[-1] == pytest.approx(res["pinion.theta"][-1],
                                                            rel=1e-12)


@pytest.mark.parametrize("args, match", [
    (["--out", "x.zip"], "ending in .fmu"),
    (["--out", "x.fmu", "--input", "nope"], "inputs.nope"),
    (["--out", "x.fmu", "--output", "nope"], "outputs.nope"),
    (["--out", "x.fmu", "--drive", "pinion.theta"], "--drive-stiffness"),
    (["--out", "x.fmu", "--drive-stiffness", "2e3"], "need --drive DOF"),
    (["--out", "x.fmu", "--rebase-dt", "0.01"], "--rebase-dt"),
])
def test_bad_arguments(tmp_path, capsys, monkeypatch, args, match):
    model = os.path.abspath("studies/models/gear_pair.toml")
    monkeypatch.chdir(tmp_path)  # (x.fmu would be written here)
    assert main(["fmu", model, *args]) == 2
    assert match in capsys.readouterr().err
    assert not os.path.exists("x.fmu")


def test_stage_driven_through_its_shaft_follows(tmp_path):
    """The clearance stage driven through a shaft spring by a host spinning it up
    (``--reference follow``: the geometry turns with the carrier): fmpy's run is the
    stepper's."""
    fmu = tmp_path / "driven.fmu"
    assert main(["fmu", "studies/models/planetary_clearance.toml", "--out", str(fmu),
                 "--drive", "carrier.theta", "--drive-stiffness", "5e7", "--drive-damping",
                 "2e4", "--input", "sun.torque", "--reference", "follow"]) == 0
    assert validate_fmu(str(fmu)) == []
    t = np.arange(N + 1) * H
    w = 60.0 * t / (N * H)
    sig = np.array(list(zip(t, -1e4 * w / 60.0, np.cumsum(w) * H, w, strict=True)),
                   dtype=[("time", float), ("sun.torque", float), ("drive.angle", float),
                          ("drive.speed", float)])
    model = gm.load("studies/models/planetary_clearance.toml")
    err, outs = _compare(str(fmu), model, sig, dict(
        dt=1e-4, drive=gm.Drive("carrier.theta", 5e7, 2e4), reference="follow"))
    assert "drive.torque" in outs
    assert err.max() <= 1e-9, dict(zip(outs, err, strict=True))


#: FMI calls on one instance in a fresh process (fmpy's low-level FMU2Slave, as a host calls
#: them; :data:`_RUN`'s reason), each printed with its status; fmpy's default logger prints
#: what the FMU logs as "[ERROR] message"
_CALLS = """
import os, sys, fmpy
from fmpy.fmi2 import FMU2Slave
fmu, script = sys.argv[1:3]
md = fmpy.read_model_description(fmu)
vr = {v.name: v.valueReference for v in md.modelVariables}
s = FMU2Slave(guid=md.guid, unzipDirectory=fmpy.extract(fmu), instanceName="gearbox",
              modelIdentifier=md.coSimulation.modelIdentifier)
def call(name, *args):
    try:
        out = getattr(s, name)(*args)
        print("OK", name, out, flush=True)
    except Exception as e:
        print("STATUS", name, getattr(e, "status", type(e).__name__), flush=True)
try:
    s.instantiate(loggingOn=True)
except Exception as e:
    print("INSTANTIATE", e, flush=True)
    os._exit(0)
def start():
    call("setupExperiment", None, 0.0)
    call("enterInitializationMode")
    call("exitInitializationMode")
exec(script)
sys.stdout.flush()
os._exit(0)
"""


def calls(fmu, script: str) -> list[str]:
    """The lines printed by :data:`_CALLS` running ``script`` on an instance of ``fmu``."""
    r = subprocess.run([sys.executable, "-c", _CALLS, str(fmu), script], capture_output=True,
                       text=True, timeout=600)
    assert r.returncode == 0, r.stderr[-2000:]
    return r.stdout.splitlines()


@pytest.fixture(scope="module")
def pair_fmu(tmp_path_factory):
    """The gear pair's FMU with its default inputs (pinion and wheel torques)."""
    fmu = tmp_path_factory.mktemp("fmu") / "pair.fmu"
    assert main(["fmu", "studies/models/gear_pair.toml", "--out", str(fmu)]) == 0
    return fmu


def test_state_machine(pair_fmu):
    """Issue 62: each call checked against the FMI 2.0 state it is allowed in; a refused
    doStep is fmi2Discard (2) with gearmodal's message logged as an error, the instance then
    in stepFailed; a step from another point than the FMU's time is refused."""
    out = calls(pair_fmu, """
call("doStep", 0.0, 1e-3)                   # before initialisation
start()
call("doStep", 0.0, 1e-3)
call("doStep", 0.498, 1e-3)                 # the host's time is not the FMU's
call("doStep", 0.001, 1e-3)                 # after a refused step
call("getReal", [vr["pinion.theta"]])
call("terminate")
call("doStep", 0.001, 1e-3)                 # after fmi2Terminate
""")
    text = "\n".join(out)
    assert out[0].startswith("[ERROR] gearmodal: fmi2DoStep refused in state instantiated")
    assert out[1] == "STATUS doStep 2"
    assert "OK doStep None" in out  # the step from 0
    assert ("currentCommunicationPoint = 0.498 s, but the FMU is at 0.001 s" in text)
    assert "fmi2DoStep refused in state stepFailed" in text
    assert any(line.startswith("OK getReal") for line in out)
    assert "OK terminate 0" in out
    assert "fmi2DoStep refused in state terminated" in text
    assert out.count("STATUS doStep 2") == 4


def test_fixed_parameter_after_initialisation(pair_fmu):
    """Setting the fixed parameter dt after initialisation is refused (pythonfmu 0.7 gives
    fmi2Fatal, 4, to any refusal but doStep's), gearmodal's message logged first."""
    out = calls(pair_fmu, 'start(); call("setReal", [vr["dt"]], [1e-3])')
    assert ("[ERROR] gearmodal: fmi2SetReal refused in state stepComplete: dt is a "
            "parameter fixed when initialisation ends") in "\n".join(out)
    assert out[-1] == "STATUS setReal 4"


@pytest.mark.parametrize("script, message", [
    ('call("setupExperiment", None, 0.0); call("enterInitializationMode");'
     'call("setReal", [vr["dt"]], [float("nan")])', "dt = nan: must be a finite number"),
    ('start(); call("doStep", 0.0, 0.0)', "communicationStepSize = 0.0: must be positive"),
    ('start(); call("doStep", 0.0, -1e-3)', "communicationStepSize = -0.001: must be positive"),
    ('start(); call("doStep", 0.0, 1.5e-4)', "by a whole number of output steps dt = 0.0001"),
    ('start(); call("doStep", 0.0, 1e9)', "advance in shorter calls"),
    ('start(); call("setReal", [vr["pinion.torque"]], [float("nan")]);'
     'call("doStep", 0.0, 1e-3)', "loads.pinion.torque = nan: must be a finite number"),
    ('call("setupExperiment", None, 0.0); call("enterInitializationMode");'
     'call("setString", [vr["result_dir"]], [os.path.join(os.path.abspath(fmu), "res")]);'
     'call("exitInitializationMode")', "cannot write the result there"),
])
def test_refusals_logged(pair_fmu, script, message):
    """Bad parameters, steps and inputs: refused with a non-OK status, the reason logged
    through the FMI logger as an error (the result folder asked under a file, the FMU)."""
    out = calls(pair_fmu, script)
    errors = [line for line in out if line.startswith("[ERROR] gearmodal:")]
    assert errors and message in errors[-1], out
    assert out[-1].startswith("STATUS") and out[-1].split()[-1] in ("2", "4")


def test_damaged_configuration(pair_fmu, tmp_path):
    """A damaged gearmodal_fmu.json inside the FMU: instantiation fails (fmi2Instantiate
    returns NULL) with gearmodal's message naming the file, not a JSONDecodeError."""
    import zipfile

    bad = tmp_path / "damaged.fmu"
    with zipfile.ZipFile(pair_fmu) as src, zipfile.ZipFile(bad, "w") as dst:
        for item in src.infolist():
            data = src.read(item)
            if item.filename.endswith("gearmodal_fmu.json"):
                data = data[:len(data) // 2]
            dst.writestr(item, data)
    out = calls(bad, "")
    assert out[-1].startswith("INSTANTIATE")
    assert any("gearmodal_fmu.json" in line and "rebuild the FMU" in line for line in out)


def test_start_time(pair_fmu):
    """Any start time: the gearbox's time 0 is the first communication point, so a
    time-invariant setup gives the same outputs from t = 1 s as from t = 0 (to the bit)."""
    sv = {"pinion.torque": 2.0, "wheel.torque": -1.0}
    a = simulate(pair_fmu, 0.01, start_values=sv)
    b = simulate(pair_fmu, 1.01, start_values=sv, start_time=1.0)
    assert len(a) == len(b) == 11
    np.testing.assert_allclose(b["time"] - 1.0, a["time"], atol=1e-12)
    for name in a.dtype.names[1:]:
        np.testing.assert_array_equal(a[name], b[name], err_msg=name)


def test_every_variable_has_its_unit_and_description(tmp_path):
    """Issue 58: each Real variable declares its SI unit (defined in UnitDefinitions with its
    base units, so a host converts), each variable a description; fmpy validates it."""
    fmu = tmp_path / "stage.fmu"
    assert main(["fmu", "studies/models/planetary_clearance.toml", "--out", str(fmu),
                 "--drive", "carrier.theta", "--drive-stiffness", "5e7"]) == 0
    assert validate_fmu(str(fmu)) == []
    md = fmpy.read_model_description(str(fmu))
    units = {u.name: u for u in md.unitDefinitions}
    by = {v.name: v for v in md.modelVariables}
    assert all(v.description for v in md.modelVariables)
    for v in md.modelVariables:
        if v.type == "Real":
            assert v.unit in units, v.name
    expect = {"dt": "s", "speed_rpm": "rpm", "sun.torque": "N.m", "drive.angle": "rad",
              "drive.speed": "rad/s", "drive.torque": "N.m", "carrier.theta": "rad",
              "carrier.theta.velocity": "rad/s", "sun_planet1.front": "N",
              "carrier_bearing.x": "N"}
    for name, unit in expect.items():
        assert by[name].unit == unit, name
    rpm = units["rpm"].baseUnit
    assert rpm.rad == 1 and rpm.s == -1 and rpm.factor == pytest.approx(np.pi / 30, rel=1e-15)
    assert (units["N.m"].baseUnit.kg, units["N.m"].baseUnit.m, units["N.m"].baseUnit.s) == \
        (1, 2, -2)
