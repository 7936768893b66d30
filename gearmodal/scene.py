"""Simulation scenes as TOML: a model file plus loads, initial conditions and solver settings.

Example (``studies/scenes/gear_rattle.toml``)::

    [scene]
    model = "../models/gear_pair.toml"   # path relative to this file
    t_end = 0.2                          # s
    dt = 1e-4                            # s, propagation and output step
    method = "exact"                     # exact | newmark | scipy | auto
    speed_rpm = 0.0                      # input speed at which speed terms are frozen
    tolerance = 0.05                     # method = "auto" only: relative, on the quantities
    start = "rest"                       # rest | equilibrium (under the loads at t = 0)

    [loads]                              # N or N m, by load name
    "pinion.torque" = { mean = 2.0, amplitude = 6.0, frequency_hz = 80.0 }
    "wheel.torque" = "balance"           # balances the others' mean on the free rotation

    [q0]                                 # initial displacements by DOF name (m, rad)
    [v0]                                 # initial velocities
    [options]                            # method options, e.g. max_events_per_step, rtol

A load is a number, a table ``{mean, amplitude, frequency_hz, phase_deg}`` (a sinusoid about
the mean), or ``"balance"``: the value that makes the loads' mean do no work on the model's free
rigid-body mode (at most one load may say so).

Loads from an aeroelastic code's output file (HAWC2 or OpenFAST, :mod:`gearmodal.io`)::

    [load_file]
    path = "run.outb"                    # relative to this file
    format = "openfast"                  # openfast | hawc2 (default: from the extension)
    t_start = 0.0                        # s of the file that becomes t = 0
    [load_file.mapping]                  # gearmodal load name = channel, or [channel, factor]
    "rotor.torque" = "RotTorq"

The turbine in wind, simulated together with the gearbox model of ``scene.model``
(:func:`gearmodal.turbine.simulate_drivetrain`)::

    [turbine]
    file = "../turbines/600kw_turbine.toml"
    rotor_speed0_rpm = 6.0               # start-up from low speed; the generator cuts in
    connected = false
    mounting_azimuth_deg = 0.0           # overrides the turbine file's
    aero_dt = 0.02                       # s, aerodynamic step
    aero_hold = "interpolate"            # interpolate | hold | linear
    gravity = true                       # the gearbox bodies' weight (false: off)

    [wind]                               # gearmodal.turbine.Wind fields
    mean_speed = 10.0
    turbulence_intensity = 0.12
    seed = 1
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .errors import ModelError, unknown
from .integrate import MAX_STEPS
from .integrate.loads import Harmonic
from .integrate.stepper import Stepper
from .io import read_loads, shaft_loads
from .model import validate as v
from .model.dump import dumps as dump_model
from .model.dump import to_toml
from .model.model import Model
from .model.schema import REQUIRED, Field, Table
from .model.toml_io import load, override
from .run import run
from .static import balance as _balance
from .static import equilibrium
from .turbine import Wind, load_turbine

#: the step limit as the file format page writes it
_MAX_STEPS = f"{MAX_STEPS:.0e}".replace("e+0", "e")

METHODS = ("exact", "newmark", "scipy", "auto")
_LOAD_UNIT = "N or N m"
#: the tables of a scene file (:mod:`gearmodal.model.schema`; ``docs/file-format.md``)
SCENE = Table("scene", (
    Field("model", "path", default=REQUIRED, doc="model file, relative to the scene file"),
    Field("t_end", "number", "s", low=0.0, low_open=True, default=REQUIRED, doc="run length",
          limits="time"),
    Field("dt", "number", "s", low=0.0, low_open=True, default=REQUIRED,
          doc=f"propagation and output step, at most t_end and t_end / {_MAX_STEPS}",
          limits="time"),
    Field("method", "choice", choices=METHODS, default="exact", doc="integrator"),
    Field("speed_rpm", "number", "rpm", low=0.0, limits="speed_rpm",
          doc="input speed (default 0; turbine scenes: the rotor's, not this)"),
    Field("tolerance", "number", low=0.0, high=10.0, low_open=True, high_open=True,
          note="a relative tolerance in (0, 10), e.g. 0.05",
          doc="method = \"auto\" only: relative tolerance on the study quantities "
              "(default 0.05)"),
    Field("start", "choice", choices=("rest", "equilibrium"),
          doc="initial state: \"rest\" (default: [q0], [v0], else zero) or "
              "\"equilibrium\" (the static equilibrium under the loads' values at t = 0, "
              "at speed_rpm; [v0] may add velocities, [q0] is refused)")),
    "The run: model, length, step, method.")
WAVE = Table("loads.<name> as a table", (
    Field("mean", "number", _LOAD_UNIT, default=0.0, doc="mean"),
    Field("amplitude", "number", _LOAD_UNIT, default=0.0, doc="amplitude"),
    Field("frequency_hz", "number", "Hz", low=0.0, high=1e8, default=0.0, doc="frequency"),
    Field("phase_deg", "number", "deg", doc="phase (default 0)"),
    Field("phase", "number", "rad", doc="phase in rad (what Scene.dumps writes; exact)")),
    "A load `mean + amplitude sin(2 pi frequency_hz t + phase)`; a load may also be a number "
    "or \"balance\" (the value that balances the others' mean).")
LOAD_FILE = Table("load_file", (
    Field("path", "path", default=REQUIRED, doc="HAWC2 or OpenFAST output, relative to the "
          "scene file"),
    Field("format", "choice", choices=("openfast", "hawc2"),
          doc="file format (default: from the extension)"),
    Field("t_start", "number", "s", low=0.0, default=0.0, doc="time of the file that becomes "
          "t = 0"),
    Field("mapping", "table", default=REQUIRED, doc="gearmodal load name = channel, or "
          "[channel, factor]")),
    "Loads from an aeroelastic code's output file.")
TURBINE = Table("turbine", (
    Field("file", "path", default=REQUIRED, doc="turbine file, relative to the scene file"),
    Field("rotor_speed0_rpm", "number", "rpm", low=0.0, high=1e3,
          doc="initial rotor speed (default 6)"),
    Field("azimuth0_deg", "number", "deg", doc="initial blade-1 azimuth (default 0)"),
    Field("connected", "boolean", doc="start on the grid (default false: cut in at "
          "synchronous speed)"),
    Field("mounting_azimuth_deg", "number", "deg", doc="overrides the turbine file's"),
    Field("aero_dt", "number", "s", low=0.0, low_open=True, high=10.0,
          doc="aerodynamic step, a whole multiple of dt (default 0.02)"),
    Field("aero_hold", "choice", choices=("interpolate", "hold", "linear"),
          doc="loads between aerodynamic steps (default interpolate)"),
    Field("rebase_speed", "number", low=0.0, low_open=True, high=1.0,
          doc="speed drift that re-bases the reference rotation (default 0.01)"),
    Field("rebase_angle", "number", "rad", low=0.0, low_open=True, high=1.0,
          doc="rigid rotation that re-bases it (default 5e-4)"),
    Field("gravity", "boolean", default=True,
          doc="the weight of every gearbox body, along the turbine file's tilt_deg"),
    Field("turning_points", "boolean",
          doc="the exact turning points, level changes and bearing load integrals of the "
              "gearbox's forces, what exact DELs, load spectra and lives come from (default "
              "true; false: none, about 45 % less gearbox integration CPU)"),
    Field("top_frequency_hz", "number", "Hz", low=1.0, high=1e5,
          doc="mass-scaling rung: gearbox modes above it slowed to it (default: none, "
              "the full model; 500 Hz: about 3x faster, its error in the fidelity guide)")),
    "The turbine in wind, simulated with the gearbox of scene.model.")
#: the scene file's tables
TABLES = ("scene", "loads", "q0", "v0", "options", "load_file", "turbine", "wind")


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
    turbine: object = None  # gearmodal.turbine.Turbine when the scene has [turbine]
    wind: object = None
    drivetrain: dict = field(default_factory=dict)
    tolerance: float = 0.05
    #: ``"rest"`` or ``"equilibrium"`` (:meth:`initial_q`)
    start: str = "rest"
    #: the ``[load_file]`` table as read (its path absolute), and the turbine file
    load_file: dict = field(default_factory=dict)
    turbine_file: str = ""

    def dumps(self, model_path: str = "model.toml") -> str:
        """The scene as scene-file text whose model is the file ``model_path`` (relative to
        the scene file; write it with ``gm.dump(scene.model, path)``). Loading the pair gives
        the same scene: numbers exact, a wave's phase in rad, a load read from a file as its
        ``[load_file]`` table, the turbine and load files by absolute path.

        Raises :class:`ModelError` naming a load given as a function (not writable)."""

        return to_toml(self._document(model_path))

    def identity(self) -> str:
        """SHA-256 of the scene's inputs as canonical text: the model (``gm.dumps``), this
        scene (:meth:`dumps`, file paths left out), the turbine's data and the load file's
        bytes. Independent of the library version, of comments and layout in the files and
        of where they are; what resumable stores key their runs by."""


        parts = [dump_model(self.model, rating=False), to_toml(self._document("", paths=False))]
        if self.turbine is not None:
            parts.append(json.dumps(dataclasses.asdict(self.turbine), sort_keys=True,
                                    default=lambda o: o.tolist()))
        if self.load_file:
            parts.append(hashlib.sha256(Path(self.load_file["path"]).read_bytes()).hexdigest())
        return hashlib.sha256("\n".join(parts).encode()).hexdigest()

    def _document(self, model_path: str, paths: bool = True) -> dict:

        sc = {"model": model_path, "t_end": self.t_end, "dt": self.dt, "method": self.method}
        if self.turbine is None:
            sc["speed_rpm"] = self.speed_rpm
        if self.method == "auto":
            sc["tolerance"] = self.tolerance
        if self.start != "rest":
            sc["start"] = self.start
        doc: dict = {"scene": sc}
        from_file = set(self.load_file.get("mapping", {}))
        loads = {}
        for name, val in self.loads.items():
            if name in from_file:
                continue
            if isinstance(val, Wave):
                loads[name] = {"mean": val.mean, "amplitude": val.amplitude,
                               "frequency_hz": val.frequency_hz, "phase": val.phase}
            elif isinstance(val, (int, float)) and not isinstance(val, bool):
                loads[name] = float(val)
            else:
                raise ModelError(f"loads.{name}", f"a load given as {type(val).__name__} "
                                 "cannot be written to a scene file; give constants, waves or "
                                 "a [load_file]")
        for key, table in (("loads", loads), ("q0", self.q0), ("v0", self.v0),
                           ("options", self.options)):
            if table:
                doc[key] = {k: (float(x) if isinstance(x, (int, float))
                                and not isinstance(x, bool) and key != "options" else x)
                            for k, x in table.items()}
        if self.load_file:
            lf = dict(self.load_file)
            if not paths:
                lf.pop("path", None)
            doc["load_file"] = lf
        if self.turbine is not None:
            tb = {"file": self.turbine_file} if paths else {}
            tb.update(self.drivetrain)
            tb["mounting_azimuth_deg"] = self.turbine.mounting_azimuth_deg
            doc["turbine"] = tb
            doc["wind"] = {k: v for k, v in dataclasses.asdict(self.wind).items()
                           if v is not None}
        return doc

    def simulate(self, progress=None, out=None):
        """Run the scene (:func:`gearmodal.run.run`, the one path every caller takes):
        :func:`gearmodal.simulate` on the model with the scene's loads, or, with a
        ``[turbine]`` table, :func:`gearmodal.turbine.simulate_drivetrain` (a
        :class:`~gearmodal.turbine.DrivetrainResult`), or with ``method = "auto"`` the step
        ladder of :func:`gearmodal.auto.choose` with the scene's ``tolerance`` (a
        :class:`~gearmodal.run.ChosenRun`: the chosen rung's result and the choice). Every
        one follows :class:`~gearmodal.run.RunResult` (``gearbox``, ``turbine``, ``choice``,
        ``save``, ``plot``). ``progress(i, n)``: after each aerodynamic step of a turbine, each
        rung of the ladder. ``out``: a directory the run's tables stream to as it goes
        (constant memory; not with ``method = "auto"``, whose rungs have their own store)."""

        return run(self, progress=progress, out=out)

    def stepper(self, **kwargs) -> Stepper:
        """A :class:`~gearmodal.Stepper` of this gearbox scene (the co-simulation API): its
        model, ``dt``, method and options, ``speed_rpm`` and initial state (``start =
        "equilibrium"`` included); its loads' values at time 0 as the loads the host sets from
        then on (a wave or series is the host's to follow). ``kwargs`` (``drive``,
        ``outputs``, ``reference``...) go to the stepper and override the scene's."""
        return Stepper(self.model, **{**self.stepper_settings(), **kwargs})

    def stepper_settings(self) -> dict:
        """The :class:`~gearmodal.Stepper` keywords this gearbox scene gives (:meth:`stepper`);
        a turbine scene or ``method = "auto"`` is refused by name."""
        if self.turbine is not None:
            raise ModelError("scene.turbine", "a turbine scene runs its own loop "
                             "(scene.simulate()); a stepper takes a gearbox scene")
        if self.method == "auto":
            raise ModelError("scene.method", "= 'auto' chooses among whole runs; give a "
                             "method (exact, newmark, scipy) to step a scene")
        return {"dt": self.dt, "method": self.method, "speed_rpm": self.speed_rpm,
                "loads": self.loads_at(0.0), "q0": self.initial_q(), "v0": self.v0,
                **self.options}

    def loads_at(self, t: float) -> dict:
        """Every load's value at time ``t`` (s), N or N m: a number as it is, a Series on its
        knots (ends held), a wave or any other function of time evaluated."""
        out = {}
        for name, val in self.loads.items():
            if isinstance(val, (int, float)):
                out[name] = float(val)
            elif hasattr(val, "index") and hasattr(val, "to_numpy"):  # a Series on its knots
                knots = np.asarray(val.index, dtype=float)
                out[name] = float(np.interp(t, knots, val.to_numpy(dtype=float)))
            else:  # a wave or any other function of time
                out[name] = float(val(t))
        return out

    def initial_q(self) -> dict:
        """The run's initial displacements by DOF name: ``[q0]`` (zero elsewhere) or, with
        ``start = "equilibrium"``, the static equilibrium (:func:`gearmodal.equilibrium`)
        under every load's value at t = 0 at ``speed_rpm``: a run of constant loads then
        starts where it stays, instead of taking the loads as a step from rest and ringing
        through its lowest modes."""
        if self.start != "equilibrium":
            return self.q0

        at0 = self.loads_at(0.0)
        try:
            eq = equilibrium(self.model, at0, self.speed_rpm)
        except ModelError as e:
            raise ModelError("scene.start", f"= \"equilibrium\": {e.message}") from None
        return {k: float(x) for k, x in eq.q.items()}


