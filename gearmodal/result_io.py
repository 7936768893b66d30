"""Reading back what results save: a versioned header per result directory and exact CSV.

Each result's ``save(dir)`` writes ``dir/result.json`` with ``{"format": <kind>, "version": n}``
besides its tables; ``load(dir)`` refuses a directory without it, of another kind, or of another
version (an older gearmodal wrote it), naming the directory. Floats in CSV are written in their
shortest exact form by pandas and read back with the round-trip parser, so a result loads to the
same numbers.
"""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd

from .errors import ModelError

__all__ = ["read_csv", "read_header", "write_header"]

HEADER = "result.json"


def write_header(directory: Path, kind: str, version: int, header: str = HEADER,
                 **data) -> None:
    """Write the directory's header (``header``, default ``result.json``): the result kind,
    its layout version and ``data`` (JSON-able)."""
    (Path(directory) / header).write_text(json.dumps(
        {"format": kind, "version": version, **data}, indent=1, default=str))


def read_header(directory, kind: str, version: int, header: str = HEADER) -> dict:
    """The header (``header``) of a result directory written by ``kind``'s ``save`` at
    ``version``; :class:`ModelError` naming the directory otherwise."""
    d = Path(directory)
    if not d.is_dir():
        raise ModelError("directory", f"= {str(d)!r}: no such result directory")
    p = d / header
    if not p.is_file():
        raise ModelError("directory", f"= {str(d)!r}: no {header}; not a saved {kind}, or "
                         "saved by an older gearmodal (run it again)")
    try:
        head = json.loads(p.read_text())
    except (OSError, ValueError) as e:
        raise ModelError("directory", f"= {str(d)!r}: unreadable {header} ({e})") from None
    if head.get("format") != kind:
        raise ModelError("directory", f"= {str(d)!r} holds a {head.get('format')!r}, not a "
                         f"{kind}")
    if head.get("version") != version:
        raise ModelError("directory", f"= {str(d)!r} was saved in layout version "
                         f"{head.get('version')!r} (an older gearmodal); this one reads "
                         f"{version}: run it again")
    return head


def read_csv(path: Path, **kw) -> pd.DataFrame:
    """A CSV the results wrote, floats exact (pandas' round-trip parser); a missing file is a
    :class:`ModelError` naming it."""
    p = Path(path)
    if not p.is_file():
        raise ModelError("directory", f"= {str(p.parent)!r}: {p.name} is missing")
    return pd.read_csv(p, float_precision="round_trip", **kw)
