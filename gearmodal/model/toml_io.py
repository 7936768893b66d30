"""Load a :class:`~gearmodal.model.Model` from a TOML file: ``gm.load(path)``, ``loads(text)``.

The TOML mirrors the builders (:func:`~gearmodal.model.builders.drivetrain`,
:func:`~gearmodal.model.builders.planetary_stage`, ...): ``[model] type`` picks the builder, and
the other tables hold its arguments. Units are SI (m, kg, kg m^2, N/m, N m/rad, N s/m) except
angles, which are given in **degrees** in keys ending in ``_deg`` (``pressure_angle_deg``,
``helix_angle_deg``, ``planet_angles_deg``, ``angle_deg``) and converted to radians for the API.
Speeds are in rpm of the input (rotor, carrier or pinion).

Every error is a :class:`~gearmodal.errors.ModelError` whose ``field`` is the full dotted TOML
path of the offending key, e.g. ``stages[0].ring.teeth = 98: ring teeth must equal sun + 2 *
planet (21 + 2 * 39 = 99)``; when loading a file the message ends with ``(in <file>)``. The
range checks are the components' and builders' own; this module checks the document's shape
(tables, unknown and missing keys, degree values) and renames the builders' field names to the
TOML paths.

Schema
------
Every table and key, with its type, unit, allowed range and default, is listed in
``docs/file-format.md``, generated from :mod:`gearmodal.model.file_schema` (the builder types)
and the components' ``SCHEMA`` (``type = "components"``, what :func:`gearmodal.dumps` writes).

Example
-------
A complete drivetrain (``studies/models/600kw.toml`` is the documented full-size one)::

    [model]
    name = "demo"
    type = "drivetrain"
    rated_speed_rpm = 22.1             # rpm of the rotor
    speed_range_rpm = [0.0, 25.0]

    [rotor]
    mass = 11000.0                     # kg
    inertia = 4.0e5                    # kg m^2

    [main_shaft]
    stiffness = 4.8e7                  # N m/rad

    [shaft_bending]
    stiffness = { x = 1.0e7, y = 1.0e7 }   # N/m

    [[stages]]
    type = "planetary"
    n_planets = 3
    mesh_stiffness = { sun_planet = 4.6e9, ring_planet = 5.0e9 }   # N/m
    backlash = 3.0e-4                  # m
    planet_bearing = 2.0e9             # N/m, radial and tangential
    carrier_bearing = 1.0e9            # N/m
    ring_support = { stiffness = { x = 1e10, y = 1e10, theta = 1e10 } }
    [stages.carrier]
    mass = 1000.0
    inertia = 110.0
    [stages.sun]
    teeth = 21
    module = 0.010                     # m
    pressure_angle_deg = 20.0
    helix_angle_deg = 7.5
    mass = 80.0
    inertia = 0.45
    [stages.planet]
    teeth = 39
    module = 0.010
    pressure_angle_deg = 20.0
    helix_angle_deg = -7.5
    mass = 140.0
    inertia = 3.5
    [stages.ring]
    teeth = 99
    module = 0.010
    pressure_angle_deg = 20.0
    helix_angle_deg = -7.5
    mass = 600.0
    inertia = 180.0

    [[stages]]
    type = "parallel"
    coupling_stiffness = 6.0e6         # N m/rad, sun shaft to the wheel
    mesh_stiffness = 3.4e9
    gear_bearing = 1.5e9
    pinion_bearing = 1.5e9
    [stages.gear]
    teeth = 82
    module = 0.00825
    pressure_angle_deg = 20.0
    helix_angle_deg = 14.0
    mass = 350.0
    inertia = 25.0
    [stages.pinion]
    teeth = 23
    module = 0.00825
    pressure_angle_deg = 20.0
    helix_angle_deg = -14.0
    mass = 90.0
    inertia = 0.4

    [generator]
    mass = 1000.0
    inertia = 15.0

    [hss_shaft]
    stiffness = 2.0e5                  # N m/rad

    [housing]
    mass = 5000.0
    inertia = 1500.0

    [suspension]
    stiffness = { x = 2.0e7, y = 2.0e7, theta = 2.0e7 }

The single-builder types put the builder's arguments in one table named after the type::

    [model]
    type = "gear_pair"
    [gear_pair]
    mesh_stiffness = 2.0e8             # N/m
    backlash = 1.0e-4                  # m
    [gear_pair.pinion]
    teeth = 20
    module = 0.004
    pressure_angle_deg = 20.0
    mass = 1.0
    inertia = 1.0e-3
    [gear_pair.wheel]
    teeth = 40
    module = 0.004
    pressure_angle_deg = 20.0
    mass = 4.0
    inertia = 1.6e-2
"""

