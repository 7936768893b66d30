"""Models as files, component by component: :func:`dumps` and :func:`dump` write any
:class:`~gearmodal.model.Model` (built by a builder, loaded from a file or assembled by hand) as
a TOML document of ``type = "components"``, which :func:`gearmodal.load` reads back to the same
components, so the model assembles to exactly the same matrices (floats are written in their
shortest exact form, angles in radians).

The document::

    [model]
    type = "components"
    name = "gear_pair"
    input = "pinion"              # the body whose speed is the model's speed

    [[frames]]                    # frames other than the ground, in order
    [[bodies]]                    # kind = "gear", "rigid" or "body"; DOF order = file order
    [[meshes]]
    [[bearings]]                  # bearings, supports and shafts
    [groups]                      # named lists of bodies (the planets of a stage...)

Each table's keys are the component's schema (:data:`Gear.SCHEMA`, :data:`Mesh.SCHEMA`...,
listed in ``docs/file-format.md``): a new component kind is one class with its ``SCHEMA``.
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np

from ..errors import ModelError
from . import rating_data
from .components import Body, Frame, Gear, RigidBody
from .model import ELEMENT_KINDS, GROUND, Model
from .schema import REQUIRED, Field, Table

__all__ = ["KINDS", "MODEL_TABLE", "dump", "dumps", "read_components", "to_toml"]

#: ``kind`` of a ``[[bodies]]`` table -> body class
KINDS = {"gear": Gear, "rigid": RigidBody, "body": Body}
MODEL_TABLE = Table('model (type = "components")', (
    Field("type", "choice", choices=("components",), default=REQUIRED,
          doc="the component-by-component form that gm.dumps writes"),
    Field("name", "string", doc="model name (default: the file name)"),
    Field("input", "name", doc="input body: the model's speed is its speed"),
    Field("output", "name", doc="output body (a drivetrain's generator side)"),
    Field("gear_ratio", "number", doc="output over input speed, as the builder computed it"),
    Field("rated_speed_rpm", "number", "rpm", low=0.0, doc="rated speed of the input"),
    Field("speed_range_rpm", "vector", "rpm", lengths=(2,), low=0.0,
          doc="[low, high] operating range of the input"),
    Field("tilt_deg", "number", "deg", low=-90.0, high=90.0, default=0.0,
          doc="shaft tilt, rotor end up (the direction of gravity)")),
    "The model's own data.")
GROUPS_TABLE = Field("groups", "names", doc="named lists of bodies")


def _arrays() -> tuple:
    """The document's arrays of tables: (key, component class, or None for the bodies)."""
    return (("frames", Frame), ("bodies", None), *((c.TABLE, c) for c in ELEMENT_KINDS))


def dumps(model: Model, rating: bool = True) -> str:
    """The model as TOML text of ``type = "components"`` (see the module docstring).

    ``gm.loads(gm.dumps(m))`` assembles to exactly the same matrices as ``m``. ``rating``:
    write the ratings' data (``model.rating``, the ``[rating]`` table) too; they change no
    matrix, so the identities of runs leave them out (``rating=False``).

    Examples
    --------
    >>> import math, gearmodal as gm
    >>> p = gm.Gear(20, 0.004, math.radians(20), mass=1.0, inertia=1e-3)
    >>> w = gm.Gear(40, 0.004, math.radians(20), mass=4.0, inertia=1.6e-2)
    >>> m = gm.gear_pair(p, w, mesh_stiffness=2e8, backlash=1e-4)
    >>> again = gm.loads(gm.dumps(m))
    >>> (again.assemble().K == m.assemble().K).all(), again.dof_names
    (np.True_, ['pinion.theta', 'wheel.theta'])
    """
    if not isinstance(model, Model):
        raise TypeError(f"gm.dumps writes a gm.Model, got {type(model).__name__}")
    meta = {"type": "components", "name": model.name, "input": model.input,
            "output": model.output, "gear_ratio": model.gear_ratio,
            "rated_speed_rpm": model.rated_speed_rpm,
            "speed_range_rpm": None if model.speed_range_rpm is None
            else list(model.speed_range_rpm), "tilt_deg": model.tilt_deg}
    doc: dict = {"model": MODEL_TABLE.write(meta)}
    frames = [f for f in model.frames.values() if f.name != GROUND]
    if frames:
        doc["frames"] = [_write(f) for f in frames]
    doc["bodies"] = [{"kind": _kind(b), **_write(b)} for b in model.bodies.values()]
    for cls in ELEMENT_KINDS:
        table = model.elements_of(cls)
        if table:
            doc[cls.TABLE] = [_write(e) for e in table.values()]
    if model.groups:
        doc["groups"] = {k: list(v) for k, v in model.groups.items()}
    if rating and getattr(model, "rating", None):
        doc["rating"] = rating_data.write(model.rating)
    return to_toml(doc)


