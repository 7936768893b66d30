"""Fatigue loads engineers design with, from any load history (issue 22, item 1).

- **Rainflow counting** (ASTM E1049) through the maintained ``rainflow`` package (pure Python,
  no compiled parts, the ASTM four-point algorithm with half cycles).
- **Damage-equivalent load** for a Woehler exponent ``m`` at ``n_ref`` cycles (Palmgren-Miner)::

      DEL = (sum_i n_i S_i^m / n_ref)^(1/m)                                              (F1)

  with ``S_i`` the rainflow ranges and ``n_i`` their counts (1/2 for half cycles). Default
  exponents: :data:`WOEHLER` (tooth root 8.7, tooth flank 13.2: the slopes of ISO 6336-2 and -3
  for case-hardened steel in the limited-life range; bearings 10/3, ISO 281's roller bearing
  exponent), each overridable.
- **Load duration distribution** (LDD: time at level) and **load revolution distribution** (LRD:
  revolutions at level; IEC 61400-4, ISO 6336-6), from samples on a time grid::

      LDD_k = sum_{t_j in bin k} dt_j,     LRD_k = sum_{t_j in bin k} |n_j| dt_j / 60        (F2)

  (``dt_j`` the time a sample stands for, ``n_j`` the shaft speed in rpm).
- **Basic rating life** of a bearing (ISO 281), from the equivalent dynamic load of a varying
  load over revolutions::

      P_eq = (sum_k N_k P_k^p / sum_k N_k)^(1/p),   L10 = (C / P_eq)^p  10^6 revolutions,
      L10h = L10 / (60 n_mean)                                                          (F3)
"""

from __future__ import annotations

import itertools
import math

import numba
import numpy as np
import pandas as pd

from .errors import ModelError
from .levelsweep import LevelSweep, Unsorted

#: default Woehler exponents (F1)
WOEHLER = {"tooth_root": 8.7, "tooth_flank": 13.2, "bearing": 10.0 / 3.0}
#: default reference number of cycles of a DEL (F1)
N_REF = 1e7
#: the exponents of the exact load integrals ``int F^p dN`` of a planet bearing's radial force
#: over the input's revolutions ``N`` (ISO 281: 3 for ball, 10/3 for roller bearings), kept per
#: peak bin by the exact method, and their columns in
#: :attr:`gearmodal.SimulationResult.peak_bins` (N^p); ``input_revolutions`` beside them
LOAD_INTEGRALS = {3.0: "int_F3_dN", 10.0 / 3.0: "int_F10_3_dN"}


def _series(name: str, values) -> np.ndarray:
    x = np.asarray(values, dtype=float).ravel()
    if x.size < 2 or not np.all(np.isfinite(x)):
        raise ModelError(name, "needs at least two finite values")
    return x


def _reversals(x: np.ndarray) -> np.ndarray:
    """The turning points of ``x`` (its ends and every local extremum; a plateau counts
    once): all the rainflow count reads, so that the counting's Python loop sees a few
    hundred points instead of every sample."""
    x = x[np.concatenate([[True], np.diff(x) != 0])]
    if x.size < 3:
        return x
    d = np.diff(x)
    turn = np.concatenate([[True], d[1:] * d[:-1] < 0, [True]])
    return x[turn]


def rainflow_cycles(load) -> pd.DataFrame:
    """Rainflow cycles of ``load`` (a sequence or Series): ``range``, ``mean``, ``count`` (1
    for a full cycle, 0.5 for a half cycle), one row per cycle, in the order counted (ASTM
    E1049-85 5.4.4, as the ``rainflow`` package counts them; tests/test_fatigue.py holds the
    two equal)."""
    rng, mean, count = _count(_reversals(_series("load", load)))
    return pd.DataFrame({"range": rng, "mean": mean, "count": count})


@numba.njit(cache=True)
def _count(x):
    """Three-point rainflow counting of the turning points ``x`` (ASTM E1049-85 5.4.4, the
    ``rainflow`` package's ``extract_cycles`` step by step): the points not yet counted are
    ``x[stack[lo:hi]]``."""
    n = x.shape[0]
    stack = np.empty(n, dtype=np.int64)
    rng = np.empty(n)
    mean = np.empty(n)
    count = np.empty(n)
    m = 0
    lo = hi = 0
    for i in range(n):
        stack[hi] = i
        hi += 1
        while hi - lo >= 3:
            x1, x2, x3 = x[stack[hi - 3]], x[stack[hi - 2]], x[stack[hi - 1]]
            X = abs(x3 - x2)
            Y = abs(x2 - x1)
            if X < Y:
                break
            if hi - lo == 3:  # Y holds the starting point: a half cycle, the start dropped
                rng[m], mean[m], count[m] = abs(x1 - x2), 0.5 * (x1 + x2), 0.5
                lo += 1
            else:  # a full cycle: the peak and valley of Y dropped
                rng[m], mean[m], count[m] = abs(x1 - x2), 0.5 * (x1 + x2), 1.0
                stack[hi - 3] = stack[hi - 1]
                hi -= 2
            m += 1
    while hi - lo > 1:  # the rest as half cycles
        x1, x2 = x[stack[lo]], x[stack[lo + 1]]
        rng[m], mean[m], count[m] = abs(x1 - x2), 0.5 * (x1 + x2), 0.5
        lo += 1
        m += 1
    return rng[:m], mean[:m], count[:m]


