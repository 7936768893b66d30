"""The gearbox inside an FMI 2.0 co-simulation FMU (:mod:`gearmodal.fmu` builds it): a
pythonfmu slave that runs a :class:`~gearmodal.integrate.stepper.Stepper`.

The FMU's resources hold the model file and ``gearmodal_fmu.json`` (what :func:`gearmodal.fmu.
export_fmu` chose: inputs, outputs, drive, method, step); the host needs Python with gearmodal
installed. Inputs are set at a communication step's start and held over it (FMI's usual
zero-order hold: the stepper's ``hold="hold"``; a drive's shaft turns at its speed input over
the step); outputs are the stepper's at the step's end. Parameters (``dt``, ``speed_rpm``,
``method``, ``result_dir``) take effect when initialisation ends.
"""

from __future__ import annotations

import json
from pathlib import Path

from pythonfmu import Fmi2Causality, Fmi2Initial, Fmi2Slave, Fmi2Variability, Real, String

from .errors import GearmodalError
from .integrate.stepper import Drive, Stepper
from .model.toml_io import load

#: the FMU's configuration file in its resources
CONFIG = "gearmodal_fmu.json"


class GearboxSlave(Fmi2Slave):
    """An FMI 2.0 co-simulation slave advancing a gearbox model (module docstring)."""

    author = "gearmodal"
    description = "Gearbox contact dynamics (gearmodal, exact piecewise-linear method)"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        res = Path(self.resources)
        self.cfg = json.loads((res / CONFIG).read_text())
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
        self.register_variable(Real("dt", **par, getter=lambda: self.dt,
                                    setter=lambda x: setattr(self, "dt", float(x))))
        self.register_variable(Real("speed_rpm", **par, getter=lambda: self.speed_rpm,
                                    setter=lambda x: setattr(self, "speed_rpm", float(x))))
        self.register_variable(String("method", **par, getter=lambda: self.method,
                                      setter=lambda x: setattr(self, "method", str(x))))
        self.register_variable(String("result_dir", **par, getter=lambda: self.result_dir,
                                      setter=lambda x: setattr(self, "result_dir", str(x))))
        for name in self.u:
            self.register_variable(Real(
                name, causality=Fmi2Causality.input, variability=Fmi2Variability.continuous,
                getter=lambda n=name: self.u[n],
                setter=lambda x, n=name: self.u.__setitem__(n, float(x))))
        if self.host is not None:
            for i, name in enumerate(("drive.angle", "drive.speed")):
                self.register_variable(Real(
                    name, causality=Fmi2Causality.input,
                    variability=Fmi2Variability.continuous,
                    getter=lambda i=i: self.host[i],
                    setter=lambda x, i=i: self.host.__setitem__(i, float(x))))
        self.stepper = self._stepper()
        self.values = self.stepper.values()
        for name in self.cfg["outputs"]:
            # initial exact: the outputs at the start are known (fmpy's validation asks for
            # it: PythonFMU issue 193)
            self.register_variable(Real(
                name, causality=Fmi2Causality.output, variability=Fmi2Variability.continuous,
                initial=Fmi2Initial.exact, getter=lambda n=name: self.values[n]))

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

    def exit_initialization_mode(self):
        self.stepper = self._stepper()
        self.values = self.stepper.values()

    def do_step(self, current_time: float, step_size: float) -> bool:
        kw = {}
        if self.host is not None:
            kw = {"drive_angle": self.host[0], "drive_speed": self.host[1]}
        try:
            self.values = self.stepper.advance(current_time + step_size, dict(self.u),
                                               hold="hold", **kw)
        except GearmodalError as e:  # a bad input or a failed solve: the step fails
            self.log(f"gearmodal: {e}")
            return False
        return True

    def terminate(self):
        if self.result_dir and self.stepper.time > 0:
            self.stepper.result()  # the streamed result's header and small tables