from __future__ import annotations

import math
import re
import tomllib
from contextlib import contextmanager
from pathlib import Path

from ..errors import ModelError
from . import builders, rating_data
from . import file_schema as fs
from . import spec as sp
from . import validate as v
from .components import Gear, RigidBody
from .dump import read_components
from .model import Model

__all__ = ["MODEL_TYPES", "load", "loads"]

MODEL_TYPES, STAGE_TYPES = fs.MODEL_TYPES, fs.STAGE_TYPES

_SECTIONS = fs.SECTIONS


# -- public API -----------------------------------------------------------------------------
def load(path, overrides: dict | None = None) -> Model:
    """Load and validate a model from the TOML file ``path``.

    ``overrides`` replaces values of the file before validation, by dotted key:
    ``{"stages.0.backlash": 2e-4, "stages.0.carrier_bearing": {"stiffness": {...}}}`` (an
    integer picks an element of an array of tables). Parameter studies use it
    (:func:`gearmodal.sweep`).

    Raises :class:`~gearmodal.errors.ModelError` naming the TOML field (and the file) for
    any invalid input, including TOML syntax errors.

    Examples
    --------
    >>> import gearmodal as gm
    >>> model = gm.load("studies/models/600kw.toml")  # doctest: +SKIP
    >>> round(model.gear_ratio, 2)  # doctest: +SKIP
    81.49
    """
    p = Path(path)
    try:
        text = p.read_bytes().decode("utf-8")
    except OSError as e:
        raise ModelError(str(p), f"cannot read the file: {e.strerror or e}") from None
    except UnicodeDecodeError as e:
        raise ModelError(str(p), f"not a UTF-8 text file ({e.reason} at byte {e.start})") \
            from None
    except ValueError as e:  # a NUL byte in the path
        raise ModelError(str(p)[:200], f"cannot read the file: {e}") from None
    return loads(text, source=str(p), default_name=p.stem, overrides=overrides)


def override(doc: dict, overrides: dict | None, label: str = "overrides") -> dict:
    """A copy of the TOML document ``doc`` with ``overrides`` (``{dotted key: value}``)
    applied. Every table on the way to a key must exist (a misspelt one raises a
    :class:`ModelError` naming the key); the last key may be new.

    >>> override({"a": {"b": 1}, "s": [{"k": 1}]}, {"a.b": 2, "s.0.k": 3})
    {'a': {'b': 2}, 's': [{'k': 3}]}
    """
    import copy

    out = copy.deepcopy(doc)
    for key, value in (overrides or {}).items():
        parts = str(key).split(".")
        node = out
        for i, part in enumerate(parts):
            where = ".".join(parts[: i + 1])
            last = i == len(parts) - 1
            if isinstance(node, list):
                if not part.isdigit() or int(part) >= len(node):
                    raise ModelError(f"{label}.{key}", f"{where}: expected an index below "
                                     f"{len(node)} into the array")
                part = int(part)
            elif not isinstance(node, dict):
                raise ModelError(f"{label}.{key}", f"{'.'.join(parts[:i])} is a value, not a "
                                 "table")
            elif not last and part not in node:
                raise ModelError(f"{label}.{key}", f"no table {where!r}; it has: "
                                 + ", ".join(map(str, node)))
            if last:
                node[part] = copy.deepcopy(value)
            else:
                node = node[part]
    return out