@numba.njit(cache=True)
def _count_into(x, stack, hi, lo_out, ms, sums):
    """:func:`_count`'s loop for a stream: the turning points ``x`` onto the residue
    ``stack[:hi]`` (values), each cycle's ``count * range^m`` added to ``sums`` for every
    exponent in ``ms`` (full cycles only: the residue's half cycles are added at the end).
    Returns the new height. A residue of the three-point count never needs more than the
    points not yet closed, which stay few (``stack`` grows by the caller when full)."""
    for i in range(x.shape[0]):
        stack[hi] = x[i]
        hi += 1
        while hi - lo_out[0] >= 3:
            x1, x2, x3 = stack[hi - 3], stack[hi - 2], stack[hi - 1]
            X = abs(x3 - x2)
            Y = abs(x2 - x1)
            if X < Y:
                break
            c = 1.0
            if hi - lo_out[0] == 3:  # Y holds the starting point: a half cycle
                c = 0.5
                lo_out[0] += 1
            else:  # a full cycle: the peak and valley of Y dropped
                stack[hi - 3] = stack[hi - 1]
                hi -= 2
            for j in range(ms.shape[0]):
                sums[j] += c * Y ** ms[j]
    return hi


class RainflowStream:
    """Rainflow counting (ASTM E1049-85 5.4.4, as :func:`rainflow_cycles`) of a load that
    comes in chunks, in constant memory: the turning points are found across the chunks'
    joins, only the residue (the points not yet closed) is kept, and each cycle adds
    ``count * range^m`` to a sum per Woehler exponent. :meth:`damage_equivalent_load` is
    then (F1) of the whole load, as :func:`damage_equivalent_load` gives it (the same cycles
    in the same order; the sums added in order instead of pairwise: rounding)."""

    def __init__(self, exponents):
        self.ms = np.array([float(m) for m in exponents])
        for m in self.ms:
            if not 1.0 <= m <= 50.0:
                raise ModelError("m", f"= {m!r}: a Woehler exponent from 1 to 50")
        self.sums = np.zeros(len(self.ms))
        self.stack = np.empty(64)
        self.hi = 0
        self.lo = np.zeros(1, dtype=np.int64)
        self.prev = None  # the last point, not yet known to be a turning point
        self.dir = 0.0
        self.n = 0
        self.closed = False

    def feed(self, load) -> None:
        """The next chunk of the load (finite values, in time order)."""
        x = np.asarray(load, dtype=float).ravel()
        if x.size == 0:
            return
        if not np.all(np.isfinite(x)):
            raise ModelError("load", "needs finite values")
        self.n += x.size
        if self.prev is not None:
            x = np.concatenate([[self.prev], x])
        x = x[np.concatenate([[True], np.diff(x) != 0])]  # a plateau counts once
        if x.size < 2:
            self.prev = float(x[0])
            return
        d = np.sign(np.diff(x))
        # the load's start (no direction yet) and a change of direction are turning points
        first = self.dir == 0.0 or d[0] != self.dir
        turn = np.concatenate([[first], d[1:] * d[:-1] < 0])
        self._push(x[:-1][turn])
        self.prev, self.dir = float(x[-1]), float(d[-1])

    def _push(self, pts: np.ndarray) -> None:
        need = self.hi + pts.size
        if need > self.stack.size:
            # the closed bottom entries are dropped, the stack grown if still short
            keep = self.stack[self.lo[0]:self.hi].copy()
            self.hi -= int(self.lo[0])
            self.lo[0] = 0
            size = max(self.stack.size, 2 * (self.hi + pts.size))
            self.stack = np.empty(size)
            self.stack[:self.hi] = keep
        self.hi = _count_into(pts, self.stack, self.hi, self.lo, self.ms, self.sums)

    def close(self) -> None:
        """The load's end: its last point, and the residue counted as half cycles."""
        if self.closed:
            return
        if self.n < 2:
            raise ModelError("load", "needs at least two finite values")
        self._push(np.array([self.prev]))
        r = self.stack[self.lo[0]:self.hi]
        for j, m in enumerate(self.ms):
            self.sums[j] += float(np.sum(0.5 * np.abs(np.diff(r)) ** m))
        self.closed = True

    def damage_equivalent_load(self, m: float, n_ref: float = N_REF) -> float:
        """(F1) for exponent ``m`` (one of those given) at ``n_ref`` cycles (closes the
        stream)."""
        self.close()
        j = int(np.flatnonzero(self.ms == float(m))[0])
        return float((self.sums[j] / n_ref) ** (1.0 / float(m)))


