"""Shaft loads from the output files of aeroelastic codes (paper section 5).

- HAWC2 (``.sel`` + ``.dat``, binary or ASCII) is read with DTU's Wind Energy Toolbox
  (``wetb.hawc2.Hawc2io.ReadHawc2``), the maintained reader of the code's own group; install
  it with ``pip install gearmodal[hawc2]``.
- OpenFAST (``.out`` text, ``.outb`` binary) is read here, following the format OpenFAST
  writes (``WrBinFAST`` in NWTC_IO: a file id, the channel count and length, per-channel scale
  and offset of the 16-bit packed data, names and units padded to the channel-name length).
  NREL's ``openfast-io`` (5.x, on PyPI) now reads both too, to the same numbers; gearmodal
  keeps its own reader because it is about 6x faster on these files, needs no further
  dependency, and refuses a binary file named ``.out`` with a message where ``openfast-io``
  fails inside its parser.

Both give a :class:`pandas.DataFrame` indexed by time (s) with the file's channel names as
columns and the units in ``df.attrs["units"]``. :func:`shaft_loads` maps channels to
gearmodal load names by name, converting units to SI.
"""

from __future__ import annotations

import re
import struct
from pathlib import Path

import numpy as np
import pandas as pd

from ..errors import ModelError

__all__ = ["OPENFAST_SHAFT", "read_hawc2", "read_loads", "read_openfast", "shaft_loads",
           "si_factor"]

#: OpenFAST ElastoDyn channels of the low-speed shaft (rotating axes at the shaft tip / hub)
#: -> a description; a typical mapping to gearmodal loads is given in the README.
OPENFAST_SHAFT = {
    "RotTorq": "rotor torque (kN m)",
    "RotThrust": "rotor thrust (kN)",
    "LSShftFys": "shaft shear force, nonrotating y (kN)",
    "LSShftFzs": "shaft shear force, nonrotating z (kN)",
    "LSSTipMys": "shaft tip bending moment, nonrotating y (kN m)",
    "LSSTipMzs": "shaft tip bending moment, nonrotating z (kN m)",
}

_UNITS = {"": 1.0, "-": 1.0, "n": 1.0, "nm": 1.0, "n-m": 1.0, "n.m": 1.0, "kn": 1e3,
          "knm": 1e3, "kn-m": 1e3, "kn.m": 1e3, "mn": 1e6, "mnm": 1e6, "mn-m": 1e6,
          "mn.m": 1e6, "s": 1.0, "sec": 1.0, "m": 1.0, "rad": 1.0, "rad/s": 1.0,
          "deg": np.pi / 180, "rpm": 2 * np.pi / 60, "w": 1.0, "kw": 1e3, "mw": 1e6}


def si_factor(unit: str) -> float:
    """Factor from ``unit`` (``kN``, ``kN-m``, ``kNm``, ``deg``, ``rpm``...) to SI."""
    key = unit.strip().strip("()[]").replace(" ", "").lower()
    if key not in _UNITS:
        raise ModelError("unit", f"= {unit!r}: unknown; known: "
                         + ", ".join(sorted(k for k in _UNITS if k)))
    return _UNITS[key]


