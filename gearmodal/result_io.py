"""Writing and reading back what results save: a versioned header per result directory, and
tables in Parquet (the default: columnar, compressed, written in row groups as a run goes and
read back lazily) or exact CSV (when asked for).

Each result's ``save(dir)`` writes ``dir/result.json`` with ``{"format": <kind>, "version": n}``
besides its tables; ``load(dir)`` refuses a directory without it, of another kind, or of another
version (an older gearmodal wrote it), naming the directory. Parquet keeps float64 as it is;
floats in CSV are written in their shortest exact form by pandas and read back with the
round-trip parser (pandas 3's default), so a result loads to the same numbers either way.

A long run streams its output rows (:class:`TableWriter`: a row group every
:data:`GROUP_ROWS` rows, so a run's memory does not grow with its duration); figures of a stored
table read a decimated view (:func:`decimated`) that keeps every bucket's extremes.
"""

from __future__ import annotations

import functools
import hashlib
import json
import os
import shutil
import uuid
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pandas as pd

from .errors import GearmodalError, ModelError

__all__ = ["FORMATS", "VIEW_ROWS", "TableWriter", "decimated", "read_csv", "read_header",
           "read_table", "table_chunks", "table_path", "thin_frame", "write_header",
           "write_table"]

HEADER = "result.json"
#: pandas 3 reads floats exactly by default and deprecates ``float_precision``
_PANDAS_3 = int(pd.__version__.split(".")[0]) >= 3
#: the formats results save their tables in
FORMATS = ("parquet", "csv")
#: rows per Parquet row group of a streamed table (a group of a 36-column table: 1.4 MB)
GROUP_ROWS = 5_000
#: row groups per part file of a long streamed table (:class:`TableWriter`): 100 s of a run
#: at 1 ms
PART_GROUPS = 20
#: rows of a figure's view of a long table (:func:`decimated`): about a thousand buckets of
#: a few columns, a bucket per pixel of a figure 9 inches wide at 130 dpi
VIEW_ROWS = 8_000
#: Parquet settings: zstd, floats byte-stream split (3.5x smaller than CSV on the turbine
#: run's q, v and forces; float64 noise bits bound it), no dictionaries for floats
_PARQUET = {"compression": "zstd", "write_page_checksum": True}
#: readers verify every page's CRC: a damaged file is refused naming it, never read as data
#: (256 garbage bytes in a stored forces table changed 33 values silently)
_VERIFY = {"page_checksum_verification": True}


#: bytes read at a time for a checksum (a long table is never read whole)
DIGEST_BLOCK = 8 * 2**20


def sha256_of(path) -> str:
    """The SHA-256 of a file, or of a folder of Parquet parts (its parts' bytes in order)."""
    h = hashlib.sha256()
    p = Path(path)
    for f in (parquet_parts(p) if p.is_dir() else [p]):
        with open(f, "rb") as fh:
            while block := fh.read(DIGEST_BLOCK):
                h.update(block)
    return h.hexdigest()


def digests(directory, names: list[str]) -> dict[str, str]:
    """``{file name: SHA-256}`` of the files (a table's file or folder) of ``directory`` among
    ``names``, those that exist."""
    d = Path(directory)
    return {n: sha256_of(d / n) for n in names if (d / n).exists()}


def verify_digests(directory, sums: dict[str, str]) -> None:
    """Every file of ``sums`` (:func:`digests`) present in ``directory`` with its SHA-256; a
    missing, changed or damaged one is a :class:`ModelError` naming it."""
    d = Path(directory)
    for name, want in sums.items():
        p = d / name
        if not p.exists():
            raise ModelError("directory", f"= {str(d)!r}: {name} is missing (it was saved)")
        if sha256_of(p) != want:
            raise ModelError("directory", f"= {str(d)!r}: {name} was damaged or changed "
                             "after it was saved (its SHA-256 differs from the saved one): "
                             "restore it or run again")


def refuses_damage(load):
    """For a result's ``load(cls, directory)``: a saved file edited or damaged so that reading
    it fails (a field of the wrong type in ``result.json``) is a :class:`ModelError` naming
    the directory, not the TypeError or AttributeError of whatever tripped on it."""

    @functools.wraps(load)
    def wrapper(cls, directory, *args, **kwargs):
        try:
            return load(cls, directory, *args, **kwargs)
        except GearmodalError:
            raise
        except (TypeError, AttributeError, ValueError, KeyError, IndexError,
                OverflowError) as e:
            raise ModelError("directory", f"= {str(directory)!r}: its saved result is damaged "
                             f"({type(e).__name__}: {e}); save it again") from None

    return wrapper


