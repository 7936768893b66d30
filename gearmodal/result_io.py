"""Writing and reading back what results save: a versioned header per result directory, and
tables in Parquet (the default: columnar, compressed, written in row groups as a run goes and
read back lazily) or exact CSV (when asked for).

Each result's ``save(dir)`` writes ``dir/result.json`` with ``{"format": <kind>, "version": n}``
besides its tables; ``load(dir)`` refuses a directory without it, of another kind, or of another
version (an older gearmodal wrote it), naming the directory. Parquet keeps float64 as it is;
floats in CSV are written in their shortest exact form by pandas and read back with the
round-trip parser, so a result loads to the same numbers either way.

A long run streams its output rows (:class:`TableWriter`: a row group every
:data:`GROUP_ROWS` rows, so a run's memory does not grow with its duration); figures of a stored
table read a decimated view (:func:`decimated`) that keeps every bucket's extremes.
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pandas as pd

from .errors import ModelError

__all__ = ["FORMATS", "TableWriter", "decimated", "read_csv", "read_header", "read_table",
           "table_chunks", "write_header", "write_table"]

HEADER = "result.json"
#: the formats results save their tables in
FORMATS = ("parquet", "csv")
#: rows per Parquet row group of a streamed table (a group of a 36-column table: 2.9 MB)
GROUP_ROWS = 10_000
#: Parquet settings: zstd, floats byte-stream split (3.5x smaller than CSV on the turbine
#: run's q, v and forces; float64 noise bits bound it), no dictionaries for floats
_PARQUET = {"compression": "zstd"}


def write_header(directory: Path, kind: str, version: int, header: str = HEADER,
                 **data) -> None:
    """Write the directory's header (``header``, default ``result.json``): the result kind,
    its layout version and ``data`` (JSON-able)."""
    (Path(directory) / header).write_text(json.dumps(
        {"format": kind, "version": version, **data}, indent=1, default=str))


def read_header(directory, kind: str, version: int | tuple[int, ...],
                header: str = HEADER) -> dict:
    """The header (``header``) of a result directory written by ``kind``'s ``save`` at
    ``version`` (or one of several); :class:`ModelError` naming the directory otherwise."""
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
    return head


def read_csv(path: Path, **kw) -> pd.DataFrame:
    """A CSV the results wrote, floats exact (pandas' round-trip parser); a missing file is a
    :class:`ModelError` naming it."""
    p = Path(path)
    if not p.is_file():
        raise ModelError("directory", f"= {str(p.parent)!r}: {p.name} is missing")
    return pd.read_csv(p, float_precision="round_trip", **kw)


def _check_format(fmt: str) -> None:
    if fmt not in FORMATS:
        raise ModelError("format", f"= {fmt!r}: must be one of {', '.join(map(repr, FORMATS))}")


def _arrow_table(df: pd.DataFrame, index_label: str | None):
    import pyarrow as pa

    cols, names = [], []
    series = [(str(c), df[c]) for c in df.columns]
    if index_label is not None:
        series.insert(0, (index_label, df.index.to_series()))
    for name, col in series:
        if col.dtype == object or pd.api.types.is_string_dtype(col.dtype):
            cols.append(pa.array(col.astype(str).to_numpy(dtype=object), type=pa.string()))
        else:
            cols.append(pa.array(col.to_numpy(), from_pandas=True))
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
    table = _arrow_table(df, index_label)
    pq.write_table(table, p, row_group_size=GROUP_ROWS, **_parquet_options(table))
    return p


def table_path(directory, name: str) -> Path:
    """``directory/name.parquet`` or, where only that exists, ``name.csv``; a missing table is
    a :class:`ModelError` naming it."""
    d = Path(directory)
    for ext in ("parquet", "csv"):
        p = d / f"{name}.{ext}"
        if p.is_file():
            return p
    raise ModelError("directory", f"= {str(d)!r}: {name}.parquet (or {name}.csv) is missing")


def read_table(directory, name: str, index_col: str | None = "time",
               columns: list[str] | None = None, **csv_kw) -> pd.DataFrame:
    """The table ``name`` of a result directory, Parquet or CSV (floats exact), indexed by
    ``index_col``; ``columns``: only these (besides the index)."""
    p = table_path(directory, name)
    if p.suffix == ".csv":
        df = read_csv(p, index_col=index_col, **csv_kw)
        return df if columns is None else df[columns]
    import pyarrow.parquet as pq

    try:
        want = None if columns is None else ([index_col] if index_col else []) + list(columns)
        df = pq.read_table(p, columns=want).to_pandas()
    except (OSError, ValueError) as e:  # pyarrow's errors derive from these
        raise ModelError("directory", f"= {str(p.parent)!r}: {p.name} is unreadable "
                         f"({str(e).splitlines()[0][:200]})") from None
    if index_col is not None:
        df = df.set_index(index_col)
    return df


def table_chunks(directory, name: str, columns: list[str] | None = None,
                 index_col: str = "time") -> Iterator[pd.DataFrame]:
    """The table ``name`` one Parquet row group at a time (a CSV table: whole), each chunk
    indexed by ``index_col``: a pass over a long run's rows in constant memory."""
    p = table_path(directory, name)
    if p.suffix == ".csv":
        yield read_table(directory, name, index_col=index_col, columns=columns)
        return
    import pyarrow.parquet as pq

    f = pq.ParquetFile(p)
    want = None if columns is None else [index_col, *columns]
    for g in range(f.num_row_groups):
        yield f.read_row_group(g, columns=want).to_pandas().set_index(index_col)


def decimated(directory, name: str, columns: list[str], max_rows: int | None = 20_000,
              index_col: str = "time") -> pd.DataFrame:
    """A view of the stored table ``name`` for figures, at most about ``max_rows`` rows: the
    rows are cut into buckets and each keeps the rows where one of ``columns`` is largest or
    smallest, so no peak or dip of a plotted column is lost. Read a row group at a time.
    ``max_rows=None``: every row of ``columns``."""
    p = table_path(directory, name)
    if max_rows is None:
        n = 0
    elif p.suffix == ".csv":
        n = sum(1 for _ in open(p)) - 1
    else:
        import pyarrow.parquet as pq

        n = pq.ParquetFile(p).metadata.num_rows
    per = 1 if max_rows is None else max(1, int(np.ceil(n * 2 * max(len(columns), 1)
                                                         / max_rows)))
    parts = []
    for chunk in table_chunks(directory, name, columns, index_col):
        if per == 1:
            parts.append(chunk)
            continue
        v = chunk.to_numpy(dtype=float)
        keep = set()
        for a in range(0, len(v), per):
            block = v[a:a + per]
            with np.errstate(invalid="ignore"):
                for j in range(block.shape[1]):
                    col = block[:, j]
                    if np.isnan(col).all():
                        continue
                    keep.update((a + int(np.nanargmax(col)), a + int(np.nanargmin(col))))
        keep.update((0, len(v) - 1))
        parts.append(chunk.iloc[sorted(keep)])
    if not parts:
        return pd.DataFrame(columns=columns)
    return pd.concat(parts)


class TableWriter:
    """Appends rows to ``directory/name.parquet`` in row groups of :data:`GROUP_ROWS` as a run
    goes (a run's rows are never all in memory). ``columns``: the value columns, after
    ``index_label``; ``dtype``: ``float`` or ``bool`` values, or ``None`` for a frame of mixed
    columns (:meth:`append_frame`). :meth:`close` writes the last group (an empty table still
    gets its file)."""

    def __init__(self, directory, name: str, columns: list[str], dtype=float,
                 index_label: str = "time"):
        import pyarrow as pa

        self.path = Path(directory) / f"{name}.parquet"
        self.columns = [str(c) for c in columns]
        self.index_label = index_label
        self.dtype = dtype
        kind = pa.bool_() if dtype is bool else pa.float64()
        self.schema = None if dtype is None else pa.schema(
            [(index_label, pa.float64())] + [(c, kind) for c in self.columns])
        self._writer = None
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

    def _flush(self) -> None:
        import pyarrow as pa
        import pyarrow.parquet as pq

        if self._n == 0 and self._writer is not None:
            return
        if self.dtype is None:
            df = pd.concat(self._rows) if self._rows else pd.DataFrame(columns=self.columns)
            table = _arrow_table(df, self.index_label)
        else:
            t = np.concatenate(self._t) if self._t else np.empty(0)
            V = np.concatenate(self._rows) if self._rows else np.empty((0, len(self.columns)),
                                                                      dtype=self.dtype)
            table = pa.Table.from_arrays([pa.array(t)] + [pa.array(V[:, j])
                                                          for j in range(V.shape[1])],
                                         schema=self.schema)
        if self._writer is None:
            self._writer = pq.ParquetWriter(self.path, table.schema,
                                            **_parquet_options(table))
        self._writer.write_table(table, row_group_size=max(len(table), 1))
        self.n_rows += len(table)
        self._t, self._rows, self._n = [], [], 0

    def close(self) -> Path:
        """Write what is left and close the file; returns its path."""
        self._flush()
        if self._writer is not None:
            self._writer.close()
            self._writer = None
        return self.path
