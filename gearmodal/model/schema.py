"""The declarative file schema: one :class:`Field` per key, one :class:`Table` per kind of table.

A field knows its type, unit, allowed range, whether the file gives it in degrees, its default
and a one-line description. From the tables come the validation of a file's table
(:meth:`Table.read`: errors name the field's path, the value, the unit and the range), the
writer's tables (:meth:`Table.write`) and the file-format reference page
(:func:`reference_markdown`, ``docs/file-format.md``, :mod:`gearmodal.reference`).

Angles are radians in the API. A field with ``degrees=True`` is given in the file in degrees
under ``<key>_deg``; a radian field of the component tables may be given either as ``<key>``
(rad, what :func:`gearmodal.dumps` writes: exact) or as ``<key>_deg``.
"""

from __future__ import annotations

import dataclasses
import math
import numbers
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import ModelError
from . import validate as v

__all__ = ["NAME", "REQUIRED", "Field", "Table", "reference_markdown"]


class _Required:
    def __repr__(self) -> str:
        return "required"


#: default of a field the file must give
REQUIRED: Any = _Required()

#: field types and how the reference page names them
TYPES = {"number": "number", "integer": "integer", "boolean": "true/false",
         "string": "string", "name": "name", "choice": "one of", "vector": "array of numbers",
         "pairs": "array of [a, b] number pairs",
         "directions": "table by direction", "names": "table of names", "angle": "number",
         "table": "table", "support": "number or support table",
         "per_mesh": "number or {sun_planet, ring_planet}",
         "alternation": "true/false or table", "path": "path", "any": "value"}
DIRECTIONS = ("x", "y", "z", "rx", "ry", "theta")


