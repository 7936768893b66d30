"""One store for the runs a study writes as it goes: a sweep's cases (:func:`gearmodal.sweep`)
and the fidelity ladder's rungs (:func:`gearmodal.choose_fidelity`).

A store is a directory with a meta file naming its layout (``format``) and the identity of what
it holds (the scene's SHA-256, the metrics...), and entries written whole: a file or a folder is
written under a temporary name and renamed into place, so a run killed at any moment leaves
either the entry or nothing, and a run started again resumes from the entries there. A store of
another layout, or made for something else, is refused by name (:class:`gearmodal.StoreError`),
never mixed.

Meta file: ``{"format": ..., "identity": {...}, ...}`` (the ladder's stores of gearmodal before
this module kept the identity at the top level: still read).
"""

from __future__ import annotations

import json
import os
import shutil
import time
import uuid
from collections.abc import Callable
from pathlib import Path

from .errors import StoreError

#: a temporary entry older than this (s) was left by a writer that was killed (an entry is
#: written in milliseconds)
STALE_S = 600.0


def write_json(path: Path, data: dict) -> None:
    """Write ``data`` as JSON to ``path`` whole or not at all (a temporary file renamed)."""
    path = Path(path)
    tmp = path.with_name(f".{path.stem}-{uuid.uuid4().hex[:8]}.json")
    tmp.write_text(json.dumps(data, indent=1, default=repr))
    os.replace(tmp, path)


class Store:
    """A store directory (module docstring).

    Parameters
    ----------
    directory : the store (made if missing).
    meta : the meta file's name (``"sweep.json"``).
    format : this layout's tag; a store of another one is refused.
    identity : what the store holds; a store made for another is refused, naming the entry
        that differs.
    compare : the identity entries compared (default: all); an entry the stored identity
        lacks is not compared (a store from before it was recorded).
    older : earlier layouts' tags this one still reads (the meta file is rewritten with
        ``format`` by :meth:`write_meta`).
    labels : how to name an entry in the refusal (default: its key, underscores as spaces).

    ``previous`` is the meta file found (``{}`` for a new store).
    """

    def __init__(self, directory, *, meta: str, format: str, identity: dict,
                 compare: tuple[str, ...] | None = None, labels: dict | None = None,
                 older: tuple[str, ...] = ()):
        self.dir = Path(directory)
        self.dir.mkdir(parents=True, exist_ok=True)
        self.meta_path = self.dir / meta
        self.format = format
        self.older = tuple(older)
        self.identity = dict(identity)
        self.previous = self._read_meta()
        if self.previous:
            old = self.previous.get("identity")
            if old is None:  # the identity at the top level (an earlier layout)
                old = {k: v for k, v in self.previous.items() if k != "format"}
            labels = labels or {}
            for key in compare or tuple(self.identity):
                if key in old and old[key] != self.identity.get(key):
                    what = labels.get(key, key.replace("_", " "))
                    raise StoreError("store", f"= {str(self.dir)!r} was made for a different "
                                     f"{what} ({key}: {old[key]!r}, not "
                                     f"{self.identity.get(key)!r}): use a new store or "
                                     "delete it")

    def _read_meta(self) -> dict:
        if not self.meta_path.exists():
            return {}
        try:
            old = json.loads(self.meta_path.read_text())
            if not isinstance(old, dict):
                raise ValueError(f"a {type(old).__name__}, not a table")
        except (OSError, ValueError) as e:  # damaged (it is written whole): unknown contents
            raise StoreError("store", f"= {str(self.dir)!r}: {self.meta_path.name} is "
                             f"unreadable ({str(e)[:120]}), so what its entries belong to is "
                             "unknown: use a new store or delete it") from None
        if old.get("format") != self.format and old.get("format") not in self.older:
            raise StoreError("store", f"= {str(self.dir)!r} was written by an older gearmodal "
                             f"(format {old.get('format', 1)!r}, this one reads "
                             f"{self.format!r}): use a new store or delete it")
        return old

    def write_meta(self, **extra) -> None:
        """Write the meta file: the format, the identity and ``extra`` entries."""
        write_json(self.meta_path, {"format": self.format, "identity": self.identity, **extra})

    def write_json(self, name: str, data: dict) -> None:
        """Write the entry ``name`` (a JSON file) whole."""
        write_json(self.dir / name, data)

    def read_json(self, name: str) -> dict | None:
        """The JSON entry ``name``, or None when there is none."""
        path = self.dir / name
        return json.loads(path.read_text()) if path.exists() else None

    def put(self, name: str, fill: Callable[[Path], None], *, replace: bool = True) -> None:
        """Write the folder entry ``name`` whole: ``fill(tmp)`` writes it into a temporary
        folder, renamed into place when complete. An entry already there is replaced (moved
        aside under a temporary name first, so that a reader finds the old entry or the new
        one, never a half-deleted one), or (``replace=False``: another run finished the same
        entry first) kept. Two writers of one entry at once: one's entry stays whole."""
        final = self.dir / name
        final.parent.mkdir(parents=True, exist_ok=True)
        tag = uuid.uuid4().hex[:8]
        tmp = final.with_name(f".tmp-{final.name}-{tag}")
        old = final.with_name(f".tmp-{final.name}-old-{tag}")
        try:
            fill(tmp)
            if replace:
                try:
                    os.rename(final, old)
                except FileNotFoundError:
                    pass
            try:
                os.rename(tmp, final)
            except OSError:
                if not final.exists():
                    raise
                # another writer put the same entry there first: keep its whole copy
        finally:
            for leftover in (tmp, old):
                if leftover.exists():
                    shutil.rmtree(leftover, ignore_errors=True)

    def drop(self, name: str) -> None:
        """Remove the entry ``name`` (a folder or a file), if there."""
        path = self.dir / name
        if path.is_dir():
            shutil.rmtree(path, ignore_errors=True)
        else:
            path.unlink(missing_ok=True)

    def clean(self, sub: str = "") -> None:
        """Remove the temporary entries a killed writer left (in ``sub``), so that the store
        holds only whole entries (one a running writer still fills is younger than
        :data:`STALE_S`)."""
        now = time.time()
        for d in (self.dir / sub).glob(".tmp-*"):
            try:
                if now - d.stat().st_mtime > STALE_S:
                    shutil.rmtree(d, ignore_errors=True)
            except OSError:
                pass