def damage_equivalent_load(load, m: float, n_ref: float = N_REF) -> float:
    """The damage-equivalent load range (F1) of ``load`` for Woehler exponent ``m`` at
    ``n_ref`` cycles (same unit as the load)."""
    if not (isinstance(m, (int, float)) and 1.0 <= m <= 50.0):
        raise ModelError("m", f"= {m!r}: a Woehler exponent from 1 to 50")
    if not (isinstance(n_ref, (int, float)) and n_ref > 0 and math.isfinite(n_ref)):
        raise ModelError("n_ref", f"= {n_ref!r}: a number of cycles > 0")
    return _del(rainflow_cycles(load), m, n_ref)


def turning_dels(result, exponents, channels: list[str] | None = None, t_from: float = 0.0,
                 n_ref: float = N_REF) -> pd.DataFrame | None:
    """DELs (F1) of a run's force channels from the exact solution: the rainflow count of
    each channel's exact turning points (:attr:`gearmodal.SimulationResult.turning_points`)
    from ``t_from`` (s) to the run's end, streamed (a stored run a row group at a time, only
    the residue kept: :class:`RainflowStream`). The count starts at the channel's value at the
    first output time at or after ``t_from`` (exact: a row of the solution) and takes every
    turning point after it, so it does not depend on the output step when ``t_from`` is on
    its grid. One row per channel (``channels``: all by default; a mesh flank ``<mesh>.front``,
    a bearing's radial force ``<element>.radial``...), one column ``m=<exponent>`` per
    Woehler exponent; ``None`` when the run has no turning points (a method other than the
    exact one's Taylor propagator, or ``turning_points=False``)."""
    ms = [float(m) for m in exponents]
    for m in ms:
        if not 1.0 <= m <= 50.0:
            raise ModelError("m", f"= {m!r}: a Woehler exponent from 1 to 50")
    if not (isinstance(n_ref, (int, float)) and n_ref > 0 and math.isfinite(n_ref)):
        raise ModelError("n_ref", f"= {n_ref!r}: a number of cycles > 0")
    chunks = result.turning_chunks()
    first = next(chunks, None)
    if first is None:
        return None
    start = _row_at(result, t_from)
    streams: dict[str, RainflowStream] = {}
    known = None if channels is None else list(channels)
    if known is not None:
        missing = [c for c in known if c not in start.index]
        if missing:
            raise ModelError("channels", f"= {missing[0]!r}: not a force channel of the run")
        for c in known:
            streams[c] = RainflowStream(ms)
            streams[c].feed([start[c]])
    t0 = float(start.name)
    for chunk in itertools.chain([first], chunks):
        chunk = chunk[chunk.index > t0]
        for ch, part in chunk.groupby("channel", sort=False, observed=True):
            st = streams.get(ch)
            if st is None:
                if known is not None or ch not in start.index:
                    continue
                st = streams[ch] = RainflowStream(ms)
                st.feed([start[ch]])
            st.feed(part["force_N"].to_numpy())
    rows = {}
    for ch, st in streams.items():
        if st.n < 2:  # no turning point after the start: the channel held its value
            st.feed([st.prev])
        rows[ch] = [st.damage_equivalent_load(m, n_ref) for m in ms]
    out = pd.DataFrame.from_dict(rows, orient="index", columns=[f"m={m:g}" for m in ms])
    out.index.name = "channel"
    return out


def _row_at(result, t_from: float) -> pd.Series:
    """The force channels' values (every force column and each bearing's radial force
    ``<element>.radial``) at the first output time at or after ``t_from`` (a Series named by
    that time)."""
    for f in result.force_chunks():
        sel = f[f.index >= t_from - 1e-9 * max(1.0, abs(t_from))]
        if len(sel):
            row = sel.iloc[0].copy()
            for c in list(row.index):
                el, _, d = c.rpartition(".")
                if d == "x" and f"{el}.y" in row.index:
                    row[f"{el}.radial"] = math.hypot(row[c], row[f"{el}.y"])
            return row
    raise ModelError("t_from", f"= {t_from!r}: after the run's last output time")


def _del(c: pd.DataFrame, m: float, n_ref: float) -> float:
    """(F1) of counted cycles ``c`` (:func:`rainflow_cycles`)."""
    if c.empty:
        return 0.0
    return float((np.sum(c["count"] * c["range"] ** m) / n_ref) ** (1.0 / m))


def _bins(x: np.ndarray, bins) -> np.ndarray:
    if isinstance(bins, int):
        lo, hi = float(x.min()), float(x.max())
        if hi == lo:
            lo, hi = lo - 0.5 * max(abs(lo), 1.0), hi + 0.5 * max(abs(hi), 1.0)
        return np.linspace(lo, hi, bins + 1)
    edges = np.asarray(bins, dtype=float)
    if edges.ndim != 1 or edges.size < 2 or np.any(np.diff(edges) <= 0):
        raise ModelError("bins", "expected a number of bins or increasing bin edges")
    return edges