def loads(text: str, source: str = "<string>", *, default_name: str | None = None,
          overrides: dict | None = None) -> Model:
    """Load and validate a model from TOML ``text``; ``source`` names it in error messages.

    Examples
    --------
    >>> from gearmodal.model.toml_io import loads
    >>> m = loads('''
    ... [model]
    ... type = "gear_pair"
    ... [gear_pair]
    ... mesh_stiffness = 2e8
    ... backlash = 1e-4
    ... [gear_pair.pinion]
    ... teeth = 20
    ... module = 0.004
    ... pressure_angle_deg = 20
    ... mass = 1.0
    ... inertia = 1e-3
    ... [gear_pair.wheel]
    ... teeth = 40
    ... module = 0.004
    ... pressure_angle_deg = 20
    ... mass = 4.0
    ... inertia = 1.6e-2
    ... ''')
    >>> m.dof_names
    ['pinion.theta', 'wheel.theta']
    """
    if not isinstance(text, str):
        raise ModelError(source, f"expected TOML text (str), got {type(text).__name__}")
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise ModelError(source, _syntax_message(e)) from None
    except RecursionError:
        raise ModelError(source, "TOML nested too deeply") from None
    doc = override(doc, overrides)
    try:
        return _build(doc, default_name)
    except ModelError as e:
        if source == "<string>":
            raise
        raise ModelError(e.field, f"{_message(e)} (in {source})") from None


# -- errors ---------------------------------------------------------------------------------
def _syntax_message(e: tomllib.TOMLDecodeError) -> str:
    text = str(e)
    m = re.search(r"\(at line (\d+), column (\d+)\)\s*$", text)
    if m:
        reason = text[:m.start()].strip()
        return f"TOML syntax error at line {m.group(1)}, column {m.group(2)}: {reason}"
    return f"TOML syntax error: {text}"


def _message(err: ModelError) -> str:
    return getattr(err, "message", str(err))


def _err(field: str, message: str) -> ModelError:
    """A ModelError whose field is already the full TOML path."""
    e = ModelError(field, message)
    e._toml_path = True
    return e


def _join(path: str, key: str) -> str:
    if not path:
        return key
    if not key:
        return path
    return f"{path}{key}" if key.startswith("[") else f"{path}.{key}"


@contextmanager
def _at(path: str, renames=()):
    """Re-raise a builder's or component's ModelError with its field as a TOML path:
    ``renames`` are ``(regex, replacement)`` pairs applied in turn to the API field name (the
    message is the builder's own)."""
    try:
        yield
    except ModelError as e:
        if getattr(e, "_toml_path", False):
            raise
        field = e.field
        for pattern, repl in renames:
            field = re.sub(pattern, repl, field)
        # a builder file gives its gears' angles in degrees: the key the user wrote
        field = re.sub(r"(^|\.)(pressure_angle|helix_angle)$", r"\1\2_deg", field)
        raise _err(_join(path, field), _message(e)) from None


def _support(path: str, value):
    """A support: a number (N/m) or a table checked by its schema (``fs.SUPPORT``); returned as
    given, for the builder."""
    if isinstance(value, dict):
        fs.SUPPORT.read(path, value)
        return {k: (dict(s) if isinstance(s, dict) else s) for k, s in value.items()}
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise _err(path, "expected a stiffness in N/m or a table with stiffness, damping and "
                         f"clearance, got {type(value).__name__} {value!r}")
    return value


# -- components -----------------------------------------------------------------------------
# Each table's keys and values are checked by its schema (file_schema.py) in the file's own
# terms (degrees, TOML paths); the builders then check only what spans several keys, and
# their errors are re-addressed by field name (``_at``), never by rewriting their text.
def _gear(path: str, value, name: str, internal: bool = False) -> Gear:
    t = fs.GEAR.read(path, value)
    with _at(path, [(rf"^{name}(\.|$)", "")]):
        return Gear(t["teeth"], t["module"], t["pressure_angle"], t["helix_angle"],
                    t.get("face_width"), internal, name=name, mass=t["mass"],
                    inertia=t["inertia"], inertia_diametral=t.get("inertia_diametral"))


