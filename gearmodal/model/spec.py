"""Builders that are their schema: each keyword parameter of a builder is declared once, in its
signature, with its file field as the annotation's metadata::

    def parallel_stage(gear: Annotated[Gear, GEAR], pinion: Annotated[Gear, GEAR], *,
                       mesh_stiffness: Annotated[float, like(Mesh.SCHEMA.by_key()["stiffness"])],
                       angle: Annotated[float, key("angle", "rad", degrees=True)] = 0.0, ...)

From the signature come the builder's file table (:func:`file_table`: keys, types, units,
ranges, defaults; the reference page ``docs/file-format.md`` is written from it), the check of
its arguments in the API (:func:`checked`: the same fields, the same ranges), the loader's
call (:func:`arguments`: the file table's values as the builder's keyword arguments, each
under its parameter's name) and the file path of an error the builder raises naming its
argument (:func:`renames`). A builder's file writes no builder tables (``gm.dumps`` writes
components), so there is no writer to derive.
"""

from __future__ import annotations

import dataclasses
import functools
import inspect
import typing
from dataclasses import dataclass

from .schema import REQUIRED, Field, Table

__all__ = ["GEAR", "RING", "Key", "arguments", "body", "checked", "entries", "file_key",
           "file_table", "group_table", "key", "like", "renames", "sections"]


@dataclass(frozen=True)
class Key:
    """A builder parameter's file entry (the metadata of its annotation): its ``field`` (the
    key filled in from the parameter's name, or ``file`` when the file names it otherwise:
    ``"carrier.mass"`` is key ``mass`` of the table ``carrier``); ``gear``: a gear table in
    the file for a :class:`~gearmodal.Gear` in the API (``internal``: a ring); ``phase_deg``:
    ``[a, phase]`` pairs whose phases the file gives in degrees; ``table``: the table that
    checks a table value's keys (one number for every key: its first field); ``body``: a
    body table in the file for a :class:`~gearmodal.RigidBody` in the API, of this default
    DOF level."""

    field: Field
    file: str = ""
    gear: bool = False
    internal: bool = False
    phase_deg: bool = False
    table: Table | None = None
    body: str = ""


def key(type: str, unit: str = "", *, file: str = "", phase_deg: bool = False,
        table: Table | None = None, **kw) -> Key:
    """A :class:`Key` with a new field (``Field`` keywords)."""
    return Key(Field("", type, unit, **kw), file, phase_deg=phase_deg, table=table)


def like(field: Field, *, file: str = "", **changes) -> Key:
    """A :class:`Key` with an existing field (a component's, its ranges stated there)."""
    return Key(dataclasses.replace(field, **changes), file)


#: a gear wheel: a gear table in the file
GEAR = Key(Field("", "table", doc="gear table"), gear=True)
#: an internal gear wheel (a ring): a gear table in the file
RING = Key(Field("", "table", doc="gear table"), gear=True, internal=True)


def body(doc: str, dofs: str) -> Key:
    """A rigid body: a body table in the file (``dofs`` its default DOF level)."""
    return Key(Field("", "table", doc=doc), body=dofs)


#: the types whose API values :func:`checked` checks by their field (the others: the builder)
CHECKED_TYPES = ("number", "integer", "angle", "choice", "vector")


@dataclass(frozen=True)
class Entry:
    """One parameter of a builder as its file has it: ``field.key`` the file key (without a
    degrees suffix) in the table ``group`` (``""``: the builder's own table),
    ``field.default`` the signature's."""

    param: str
    field: Field
    key: Key
    group: str = ""

    @property
    def gear(self) -> bool:
        return self.key.gear

    @property
    def path(self) -> str:
        """Where the file gives it, from the builder's table (``carrier.mass``)."""
        return f"{self.group}.{self.field.file_key}" if self.group else self.field.file_key