def _level_index(edges: np.ndarray, x: np.ndarray) -> np.ndarray:
    """The level bin of each value: ``[e_j, e_(j+1))``, below the first edge the first bin,
    from the last on the last (the exact kernel's ``_level_bin``)."""
    return np.clip(np.searchsorted(edges, x, side="right") - 1, 0, len(edges) - 2)


def _weights(t: np.ndarray) -> np.ndarray:
    """The time each sample stands for: half the gaps to its neighbours (trapezoid rule)."""
    dt = np.diff(t)
    if np.any(dt <= 0):
        raise ModelError("time", "must increase")
    w = np.zeros_like(t)
    w[:-1] += dt / 2
    w[1:] += dt / 2
    return w


def load_duration(load: pd.Series, bins=20) -> pd.DataFrame:
    """LDD (F2) of a load sampled on a time index (s): ``level_low``, ``level_high``,
    ``time_s`` per bin (``bins``: a count over the load's range, or the edges)."""
    x = _series("load", load)
    t = np.asarray(load.index, dtype=float)
    edges = _bins(x, bins)
    k = _level_index(edges, x)
    time = np.bincount(k, weights=_weights(t), minlength=len(edges) - 1)
    return pd.DataFrame({"level_low": edges[:-1], "level_high": edges[1:], "time_s": time})


def load_revolutions(load: pd.Series, speed_rpm, bins=20) -> pd.DataFrame:
    """LRD (F2) of a load sampled on a time index (s), with the shaft speed (rpm, a number or
    a series on the same times): ``level_low``, ``level_high``, ``revolutions`` per bin."""
    x = _series("load", load)
    t = np.asarray(load.index, dtype=float)
    n = np.broadcast_to(np.asarray(speed_rpm, dtype=float), x.shape)
    if not np.all(np.isfinite(n)):
        raise ModelError("speed_rpm", "must be finite")
    edges = _bins(x, bins)
    k = _level_index(edges, x)
    revs = np.bincount(k, weights=_weights(t) * np.abs(n) / 60.0, minlength=len(edges) - 1)
    return pd.DataFrame({"level_low": edges[:-1], "level_high": edges[1:],
                         "revolutions": revs})


def rating_life(load: pd.Series, speed_rpm, C: float, p: float = WOEHLER["bearing"]) -> dict:
    """ISO 281 basic rating life (F3) of a bearing of dynamic load rating ``C`` (N) under the
    radial load ``load`` (N, on a time index, s) at ``speed_rpm``: ``equivalent_load_N``,
    ``l10_million_revolutions``, ``l10_h``."""
    _check_rating(C, p)
    x = np.abs(_series("load", load))
    t = np.asarray(load.index, dtype=float)
    n = np.abs(np.broadcast_to(np.asarray(speed_rpm, dtype=float), x.shape))
    revs = _weights(t) * n / 60.0
    total = float(revs.sum())
    if not total > 0:
        raise ModelError("speed_rpm", "the bearing makes no revolution over the load history")
    p_eq = float((np.sum(revs * x**p) / total) ** (1.0 / p))
    return _basic_life(C, p, p_eq, total, float(t[-1] - t[0]))


def _check_rating(C, p, name: str = "C") -> None:
    """Refuse a dynamic load rating (the field ``name``) or life exponent outside what ISO 281
    means."""
    if not (isinstance(C, (int, float)) and C > 0 and math.isfinite(C)):
        raise ModelError(name, f"= {C!r}: the dynamic load rating, N > 0")
    if not (isinstance(p, (int, float)) and 1.0 <= p <= 10.0):
        raise ModelError("p", f"= {p!r}: the life exponent (3 ball, 10/3 roller bearings)")


def _basic_life(C: float, p: float, p_eq: float, revolutions: float, duration: float) -> dict:
    """ISO 281 basic rating life (F3) at equivalent load ``p_eq`` (N) of a bearing that makes
    ``revolutions`` in ``duration`` (s): ``L10 = (C / P_eq)^p`` million revolutions, and in
    hours at that mean speed."""
    l10 = (C / p_eq) ** p if p_eq > 0 else math.inf
    n_mean = revolutions * 60.0 / duration  # rpm
    return {"equivalent_load_N": p_eq, "l10_million_revolutions": l10,
            "l10_h": l10 * 1e6 / (60.0 * n_mean)}