@contextmanager
def replacing(directory, markers: tuple[str, ...] = (HEADER,)):
    """The directory a result is written to: ``directory`` itself, unless it holds a saved
    result already (one of ``markers``), which then stays readable until the new one is
    complete: the new one is written beside it and swapped in by two renames (a save that
    fails half-way, a full disk, leaves the earlier result as it was)."""
    d = Path(directory)
    if not (d.is_dir() and any((d / m).exists() for m in markers)):
        d.mkdir(parents=True, exist_ok=True)
        yield d
        return
    tag = uuid.uuid4().hex[:8]
    tmp = d.parent / f".{d.name}.saving-{tag}"
    tmp.mkdir()
    try:
        yield tmp
        old = d.parent / f".{d.name}.old-{tag}"
        os.rename(d, old)
        os.rename(tmp, d)
        shutil.rmtree(old, ignore_errors=True)
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)


def write_header(directory: Path, kind: str, version: int, header: str = HEADER,
                 **data) -> None:
    """Write the directory's header (``header``, default ``result.json``): the result kind,
    its layout version and ``data`` (JSON-able), with the digest of its own fields
    (``header_sha256``: :func:`read_header` refuses a header edited after the save)."""
    head = json.loads(json.dumps({"format": kind, "version": version, **data}, default=str))
    head["header_sha256"] = _header_digest(head)
    (Path(directory) / header).write_text(json.dumps(head, indent=1))


def _header_digest(head: dict) -> str:
    """SHA-256 of a header's fields but its own digest, as canonical JSON."""
    body = {k: v for k, v in head.items() if k != "header_sha256"}
    return hashlib.sha256(json.dumps(body, sort_keys=True).encode()).hexdigest()


def file_in_the_way(path) -> Path | None:
    """The file at ``path`` or at one of its parent folders, where a folder would have to be
    made to write ``path`` (``None``: nothing in the way)."""
    for p in (Path(path), *Path(path).parents):
        if p.exists() and not p.is_dir():
            return p
    return None


def read_header(directory, kind: str, version: int | tuple[int, ...],
                header: str = HEADER) -> dict:
    """The header (``header``) of a result directory written by ``kind``'s ``save`` at
    ``version`` (or one of several), its fields as saved (``header_sha256``);
    :class:`ModelError` naming the directory otherwise."""
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
    versions = version if isinstance(version, tuple) else (version,)
    got = head.get("version")
    if got not in versions:
        who = "a newer" if isinstance(got, int) and got > max(versions) else "an older"
        raise ModelError("directory", f"= {str(d)!r} was saved in layout version "
                         f"{got!r} ({who} gearmodal); this one reads "
                         f"{', '.join(map(str, versions))}: run it again")
    if "header_sha256" in head and head["header_sha256"] != _header_digest(head):
        raise ModelError("directory", f"= {str(d)!r}: {header} was changed or damaged after it "
                         "was saved (its digest does not match): save the result again")
    return head


def read_csv(path: Path, **kw) -> pd.DataFrame:
    """A CSV the results wrote, floats exact (pandas' round-trip parser); a missing file is a
    :class:`ModelError` naming it."""
    p = Path(path)
    if not p.is_file():
        raise ModelError("directory", f"= {str(p.parent)!r}: {p.name} is missing")
    if _PANDAS_3:  # its default parser is exact (float_precision is deprecated)
        return pd.read_csv(p, **kw)
    return pd.read_csv(p, float_precision="round_trip", **kw)


def _check_format(fmt: str) -> None:
    if fmt not in FORMATS:
        raise ModelError("format", f"= {fmt!r}: must be one of {', '.join(map(repr, FORMATS))}")


def _arrow_array(values):
    """An Arrow array of a numpy column: floats as they are (NaN stays NaN, not null), text
    as strings."""
    import pyarrow as pa

    v = np.asarray(values)
    if v.dtype == object or v.dtype.kind in "US":
        return pa.array(v.astype(str).astype(object), type=pa.string())
    return pa.array(v)


def _arrow_table(df: pd.DataFrame, index_label: str | None):
    import pyarrow as pa

    cols, names = [], []
    series = [(str(c), df[c]) for c in df.columns]
    if index_label is not None:
        series.insert(0, (index_label, df.index.to_series()))
    for name, col in series:
        if col.dtype == object or pd.api.types.is_string_dtype(col.dtype):
            cols.append(_arrow_array(col.astype(str).to_numpy(dtype=object)))
        else:
            cols.append(_arrow_array(col.to_numpy()))
        names.append(name)
    return pa.Table.from_arrays(cols, names=names)


