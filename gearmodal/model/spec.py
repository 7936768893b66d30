"""Builders that are their schema: each keyword parameter of a builder is declared once, in its
signature, with its file field as the annotation's metadata::

    def parallel_stage(gear: Annotated[Gear, GEAR], pinion: Annotated[Gear, GEAR], *,
                       mesh_stiffness: Annotated[float, like(MESH["stiffness"])], ...)

From the signature come the builder's file table (:func:`file_table`: keys, types, units,
ranges, defaults; the reference page ``docs/file-format.md`` is written from it), the check of
its arguments in the API (:func:`checked`: the same fields, the same ranges) and the loader's
call (:func:`arguments`: the file table's values as the builder's keyword arguments, each
under its parameter's name).
"""

from __future__ import annotations

import dataclasses
import functools
import inspect
import typing
from dataclasses import dataclass

from .schema import REQUIRED, Field, Table

__all__ = ["GEAR", "Key", "arguments", "checked", "entries", "file_key", "file_table", "key",
           "like", "renames"]


@dataclass(frozen=True)
class Key:
    """A builder parameter's file entry (the metadata of its annotation): its ``field`` (the
    key filled in from the parameter's name, or ``file`` when the file names it otherwise),
    and ``gear``: a gear table in the file for a :class:`~gearmodal.Gear` in the API."""

    field: Field
    file: str = ""
    gear: bool = False


def key(type: str, unit: str = "", *, file: str = "", **kw) -> Key:
    """A :class:`Key` with a new field (``Field`` keywords)."""
    return Key(Field("", type, unit, **kw), file)


def like(field: Field, *, file: str = "", **changes) -> Key:
    """A :class:`Key` with an existing field (a component's, its ranges stated there)."""
    return Key(dataclasses.replace(field, **changes), file)


#: a gear wheel: a gear table in the file
GEAR = Key(Field("", "table", doc="gear table"), gear=True)
#: the types whose API values :func:`checked` checks by their field (the others: the builder)
CHECKED_TYPES = ("number", "integer", "angle", "choice", "vector")


@dataclass(frozen=True)
class Entry:
    """One parameter of a builder as its file has it: ``field.key`` the file key (without a
    degrees suffix), ``field.default`` the signature's."""

    param: str
    field: Field
    gear: bool


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
        field = dataclasses.replace(k.field, key=k.file or name,
                                    default=k.field.default if default is None else default)
        out.append(Entry(name, field, k.gear))
    return tuple(out)


def file_table(fn, title: str, doc: str, before: tuple = (), after: tuple = ()) -> Table:
    """The file table of builder ``fn``: ``before``, its parameters' fields, ``after``."""
    return Table(title, (*before, *(e.field for e in entries(fn)), *after), doc)


def file_key(fn, param: str) -> str:
    """The file key of parameter ``param`` of ``fn`` (with ``_deg`` for an angle the file
    gives in degrees); ``param`` itself when it is not in the file."""
    for e in entries(fn):
        if e.param == param:
            return e.field.file_key
    return param


def arguments(fn, table: dict, convert) -> dict:
    """The keyword arguments of builder ``fn`` from its file ``table`` as read
    (:meth:`Table.read`): each value under its parameter's name, as ``convert(entry, value)``
    makes it (a gear table a gear); keys absent with no default are left out (the builder's
    default)."""
    return {e.param: convert(e, table[e.field.key]) for e in entries(fn)
            if e.field.key in table}


def renames(fn) -> list[tuple[str, str]]:
    """``(pattern, replacement)`` pairs from ``fn``'s parameter names to their file keys where
    they differ (its errors name its parameters)."""
    return [(rf"^{e.param}(\.|\[|$)", rf"{e.field.file_key}\1") for e in entries(fn)
            if e.field.file_key != e.param]


def checked(fn):
    """Check ``fn``'s arguments of the types :data:`CHECKED_TYPES` by their fields before it
    runs (the file's ranges, stated once): errors name ``<name>.<parameter>``, ``name`` the
    builder's ``name`` argument where it has one, else the builder's own name."""
    sig = inspect.signature(fn)

    @functools.wraps(fn)
    def run(*args, **kwargs):
        bound = sig.bind(*args, **kwargs)
        bound.apply_defaults()
        a = bound.arguments
        label = a.get("name", fn.__name__)
        for e in entries(fn):
            if e.field.type in CHECKED_TYPES and not e.gear:
                a[e.param] = e.field.check(f"{label}.{e.param}", a[e.param])
        return fn(*bound.args, **bound.kwargs)

    return run