@dataclass(frozen=True)
class Wave(Harmonic):
    """A scene's load ``mean + amplitude sin(2 pi frequency_hz t + phase)`` (N or N m;
    ``phase`` in rad): a :class:`gearmodal.Harmonic`, which the exact method integrates
    exactly. A plain object, so a scene with waves pickles (sweeps on a process pool, the
    fingerprint of :func:`gearmodal.auto.choose`'s store)."""


def _wave(field_: str, spec: dict):
    w = WAVE.read(field_, spec)
    if "phase" in w and "phase_deg" in w:
        raise ModelError(f"{field_}.phase", "given twice (phase in rad and phase_deg); give one")
    ph = w["phase"] if "phase" in w else math.radians(w.get("phase_deg", 0.0))
    return Wave(w["mean"], w["amplitude"], w["frequency_hz"], ph), w["mean"]


def load_scene(path, overrides: dict | None = None) -> Scene:
    """Read and validate a scene file; errors name the TOML field and the file.

    ``overrides`` (``{dotted key: value}``) changes the scene before validation: keys of the
    scene file (``"turbine.mounting_azimuth_deg"``, ``"scene.t_end"``, ``"wind.seed"``) or,
    with the prefix ``model.``, keys of its model file (``"model.stages.0.backlash"``). This is
    how :func:`gearmodal.sweep` makes its cases.
    """
    p = Path(path)
    try:
        raw = p.read_bytes()
    except FileNotFoundError:
        raise ModelError(str(p), "no such scene file") from None
    except (OSError, ValueError) as e:  # a directory, a NUL in the path
        why = getattr(e, "strerror", None) or e
        raise ModelError(str(p), f"cannot read the scene file: {why}") from None
    try:
        doc = tomllib.loads(raw.decode("utf-8"))
    except UnicodeDecodeError as e:
        raise ModelError(str(p), f"not a UTF-8 text file ({e.reason} at byte {e.start})") \
            from None
    except tomllib.TOMLDecodeError as e:
        raise ModelError(str(p), f"TOML syntax error: {e}") from None
    except RecursionError:
        raise ModelError(str(p), "TOML nested too deeply") from None

    overrides = dict(overrides or {})
    for table in ("options", "q0", "v0", "loads"):  # tables a scene may leave out
        if any(str(k).startswith(table + ".") for k in overrides) and table not in doc:
            doc[table] = {}
    for table in ("q0", "v0", "loads"):  # their keys are names with dots ("carrier.torque")
        for key in [k for k in overrides if str(k).startswith(table + ".")]:
            if not isinstance(doc[table], dict):
                break  # the scene's own error names it
            doc[table][str(key)[len(table) + 1:]] = overrides.pop(key)
    model_over = {k[len("model."):]: x for k, x in overrides.items() if k.startswith("model.")}
    doc = override(doc, {k: x for k, x in overrides.items() if not k.startswith("model.")})
    try:
        return _scene(doc, p, model_over)
    except ModelError as e:
        raise ModelError(e.field, f"{e.message} (in {p})") from None