def _parquet_options(table) -> dict:
    import pyarrow as pa

    floats = [f.name for f in table.schema if pa.types.is_floating(f.type)]
    return {**_PARQUET, "use_dictionary": [f.name for f in table.schema
                                           if f.name not in floats],
            "use_byte_stream_split": floats or False}


def write_table(df: pd.DataFrame, directory, name: str, fmt: str = "parquet",
                index_label: str | None = "time") -> Path:
    """Write ``df`` as ``directory/name.parquet`` (or ``.csv``) with its index as the column
    ``index_label`` (``None``: no index); returns the path."""
    _check_format(fmt)
    d = Path(directory)
    if fmt == "csv":
        p = d / f"{name}.csv"
        if index_label is None:
            df.to_csv(p, index=False)
        else:
            df.to_csv(p, index_label=index_label)
        return p
    import pyarrow.parquet as pq

    p = d / f"{name}.parquet"
    remove_table(p)  # a folder of parts a streamed run left
    table = _arrow_table(df, index_label)
    pq.write_table(table, p, row_group_size=GROUP_ROWS, **_parquet_options(table))
    return p


def table_path(directory, name: str) -> Path:
    """``directory/name.parquet`` (a file, or a folder of parts: a long streamed table) or,
    where only that exists, ``name.csv``; a missing table is a :class:`ModelError` naming
    it."""
    d = Path(directory)
    for ext in ("parquet", "csv"):
        p = d / f"{name}.{ext}"
        if p.exists():
            return p
    raise ModelError("directory", f"= {str(d)!r}: {name}.parquet (or {name}.csv) is missing")


def read_table(directory, name: str, index_col: str | None = "time",
               columns: list[str] | None = None, **csv_kw) -> pd.DataFrame:
    """The table ``name`` of a result directory, Parquet or CSV (floats exact), indexed by
    ``index_col``; ``columns``: only these (besides the index)."""
    p = table_path(directory, name)
    if p.suffix == ".csv":
        try:
            df = read_csv(p, index_col=index_col, **csv_kw)
        except (ValueError, pd.errors.ParserError) as e:  # (EmptyDataError is a ValueError)
            raise ModelError("directory", f"= {str(p.parent)!r}: {p.name} is unreadable "
                             f"({str(e).splitlines()[0][:200]})") from None
        return df if columns is None else df[columns]
    import pyarrow.parquet as pq

    try:
        want = None if columns is None else ([index_col] if index_col else []) + list(columns)
        parts = [pq.read_table(f, columns=want, **_VERIFY).to_pandas()
                 for f in parquet_parts(p)]
        df = pd.concat(parts, ignore_index=True) if len(parts) > 1 else parts[0]
    except (OSError, ValueError) as e:  # pyarrow's errors derive from these
        raise ModelError("directory", f"= {str(p.parent)!r}: {p.name} is unreadable "
                         f"({str(e).splitlines()[0][:200]})") from None
    if index_col is not None:
        df = df.set_index(index_col)
    return df


@contextmanager
def _readable(path: Path):
    """Re-raise a Parquet reader's error (a damaged or truncated file, a page whose checksum
    fails) as a :class:`ModelError` naming the file."""
    try:
        yield
    except (OSError, ValueError) as e:  # pyarrow's errors derive from these
        raise ModelError("directory", f"= {str(Path(path).parent)!r}: {Path(path).name} is "
                         f"unreadable ({str(e).splitlines()[0][:200]})") from None


def parquet_parts(path: Path) -> list[Path]:
    """The files of a Parquet table in row order: the file itself, or a folder's parts."""
    p = Path(path)
    return sorted(p.glob("part-*.parquet")) if p.is_dir() else [p]


def copy_table(src: Path, directory) -> Path:
    """Copy a stored table (a file or a folder of parts) into ``directory``."""
    dst = Path(directory) / src.name
    if dst.exists() and dst.is_dir():
        shutil.rmtree(dst)
    if src.is_dir():
        shutil.copytree(src, dst)
    else:
        shutil.copyfile(src, dst)
    return dst


def remove_table(path: Path) -> None:
    """Remove a stored table (a file or a folder of parts) if it is there."""
    p = Path(path)
    if p.is_dir():
        shutil.rmtree(p)
    elif p.exists():
        p.unlink()


