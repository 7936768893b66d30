"""The gearbox inside an FMI 2.0 co-simulation FMU (:mod:`gearmodal.fmu` builds it): a
pythonfmu slave that runs a :class:`~gearmodal.integrate.stepper.Stepper`.

The FMU's resources hold the model file and ``gearmodal_fmu.json`` (what :func:`gearmodal.fmu.
export_fmu` chose: inputs, outputs, drive, method, step); the host needs Python with gearmodal
installed. Inputs are set at a communication step's start and held over it (FMI's usual
zero-order hold: the stepper's ``hold="hold"``; a drive's shaft turns at its speed input over
the step); outputs are the stepper's at the step's end. Parameters (``dt``, ``speed_rpm``,
``method``, ``result_dir``) take effect when initialisation ends and are fixed after it.

**The FMI 2.0 state machine** (FMI 2.0.4, section 4.2.4, the co-simulation state chart) is
enforced: every call is checked against the states it is allowed in (:data:`ALLOWED`), every
refusal is logged through the host's FMI logger (status ``fmi2Error``, category
``logStatusError``) with a message naming the call, the state and what to do. pythonfmu 0.7
gives the slave two ways to refuse: ``fmi2DoStep`` returns ``fmi2Discard`` (the step is not
taken; the instance then takes only getters, ``fmi2Terminate``, ``fmi2Reset`` and
``fmi2FreeInstance``, FMI's *stepFailed*), and every other call returns ``fmi2Fatal`` (its
loader turns a Python exception into that status; there is no path to ``fmi2Error``).

**Time.** FMI's first ``fmi2DoStep`` starts at the experiment's start time (pythonfmu 0.7
passes ``fmi2SetupExperiment``'s start time to Python, not its stop time): the gearbox's time 0
is that point, any start time gives the same run, and every later call must start where the
last one ended (to 1e-9 of the time, the host's accumulated rounding) or it is refused.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

from pythonfmu import Fmi2Causality, Fmi2Initial, Fmi2Slave, Fmi2Variability, Real, String
from pythonfmu.enums import Fmi2Status

from .errors import GearmodalError, ModelError, SolveError
from .integrate.stepper import Drive, Stepper
from .model.toml_io import load
from .units import BASE_UNITS, load_unit, output_units

#: the FMU's configuration file in its resources
CONFIG = "gearmodal_fmu.json"

#: the slave's states (FMI 2.0 co-simulation; "stepFailed": a refused or failed step)
STATES = ("instantiated", "initializationMode", "stepComplete", "stepFailed", "terminated")

#: the states each call is allowed in (FMI 2.0.4, table 4.2.4); setters of a parameter
#: (variability fixed) only before initialisation ends, of an input also while stepping;
#: getters also before initialisation (the start values: pythonfmu's builder reads them)
ALLOWED = {
    "fmi2EnterInitializationMode": ("instantiated",),
    "fmi2ExitInitializationMode": ("initializationMode",),
    "fmi2DoStep": ("stepComplete",),
    "fmi2Terminate": ("stepComplete", "stepFailed"),
    "fmi2Get": ("instantiated", "initializationMode", "stepComplete", "stepFailed", "terminated"),
    "fmi2Set parameter": ("instantiated", "initializationMode"),
    "fmi2Set input": ("instantiated", "initializationMode", "stepComplete"),
}

#: a communication point this close (relative to the time, or to dt) to the FMU's is its own
TIME_TOL = 1e-9


class UnitReal(Real):
    """A Real variable with its unit (FMI 2.0 ``unit``, defined in the description's
    ``UnitDefinitions``; pythonfmu 0.7's Real has none)."""

    def __init__(self, name: str, unit: str | None = None, **kwargs):
        super().__init__(name, **kwargs)
        self.unit = unit

    def to_xml(self):
        node = super().to_xml()
        if self.unit:
            node.find("Real").set("unit", self.unit)
        return node


def _describe(name: str, unit: str, kind: str) -> str:
    """A variable's description: what it is, its unit, when it applies."""
    if kind == "input":
        return f"load {name} ({unit}), set at a communication step's start, held over it"
    if name == "drive.torque":
        return "torque of the drive's spring-damper on the host's shaft (N.m; on the " \
               "gearbox: the opposite)"
    if name.endswith(".velocity"):
        return f"velocity of {name[:-9]} ({unit}; rotations absolute) at the step's end"
    if unit in ("m", "rad"):
        return f"coordinate {name} ({unit}; rotations absolute) at the step's end"
    if name.rsplit(".", 1)[-1] in ("front", "back"):
        return f"contact force on flank {name} ({unit}, >= 0: a flank only pushes) at the " \
               "step's end"
    return f"force of spring {name} ({unit}) at the step's end"


class GearboxSlave(Fmi2Slave):
    """An FMI 2.0 co-simulation slave advancing a gearbox model (module docstring)."""

    author = "gearmodal"
    description = "Gearbox contact dynamics (gearmodal, exact piecewise-linear method)"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.state = "instantiated"
        self.failure = ""  # why the instance is in stepFailed
        self.t0: float | None = None  # the first doStep's communication point
        res = Path(self.resources)
        self.cfg = _config(res / CONFIG)
        self.model = load(res / self.cfg["model"])
        self.dt = float(self.cfg["dt"])
        self.speed_rpm = float(self.cfg["speed_rpm"])
        self.method = str(self.cfg["method"])
        self.result_dir = ""
        self.u = {k: float(x) for k, x in self.cfg["inputs"].items()}
        drive = self.cfg.get("drive")
        self.host = [float(drive.get("angle0", 0.0)), float(drive.get("speed0", 0.0))] \
            if drive else None
        par = {"causality": Fmi2Causality.parameter, "variability": Fmi2Variability.fixed}
        self.register_variable(UnitReal(
            "dt", "s", **par, getter=lambda: self.dt,
            setter=lambda x: setattr(self, "dt", float(x)),
            description="output step (s): a communication step is a whole number of them"))
        self.register_variable(UnitReal(
            "speed_rpm", "rpm", **par, getter=lambda: self.speed_rpm,
            setter=lambda x: setattr(self, "speed_rpm", float(x)),
            description="speed of the reference rotation at the input (rpm)"))
        self.register_variable(String(
            "method", **par, getter=lambda: self.method,
            setter=lambda x: setattr(self, "method", str(x)),
            description="integration method: exact (default), newmark or scipy"))
        self.register_variable(String(
            "result_dir", **par, getter=lambda: self.result_dir,
            setter=lambda x: setattr(self, "result_dir", str(x)),
            description="folder the gearbox's own result streams to (empty: none kept)"))
        for name in self.u:
            unit = load_unit(name)
            self.register_variable(UnitReal(
                name, unit, causality=Fmi2Causality.input,
                variability=Fmi2Variability.continuous, getter=lambda n=name: self.u[n],
                setter=lambda x, n=name: self.u.__setitem__(n, float(x)),
                description=_describe(name, unit, "input")))
        if self.host is not None:
            for i, (name, unit, what) in enumerate((
                    ("drive.angle", "rad", "angle"), ("drive.speed", "rad/s", "speed"))):
                self.register_variable(UnitReal(
                    name, unit, causality=Fmi2Causality.input,
                    variability=Fmi2Variability.continuous,
                    getter=lambda i=i: self.host[i],
                    setter=lambda x, i=i: self.host.__setitem__(i, float(x)),
                    description=f"the host's shaft {what} ({unit}, absolute) at the step's "
                                f"start; it turns at drive.speed over the step"))
        self.stepper = self._stepper()
        self.values = self.stepper.values()
        units = output_units(self.model, self.cfg["outputs"])
        for name in self.cfg["outputs"]:
            # initial exact: the outputs at the start are known (fmpy's validation asks for
            # it: PythonFMU issue 193)
            self.register_variable(UnitReal(
                name, units[name], causality=Fmi2Causality.output,
                variability=Fmi2Variability.continuous, initial=Fmi2Initial.exact,
                getter=lambda n=name: self.values[n],
                description=_describe(name, units[name], "output")))

    def to_xml(self, model_options=None):
        """pythonfmu's model description with the units used defined (``UnitDefinitions``
        after ``CoSimulation``, as FMI 2.0's schema orders them)."""
        from xml.etree.ElementTree import Element, SubElement

        root = super().to_xml(model_options or {})
        used = sorted({v.unit for v in self.vars.values() if getattr(v, "unit", None)})
        if used:
            defs = Element("UnitDefinitions")
            for unit in used:
                base = {k: str(x) for k, x in BASE_UNITS[unit].items()}
                SubElement(SubElement(defs, "Unit", name=unit), "BaseUnit", base)
            at = [c.tag for c in root].index("CoSimulation") + 1
            root.insert(at, defs)
        return root

    # -- the state machine ------------------------------------------------------------------

    def _refuse(self, call: str, why: str, state: bool = False) -> str:
        """Log the refusal of ``call`` through the host's FMI logger (``state``: because of
        the state the instance is in): the message."""
        msg = (f"gearmodal: {call} refused in state {self.state}: {why}" if state
               else f"gearmodal: {call} refused: {why}")
        self.log(msg, Fmi2Status.error)
        return msg

    def _state_error(self, call: str) -> str:
        """Why ``call`` is not allowed in the present state ('' if it is)."""
        allowed = ALLOWED[call]
        if self.state in allowed:
            return ""
        why = f"allowed in {', '.join(allowed)}"
        if self.state == "stepFailed" and self.failure:
            why += f" (the step failed: {self.failure})"
        return why

    def _check(self, call: str) -> None:
        """Refuse (raise: ``fmi2Fatal`` with the message) ``call`` outside its states."""
        why = self._state_error(call)
        if why:
            raise ModelError(call, self._refuse(call, why, state=True))

    def _vars(self, call: str, vrs) -> list:
        """The variables of value references ``vrs``; an unknown one refused by name."""
        try:
            return [self.vars[vr] for vr in vrs]
        except KeyError as e:
            raise ModelError(call, self._refuse(
                call, f"no variable has value reference {e.args[0]} (this FMU has 0 to "
                      f"{len(self.vars) - 1})")) from None

    def _may_set(self, call: str, vrs, values) -> None:
        for var, val in zip(self._vars(call, vrs), values, strict=True):
            if var.causality == Fmi2Causality.output:
                raise ModelError(call, self._refuse(call, f"{var.name} is an output"))
            kind = "parameter" if var.causality == Fmi2Causality.parameter else "input"
            if self.state not in ALLOWED[f"fmi2Set {kind}"]:
                raise ModelError(call, self._refuse(
                    call, state=True, why=f"{var.name} is a {kind}"
                    + (" fixed when initialisation ends: set it before "
                       "fmi2ExitInitializationMode" if kind == "parameter" else
                       f", set in {', '.join(ALLOWED['fmi2Set input'])}")))
            if kind == "parameter":
                why = _parameter_error(var.name, val)
                if why:
                    raise ModelError(call, self._refuse(call, why))

    def _get(self, call: str, read, vrs) -> list:
        """``read(vrs)`` (pythonfmu's getter) in a state that allows it; an unknown value
        reference refused by name (looked up only when pythonfmu's lookup fails: a host
        reads every output every step)."""
        self._check("fmi2Get")
        try:
            return read(vrs)
        except KeyError:
            self._vars(call, vrs)
            raise

    def set_real(self, vrs, values):
        self._may_set("fmi2SetReal", vrs, values)
        super().set_real(vrs, values)

    def set_string(self, vrs, values):
        self._may_set("fmi2SetString", vrs, values)
        super().set_string(vrs, values)

    def set_integer(self, vrs, values):
        self._vars("fmi2SetInteger", vrs)
        super().set_integer(vrs, values)

    def set_boolean(self, vrs, values):
        self._vars("fmi2SetBoolean", vrs)
        super().set_boolean(vrs, values)

    def get_real(self, vrs):
        return self._get("fmi2GetReal", super().get_real, vrs)

    def get_string(self, vrs):
        return self._get("fmi2GetString", super().get_string, vrs)

    def get_integer(self, vrs):
        return self._get("fmi2GetInteger", super().get_integer, vrs)

    def get_boolean(self, vrs):
        return self._get("fmi2GetBoolean", super().get_boolean, vrs)

    # -- the calls --------------------------------------------------------------------------

    def _stepper(self) -> Stepper:
        """A stepper from the parameters and the inputs' present values."""
        d = self.cfg.get("drive")
        drive = None
        if d:
            drive = Drive(d["dof"], d["stiffness"], d.get("damping", 0.0),
                          angle0=self.host[0], speed0=self.host[1])
        return Stepper(self.model, dt=self.dt, loads=dict(self.u), drive=drive,
                       outputs=list(self.cfg["outputs"]), method=self.method,
                       speed_rpm=self.speed_rpm, out=self.result_dir or None,
                       record=bool(self.result_dir),
                       reference=self.cfg.get("reference", "fixed"),
                       rebase_dt=self.cfg.get("rebase_dt"))

    def enter_initialization_mode(self):
        self._check("fmi2EnterInitializationMode")
        self.state = "initializationMode"

    def exit_initialization_mode(self):
        call = "fmi2ExitInitializationMode"
        self._check(call)
        try:
            self.stepper = self._stepper()
        except GearmodalError as e:
            raise ModelError(call, self._refuse(call, str(e))) from e
        except OSError as e:  # result_dir: a folder that cannot be written
            raise ModelError(call, self._refuse(
                call, f"result_dir = {self.result_dir!r}: cannot write the result there "
                      f"({type(e).__name__}: {e})")) from e
        self.values = self.stepper.values()
        self.state = "stepComplete"

    def do_step(self, current_time: float, step_size: float) -> bool:
        call = "fmi2DoStep"
        why = self._state_error(call)
        if why:
            self._refuse(call, why, state=True)
            return False
        why = self._step_error(current_time, step_size)
        if why:
            return self._fail(call, why)
        if self.t0 is None:
            self.t0 = float(current_time)
        kw = {}
        if self.host is not None:
            kw = {"drive_angle": self.host[0], "drive_speed": self.host[1]}
        try:
            self.values = self.stepper.advance(self.stepper.time + step_size, dict(self.u),
                                               hold="hold", **kw)
        except SolveError as e:
            return self._fail(call, f"t = {current_time!r} s failed: {e}")
        except GearmodalError as e:  # a bad input or step: the step is not taken
            return self._fail(call, f"t = {current_time!r} s, step {step_size!r} s: {e}")
        except Exception as e:  # anything else: the host logs it, the process goes on
            return self._fail(call, f"t = {current_time!r} s: internal error "
                                    f"{type(e).__name__}: {e}")
        return True

    def _step_error(self, current_time: float, step_size: float) -> str:
        """Why a step from ``current_time`` over ``step_size`` cannot be taken ('' if it can)."""
        if not (math.isfinite(current_time) and math.isfinite(step_size)):
            return (f"currentCommunicationPoint = {current_time!r}, communicationStepSize = "
                    f"{step_size!r}: must be finite")
        if step_size <= 0:
            return f"communicationStepSize = {step_size!r}: must be positive"
        if self.t0 is not None:
            reached = self.t0 + self.stepper.time
            if abs(current_time - reached) > TIME_TOL * max(abs(current_time), self.dt):
                return (f"currentCommunicationPoint = {current_time!r} s, but the FMU is at "
                        f"{reached!r} s (started at {self.t0!r} s, {self.stepper.time!r} s "
                        "done): a step starts where the last one ended")
        return ""

    def _fail(self, call: str, why: str) -> bool:
        """The step is refused: logged, the instance in stepFailed (FMI 2.0)."""
        self._refuse(call, why)
        self.state, self.failure = "stepFailed", why
        return False

    def terminate(self):
        self._check("fmi2Terminate")
        state, self.state = self.state, "terminated"
        if state == "stepComplete" and self.result_dir and self.stepper.time > 0:
            self.stepper.result()  # the streamed result's header and small tables


def _config(path: Path) -> dict:
    """The FMU's configuration, or a :class:`ModelError` naming the damaged file."""
    try:
        cfg = json.loads(path.read_text())
        if not isinstance(cfg, dict):
            raise ValueError(f"a {type(cfg).__name__}, not a table")
        for key in ("model", "dt", "speed_rpm", "method", "inputs", "outputs"):
            if key not in cfg:
                raise ValueError(f"no {key!r}")
    except (OSError, ValueError) as e:
        raise ModelError(CONFIG, f"{path}: damaged or missing ({e}); rebuild the FMU with "
                                 "gearmodal fmu") from None
    return cfg


def _parameter_error(name: str, val) -> str:
    """Why ``val`` cannot be parameter ``name`` ('' if it can); the stepper checks the rest
    (the method's name, the output grid) when initialisation ends."""
    if name in ("dt", "speed_rpm"):
        if not isinstance(val, (int, float)) or not math.isfinite(val):
            return f"{name} = {val!r}: must be a finite number"
        if name == "dt" and val <= 0:
            return f"dt = {val!r}: must be positive (s)"
    return ""