# -- HAWC2 --------------------------------------------------------------------------------------
def read_hawc2(path) -> pd.DataFrame:
    """Read a HAWC2 result (``name.sel`` with ``name.dat``, binary or ASCII) with wetb.

    Columns are the channel names of the ``.sel`` file (made unique by appending the channel
    number where a name repeats); ``attrs["units"]`` and ``attrs["descriptions"]`` by column.
    The index is the ``Time`` channel when there is one, else HAWC2's sample times."""
    try:
        from wetb.hawc2.Hawc2io import ReadHawc2
    except ImportError as err:  # pragma: no cover - depends on the environment
        raise ModelError("hawc2", "reading HAWC2 files needs the Wind Energy Toolbox: "
                         "pip install 'gearmodal[hawc2]'") from err
    p = Path(path)
    base = p.with_suffix("") if p.suffix.lower() in (".sel", ".dat") else p
    if not Path(str(base) + ".sel").is_file():
        raise ModelError("path", f"= {str(path)!r}: no HAWC2 .sel file {base}.sel")
    reader = ReadHawc2(str(base))
    data = np.asarray(reader.ReadAll(), dtype=float)
    names, units, desc = reader.ChInfo
    cols = _unique(names)
    df = pd.DataFrame(data, columns=cols)
    time_col = next((c for c, n in zip(cols, names, strict=True) if n.lower() == "time"), None)
    if time_col is not None:
        df.index = pd.Index(df.pop(time_col).to_numpy(), name="time")
    else:
        df.index = pd.Index(np.asarray(reader.t, dtype=float), name="time")
    df.attrs["units"] = {c: u for c, u, n in zip(cols, units, names, strict=True)
                         if c in df.columns}
    df.attrs["descriptions"] = {c: d for c, d in zip(cols, desc, strict=True)
                                if c in df.columns}
    df.attrs["format"] = reader.FileFormat
    return df


# -- OpenFAST -----------------------------------------------------------------------------------
def read_openfast(path) -> pd.DataFrame:
    """Read an OpenFAST output file: ``.out`` (text) or ``.outb`` (binary)."""
    p = Path(path)
    if not p.is_file():
        raise ModelError("path", f"= {str(path)!r}: no such file")
    if p.suffix.lower() == ".outb":
        return _read_outb(p)
    return _read_out(p)


def _read_out(p: Path) -> pd.DataFrame:
    lines = p.read_text(errors="replace").splitlines()
    for i, line in enumerate(lines[:-1]):
        tok = line.split()
        if tok and tok[0].lower() == "time" and lines[i + 1].strip().startswith("("):
            names = tok
            units = re.findall(r"\(([^)]*)\)", lines[i + 1])
            break
    else:
        raise ModelError("path", f"= {str(p)!r}: no channel header (a line starting with "
                         "'Time' followed by a line of units in parentheses)")
    rows = [r.split() for r in lines[i + 2:] if r.strip()]
    # OpenFAST closes a text output with a line of its own ("This output file was closed
    # ..."): text after the last data row ends the data
    end = len(rows)
    while end and not _numeric(rows[end - 1][0]):
        end -= 1
    rows = rows[:end]
    try:
        data = np.array(rows, dtype=float)
    except ValueError as err:
        raise ModelError("path", f"= {str(p)!r}: non-numeric or ragged data rows") from err
    if data.ndim != 2 or data.shape[1] != len(names):
        raise ModelError("path", f"= {str(p)!r}: {len(names)} channels in the header, rows "
                         f"of {data.shape[1] if data.ndim == 2 else 0} values")
    return _frame(names, units, data)


def _numeric(token: str) -> bool:
    try:
        float(token)
    except ValueError:
        return False
    return True