def table_chunks(directory, name: str, columns: list[str] | None = None,
                 index_col: str = "time") -> Iterator[pd.DataFrame]:
    """The table ``name`` one Parquet row group at a time (a CSV table: whole), each chunk
    indexed by ``index_col``: a pass over a long run's rows in constant memory."""
    p = table_path(directory, name)
    if p.suffix == ".csv":
        yield read_table(directory, name, index_col=index_col, columns=columns)
        return
    import pyarrow.parquet as pq

    want = None if columns is None else [index_col, *columns]
    for part in parquet_parts(p):
        with _readable(part):
            f = pq.ParquetFile(part, **_VERIFY)
        for g in range(f.num_row_groups):
            with _readable(part):
                chunk = f.read_row_group(g, columns=want)
            yield chunk.to_pandas().set_index(index_col)


def decimated(directory, name: str, columns: list[str], max_rows: int | None = VIEW_ROWS,
              index_col: str = "time") -> pd.DataFrame:
    """A view of the stored table ``name`` for figures, at most about ``max_rows`` rows: the
    rows are cut into buckets and each keeps the rows where one of ``columns`` is largest or
    smallest, so no peak or dip of a plotted column is lost. Read a row group at a time,
    straight into arrays. ``max_rows=None``: every row of ``columns``."""
    columns = list(columns)
    p = table_path(directory, name)
    if p.suffix == ".csv":
        full = read_table(directory, name, index_col=index_col, columns=columns)
        groups = [(full.index.to_numpy(dtype=float), full.to_numpy(dtype=float))]
        n = len(full)
    else:
        import pyarrow.parquet as pq

        parts = parquet_parts(p)
        with _readable(p):
            files = [pq.ParquetFile(f, **_VERIFY) for f in parts]
        n = sum(f.metadata.num_rows for f in files)

        def read():
            for part, f in zip(parts, files, strict=True):
                for g in range(f.num_row_groups):
                    with _readable(part):
                        tb = f.read_row_group(g, columns=[index_col, *columns])
                    yield (tb.column(0).to_numpy(),
                           np.column_stack([tb.column(j + 1).to_numpy().astype(float)
                                            for j in range(len(columns))])
                           if columns else np.empty((tb.num_rows, 0)))

        groups = read()
    return _thin(groups, n, columns, max_rows, index_col)


def thin_frame(df: pd.DataFrame, max_rows: int = VIEW_ROWS) -> pd.DataFrame:
    """:func:`decimated` of a table in memory (float columns, indexed by time): the same
    buckets, each keeping its extremes."""
    t = df.index.to_numpy(dtype=float)
    V = df.to_numpy(dtype=float)
    groups = ((t[a:a + GROUP_ROWS], V[a:a + GROUP_ROWS]) for a in range(0, len(t), GROUP_ROWS))
    return _thin(groups, len(t), [str(c) for c in df.columns], max_rows,
                 df.index.name or "time")