@functools.cache
def entries(fn) -> tuple[Entry, ...]:
    """The parameters of builder ``fn`` that carry a :class:`Key`, in signature order."""
    fn = inspect.unwrap(fn)
    hints = typing.get_type_hints(fn, include_extras=True)
    out = []
    for name, p in inspect.signature(fn).parameters.items():
        h = hints.get(name)
        if typing.get_origin(h) is not typing.Annotated:
            continue
        keys = [m for m in typing.get_args(h)[1:] if isinstance(m, Key)]
        if not keys:
            continue
        k = keys[0]
        default = REQUIRED if p.default is inspect.Parameter.empty else p.default
        group, _, file_key = (k.file or name).rpartition(".")
        if default is None and k.field.default is not REQUIRED:  # the file's default, or none
            default = k.field.default
        field = dataclasses.replace(k.field, key=file_key, default=default)
        out.append(Entry(name, field, k, group))
    return tuple(out)


def file_table(fn, title: str, doc: str, before: tuple = (), after: tuple = (),
               groups: dict | None = None) -> Table:
    """The file table of builder ``fn``: ``before``, its parameters' fields in signature
    order (a group's, ``carrier.mass``..., as one table field ``groups[name]``, where its
    first member stands), ``after``."""
    fields, seen = [], set()
    for e in entries(fn):
        if not e.group:
            fields.append(e.field)
        elif e.group not in seen:
            seen.add(e.group)
            fields.append(groups[e.group])
    return Table(title, (*before, *fields, *after), doc)


def group_table(fn, group: str, title: str, doc: str) -> Table:
    """The table ``group`` of builder ``fn``'s file (its parameters ``file="<group>.<key>"``)."""
    return Table(title, tuple(e.field for e in entries(fn) if e.group == group), doc)


def sections(fn, before: dict, after: dict) -> dict:
    """``{section: required}`` of a builder whose file is a document of sections
    (:func:`gearmodal.drivetrain`): ``before``, then each parameter's table (its group's, or
    its own), required when a member is, then ``after``."""
    out = dict(before)
    for e in entries(fn):
        sec = e.group or e.field.key
        out[sec] = out.get(sec, False) or e.field.required
    return {**out, **after}


def file_key(fn, param: str) -> str:
    """Where the file gives parameter ``param`` of ``fn`` (with ``_deg`` for an angle the file
    gives in degrees; ``carrier.mass`` in a group); ``param`` itself when it is not there."""
    for e in entries(fn):
        if e.param == param:
            return e.path
    return param


def arguments(fn, table: dict, convert, groups: dict | None = None) -> dict:
    """The keyword arguments of builder ``fn`` from its file ``table`` as read
    (:meth:`Table.read`; ``groups``: its group tables as read, by name): each value under its
    parameter's name, as ``convert(entry, value)`` makes it (a gear table a gear); keys absent
    with no default are left out (the builder's default)."""
    out = {}
    for e in entries(fn):
        t = groups[e.group] if e.group else table
        if e.field.key in t:
            out[e.param] = convert(e, t[e.field.key])
    return out


def renames(fn) -> list[tuple[str, str]]:
    """``(pattern, replacement)`` pairs from ``fn``'s parameter names to their file keys where
    they differ (its errors name its parameters)."""
    return [(rf"^{e.param}(\.|\[|$)", rf"{e.path}\1") for e in entries(fn)
            if e.path != e.param]


def checked(fn):
    """Check ``fn``'s arguments of the types :data:`CHECKED_TYPES` by their fields before it
    runs (the file's ranges, stated once): errors name ``<name>.<parameter>``, ``name`` the
    builder's ``name`` argument where it has one, else the builder's own name."""
    sig = inspect.signature(fn)

    @functools.wraps(fn)
    def run(*args, **kwargs):
        try:
            bound = sig.bind(*args, **kwargs)
        except TypeError as err:  # as Python words it, with the builder's name
            raise TypeError(f"{fn.__name__}() {err}") from None
        bound.apply_defaults()
        a = bound.arguments
        label = a.get("name", fn.__name__)
        for e in entries(fn):
            if e.field.type in CHECKED_TYPES and not e.gear:
                a[e.param] = e.field.check(f"{label}.{e.param}", a[e.param])
        return fn(*bound.args, **bound.kwargs)

    # what help() and an editor show: the types without the file metadata
    hints = typing.get_type_hints(fn)
    run.__signature__ = sig.replace(parameters=[
        p.replace(annotation=hints.get(name, p.annotation))
        for name, p in sig.parameters.items()], return_annotation=hints.get("return"))
    return run