def dump(model: Model, path) -> Path:
    """Write :func:`dumps` of ``model`` to ``path`` (UTF-8); returns the path."""
    p = Path(path)
    p.write_text(dumps(model), encoding="utf-8")
    return p


def _kind(body) -> str:
    for kind, cls in KINDS.items():
        if type(body) is cls:
            return kind
    raise TypeError(f"gm.dumps cannot write a body of type {type(body).__name__}; give the "
                    "class a SCHEMA and a kind in gearmodal.model.dump.KINDS")


def _write(component) -> dict:
    schema = type(component).SCHEMA
    return schema.write({f.key: getattr(component, f.key) for f in schema.fields})


# -- the TOML text ------------------------------------------------------------------------------
def to_toml(doc: dict) -> str:
    """TOML text of a document of tables (``{name: {key: value}}``) and arrays of tables
    (``{name: [{key: value}, ...]}``), in the document's order, one value per line, arrays
    and tables of values inline.

    The layout is gearmodal's own (not a TOML library's, whose layout may change between
    releases) because the text is a model's identity (:mod:`gearmodal.studies` hashes it).
    Floats are written in their shortest exact form (``repr``; in exponent form from 1e6).

    >>> print(to_toml({"model": {"name": "m", "k": 4.6e9}, "b": [{"at": [0.0, 1e-5]}]}))
    [model]
    name = "m"
    k = 4.6e+09
    <BLANKLINE>
    [[b]]
    at = [0.0, 1e-05]
    <BLANKLINE>
    """
    out = []
    for name, value in doc.items():
        items = value if isinstance(value, list) else [value]
        head = f"[[{_key(name)}]]" if isinstance(value, list) else f"[{_key(name)}]"
        for item in items:
            out.append(head)
            out += [f"{_key(k)} = {_value(x)}" for k, x in item.items()]
            out.append("")
    return "\n".join(out)


def _key(k: str) -> str:
    return k if re.fullmatch(r"[A-Za-z0-9_-]+", k) else _string(k)


def _string(text: str) -> str:
    """A TOML basic string: the characters as they are (JSON's ``\\ud83d\\ude00`` for one
    beyond the BMP is no TOML escape: a name with an emoji wrote a file ``gm.loads``
    refused), quotes, backslashes and control characters escaped (DEL too, as TOML asks)."""
    return json.dumps(text, ensure_ascii=False).replace("\x7f", "\\u007f")


def _value(x) -> str:
    if isinstance(x, bool):
        return "true" if x else "false"
    if isinstance(x, int):
        return str(x)
    if isinstance(x, float):
        if math.isnan(x):
            return "nan"
        if math.isinf(x):
            return "inf" if x > 0 else "-inf"
        text = repr(x)
        if 1e6 <= abs(x) < 1e16:
            text = np.format_float_scientific(x, unique=True, trim="-")
        return text
    if isinstance(x, str):
        return _string(x)
    if isinstance(x, (list, tuple)):
        return "[" + ", ".join(_value(y) for y in x) + "]"
    if isinstance(x, dict):
        return "{ " + ", ".join(f"{_key(k)} = {_value(y)}" for k, y in x.items()) + " }" \
            if x else "{}"
    raise TypeError(f"cannot write {type(x).__name__} {x!r} to TOML")