def _body(path: str, value, name: str, default_dofs: str) -> RigidBody:
    t = fs.BODY.read(path, value)
    with _at(path, [(rf"^{name}(\.|$)", "")]):
        return RigidBody(name=name, mass=t["mass"], inertia=t["inertia"],
                         inertia_diametral=t.get("inertia_diametral"),
                         dofs=t.get("dofs", default_dofs))


def _mesh_renames(table: bool) -> list:
    """Map the names of the meshes a stage builder creates back to the stage's keys."""
    return [(r"^(sun|ring)_planet\d+\.stiffness$",
             r"mesh_stiffness.\1_planet" if table else "mesh_stiffness"),
            (r"^((sun|ring)_planet\d+|mesh)\.backlash$", "backlash"),
            (r"^((sun|ring)_planet\d+|mesh)\.damping$", "mesh_damping"),
            (r"^mesh\.stiffness$", "mesh_stiffness")]


def _stage_type(path: str, t: dict, expected: str | None) -> None:
    if expected is not None and "type" in t and t["type"] != expected:
        raise _err(_join(path, "type"), f"= {t['type']!r}: this table is a {expected} stage")


def _stage_table(table, path: str, value, in_drivetrain: bool) -> dict:
    """A stage table checked by its schema; ``name`` and ``coupling_stiffness`` only in a
    drivetrain's ``[[stages]]``."""
    if not in_drivetrain and isinstance(value, dict):
        for key in ("name", "coupling_stiffness"):
            if key in value:
                allowed = [f.file_key for f in table.fields
                           if f.key not in ("name", "coupling_stiffness")]
                raise _err(_join(path, key), "unknown key; allowed: " + ", ".join(allowed))
    return table.read(path, value)


def _per_mesh(path: str, value):
    return fs.PER_MESH.read(path, value) if isinstance(value, dict) else value


def _planetary(path: str, value, in_drivetrain: bool = False) -> Model:
    t = _stage_table(fs.PLANETARY, path, value, in_drivetrain)
    _stage_type(path, t, "planetary")
    carrier = fs.CARRIER.read(_join(path, "carrier"), t["carrier"])
    build = builders.planetary_stage
    kwargs = sp.arguments(build, t, _convert(path), {"carrier": carrier})
    sun, planet, ring = kwargs["sun"], kwargs["planet"], kwargs["ring"]
    n = kwargs["n_planets"]
    if kwargs.get("planet_angles") is None and (sun.teeth + ring.teeth) % n and (
            "centre_distance" in t or ring.teeth == sun.teeth + 2 * planet.teeth):
        raise _err(_join(path, "n_planets"), f"= {n}: planets cannot be equally spaced, (sun + "
                   f"ring teeth) = {sun.teeth + ring.teeth} is not divisible by {n}; give "
                   "planet_angles_deg")
    renames = [(r"^planetary_stage(\.|$)", ""), *sp.renames(build),
               *_mesh_renames(isinstance(kwargs["mesh_stiffness"], dict)),
               (r"^planet\d+_bearing(\.|$)", r"planet_bearing\1")]
    with _at(path, renames):
        return build(**kwargs)


def _degrees_pairs(path: str, value, table: bool = False):
    """``[a, phase_deg]`` pairs (a list, or a table of lists) with the phase in radians, for
    the builders; other shapes go through for the builder to refuse by name."""
    def conv(p, x):
        if isinstance(x, list) and len(x) == 2:
            return [x[0], math.radians(v.number(f"{p}[1]", x[1], "deg"))]
        return x

    if value is None:
        return None
    if isinstance(value, dict):
        return {k: (conv(_join(path, k), x) if table else
                    [conv(f"{_join(path, k)}[{i}]", y) for i, y in enumerate(x)]
                    if isinstance(x, list) else x) for k, x in value.items()}
    if isinstance(value, list) and not table:
        return [conv(f"{path}[{i}]", x) for i, x in enumerate(value)]
    return value