def _thin(groups, n: int, columns: list[str], max_rows: int | None,
          index_col: str) -> pd.DataFrame:
    """Rows of ``groups`` (``(t, V)`` chunks of ``n`` rows in all) in buckets sized for about
    ``max_rows`` rows, each keeping the rows where a column is largest or smallest."""
    per = 1 if max_rows is None else max(1, int(np.ceil(n * 2 * max(len(columns), 1)
                                                         / max_rows)))
    ts, vs = [], []
    for t, V in groups:
        if per > 1 and len(t) and V.shape[1]:
            nb = -(-len(t) // per)
            pad = nb * per - len(t)
            hi = np.pad(np.where(np.isnan(V), -np.inf, V), ((0, pad), (0, 0)),
                        constant_values=-np.inf).reshape(nb, per, -1)
            lo = np.pad(np.where(np.isnan(V), np.inf, V), ((0, pad), (0, 0)),
                        constant_values=np.inf).reshape(nb, per, -1)
            base = (np.arange(nb) * per)[:, None]
            keep = np.unique(np.concatenate([(base + hi.argmax(axis=1)).ravel(),
                                             (base + lo.argmin(axis=1)).ravel(),
                                             [0, len(t) - 1]]))
            keep = keep[keep < len(t)]
            t, V = t[keep], V[keep]
        ts.append(t)
        vs.append(V)
    t = np.concatenate(ts) if ts else np.empty(0)
    V = np.concatenate(vs) if vs else np.empty((0, len(columns)))
    return pd.DataFrame(V, index=pd.Index(t, name=index_col), columns=columns)


class TableWriter:
    """Appends rows to ``directory/name.parquet`` in row groups of :data:`GROUP_ROWS` as a run
    goes (a run's rows are never all in memory). ``columns``: the value columns, after
    ``index_label``; ``dtype``: ``float`` or ``bool`` values, or ``None`` for a frame of mixed
    columns (:meth:`append_frame`). :meth:`close` writes the last group (an empty table still
    gets its file).

    A Parquet writer holds every row group's description until it closes (0.8 kB per column
    and group: 80 MB for an hour of the turbine's rows at 1 ms), so a long table is written
    in parts of :data:`PART_GROUPS` groups, each closed when full: ``name.parquet`` is then a
    folder of ``part-00000.parquet``... in row order (as Spark and Dask write them;
    ``pandas.read_parquet`` reads the folder), a single file when one part holds it all."""

    def __init__(self, directory, name: str, columns: list[str], dtype=float,
                 index_label: str = "time"):
        self.directory = Path(directory)
        self.path = self.directory / f"{name}.parquet"
        self._parts = self.directory / f".{name}.parquet.parts"
        remove_table(self._parts)
        self.columns = [str(c) for c in columns]
        self.index_label = index_label
        self.dtype = dtype
        self._writer = None
        self._n_parts = 0
        self._groups = 0
        self._t: list[np.ndarray] = []
        self._rows: list = []
        self._n = 0
        self.n_rows = 0

    def append(self, t: np.ndarray, values: np.ndarray) -> None:
        """Rows at times ``t`` (m,) with ``values`` (m, columns)."""
        if len(t) == 0:
            return
        self._t.append(np.array(t, dtype=float))
        self._rows.append(np.array(values, dtype=self.dtype))
        self._n += len(t)
        if self._n >= GROUP_ROWS:
            self._flush()

    def append_frame(self, df: pd.DataFrame) -> None:
        """Rows of a frame with the columns given, indexed by ``index_label``'s values."""
        if len(df) == 0:
            return
        self._rows.append(df)
        self._n += len(df)
        if self._n >= GROUP_ROWS:
            self._flush()

    def _table(self):
        import pyarrow as pa

        if self.dtype is None:
            df = pd.concat(self._rows) if self._rows else pd.DataFrame(
                {c: np.empty(0) for c in self.columns},
                index=pd.Index(np.empty(0), name=self.index_label))
            return _arrow_table(df, self.index_label)
        t = np.concatenate(self._t) if self._t else np.empty(0)
        V = np.concatenate(self._rows) if self._rows else np.empty((0, len(self.columns)),
                                                                  dtype=self.dtype)
        return pa.Table.from_arrays([_arrow_array(t)] + [_arrow_array(V[:, j])
                                                         for j in range(V.shape[1])],
                                    names=[self.index_label, *self.columns])

    def _flush(self) -> None:
        import pyarrow.parquet as pq

        if self._n == 0 and self._writer is not None:
            return
        table = self._table()
        if self._writer is None:
            self._parts.mkdir(parents=True, exist_ok=True)
            self._writer = pq.ParquetWriter(
                self._parts / f"part-{self._n_parts:05d}.parquet", table.schema,
                **_parquet_options(table))
            self._n_parts += 1
        try:
            self._writer.write_table(table, row_group_size=max(len(table), 1))
        except BaseException:
            self._abandon()
            raise
        self.n_rows += len(table)
        self._t, self._rows, self._n = [], [], 0
        self._groups += 1
        if self._groups % PART_GROUPS == 0:  # a part full: its descriptions freed
            self._close_writer()

    def _close_writer(self) -> None:
        try:
            self._writer.close()
        except BaseException:
            self._abandon()
            raise
        self._writer = None

    def _abandon(self) -> None:
        """Drop the writer after a failed write (a full disk): closed once, quietly, and
        marked closed, so that its ``__del__`` does not try again and print the error a
        second time ("Exception ignored in ParquetWriter.__del__") after the clean one."""
        w, self._writer = self._writer, None
        if w is None:
            return
        try:
            w.close()
        except Exception:  # the error being raised is the one to report
            pass
        w.is_open = False
        if getattr(w, "file_handle", None) is not None:
            try:
                w.file_handle.close()
            except Exception:
                pass

    def close(self) -> Path:
        """Write what is left and close the table; returns its path."""
        if self._n or self._n_parts == 0:
            self._flush()
        if self._writer is not None:
            self._close_writer()
        remove_table(self.path)
        if self._n_parts == 1:
            (self._parts / "part-00000.parquet").replace(self.path)
            self._parts.rmdir()
        else:
            self._parts.replace(self.path)
        return self.path