@dataclass(frozen=True)
class Field:
    """One key of a file table.

    Parameters
    ----------
    key : the key in the file (and the attribute of the component unless ``attr`` is given).
    type : one of :data:`TYPES`: ``number`` (finite float), ``integer``, ``boolean``,
        ``string``, ``name`` (a component name, dotted parts allowed), ``choice``, ``vector``
        (``length`` numbers), ``directions`` (a table keyed by x, y, z, rx, ry, theta),
        ``names`` (a table of names to lists of names), ``angle`` (radians; see ``degrees``).
    unit : SI unit of the value in the API (``rad`` for angles).
    low, high : the allowed range; ``low_open``/``high_open`` make a bound exclusive.
    degrees : the file gives the value in degrees under ``<key>_deg`` only.
    default : the value when the key is absent; :data:`REQUIRED` if it must be given; ``None``
        for an optional value the component fills in (written only when set).
    doc : a one-line description (the reference page).
    choices : allowed values of a ``choice``.
    lengths : the allowed numbers of entries of a ``vector`` (any if empty).
    note : a hint added to range errors (``modules are in metres: 10 mm = 0.010``).
    limits : a kind of :data:`gearmodal.model.validate.LIMITS` (``"mass"``...): the range of
        ``|value|`` the solvers handle, checked after ``low``/``high``.
    deg_floor : an angle given in degrees (``<key>_deg``) whose size is not zero but below
        this many degrees is refused with a hint: a drivetrain has no such gear, and the
        number is most likely radians typed into a degree key (``pressure_angle_deg = 0.349``).
    """

    key: str
    type: str
    unit: str = ""
    low: float | None = None
    high: float | None = None
    low_open: bool = False
    high_open: bool = False
    degrees: bool = False
    default: Any = None
    doc: str = ""
    choices: tuple = ()
    lengths: tuple = ()
    note: str = ""
    limits: str = ""
    deg_floor: float | None = None

    @property
    def required(self) -> bool:
        return self.default is REQUIRED

    @property
    def file_key(self) -> str:
        """The key in the file (``<key>_deg`` for a field given in degrees)."""
        return f"{self.key}_deg" if self.degrees else self.key

    @property
    def hint(self) -> str:
        """What to give, in a few words (shown for a missing key): the unit, or the type."""
        if self.degrees:
            return "list of deg" if self.type == "vector" else "deg"
        if self.type == "choice":
            c = list(map(str, self.choices))
            return c[0] if len(c) == 1 else ", ".join(c[:-1]) + " or " + c[-1]
        return self.unit or TYPES[self.type]

    def range_text(self) -> str:
        """The allowed range in words, e.g. ``> 0 kg`` or ``in [1, 10]``."""
        u = f" {self.unit}" if self.unit else ""
        if self.type == "choice":
            return "one of " + ", ".join(map(repr, self.choices))
        lo, hi = self.low, self.high
        if lo is not None and hi is not None:
            return (f"in {'(' if self.low_open else '['}{lo:.6g}, {hi:.6g}"
                    f"{')' if self.high_open else ']'}{u}")
        if lo is not None:
            return f"{'>' if self.low_open else '>='} {lo:.6g}{u}"
        if hi is not None:
            return f"{'<' if self.high_open else '<='} {hi:.6g}{u}"
        return self.unit

    # -- reading ------------------------------------------------------------------------
    def read(self, path: str, value):
        """``value`` from a file, checked and converted to the API's (radians for angles);
        raises :class:`ModelError` naming ``path``."""
        t = self.type
        if t in ("number", "angle"):
            x = v.number(path, value, self.unit)
            if self.unit == "deg" and self.deg_floor is not None \
                    and 0.0 < abs(x) < self.deg_floor:
                raise ModelError(path, f"= {x!r} deg: a pressure angle under "
                                 f"{self.deg_floor:g} deg is not a gear a drivetrain has; if "
                                 f"{x!r} is in radians, give {math.degrees(x):.4g}")
            self._in_range(path, x)
            return x
        if t == "integer":
            x = v.integer(path, value, minimum=int(self.low) if self.low is not None
                          else -(2**62))
            if self.high is not None and x > self.high:
                raise ModelError(path, f"= {x}: must be an integer <= {self.high:g}"
                                 + (f" ({self.note})" if self.note else ""))
            if self.limits:
                v.plausible(path, x, self.limits)
            return x
        if t == "boolean":
            if not isinstance(value, bool):
                raise ModelError(path, f"expected true or false, got {type(value).__name__} "
                                       f"{value!r}")
            return value
        if t == "string":
            if not isinstance(value, str):
                raise ModelError(path, f"expected a string, got {type(value).__name__} "
                                       f"{value!r}")
            return value
        if t == "name":
            return _dotted_name(path, value)
        if t == "choice":
            return v.choice(path, value, self.choices)
        if t == "vector":
            if not isinstance(value, list) or (self.lengths and len(value) not in self.lengths):
                n = " or ".join(map(str, self.lengths)) or "some"
                raise ModelError(path, f"= {value!r}: expected an array of {n} numbers"
                                 + (f" in {self.unit}" if self.unit else ""))
            out = [v.number(f"{path}[{i}]", x, self.unit) for i, x in enumerate(value)]
            for i, x in enumerate(out):
                self._in_range(f"{path}[{i}]", x)
            return out
        if t == "pairs":
            if not isinstance(value, list) or not all(isinstance(x, list) and len(x) == 2
                                                      for x in value):
                raise ModelError(path, f"= {value!r}: expected an array of [a, b] pairs"
                                 + (f" in {self.unit}" if self.unit else ""))
            out = []
            for i, pair in enumerate(value):
                out.append([v.number(f"{path}[{i}][{j}]", x, self.unit)
                            for j, x in enumerate(pair)])
                for j, x in enumerate(out[-1]):
                    self._in_range(f"{path}[{i}][{j}]", x)
            return out
        if t == "directions":
            if not isinstance(value, dict):
                raise ModelError(path, f"expected a table keyed by direction "
                                       f"({', '.join(DIRECTIONS)}), got "
                                       f"{type(value).__name__} {value!r}")
            out = {}
            for k, x in value.items():
                if k not in DIRECTIONS:
                    raise ModelError(f"{path}.{k}", "unknown direction; allowed: "
                                     + ", ".join(DIRECTIONS))
                out[k] = v.number(f"{path}.{k}", x, self.unit)
                self._in_range(f"{path}.{k}", out[k])
            return out
        if t == "path":
            if not isinstance(value, str) or not value or "\x00" in value:
                raise ModelError(path, f"= {value!r}: expected a file path (a non-empty string "
                                       "without NUL characters)")
            return value
        if t in ("table", "support", "per_mesh", "alternation", "any"):
            ok = {"table": (dict,), "support": (dict, int, float), "per_mesh": (dict, int, float),
                  "alternation": (dict, bool), "any": (object,)}[t]
            if not isinstance(value, ok) or (t in ("support", "per_mesh") and
                                             isinstance(value, bool)):
                raise ModelError(path, f"expected a {TYPES[t]}, got {type(value).__name__} "
                                       f"{value!r}")
            if t == "per_mesh" and not isinstance(value, dict):  # one number for every mesh
                x = v.number(path, value, self.unit)
                self._in_range(path, x)
                return x
            return value
        if t == "names":
            if not isinstance(value, dict):
                raise ModelError(path, f"expected a table of names, got {value!r}")
            out = {}
            for k, x in value.items():
                if isinstance(x, list):
                    out[k] = [_dotted_name(f"{path}.{k}[{i}]", n) for i, n in enumerate(x)]
                else:
                    out[k] = _dotted_name(f"{path}.{k}", x)
            return out
        raise AssertionError(f"unknown field type {t!r}")

    def check(self, path: str, value):
        """``value`` as a component holds it (the API's: radians, tuples), checked against this
        field's type and range, the one statement of them for the file and the API; raises
        :class:`ModelError` naming ``path``. ``None`` passes where the field is optional
        (default ``None``)."""
        if value is None and self.default is None:
            return None
        t = self.type
        if t in ("vector", "pairs") and not isinstance(value, (list, str, bytes, dict)):
            try:  # an API caller's tuple, array or any iterable: its entries as a list
                value = list(value.tolist() if isinstance(value, np.ndarray) else value)
            except TypeError:
                pass  # not iterable: refused below, by name
        if t == "pairs" and isinstance(value, list):
            value = [list(x.tolist() if isinstance(x, np.ndarray) else x)
                     if isinstance(x, (tuple, np.ndarray)) else x for x in value]
        if t == "boolean" and isinstance(value, np.bool_):
            value = bool(value)
        if t == "angle" and self.low is not None and self.high is not None \
                and not self.low_open:  # with the hint for degrees given as radians
            return v.angle(path, value, low=self.low, high=self.high,
                           high_strict=self.high_open)
        if t == "angle":
            x = v.number(path, value, "rad")
            self._in_range(path, x)
            return x
        out = self.read(path, value)
        if t == "vector":
            return tuple(out)
        if t == "pairs":
            return tuple(tuple(p) for p in out)
        return out

    def _in_range(self, path: str, x: float) -> None:
        """Raise naming the bound ``x`` violates (``= -3.0: must be > 0 kg``)."""
        u = f" {self.unit}" if self.unit else ""
        msg = None
        below = self.low is not None and (x <= self.low if self.low_open else x < self.low)
        above = self.high is not None and (x >= self.high if self.high_open else x > self.high)
        if (below or above) and self.low is not None and self.high is not None:
            msg = f"must lie {self.range_text()}"  # the whole range
        elif below:
            msg = f"must be {'>' if self.low_open else '>='} {self.low:g}{u}"
        elif above:
            msg = f"must be {'<' if self.high_open else '<='} {self.high:g}{u}"
        if msg:
            raise ModelError(path, f"= {x!r}: {msg}" + (f" ({self.note})" if self.note else ""))
        if self.limits:
            v.plausible(path, x, self.limits)