def _convert(path: str):
    """What a builder takes for a file value (:func:`gearmodal.model.spec.arguments`): a gear
    for a gear table, a support or a value per mesh checked by its schema, ``[a, phase]``
    pairs with their phases in radians."""
    def convert(entry, value):
        where = _join(path, entry.path)
        if entry.gear:
            return _gear(where, value, entry.field.key, internal=entry.key.internal)
        if entry.key.body:
            return _body(where, value, entry.field.key, entry.key.body)
        if entry.field.type == "support":
            return _support(where, value)
        if entry.key.table is not None:  # its keys checked (one number: every key's)
            tab = entry.key.table
            read = tab.read(where, value) if isinstance(value, dict) \
                else tab.fields[0].read(where, value)
            if entry.field.unit != "deg":
                return value  # (the builder checks the ranges)
            return {k: math.radians(a) for k, a in read.items()} if isinstance(read, dict) \
                else math.radians(read)
        if entry.field.type == "per_mesh":
            return _per_mesh(where, value)
        if entry.key.phase_deg:
            return _degrees_pairs(where, value, table=entry.field.type == "table")
        return value
    return convert


def _parallel(path: str, value, in_drivetrain: bool = False) -> Model:
    t = _stage_table(fs.PARALLEL, path, value, in_drivetrain)
    _stage_type(path, t, "parallel")
    build = builders.parallel_stage
    kwargs = sp.arguments(build, t, _convert(path))  # (their errors are the file's already)
    renames = [(r"^parallel_stage(\.|$)", ""), *sp.renames(build), *_mesh_renames(False)]
    with _at(path, renames):
        return build(**kwargs)


def _gear_pair(path: str, value) -> Model:
    t = fs.GEAR_PAIR.read(path, value)
    build = builders.gear_pair
    kwargs = sp.arguments(build, t, _convert(path))  # (their errors are the file's already)
    renames = [(r"^gear_pair(\.|$)", ""), *sp.renames(build), *_mesh_renames(False),
               (r"^(pinion|wheel)_bearing(\.|$)", r"bearing\2")]
    with _at(path, renames):
        return build(**kwargs)


def _lin_parker(path: str, value) -> Model:
    t = fs.LIN_PARKER.read(path, value)
    build = builders.lin_parker_stage
    kwargs = sp.arguments(build, t, _convert(path))
    renames = [(r"^lin_parker_stage(\.|$)", ""), *sp.renames(build),
               (r"^(carrier|ring|sun|planet)\d*\.mass$", r"mass.\1"),
               (r"^(sun|ring)_planet\d+\.backlash$", "backlash"),
               (r"^(sun|ring)_planet\d+\.damping$", "mesh_damping")]
    with _at(path, renames):
        return build(**kwargs)


def _drivetrain(doc: dict) -> Model:
    chain = builders.drivetrain
    shafts = {"main_shaft": fs.SHAFT.read("main_shaft", doc["main_shaft"]), "hss_shaft": {}}
    stages_doc = doc["stages"]
    if not isinstance(stages_doc, list) or not all(isinstance(s, dict) for s in stages_doc):
        raise _err("stages", f"expected an array of tables [[stages]], got "
                             f"{type(stages_doc).__name__} {stages_doc!r}")
    stages, names, couplings = [], [], []
    for k, st in enumerate(stages_doc):
        path = f"stages[{k}]"
        if "type" not in st:
            raise _err(_join(path, "type"), "missing: required key (planetary or parallel)")
        with _at("", ()):
            kind = v.choice(_join(path, "type"), st["type"], STAGE_TYPES)
        build = _planetary if kind == "planetary" else _parallel
        stages.append(build(path, st, in_drivetrain=True))
        name = st.get("name", f"stage{k + 1}")
        with _at("", ()):
            v.name(_join(path, "name"), name)
        if name in names:
            raise _err(_join(path, "name"), f"= {name!r}: already used by "
                                            f"stages[{names.index(name)}]")
        names.append(name)
        if "coupling_stiffness" in st:
            if k == 0:
                raise _err(_join(path, "coupling_stiffness"), "not allowed on the first stage: "
                           "it is coupled to the rotor by [main_shaft]")
            couplings.append(st["coupling_stiffness"])
        elif k > 0:
            couplings.append(1e9)
    # the sections that go together, each with the other
    for have, need, what in (("generator", "hss_shaft", "stiffness in N m/rad"),
                             ("housing", "suspension", "stiffness table in N/m")):
        if have in doc and need not in doc:
            raise _err(need, f"missing section [{need}] ({what}), required with [{have}]")
        if need in doc and have not in doc:
            raise _err(need, f"given without [{have}]")
    if "hss_shaft" in doc:
        shafts["hss_shaft"] = fs.SHAFT.read("hss_shaft", doc["hss_shaft"])
    kwargs = sp.arguments(chain, doc, _convert(""), shafts)
    renames = [(r"^drivetrain(\.|$)", ""), *sp.renames(chain),
               (r"^coupling(\d+)\.stiffness$", r"stages[\1].coupling_stiffness")]
    with _at("", renames):
        return chain(stages=stages, couplings=couplings, stage_names=names, **kwargs)