# -- reading ----------------------------------------------------------------------------------
def read_components(doc: dict, default_name: str | None = None) -> Model:
    """The :class:`Model` of a ``type = "components"`` document (parsed TOML); every error is a
    :class:`ModelError` whose field is the path in the document (``bodies[2].mass``)."""
    for key in doc:
        if key not in ("model", *(a for a, _ in _arrays()), "groups", "rating"):
            raise ModelError(key, "unknown section for type = 'components'; allowed: model, "
                             + ", ".join(a for a, _ in _arrays()) + ", groups, rating")
    meta = MODEL_TABLE.read("model", doc["model"])
    model = Model(meta.get("name", default_name or "model"), input=meta.get("input"),
                  rated_speed_rpm=meta.get("rated_speed_rpm"),
                  speed_range_rpm=tuple(meta["speed_range_rpm"])
                  if "speed_range_rpm" in meta else None, tilt_deg=meta.get("tilt_deg", 0.0))
    model.output = meta.get("output")
    model.gear_ratio = meta.get("gear_ratio")
    paths: dict[str, str] = {}
    for key, cls in _arrays():
        items = doc.get(key, [])
        if not isinstance(items, list) or not all(isinstance(t, dict) for t in items):
            raise ModelError(key, f"expected an array of tables [[{key}]], got "
                                  f"{type(items).__name__}")
        for i, t in enumerate(items):
            path = f"{key}[{i}]"
            c = cls
            if c is None:
                if "kind" not in t:
                    raise ModelError(f"{path}.kind", "missing: required key ("
                                     + ", ".join(KINDS) + ")")
                if t["kind"] not in KINDS:
                    raise ModelError(f"{path}.kind", f"= {t['kind']!r}: must be one of "
                                     + ", ".join(map(repr, KINDS)))
                c = KINDS[t["kind"]]
            comp = _build(c, path, c.SCHEMA.read(path, t))
            if isinstance(comp, Frame):  # frames share names with their bodies
                paths.setdefault(comp.name, path)
            else:
                paths[comp.name] = path
            try:
                model.add(comp)
            except ModelError as e:
                raise ModelError(f"{path}.name", e.message) from None
    if "groups" in doc:
        model.groups = {k: list(v) if isinstance(v, list) else [v]
                        for k, v in GROUPS_TABLE.read("groups", doc["groups"]).items()}
        for g, members in model.groups.items():
            for j, b in enumerate(members):
                if b not in model.bodies:
                    raise ModelError(f"groups.{g}[{j}]", f"= {b!r}: no such body")
    try:
        model.check()
    except ModelError as e:
        raise _located(e, paths) from None
    if "rating" in doc:
        model.rating = rating_data.read("rating", doc["rating"])
        rating_data.check_names(model.rating, model)
    return model


def _build(cls, path: str, values: dict):
    """``cls(**values)`` under a placeholder name: the constructors check single names, a
    model's are dotted (``stage1.sun``); their errors are re-addressed to ``path``."""
    name = values["name"]
    tmp = name.replace(".", "_")
    try:
        comp = cls(**{**values, "name": tmp})
    except ModelError as e:
        field = e.field
        if field == tmp or field.startswith(tmp + "."):
            field = path + field[len(tmp):]
        raise ModelError(field, e.message) from None
    comp.name = name
    return comp


def _located(e: ModelError, paths: dict[str, str]) -> ModelError:
    """``e`` with its field's component name replaced by the component's path in the file."""
    best = ""
    for name in paths:
        if (e.field == name or e.field.startswith(name + ".")) and len(name) > len(best):
            best = name
    if not best:
        return e
    return ModelError(paths[best] + e.field[len(best):], e.message)