def _dotted_name(path: str, value) -> str:
    """A component name as models hold it: dot-separated parts (``stage1.sun``), each a
    non-empty string without surrounding spaces."""
    if not isinstance(value, str):
        raise ModelError(path, f"expected a name (string), got {type(value).__name__} "
                               f"{value!r}")
    if not all(p and p.strip() == p for p in value.split(".")):
        raise ModelError(path, f"= {value!r}: must be non-empty parts without surrounding "
                               "spaces, separated by dots")
    return value


#: the ``name`` of every component table
NAME = Field("name", "name", default=REQUIRED, doc="unique name; dots separate the prefixes "
             "a drivetrain adds (`stage1.sun`)")
#: where an element belongs in its gearbox (data the builders set; kept by gm.dumps)
STRUCTURE = (
    Field("stage", "string", default="", doc="stage it belongs to (a drivetrain's `stage1`)"),
    Field("role", "string", default="", doc="its role in the stage (`carrier`, `sun`, "
          "`planet`, `sun_planet`, `planet_bearing`...)"),
)


@dataclass(frozen=True)
class Table:
    """A kind of file table: its fields in file order and a one-line description."""

    name: str
    fields: tuple
    doc: str = ""
    extra_keys: tuple = field(default=())  # keys handled by the reader itself (e.g. "kind")

    def by_key(self) -> dict:
        return {f.key: f for f in self.fields}

    def read(self, path: str, value) -> dict:
        """The table's values from a file, checked: ``{key: value}`` with defaults filled in
        (a ``None`` default stays absent). Unknown and missing keys raise
        :class:`ModelError` naming them."""
        if not isinstance(value, dict):
            raise ModelError(path, f"expected a table, got {type(value).__name__} {value!r}")
        fields = self.by_key()
        allowed = [*self.extra_keys]
        for f in self.fields:
            allowed.append(f"{f.key}_deg" if f.degrees else f.key)
            if f.type == "angle" and not f.degrees:
                allowed.append(f"{f.key}_deg")
        out = {}
        for key, val in value.items():
            if key in self.extra_keys:
                continue
            base = key[:-4] if key.endswith("_deg") else key
            f = fields.get(key) or fields.get(base)
            if key not in allowed or f is None:
                hint = f" (angles are given in degrees: {key}_deg)" \
                    if f"{key}_deg" in allowed else ""
                raise ModelError(_join(path, key), f"unknown key{hint}; allowed: "
                                 + ", ".join(allowed))
            if f.key in out:
                raise ModelError(_join(path, key), f"{f.key} is given twice (in rad and in "
                                 "deg); give one")
            if f.degrees and f.type == "vector":
                out[f.key] = [math.radians(d) for d in dataclasses.replace(
                    f, unit="deg", low=None, high=None).read(_join(path, key), val)]
            elif key.endswith("_deg") and f.type == "angle":
                deg = v.number(_join(path, key), val, "deg")
                if f.deg_floor is not None and 0.0 < abs(deg) < f.deg_floor:
                    raise ModelError(_join(path, key), f"= {deg!r} deg: a "
                                     f"{f.key.replace('_', ' ')} under {f.deg_floor:g} deg "
                                     "is not a gear a drivetrain "
                                     f"has; if {deg!r} is in radians, give "
                                     f"{key} = {math.degrees(deg):.4g}")
                rad = math.radians(deg)
                try:
                    f._in_range(_join(path, key), rad)
                except ModelError:
                    lo = "" if f.low is None else f"{math.degrees(f.low):.6g}"
                    hi = "" if f.high is None else f"{math.degrees(f.high):.6g}"
                    raise ModelError(_join(path, key), f"= {deg!r} deg: must lie in "
                                     f"{'(' if f.low_open else '['}{lo}, {hi}"
                                     f"{')' if f.high_open else ']'} deg") from None
                out[f.key] = rad
            else:
                out[f.key] = f.read(_join(path, key), val)
        for f in self.fields:
            if f.key in out:
                continue
            if f.required:
                key = f"{f.key}_deg" if f.degrees else f.key
                raise ModelError(_join(path, key), f"missing: required key ({f.hint})")
            if f.default is not None:
                out[f.key] = _fresh(f.default)
        return out

    def check(self, component, keys, label: str | None = None) -> None:
        """Check and convert the attributes ``keys`` of ``component`` (an instance of the kind
        this table describes) in place, by their fields (:meth:`Field.check`): errors name
        ``<label>.<key>`` (``label`` default: the component's name)."""
        fields = self.by_key()
        label = component.name if label is None else label
        for key in keys:
            setattr(component, key, fields[key].check(f"{label}.{key}",
                                                      getattr(component, key)))

    def write(self, values: dict) -> dict:
        """A file table of ``values`` (``{key: API value}``): ``None`` and values equal to
        their default left out, angles in radians (exact)."""
        out = {}
        for f in self.fields:
            if f.key not in values:
                continue
            x = values[f.key]
            if x is None or (not f.required and f.default is not None and _same(x, f.default)):
                continue
            out[f.key] = _plain(x)
        return out