def _read_outb(p: Path) -> pd.DataFrame:
    raw = p.read_bytes()
    pos = 0

    def take(fmt):
        nonlocal pos
        size = struct.calcsize(fmt)
        if pos + size > len(raw):
            raise ModelError("path", f"= {str(p)!r}: truncated OpenFAST binary file")
        out = struct.unpack_from(fmt, raw, pos)
        pos += size
        return out

    (file_id,) = take("<h")
    if file_id not in (1, 2, 3, 4):
        raise ModelError("path", f"= {str(p)!r}: unknown OpenFAST binary file id {file_id}")
    chan_len = take("<h")[0] if file_id == 4 else 10
    n_ch, n_t = take("<ii")
    if file_id == 1:
        time_scl, time_off = take("<dd")
    else:
        t_first, t_inc = take("<dd")
    if file_id != 3:
        scl = np.array(take(f"<{n_ch}f"))
        off = np.array(take(f"<{n_ch}f"))
    (len_desc,) = take("<i")
    pos += len_desc
    names = [raw[pos + k * chan_len:pos + (k + 1) * chan_len].decode("latin-1").strip()
             for k in range(n_ch + 1)]
    pos += (n_ch + 1) * chan_len
    units = [raw[pos + k * chan_len:pos + (k + 1) * chan_len].decode("latin-1").strip()
             .strip("()") for k in range(n_ch + 1)]
    pos += (n_ch + 1) * chan_len
    if file_id == 1:
        packed_t = np.frombuffer(raw, "<i4", n_t, pos)
        pos += 4 * n_t
        t = (packed_t - time_off) / time_scl
    else:
        t = t_first + t_inc * np.arange(n_t)
    if file_id == 3:
        vals = np.frombuffer(raw, "<f8", n_t * n_ch, pos).reshape(n_t, n_ch)
    else:
        packed = np.frombuffer(raw, "<i2", n_t * n_ch, pos).reshape(n_t, n_ch)
        vals = (packed - off) / scl
    return _frame(names, units, np.column_stack([t, vals]))


def _frame(names, units, data) -> pd.DataFrame:
    cols = _unique(names)
    df = pd.DataFrame(data[:, 1:], index=pd.Index(data[:, 0], name="time"), columns=cols[1:])
    df.attrs["units"] = dict(zip(cols[1:], list(units)[1:], strict=False))
    return df


def _unique(names) -> list[str]:
    seen: dict[str, int] = {}
    out = []
    for k, n in enumerate(names):
        n = str(n).strip()
        out.append(n if n not in seen else f"{n}#{k + 1}")
        seen[n] = k
    return out


# -- any file -> gearmodal loads -----------------------------------------------------------
def read_loads(path, format: str | None = None) -> pd.DataFrame:
    """Read a HAWC2 (``.sel``/``.dat``) or OpenFAST (``.out``/``.outb``) output file; the
    format follows from the extension unless ``format`` is ``"hawc2"`` or ``"openfast"``."""
    p = Path(path)
    fmt = format or ("hawc2" if p.suffix.lower() in (".sel", ".dat") else
                     "openfast" if p.suffix.lower() in (".out", ".outb") else None)
    if fmt == "hawc2":
        return read_hawc2(p)
    if fmt == "openfast":
        return read_openfast(p)
    raise ModelError("format", f"= {format!r} for {str(path)!r}: use 'hawc2' (.sel/.dat) or "
                     "'openfast' (.out/.outb)")


def shaft_loads(data: pd.DataFrame, mapping: dict, *, t_start: float = 0.0) -> dict:
    """Gearmodal loads from aeroelastic channels.

    ``mapping`` maps a gearmodal load name to a channel name, or to ``(channel, factor)`` to
    scale it (e.g. ``-1`` for a sign convention, or a lever arm). Units are converted to SI
    from ``data.attrs["units"]``. Returns ``{load name: pandas.Series}`` indexed by time
    shifted so that ``t_start`` is 0, for :func:`gearmodal.simulate`'s ``loads``.

    A missing channel raises :class:`ModelError` naming it and listing the channels present.
    """
    units = data.attrs.get("units", {})
    out = {}
    for load, spec in mapping.items():
        chan, factor = (spec, 1.0) if isinstance(spec, str) else (spec[0], float(spec[1]))
        if chan not in data.columns:
            low = {c.lower(): c for c in data.columns}
            if chan.lower() in low:
                chan = low[chan.lower()]
            else:
                raise ModelError(f"mapping.{load}", f"= {chan!r}: no such channel; channels: "
                                 + ", ".join(map(str, data.columns)))
        s = data[chan].astype(float) * (factor * si_factor(units.get(chan, "")))
        s = s[s.index >= t_start]
        s.index = pd.Index(np.asarray(s.index, dtype=float) - t_start, name="time")
        out[load] = s
    return out
