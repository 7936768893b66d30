"""A gearbox model as an FMI 2.0 co-simulation FMU: ``gearmodal fmu MODEL.toml --out
gearbox.fmu`` (the ``fmu`` extra: pythonfmu).

The FMU wraps :class:`~gearmodal.fmu_slave.GearboxSlave`, which runs the public stepping API
(:class:`~gearmodal.integrate.stepper.Stepper`) on the model file it carries. It holds Python
source, not a compiled model: the host that loads it needs Python 3.10 or later with
gearmodal installed (pythonfmu's loader binaries: Linux x86-64, Windows x86-64, macOS). What it
offers by name:

- **inputs**: the model's loads chosen (default: the torque on every input or output wheel,
  N m), and with a drive (``--drive DOF``) the host's shaft ``drive.angle`` (rad) and
  ``drive.speed`` (rad/s), acting through the drive's spring-damper;
- **outputs**: any of the stepper's outputs (default: the driven wheels' angles and speeds,
  ``drive.torque`` with a drive, and every mesh flank and bearing force);
- **parameters**: ``dt`` (the output step, s: a communication step must be a whole number of
  them), ``speed_rpm``, ``method``, ``result_dir`` (a folder the gearbox's own result streams
  to; empty: none kept, constant memory); the reference rotation (``--reference follow``: it
  follows the drivetrain, as a host driving a planetary stage at a varying speed needs) is
  fixed when the FMU is built.
"""

from __future__ import annotations

import json
import re
import shutil
import sys
import tempfile
from pathlib import Path

from .errors import ModelError, unknown
from .model.model import Model
from .model.toml_io import load
from .result_io import file_in_the_way

__all__ = ["DEFAULT_DT", "export_fmu", "wheel_torques"]

#: the FMU's default output step, s
DEFAULT_DT = 1e-4
#: the roles of the wheels whose torques are an FMU's default inputs
WHEEL_ROLES = ("rotor", "generator", "carrier", "sun", "pinion", "wheel", "gear")


def wheel_torques(model: Model) -> list[str]:
    """The torque loads of the model's input and output wheels (roles :data:`WHEEL_ROLES`),
    in the model's order: an FMU's default inputs."""
    names = model.assemble().load_names
    out = []
    for body in model.bodies.values():
        name = f"{body.name}.torque"
        if getattr(body, "role", None) in WHEEL_ROLES and name in names:
            out.append(name)
    return out


def export_fmu(model_file, out, *, inputs: list[str] | None = None,
               outputs: list[str] | None = None, drive: dict | None = None,
               dt: float = DEFAULT_DT, speed_rpm: float = 0.0,
               method: str = "exact", reference: str = "fixed",
               rebase_dt: float | None = None) -> Path:
    """Build the FMU of the model in ``model_file`` at ``out`` (a ``.fmu`` path).

    ``inputs``: load names (default :func:`wheel_torques`); ``outputs``: stepper output names
    (module docstring); ``drive``: ``{"dof", "stiffness", "damping", "angle0", "speed0"}``
    (a :class:`~gearmodal.integrate.stepper.Drive`); ``dt``, ``speed_rpm``, ``method``: the
    parameters' start values; ``reference``, ``rebase_dt``: the stepper's (``"follow"``: the
    geometry turns with the drivetrain, for a host that drives it at a varying speed). Every
    name is checked (a :class:`ModelError` names the wrong one)
    by making the stepper once before the FMU is written."""
    out = Path(out)
    if out.suffix != ".fmu":
        raise ModelError("--out", f"= {str(out)!r}: give a file name ending in .fmu")
    if out.is_dir():
        raise ModelError("--out", f"= {str(out)!r} is a folder: give the FMU's file name")
    if (f := file_in_the_way(out.parent)) is not None:  # where the FMU's folder would be
        raise ModelError("--out", f"= {str(out)!r}: cannot write there ({str(f)!r} is a file, "
                         "not a folder)")
    try:
        from pythonfmu import FmuBuilder
    except ImportError:
        raise ModelError("fmu", "needs pythonfmu: pip install 'gearmodal[fmu]'") from None
    from .integrate.stepper import Drive, Stepper

    src = Path(model_file)
    model = load(src)
    names = model.assemble().load_names
    inputs = wheel_torques(model) if inputs is None else list(inputs)
    for name in inputs:
        if name not in names:
            raise ModelError(f"inputs.{name}", unknown("load", name, names))
    dr = None
    if drive:
        dr = Drive(drive["dof"], drive["stiffness"], drive.get("damping", 0.0))
    probe = Stepper(model, dt=dt, loads=dict.fromkeys(inputs, 0.0), drive=dr,
                    speed_rpm=speed_rpm, method=method, record=False, reference=reference,
                    rebase_dt=rebase_dt)
    if outputs is None:
        outputs = default_outputs(model, probe, inputs, dr)
    for name in outputs:
        if name not in probe.output_names:
            raise ModelError(f"outputs.{name}", unknown("output", name, probe.output_names))
    ident = re.sub(r"\W", "_", model.name or src.stem) or "gearbox"
    if not ident[0].isalpha():
        ident = "gearbox_" + ident
    cfg = {"model": src.name, "dt": dt, "speed_rpm": speed_rpm, "method": method,
           "reference": reference, "rebase_dt": rebase_dt,
           "inputs": dict.fromkeys(inputs, 0.0), "outputs": list(outputs),
           "drive": None if not drive else {k: float(v) if k != "dof" else v
                                             for k, v in drive.items()}}
    with tempfile.TemporaryDirectory(prefix="gearmodal_fmu_") as td:
        d = Path(td)
        script = d / f"{ident}.py"
        script.write_text(
            f'"""The FMU class of model {model.name!r} (written by gearmodal fmu)."""\n\n'
            "from gearmodal.fmu_slave import GearboxSlave\n\n\n"
            f"class {ident}(GearboxSlave):\n"
            f'    """{model.name} as an FMI 2.0 co-simulation slave."""\n')
        res = d / "res"
        res.mkdir()
        shutil.copy2(src, res / src.name)
        (res / "gearmodal_fmu.json").write_text(json.dumps(cfg, indent=2))
        out.parent.mkdir(parents=True, exist_ok=True)
        # pythonfmu imports the script by its module name: an FMU of the same name run in
        # this process (by fmpy) left its module there
        sys.modules.pop(ident, None)
        try:
            FmuBuilder.build_FMU(script, dest=out,
                                 project_files=[res / src.name, res / "gearmodal_fmu.json"])
        finally:
            sys.modules.pop(ident, None)
            if str(d) in sys.path:
                sys.path.remove(str(d))
    return out


def default_outputs(model: Model, stepper, inputs: list[str], drive) -> list[str]:
    """The driven wheels' angles and speeds, the drive's torque and every force column."""
    wheels = [nm.rsplit(".", 1)[0] + ".theta" for nm in inputs]
    if drive is not None:
        wheels.insert(0, drive.dof)
    outs = []
    for w in dict.fromkeys(wheels):
        if w in stepper.output_names:
            outs += [w, f"{w}.velocity"]
    if drive is not None:
        outs.append("drive.torque")
    return outs + list(stepper.fmap.labels)