def level_spectrum(result, channels: list[str], *, t_from: float = 0.0,
                   t_to: float | None = None, edges: str = "table") -> pd.DataFrame | None:
    """The exact load duration and revolution distributions (LDD and LRD, F2) of the largest
    of ``channels`` from ``t_from`` to ``t_to`` (s; the run's end by default), from the run's
    exact level changes (:attr:`gearmodal.SimulationResult.level_changes`): between two
    changes every channel stays in its bin, so the largest's bin is the largest of theirs, and
    the time and the model input's revolutions in each bin are sums over exact intervals (the
    revolutions those of the input's own speed, integrated on every piece's series); none
    depends on the output step. The channels share their edges (mesh flanks, or planet
    bearings' radial forces: :data:`LEVELS`). Columns ``level_low``, ``level_high``,
    ``time_s``, ``revolutions`` (NaN for a model without an ``input``; exact where ``t_from``
    and ``t_to`` are on the peak bins' grid or the run's end); ``None`` when the run has no
    level changes (a method other than the exact one's Taylor propagator,
    ``turning_points=False``). ``edges``: ``"table"`` the bins of :data:`LEVELS` (the
    lifetime tables': what lies above their top edge in their top bin), ``"run"`` the run's
    own, :data:`RUN_LEVELS`."""
    if edges not in ("table", "run"):
        raise ModelError("edges", f"= {edges!r}: 'table' or 'run'")
    chunks = result.level_chunks()
    first = next(chunks, None)
    if first is None:
        return None
    end = result.time_span()[1]
    t1 = end if t_to is None else float(t_to)
    if not (math.isfinite(t1) and t1 <= end + 1e-12 * max(1.0, abs(end))):
        raise ModelError("t_to", f"= {t_to!r}: must be at most the run's end, {end!r} s")
    if not (math.isfinite(t_from) and t_from < t1):
        raise ModelError("t_from", f"= {t_from!r}: must be before the end, {t1!r} s")
    # a flank's levels or a planet bearing's (turns.TurnPoints gives them so)
    kinds = {"planet_bearing_force_N" if c.endswith(".radial") else "tooth_force_N"
             for c in channels}
    if len(kinds) != 1:
        raise ModelError("channels", "one kind of channel: mesh flanks or planet bearings' "
                         "radial forces (their levels differ)")
    kind = kinds.pop()
    run = RUN_LEVELS[kind]
    sweep = LevelSweep(channels, run, t_from, t1)
    try:
        for chunk in itertools.chain([first], chunks):
            sweep.feed(chunk)
    except Unsorted:  # a table written before its rows were sorted: swept whole
        sweep = LevelSweep(channels, run, t_from, t1)
        sweep.feed(pd.concat(list(result.level_chunks())).sort_index(kind="stable"))
    table = sweep.table()
    if edges == "run":
        return table
    coarse = LEVELS[kind]  # the run's first bins are LEVELS' own, the rest merged on top
    nb = len(coarse) - 1
    idx = np.minimum(np.arange(len(table)), nb - 1)
    return pd.DataFrame({"level_low": coarse[:-1], "level_high": coarse[1:],
                         "time_s": np.bincount(idx, table.time_s.to_numpy(), nb),
                         "revolutions": np.bincount(idx, table.revolutions.to_numpy(), nb)})


def equivalent_loads(result, p: float, *, t_from: float = 0.0) -> pd.DataFrame | None:
    """The ISO 281 equivalent load (F3) of every planet bearing's radial force from the exact
    solution, from ``t_from`` (s) to the run's end, over the revolutions of the model's input
    (its own speed, every piece's series)::

        P_eq^p = int F^p dN / int dN

    each integral that of every piece's series (Gauss-Legendre: to rounding on the turbine
    runs, 3e-10 on the double-contact stage's rattle), kept per peak bin
    (:attr:`gearmodal.SimulationResult.peak_bins`: ``int_F3_dN``, ``int_F10_3_dN``,
    ``input_revolutions``). It does not depend on the output step. Indexed by channel
    (``<element>.radial``): ``equivalent_load_N``, ``revolutions`` (the input's); ``None``
    where the run has no load integrals (a method other than the exact one's Taylor
    propagator, ``turning_points=False``, a model without an ``input``), ``p`` is not one of
    :data:`LOAD_INTEGRALS` or ``t_from`` is not on the bins' grid."""
    col = next((c for q, c in LOAD_INTEGRALS.items() if abs(q - p) <= 1e-12 * q), None)
    bins = result.peak_bins
    pbin = result.settings.get("peak_bin")
    if col is None or bins is None or col not in bins.columns or not pbin:
        return None
    k = t_from / pbin
    if abs(k - round(k)) > 1e-9 * max(1.0, abs(k)):
        return None
    b = bins[(bins.bin_start_s >= round(k) * pbin - 1e-9 * pbin) & bins[col].notna()]
    if b.empty:
        return None
    sums = b.groupby("channel", sort=False)[[col, "input_revolutions"]].sum()
    if not (sums.input_revolutions > 0).all():
        raise ModelError("result", "the input makes no revolution over the load history: "
                         "no equivalent load over revolutions")
    out = pd.DataFrame({"equivalent_load_N": (sums[col] / sums.input_revolutions)
                        ** (1.0 / p), "revolutions": sums.input_revolutions})
    out.index.name = "channel"
    return out