#: the ``[scene]`` keys a setting (:func:`settings`) names without its table
SCENE_KEYS = ("model", "t_end", "dt", "method", "speed_rpm", "tolerance", "start")


def settings(pairs) -> dict:
    """Scene overrides (:func:`load_scene`) from ``KEY=VALUE`` texts, as the command line's
    ``--set`` gives them: ``method=newmark``, ``dt=1e-4``, ``options.rtol=1e-3``,
    ``loads.carrier.torque=2e5``, ``model.stages.0.backlash=1e-4``. A key of the ``[scene]``
    table (:data:`SCENE_KEYS`, the names of :func:`gearmodal.simulate`'s keywords) needs no
    table; the others name theirs. A value is read as a TOML value (``1e-4``, ``true``,
    ``"text"``), else taken as text (``newmark``).

    Raises :class:`ModelError` naming a text without ``=`` or with an empty key."""
    out = {}
    for text in pairs:
        key, sep, value = str(text).partition("=")
        key = key.strip()
        if not sep or not key:
            raise ModelError("--set", f"= {text!r}: expected KEY=VALUE (for instance "
                             "method=newmark, dt=1e-4, options.rtol=1e-3)")
        try:
            val = tomllib.loads(f"v = {value.strip()}")["v"]
        except tomllib.TOMLDecodeError:
            try:  # numbers TOML does not write (".001", "1.")
                val = float(value)
            except ValueError:
                val = value.strip()
        out[f"scene.{key}" if key in SCENE_KEYS else key] = val
    return out


