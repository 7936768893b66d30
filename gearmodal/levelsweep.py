"""The exact load spectrum of the largest of several channels, swept over a run's level
changes a chunk at a time (constant memory; :func:`gearmodal.fatigue.level_spectrum`).

A run's level-change table (:attr:`gearmodal.SimulationResult.level_changes`) says, for each
channel, the bin of ``LEVELS`` its force is in from each change on, and carries the model
input's revolutions at every row. Between two consecutive change instants ``u_i < u_(i+1)``
of any channel every channel stays in its bin, so the largest force is in the bin

    top_i = max over the channels of their bins at u_i                                 (L1)

and the bin's time and revolutions gain ``u_(i+1) - u_i`` and ``R(u_(i+1)) - R(u_i)``, ``R`` the
input's revolutions from the start, linear between the rows that carry it (exact at a row;
the span's ends ``t_from``, ``t_to`` interpolated between the rows around them)     (L2)

:class:`LevelSweep` takes the table's rows in time order, a chunk at a time, and keeps only
each channel's current bin, the open interval's start and the sums: a stored 600 s turbine
run's 2.0 million level changes no longer sit in memory at once (the call took 306 MB, now
70 MB, most of it Arrow's first read: ``benchmarks/fatigue_memory.py``). A chunk's rows
at its last instant wait for the next chunk (more rows of that instant may follow), and a
span end waits for the first row after it (its ``R``).
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from .errors import ModelError

__all__ = ["LevelSweep", "Unsorted", "MARK"]

#: the channel of the level-change table's marks of the model input's revolutions (bin -1;
#: written by :mod:`gearmodal.integrate.turns`)
MARK = "input"


class Unsorted(Exception):
    """The rows fed are not in time order (a level-change table written before gearmodal
    sorted it): sweep the table sorted whole instead."""


class LevelSweep:
    """(L1)-(L2) over ``channels`` (names of the level-change table) on the level ``edges``,
    from ``t_from`` to ``t_to`` (s): :meth:`feed` the table's chunks in time order, then
    :meth:`table`. The rows of channel :data:`MARK` carry the input's revolutions only."""

    def __init__(self, channels: list[str], edges: np.ndarray, t_from: float, t_to: float):
        self.channels = list(channels)
        self.lookup = pd.Index([*self.channels, MARK])
        self.edges = np.asarray(edges, dtype=float)
        self.t_from, self.t_to = float(t_from), float(t_to)
        nb = len(self.edges) - 1
        self.time = np.zeros(nb)
        self.revs = np.zeros(nb)
        self.bins = np.full(len(self.channels), -1, dtype=np.int64)  # -1: no change yet
        self.seen = np.zeros(len(self.channels), dtype=bool)  # a change before t_to
        self.last_mark = (0.0, 0.0)  # the input's revolutions: 0 at the start
        self.u0 = self.R0 = None  # the open interval's start and its revolutions
        self.top0 = -1
        self.done = False
        self.early = False  # a channel without a bin inside the span
        self.latest = -math.inf  # the last instant fed
        self.wait = self._empty()  # rows at the last instant fed

    @staticmethod
    def _empty() -> tuple:
        return np.empty(0), np.empty(0, dtype=np.int64), np.empty(0, dtype=np.int64), \
            np.empty(0)

    def feed(self, chunk: pd.DataFrame) -> None:
        """The next rows of the table (index ``time``; ``channel``, ``bin``, ``level_low_N``,
        ``input_revolutions``). Raises :class:`Unsorted` at a row before one already fed."""
        pos = self.lookup.get_indexer(chunk["channel"])  # the channels, then the mark
        keep = pos >= 0
        t = np.asarray(chunk.index, dtype=float)[keep]
        if not len(t):
            return
        if t[0] < self.latest or np.any(np.diff(t) < 0):
            raise Unsorted
        c = np.where(pos[keep] == len(self.channels), -1, pos[keep])  # -1: a mark
        b = chunk["bin"].to_numpy(dtype=np.int64)[keep]
        low = chunk["level_low_N"].to_numpy(dtype=float)[keep]
        ok = (c >= 0) & (b >= 0)
        wrong = np.flatnonzero(self.edges[b[ok]] != low[ok])
        if len(wrong):
            raise ModelError("level_changes", f"{self.channels[c[ok][wrong[0]]]!r}: its "
                             "levels are not those of fatigue.RUN_LEVELS (a run of another "
                             "gearmodal?)")
        r = chunk["input_revolutions"].to_numpy(dtype=float)[keep]
        rows = tuple(np.concatenate([w, x]) for w, x in zip(self.wait, (t, c, b, r), strict=True))
        self.latest = float(t[-1])
        cut = int(np.searchsorted(rows[0], self.latest, side="left"))
        self.wait = tuple(x[cut:] for x in rows)
        self._sweep(tuple(x[:cut] for x in rows), self.latest)

    def table(self) -> pd.DataFrame:
        """The spectrum: ``level_low``, ``level_high``, ``time_s``, ``revolutions``. Raises
        :class:`ModelError` naming ``channels`` for a channel without level changes before
        the span's end, or ``t_from`` for a span starting before a channel's first row."""
        rows, self.wait = self.wait, self._empty()
        self._sweep(rows, math.inf)
        missing = [c for c, s in zip(self.channels, self.seen, strict=True) if not s]
        if missing:
            raise ModelError("channels", f"= {missing[0]!r}: no level changes of that channel "
                             "(a mesh flank or a planet bearing's radial force)")
        if self.early:
            raise ModelError("t_from", f"= {self.t_from!r}: before the run's start")
        return pd.DataFrame({"level_low": self.edges[:-1], "level_high": self.edges[1:],
                             "time_s": self.time, "revolutions": self.revs})

    def _sweep(self, rows: tuple, horizon: float) -> None:
        """A block of rows in time order, every row fed before ``horizon`` (s) in it or
        earlier: its change instants in the span, and the span's ends before the horizon,
        added to the sums."""
        t, c, b, r = rows
        change = (c >= 0) & (b >= 0) & (t < self.t_to)
        self.seen[np.unique(c[change])] = True
        if not self.done:
            u = t[change & (t > self.t_from)]
            ends = [x for x, due in ((self.t_from, self.u0 is None), (self.t_to, True))
                    if due and x < horizon]
            u = np.unique(np.concatenate([u, ends]))
            if len(u):
                self._add(u, t[change], c[change], b[change], t, r)
        for k in np.unique(c[(c >= 0) & (b >= 0)]):  # each channel's bin after the block
            self.bins[k] = b[(c == k) & (b >= 0)][-1]
        if len(t):
            self.last_mark = (float(t[-1]), float(r[-1]))

    def _add(self, u, tc, cc, bc, t, r) -> None:
        """The intervals from the open one's start through the instants ``u`` (sorted, in the
        span) to the sums; the block's changes ``(tc, cc, bc)``, its rows' revolutions
        ``(t, r)``."""
        top = self._tops(tc, cc, bc, u)
        # R (L2): between the row before the block, the block's rows and the first waiting row
        R = np.interp(u, np.concatenate([[self.last_mark[0]], t, self.wait[0][:1]]),
                      np.concatenate([[self.last_mark[1]], r, self.wait[3][:1]]))
        if self.u0 is None:  # u[0] is t_from
            self.u0, self.R0, self.top0 = float(u[0]), float(R[0]), int(top[0])
            u, R, top = u[1:], R[1:], top[1:]
        if len(u):
            tops = np.concatenate([[self.top0], top[:-1]])
            nb = len(self.time)
            self.time += np.bincount(tops, weights=np.diff(np.concatenate([[self.u0], u])),
                                     minlength=nb)
            self.revs += np.bincount(tops, weights=np.diff(np.concatenate([[self.R0], R])),
                                     minlength=nb)
            self.u0, self.R0, self.top0 = float(u[-1]), float(R[-1]), int(top[-1])
        self.done = self.u0 >= self.t_to

    def _tops(self, t: np.ndarray, c: np.ndarray, b: np.ndarray, u: np.ndarray) -> np.ndarray:
        """(L1) at the instants ``u`` (after the changes at them) from the block's changes
        ``(t, c, b)`` and the bins before the block; the span's end needs none."""
        top = np.full(len(u), -1, dtype=np.int64)
        inside = u < self.t_to
        for k in range(len(self.channels)):
            sel = c == k
            at = np.searchsorted(t[sel], u, side="right") - 1
            bk = np.where(at >= 0, b[sel][np.maximum(at, 0)], self.bins[k]) if sel.any() \
                else np.full(len(u), self.bins[k])
            self.early |= bool(np.any(bk[inside] < 0))  # raised by table()
            top = np.maximum(top, bk)
        return np.maximum(top, 0)