class UpperPercentile:
    """The ``q``-th percentile (numpy's default, linear) of ``n`` values that come in chunks,
    from the few largest alone: with ``h = (n - 1) q / 100`` it interpolates the order
    statistics ``floor(h)`` and ``floor(h) + 1`` (ascending), both among the ``n - floor(h)
    + 1`` largest, so only those are kept (1 % of a run's rows and two for the 99th; the rows
    no longer sit in memory). :meth:`value` is ``np.percentile`` of all of them, to the bit
    (numpy's formula: ``a + (b - a) g``, or ``b - (b - a)(1 - g)`` where ``g >= 1/2``)."""

    def __init__(self, n: int, q: float):
        self.n, self.q = int(n), float(q)
        self.h = (self.n - 1) * (self.q / 100.0)
        self.lo = min(max(int(math.floor(self.h)), 0), max(self.n - 1, 0))
        self.m = self.n - self.lo + 1  # the largest ones kept (one more than needed)
        self.top = np.empty(0)
        self.seen = 0

    def push(self, values) -> None:
        x = np.asarray(values, dtype=float).ravel()
        self.seen += x.size
        both = np.concatenate([self.top, x])
        if both.size > self.m:
            both = np.partition(both, both.size - self.m)[both.size - self.m:]
        self.top = both

    def value(self) -> float:
        if self.seen != self.n or self.n == 0:
            raise ModelError("n", f"= {self.n}: {self.seen} values came")
        top = np.sort(self.top)
        first = self.n - top.size  # the rank of top[0] among all the values
        a = top[self.lo - first]
        b = top[min(self.lo + 1, self.n - 1) - first]
        g = self.h - math.floor(self.h)
        d = b - a
        return float(b - d * (1.0 - g) if g >= 0.5 else a + d * g)


#: load levels of the lifetime LDD/LRD tables of :func:`drivetrain_fatigue` (N m, N, N):
#: fixed edges, so that runs add up bin by bin
LEVELS = {"rotor_torque_Nm": np.linspace(-2e5, 6e5, 81),
          "tooth_force_N": np.linspace(0.0, 4e5, 81),
          "planet_bearing_force_N": np.linspace(0.0, 6e5, 81)}


#: the level edges a run records its level changes on (:mod:`gearmodal.integrate.turns`),
#: those of :data:`LEVELS` (a run's spectrum above 400 kN on a tooth, 600 kN on a planet
#: bearing is clipped into the top bin, which the ratings refuse to rate on; widening them to
#: a multi-megawatt gearbox's forces is open: tried with 401 edges and reverted on a CI
#: suspicion that proved unrelated, CHANGELOG 2026-12-08); ``edges="run"`` of
#: :func:`level_spectrum` gives them, the lifetime tables ``LEVELS``' own
RUN_LEVELS = {"tooth_force_N": LEVELS["tooth_force_N"],
              "planet_bearing_force_N": LEVELS["planet_bearing_force_N"]}