def _scene(doc: dict, p: Path, model_overrides: dict | None = None) -> Scene:
    for key in doc:
        if key not in TABLES:
            raise ModelError(key, "unknown table; allowed: " + ", ".join(TABLES))
    for key in ("loads", "q0", "v0", "options", "load_file", "turbine", "wind"):
        if key in doc and not isinstance(doc[key], dict):
            raise ModelError(key, f"expected a table [{key}], got {type(doc[key]).__name__} "
                                  f"{doc[key]!r}")
    if not isinstance(doc.get("scene"), dict):
        raise ModelError("scene", "missing: the [scene] table with model, t_end, dt")
    raw = doc["scene"]
    if "model" not in raw:
        raise ModelError("scene.model", "missing: required key (the model file)")
    model_file = SCENE.by_key()["model"].read("scene.model", raw["model"])

    try:  # the model first: its errors are the first a new scene meets
        model = load(p.parent / model_file, overrides=model_overrides)
    except ModelError as e:
        if e.field.startswith("overrides."):  # a sweep's model key: name it as given
            raise ModelError("model." + e.field[len("overrides."):], e.message) from None
        raise
    sc = SCENE.read("scene", raw)
    t_end, dt, method = sc["t_end"], sc["dt"], sc["method"]
    if dt > t_end:
        raise ModelError("scene.dt", f"= {dt!r}: must be at most scene.t_end = {t_end!r} s")
    if t_end / dt > MAX_STEPS:
        raise ModelError("scene.dt", f"= {dt!r}: scene.t_end / dt = {t_end / dt:.3g} steps; at "
                         f"most {_MAX_STEPS}")
    tolerance = 0.05
    if "tolerance" in sc:
        if method != "auto":
            raise ModelError("scene.tolerance", "is used by method = 'auto' only")
        tolerance = sc["tolerance"]
    speed = sc.get("speed_rpm", 0.0)
    loads, means, balance = {}, {}, None
    load_file = {}
    if "load_file" in doc:
        for name, ser in _load_file(doc["load_file"], p).items():
            loads[name], means[name] = ser, float(ser.mean())
        load_file = {**doc["load_file"],
                     "path": str((p.parent / str(doc["load_file"]["path"])).resolve())}
    for name, spec in doc.get("loads", {}).items():
        f = f"loads.{name}"
        if spec == "balance":
            if balance is not None:
                raise ModelError(f, f"only one load may be 'balance' ({balance} already is)")
            balance = name
        elif isinstance(spec, dict):
            loads[name], means[name] = _wave(f, spec)
        else:
            loads[name] = means[name] = v.number(f, spec, _LOAD_UNIT)
    asm = model.assemble()
    for name in [*loads, *([balance] if balance else [])]:
        if name not in asm.load_names:
            raise ModelError(f"loads.{name}", unknown("load", name, asm.load_names))
    if balance:

        loads[balance] = _balance(asm, means, on=balance)[balance]
    q0 = {k: v.number(f"q0.{k}", x, "m or rad") for k, x in doc.get("q0", {}).items()}
    start = sc.get("start", "rest")
    if start == "equilibrium" and q0:
        raise ModelError("scene.start", "= \"equilibrium\" sets the initial displacements: "
                         "remove [q0] (or start = \"rest\")")
    v0 = {k: v.number(f"v0.{k}", x, "m/s or rad/s") for k, x in doc.get("v0", {}).items()}
    options = dict(doc.get("options", {}))
    turbine, wind, drivetrain = None, None, {}
    if "turbine" in doc:
        if loads or "load_file" in doc:
            raise ModelError("turbine", "a turbine scene computes its own loads: remove "
                             "[loads] and [load_file]")
        for key in ("q0", "v0"):
            if doc.get(key):
                raise ModelError(key, "a turbine scene starts from the accelerating "
                                 "equilibrium: remove [" + key + "]")
        if "start" in sc:
            raise ModelError("scene.start", "a turbine scene always starts from the "
                             "drivetrain's accelerating equilibrium: remove it")
        if "speed_rpm" in sc:
            raise ModelError("scene.speed_rpm", "a turbine scene's speed is the rotor's: "
                             "set turbine.rotor_speed0_rpm instead")
        turbine, wind, drivetrain = _turbine(doc["turbine"], doc.get("wind", {}), p, t_end)
    elif "wind" in doc:
        raise ModelError("wind", "needs a [turbine] table")
    turbine_file = str((p.parent / str(doc["turbine"]["file"])).resolve()) \
        if turbine is not None else ""
    return Scene(model=model, t_end=t_end, dt=dt, method=method, speed_rpm=speed, loads=loads,
                 q0=q0, v0=v0, options=options, source=str(p), turbine=turbine, wind=wind,
                 drivetrain=drivetrain, tolerance=tolerance, load_file=load_file,
                 turbine_file=turbine_file, start=start)


def _load_file(spec: dict, p: Path) -> dict:
    """``[load_file]``: loads as Series from an aeroelastic output file."""

    lf = LOAD_FILE.read("load_file", spec)
    if not lf["mapping"]:
        raise ModelError("load_file.mapping", "expected a table: load name = channel")
    path = p.parent / lf["path"]
    if not path.is_file():
        raise ModelError("load_file.path", f"= {lf['path']!r}: no such file ({path})")
    data = read_loads(path, lf.get("format"))
    return shaft_loads(data, dict(lf["mapping"]), t_start=lf["t_start"])


def _turbine(spec: dict, wspec: dict, p: Path, t_end: float):
    """``[turbine]`` and ``[wind]``: the turbine, its wind and the drivetrain run options."""

    tb = TURBINE.read("turbine", spec)
    turbine = load_turbine(p.parent / tb.pop("file"))
    if "mounting_azimuth_deg" in tb:
        turbine.mounting_azimuth_deg = tb.pop("mounting_azimuth_deg")
    wargs = {"hub_height": turbine.hub_height, "half_width": 1.1 * turbine.rotor.radius,
             "duration": t_end + 1.0, **Wind.SCHEMA.read("wind", wspec)}
    return turbine, Wind(**wargs), tb