def _same(a, b) -> bool:
    """Whether a value equals a field's default (same type: 0 is written where 0.0 is the
    default, so that the file gives back exactly what the model held)."""
    a = list(a) if isinstance(a, tuple) else a
    b = list(b) if isinstance(b, tuple) else b
    return type(a) is type(b) and a == b


def _fresh(x):
    return dict(x) if isinstance(x, dict) else list(x) if isinstance(x, (list, tuple)) else x


def _plain(x):
    """Python values TOML can hold (tuples as lists, numpy scalars as floats)."""
    if isinstance(x, dict):
        return {k: _plain(y) for k, y in x.items()}
    if isinstance(x, (list, tuple)):
        return [_plain(y) for y in x]
    if isinstance(x, bool) or isinstance(x, str):
        return x
    if isinstance(x, numbers.Integral):
        return int(x)
    if isinstance(x, numbers.Real):
        return float(x)  # numpy floats print as np.float64(...) otherwise
    return x


def _join(path: str, key: str) -> str:
    return f"{path}.{key}" if path else key


# -- the reference page ---------------------------------------------------------------------
def reference_markdown(sections: list[tuple[str, str, list[Table]]]) -> str:
    """The file-format reference: for each ``(title, text, tables)`` section a table per
    :class:`Table` with every field's key, type, unit, range, default and description."""
    lines = ["# File formats", "",
             "Generated from the schema (`gearmodal/model/schema.py`) by `python -m "
             "gearmodal.reference`; do not "
             "edit by hand (a test checks that it is current).", ""]
    for title, text, tables in sections:
        lines += [f"## {title}", "", text, ""]
        for t in tables:
            lines += [f"### `{t.name}`", "", t.doc, "",
                      "| key | type | unit | allowed | default | description |",
                      "|---|---|---|---|---|---|"]
            for f in t.fields:
                key = f"{f.key}_deg" if f.degrees else f.key
                if f.type == "angle" and not f.degrees:
                    key = f"{f.key}` or `{f.key}_deg"
                unit = "deg" if f.degrees else f.unit
                typ = TYPES[f.type]
                rng = f.range_text()
                if rng == f.unit:  # no bounds: the unit column says it
                    rng = ""
                if f.unit == "deg" and f.deg_floor is not None and f.low is not None \
                        and f.low > 0 and f.high is not None:  # a plausible angle in degrees
                    rng = f"in [{f.deg_floor:g}, {f.high:g}{')' if f.high_open else ']'} deg"
                if f.degrees and (f.low is not None or f.high is not None):
                    lo = "" if f.low is None else f"{math.degrees(f.low):.6g}"
                    hi = "" if f.high is None else f"{math.degrees(f.high):.6g}"
                    low_open = f.low_open
                    if f.deg_floor is not None and f.low is not None and f.low > 0:
                        lo, low_open = f"{f.deg_floor:g}", False
                    rng = f"in {'(' if low_open else '['}{lo}, {hi}" \
                          f"{')' if f.high_open else ']'} deg"
                    if f.deg_floor is not None and not (f.low is not None and f.low > 0):
                        rng += f", 0 or at least {f.deg_floor:g} in size"
                if f.type == "choice":
                    typ, rng = "string", rng
                elif f.type == "vector":
                    n = " or ".join(map(str, f.lengths))
                    typ = f"array of {n} numbers" if n else typ
                if f.limits:
                    lo, hi, _ = v.LIMITS[f.limits]
                    rng = f"{rng}; magnitude the solvers take: [{lo:g}, {hi:g}]".lstrip("; ")
                dflt = "required" if f.required else ("—" if f.default is None
                                                      else f"`{_show(f.default)}`")
                cells = [f"`{key}`", typ, unit, rng, dflt, f.doc]
                # a pipe inside a cell would end it (Markdown tables): escaped
                lines.append("| " + " | ".join(str(c).replace("|", "\\|") for c in cells)
                             + " |")
            lines.append("")
    return "\n".join(lines).rstrip() + "\n"


def _show(x) -> str:
    if isinstance(x, bool):
        return "true" if x else "false"
    if isinstance(x, str):
        return f'"{x}"'
    if isinstance(x, dict):
        return "{" + ", ".join(f"{k} = {_show(y)}" for k, y in x.items()) + "}"
    if isinstance(x, (list, tuple)):
        return "[" + ", ".join(_show(y) for y in x) + "]"
    return repr(x)