def drivetrain_fatigue(result, *, bearing_C: float, planet_spin: float, t_skip: float = 5.0,
                       woehler: dict | None = None, n_ref: float = N_REF,
                       tables: bool = True) -> dict:
    """Fatigue quantities of one turbine run (a :class:`gearmodal.turbine.DrivetrainResult`)
    after its first ``t_skip`` s (the start's transient): one row for a design-load-case
    table (``gearmodal study fatigue``).

    - ``del_tooth_N``: the largest tooth-root DEL (F1, ``woehler["tooth_root"]``) of the
      first planetary stage's flank forces (sun-planet and ring-planet, front and back, every
      planet); ``del_tooth_flank_N`` likewise with the flank exponent;
    - ``del_planet_bearing_N``: the largest DEL of a planet bearing's radial force (bearing
      exponent);
    - ``dels_exact``: True where these three DELs count the exact solution's turning points
      (:func:`turning_dels`: they do not depend on the output step when ``t_skip`` is on its
      grid), False where the run has none and they count the output rows;
    - ``l10_planet_bearing_h``: the shortest ISO 281 life (F3) of a planet bearing of dynamic
      rating ``bearing_C`` (N), its revolutions those of the planet on its pin
      (``planet_spin`` per rotor revolution: ``z_ring / z_planet`` for a carrier input; the
      rotor's revolutions at its own speed on every piece where ``life_exact``, else the
      turbine's rotor speed at the rows); ``planet_bearing_revolutions`` and
      ``planet_bearing_peq_N`` of that bearing (what a lifetime sum needs);
    - ``life_exact``: True where these come from the exact solution's load integrals
      (:func:`equivalent_loads`: independent of the output step when ``t_skip`` is on the
      peak bins), False where the run has none and the output rows are summed;
    - ``del_rotor_torque_Nm`` (exponent of the tooth root, the turbine's rotor torque on its
      aerodynamic step), ``mean_power_W``,
      ``max_front_force_N`` (the exact maximum of the solution,
      :meth:`~gearmodal.SimulationResult.peaks`, where the run has it and ``t_skip`` is on its
      peak bins), ``p99_tooth_force_N`` and ``p99_planet_bearing_force_N`` (99th
      percentiles over the output times), ``duration_s`` (the time counted).

    With ``tables`` the dict holds ``"tables"``: ``spectra``, the LDD (time) and LRD (rotor
    revolutions) at the fixed levels :data:`LEVELS` of the rotor torque (on the turbine's
    step), the largest tooth force and the radial force of the planet bearing with the
    shortest life (from the exact level changes, :func:`level_spectrum`, where the run has
    them, else from the output rows).
    """
    ex = {**WOEHLER, **(woehler or {})}
    for key, m in ex.items():
        if not (isinstance(m, (int, float)) and 1.0 <= m <= 50.0):
            raise ModelError(f"woehler.{key}", f"= {m!r}: a Woehler exponent from 1 to 50")
    sim, tur = result.gearbox, result.turbine.loads
    if not (isinstance(t_skip, (int, float)) and 0 <= t_skip < sim.time_span()[1]):
        raise ModelError("t_skip", f"= {t_skip!r}: must be >= 0 and shorter than the run")
    columns = sim.force_columns()
    stage = sim.meshes()
    flanks = [f"{m}.{side}" for m in stage if m.startswith(stage[0].split(".")[0] + ".")
              for side in ("front", "back") if f"{m}.{side}" in columns]
    bearings = [b for b in sim.elements_of("planet_bearing")
                if f"{b}.x" in columns and f"{b}.y" in columns]
    if not flanks or not bearings:
        raise ModelError("result", "needs a planetary stage's flank and planet-bearing forces")
    if not (isinstance(planet_spin, (int, float)) and planet_spin > 0
            and math.isfinite(planet_spin)):
        raise ModelError("planet_spin", f"= {planet_spin!r}: planet revolutions on the pin "
                         "per rotor revolution, > 0")
    _check_rating(bearing_C, ex["bearing"], "bearing_C")
    # the DELs from the exact solution's turning points where the run has them (they do not
    # depend on the output step), else from the rows
    # (one pass over the turning points for every channel and exponent)
    exact = turning_dels(sim, (ex["tooth_root"], ex["tooth_flank"], ex["bearing"]),
                         [*flanks, *(f"{b}.radial" for b in bearings)], t_skip, n_ref)
    # the bearings' equivalent loads and the load spectra from the exact solution where the
    # run has them (independent of the output step), else from the rows
    peq = equivalent_loads(sim, ex["bearing"], t_from=t_skip)
    # the rows are kept only where a statistic has no exact source (a run without the exact
    # tables); the 99th percentiles need the largest 1 % of them (UpperPercentile)
    keep_rows = exact is None or peq is None or next(sim.level_chunks(), None) is None
    n = sum(int(np.count_nonzero(np.asarray(f.index, dtype=float) >= t_skip))
            for f in sim.force_chunks([]))
    if n == 0:
        raise ModelError("t_skip", f"= {t_skip!r}: no output row at or after it")
    p99 = {k: UpperPercentile(n, 99.0) for k in ("teeth", *bearings)}
    # the run's forces a chunk of rows at a time (a stored run's row groups): the flank forces
    # counted as they come (RainflowStream) where there are no turning points
    streams = {c: RainflowStream((ex["tooth_root"], ex["tooth_flank"])) for c in flanks}
    keep: dict[str, list] = {k: [] for k in ("t", "speed", "teeth", *bearings)}
    for f in sim.force_chunks([*flanks, *(f"{b}.{d}" for b in bearings for d in "xy")]):
        f = f[f.index >= t_skip]
        if f.empty:
            continue
        per_row = {"teeth": f[flanks].max(axis=1).to_numpy(),
                   **{b: np.hypot(f[f"{b}.x"], f[f"{b}.y"]).to_numpy() for b in bearings}}
        for k, x in per_row.items():
            p99[k].push(x)
            if keep_rows:
                keep[k].append(x)
        if keep_rows:
            keep["t"].append(np.asarray(f.index, dtype=float))
            keep["speed"].append(tur["rotor_speed_rpm"].reindex(f.index, method="nearest")
                                 .to_numpy())
        if exact is None:
            for c in flanks:
                streams[c].feed(f[c].to_numpy())
    if keep_rows:
        t = np.concatenate(keep["t"])
        index = pd.Index(t, name="time")
        speed = np.concatenate(keep["speed"])
        teeth = np.concatenate(keep["teeth"])
        radial = {b: pd.Series(np.concatenate(keep[b]), index=index) for b in bearings}
    ratio = float(planet_spin)
    rotor_rpm = tur["rotor_speed_rpm"]  # on the turbine's (aerodynamic) step
    t_end = sim.time_span()[1]
    if peq is not None:
        peq = peq.rename(index=lambda c: c[:-len(".radial")])
        short = worst = str(peq["equivalent_load_N"].idxmax())
        revs = ratio * float(peq.loc[short, "revolutions"])
        duration = t_end - t_skip
        life = _basic_life(bearing_C, ex["bearing"], float(peq.loc[short, "equivalent_load_N"]),
                           revs, duration)
    else:
        worst = max(radial, key=lambda b: float(np.mean(radial[b] ** ex["bearing"])))
        lives = {b: rating_life(radial[b], ratio * speed, bearing_C, ex["bearing"])
                 for b in bearings}
        short = min(lives, key=lambda b: lives[b]["l10_h"])
        life = lives[short]
        revs = float(np.sum(_weights(t) * ratio * np.abs(speed) / 60.0))
        duration = float(t[-1] - t[0])
    if exact is not None:
        dels = {"del_tooth_N": float(exact.iloc[:, 0][flanks].max()),
                "del_tooth_flank_N": float(exact.iloc[:, 1][flanks].max()),
                "del_planet_bearing_N": float(exact.iloc[:, 2].drop(flanks).max())}
    else:
        dels = {"del_tooth_N": max(st.damage_equivalent_load(ex["tooth_root"], n_ref)
                                   for st in streams.values()),
                "del_tooth_flank_N": max(st.damage_equivalent_load(ex["tooth_flank"], n_ref)
                                         for st in streams.values()),
                "del_planet_bearing_N": max(damage_equivalent_load(r, ex["bearing"], n_ref)
                                            for r in radial.values())}
    # the rotor torque on the turbine's own (aerodynamic) step, not the gearbox's rows
    rotor = tur["torque_Nm"][tur.index >= t_skip - 1e-9]
    row = {"duration_s": duration,
           **dels,
           "dels_exact": exact is not None,
           "l10_planet_bearing_h": life["l10_h"],
           "planet_bearing_peq_N": life["equivalent_load_N"],
           "planet_bearing_revolutions": revs,
           "life_exact": peq is not None,
           "del_rotor_torque_Nm": damage_equivalent_load(rotor, ex["tooth_root"], n_ref),
           "max_front_force_N": float(sim.peaks(t_skip)["peak_force_N"][flanks].max()),
           "p99_tooth_force_N": p99["teeth"].value(),
           "p99_planet_bearing_force_N": p99[worst].value(),
           "mean_power_W": float(tur["power_W"][tur.index >= t_skip].mean())}
    if tables:
        kept = (teeth, radial[worst], index, speed) if keep_rows else None
        row["tables"] = {"spectra": _spectra(sim, flanks, worst, rotor, rotor_rpm, kept,
                                             t_skip)}
    return row


