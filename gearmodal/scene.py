"""Simulation scenes as TOML: a model file plus loads, initial conditions and solver settings.

Example (``studies/scenes/gear_rattle.toml``)::

    [scene]
    model = "../models/gear_pair.toml"   # path relative to this file
    t_end = 0.2                          # s
    dt = 1e-4                            # s, propagation and output step
    method = "exact"                     # exact | newmark | scipy
    speed_rpm = 0.0                      # input speed at which speed terms are frozen

    [loads]                              # N or N m, by load name
    "pinion.torque" = { mean = 2.0, amplitude = 6.0, frequency_hz = 80.0 }
    "wheel.torque" = "balance"           # balances the others' mean on the free rotation

    [q0]                                 # initial displacements by DOF name (m, rad)
    [v0]                                 # initial velocities
    [options]                            # method options, e.g. max_events_per_step, rtol

A load is a number, a table ``{mean, amplitude, frequency_hz, phase_deg}`` (a sinusoid about
the mean), or ``"balance"``: the value that makes the loads' mean do no work on the model's free
rigid-body mode (at most one load may say so).
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

from .errors import ModelError
from .model import validate as v
from .model.model import Model

_SCENE_KEYS = {"model", "t_end", "dt", "method", "speed_rpm"}
_TOP = {"scene", "loads", "q0", "v0", "options"}
_WAVE = {"mean", "amplitude", "frequency_hz", "phase_deg"}


@dataclass
class Scene:
    """A loaded scene: the model and the keyword arguments of :func:`gearmodal.simulate`."""

    model: Model
    t_end: float
    dt: float
    method: str = "exact"
    speed_rpm: float = 0.0
    loads: dict = field(default_factory=dict)
    q0: dict = field(default_factory=dict)
    v0: dict = field(default_factory=dict)
    options: dict = field(default_factory=dict)
    source: str = ""

    def simulate(self):
        """Run :func:`gearmodal.simulate` with this scene's settings."""
        from .integrate import simulate

        return simulate(self.model, self.t_end, dt=self.dt, loads=self.loads, q0=self.q0,
                        v0=self.v0, method=self.method, speed_rpm=self.speed_rpm,
                        **self.options)


def _wave(field_: str, spec: dict):
    for key in spec:
        if key not in _WAVE:
            raise ModelError(f"{field_}.{key}", "unknown key; allowed: " + ", ".join(sorted(_WAVE)))
    mean = v.number(f"{field_}.mean", spec.get("mean", 0.0), "N or N m")
    amp = v.number(f"{field_}.amplitude", spec.get("amplitude", 0.0), "N or N m")
    f = v.nonnegative(f"{field_}.frequency_hz", spec.get("frequency_hz", 0.0), "Hz")
    ph = math.radians(v.number(f"{field_}.phase_deg", spec.get("phase_deg", 0.0), "deg"))

    def load(t, mean=mean, amp=amp, f=f, ph=ph):
        return mean + amp * math.sin(2 * math.pi * f * t + ph)

    return load, mean


def load_scene(path) -> Scene:
    """Read and validate a scene file; errors name the TOML field and the file."""
    p = Path(path)
    try:
        doc = tomllib.loads(p.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise ModelError(str(p), "no such scene file") from None
    except tomllib.TOMLDecodeError as e:
        raise ModelError(str(p), f"TOML syntax error: {e}") from None
    try:
        return _scene(doc, p)
    except ModelError as e:
        raise ModelError(e.field, f"{e.message} (in {p})") from None


def _scene(doc: dict, p: Path) -> Scene:
    for key in doc:
        if key not in _TOP:
            raise ModelError(key, "unknown table; allowed: " + ", ".join(sorted(_TOP)))
    sc = doc.get("scene")
    if not isinstance(sc, dict):
        raise ModelError("scene", "missing: the [scene] table with model, t_end, dt")
    for key in sc:
        if key not in _SCENE_KEYS:
            raise ModelError(f"scene.{key}", "unknown key; allowed: "
                             + ", ".join(sorted(_SCENE_KEYS)))
    for key in ("model", "t_end", "dt"):
        if key not in sc:
            raise ModelError(f"scene.{key}", "missing")
    if not isinstance(sc["model"], str):
        raise ModelError("scene.model", f"= {sc['model']!r}: expected a path to a model file")
    from .model.toml_io import load

    model = load(p.parent / sc["model"])
    t_end = v.positive("scene.t_end", sc["t_end"], "s")
    dt = v.positive("scene.dt", sc["dt"], "s")
    method = v.choice("scene.method", sc.get("method", "exact"), ("exact", "newmark", "scipy"))
    speed = v.nonnegative("scene.speed_rpm", sc.get("speed_rpm", 0.0), "rpm")
    loads, means, balance = {}, {}, None
    for name, spec in doc.get("loads", {}).items():
        f = f"loads.{name}"
        if spec == "balance":
            if balance is not None:
                raise ModelError(f, f"only one load may be 'balance' ({balance} already is)")
            balance = name
        elif isinstance(spec, dict):
            loads[name], means[name] = _wave(f, spec)
        else:
            loads[name] = means[name] = v.number(f, spec, "N or N m")
    asm = model.assemble()
    for name in [*loads, *([balance] if balance else [])]:
        if name not in asm.load_names:
            raise ModelError(f"loads.{name}", "no such load; available: "
                             + ", ".join(asm.load_names))
    if balance:
        from .static import balance as _balance

        loads[balance] = _balance(asm, means, on=balance)[balance]
    q0 = {k: v.number(f"q0.{k}", x, "m or rad") for k, x in doc.get("q0", {}).items()}
    v0 = {k: v.number(f"v0.{k}", x, "m/s or rad/s") for k, x in doc.get("v0", {}).items()}
    options = dict(doc.get("options", {}))
    return Scene(model=model, t_end=t_end, dt=dt, method=method, speed_rpm=speed, loads=loads,
                 q0=q0, v0=v0, options=options, source=str(p))