# -- document -------------------------------------------------------------------------------
def _build(doc: dict, default_name: str | None) -> Model:
    if "model" not in doc:
        raise _err("model", "missing section [model] (with type = "
                            + " | ".join(repr(t) for t in MODEL_TYPES) + ")")
    if isinstance(doc["model"], dict) and doc["model"].get("type") == "components":
        return read_components(doc, default_name)  # what gm.dumps writes
    meta = fs.MODEL.read("model", doc["model"])
    kind = meta["type"]
    sections = _SECTIONS[kind]
    for key in doc:
        if key not in sections and key != "rating":
            raise _err(key, f"unknown section for type = {kind!r}; allowed: "
                            + ", ".join([*sections, "rating"]))
    for key, required in sections.items():
        if required and key not in doc:
            raise _err(key, f"missing section [{key}] (required for type = {kind!r})")
    name = meta.get("name", default_name or kind)
    if not isinstance(name, str) or not name:
        raise _err("model.name", f"= {name!r}: expected a non-empty string")
    rated, span = _speeds(meta)

    if kind == "drivetrain":
        model = _drivetrain(doc)
    elif kind == "gear_pair":
        model = _gear_pair("gear_pair", doc["gear_pair"])
    elif kind == "planetary_stage":
        model = _planetary("planetary_stage", doc["planetary_stage"])
    elif kind == "parallel_stage":
        model = _parallel("parallel_stage", doc["parallel_stage"])
    else:
        model = _lin_parker("lin_parker_stage", doc["lin_parker_stage"])
    model.name = name
    model.rated_speed_rpm = rated
    model.speed_range_rpm = span
    with _at("", ()):
        model.tilt_deg = fs.MODEL.by_key()["tilt_deg"].read("model.tilt_deg",
                                                             meta.get("tilt_deg", 0.0))
    with _at("", ()):
        model.check()
        _rating(doc, model)
    return model


def _rating(doc: dict, model: Model) -> None:
    """The optional ``[rating]`` table onto ``model.rating`` (checked against its names)."""
    if "rating" in doc:
        model.rating = rating_data.read("rating", doc["rating"])
        rating_data.check_names(model.rating, model)


def _speeds(meta: dict):
    rated = span = None
    with _at("", ()):
        if "rated_speed_rpm" in meta:
            rated = v.nonnegative("model.rated_speed_rpm", meta["rated_speed_rpm"], "rpm")
        if "speed_range_rpm" in meta:
            r = meta["speed_range_rpm"]
            if not isinstance(r, list) or len(r) != 2:
                raise _err("model.speed_range_rpm", f"= {r!r}: expected [low, high] in rpm")
            lo = v.nonnegative("model.speed_range_rpm[0]", r[0], "rpm")
            hi = v.nonnegative("model.speed_range_rpm[1]", r[1], "rpm")
            if hi <= lo:
                raise _err("model.speed_range_rpm", f"= {r!r}: high must exceed low")
            span = (lo, hi)
    if rated is not None and span is not None and not span[0] <= rated <= span[1]:
        raise _err("model.rated_speed_rpm", f"= {rated!r}: outside speed_range_rpm "
                                            f"[{span[0]:g}, {span[1]:g}]")
    return rated, span