def _spectra(sim, flanks, worst, rotor, rotor_rpm, kept, t_skip):
    """:func:`drivetrain_fatigue`'s LDD and LRD tables at :data:`LEVELS`: the rotor torque on
    the turbine's step; the largest flank force and the ``worst`` planet bearing's radial
    force from the run's exact level changes (:func:`level_spectrum`) where it has them, else
    from the output rows ``kept`` = ``(teeth, radial, index, speed)`` (the largest flank
    force and the bearing's on the rows' times ``index``, with the rotor ``speed``)."""
    # the rotor torque: each aerodynamic step's value held over its step (the last to the
    # run's end), its revolutions at the step's rotor speed
    edges = LEVELS["rotor_torque_Nm"]
    t = np.asarray(rotor.index, dtype=float)
    held = np.diff(np.append(t, sim.time_span()[1]))
    spin = np.abs(rotor_rpm.reindex(rotor.index).to_numpy()) / 60.0
    k = _level_index(edges, rotor.to_numpy())
    parts = [pd.DataFrame({"level_low": edges[:-1], "level_high": edges[1:],
                           "time_s": np.bincount(k, held, minlength=len(edges) - 1),
                           "quantity": "rotor_torque_Nm",
                           "revolutions": np.bincount(k, held * spin,
                                                      minlength=len(edges) - 1)})]
    for j, (name, channels) in enumerate((("tooth_force_N", flanks),
                                          ("planet_bearing_force_N", [f"{worst}.radial"]))):
        edges = LEVELS[name]
        exact = level_spectrum(sim, channels, t_from=t_skip)
        if exact is None:
            rows, index, speed = kept[j], kept[2], kept[3]
            x = pd.Series(np.clip(np.asarray(rows), edges[0], edges[-1]), index=index)
            exact = load_duration(x, edges).assign(
                revolutions=load_revolutions(x, pd.Series(speed, index=index), edges)
                ["revolutions"])
        parts.append(exact.assign(quantity=name)[["level_low", "level_high", "time_s",
                                                  "quantity", "revolutions"]])
    return pd.concat(parts, ignore_index=True)

