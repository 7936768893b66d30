"""Exact turning points of a run's forces (DESIGN 3.2: load statistics from the exact solution;
issue 34 item 3).

Rainflow counting reads a load's turning points only (its ends and every local extremum). The
exact method's Taylor propagator knows each piece's series, so the kernel finds every interior
extremum of every tracked channel on it (:func:`gearmodal.integrate.taylor.poly_turns`: the
roots of the series' derivative by Bernstein subdivision, none missed, located to rounding)
and passes the piece's end values and extrema, and the values on both sides of a jump (a
contact switching, a mesh stiffness changing), through a filter that keeps only the points
where the channel turns. The sequence is the exact signal's turning points: it does not
depend on the output step (the rows only sample the same solution), and a rainflow count,
DEL or peak computed from it is the exact signal's.

Channels, as :class:`~gearmodal.integrate.peaks.PeakTracker`'s: every force column of one
contact or of a dead band's two sides (a mesh flank, a bearing clearance's direction: the
column's value, 0 while open) and the radial force ``sqrt(F_x^2 + F_y^2)`` of every planet
bearing (``<element>.radial``).

:class:`TurnPoints` holds the kernel's state between calls (each channel's last point and
direction) and the points found; the driver drains them after every call, to its sink (a
streamed run's ``turning_points`` table) or to memory. The table (:func:`turn_table`):
``time`` (s), ``channel``, ``force_N``, each channel's rows in time order; a channel's first row is
its value at the run's start and its last its value at the run's end.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..fatigue import RUN_LEVELS
from ..levelsweep import MARK
from .taylor import LEVEL0

__all__ = ["TurnPoints", "turn_table", "level_table", "TURN_COLUMNS", "LEVEL_COLUMNS"]

#: the columns of the turning-point table (its index is ``time``)
TURN_COLUMNS = ("channel", "force_N")
#: the columns of the level-change table (its index is ``time``)
LEVEL_COLUMNS = ("channel", "bin", "level_low_N", "level_high_N", "input_revolutions")
#: rows of the kernel's first point buffer (it grows as a run needs)
FIRST_ROOM = 4096
#: rows the buffer may hold before a driver's call hands them on (:meth:`TurnPoints.drain`)
DRAIN_ROWS = 50_000
#: pandas 3 has a string dtype of its own ("str"); pandas 2 keeps labels as objects
_PANDAS_3 = int(pd.__version__.split(".")[0]) >= 3


def contact_channels(columns) -> tuple[list[str], np.ndarray, np.ndarray]:
    """The contact channels of a force table's contact ``columns`` (``Contacts.columns``):
    ``(labels, TCH, TCW)``, a column of one contact (weight 1) or of a dead band's two sides
    (+1 and -1, never closed together); a combination of more contacts (a polygon's facets)
    is not a channel."""
    by_col: dict[str, list[tuple[int, float]]] = {}
    for e, parts in enumerate(columns):
        for key, w in parts:
            by_col.setdefault(key, []).append((e, float(w)))
    labels, ch, cw = [], [], []
    for key, parts in by_col.items():
        if sorted(w for _, w in parts) not in ([1.0], [-1.0, 1.0]):
            continue
        labels.append(key)
        es = [e for e, _ in parts] + [-1]
        ws = [w for _, w in parts] + [0.0]
        ch.append(es[:2])
        cw.append(ws[:2])
    return (labels, np.array(ch, dtype=np.int64).reshape(-1, 2),
            np.array(cw, dtype=float).reshape(-1, 2))


class TurnPoints:
    """The exact turning points of one run (module docstring): the kernel's arrays and the
    points it found.

    Parameters
    ----------
    system : the run's first :class:`~gearmodal.integrate.system.PiecewiseLinearSystem`.
    radial : the labels of the spring channels the kernel tracks (the peak tracker's
        ``channels``, in its ``chp`` order).
    enabled : False: no channel (the kernel skips the work; the run has no turning points).
    """

    def __init__(self, system, radial: list[str], enabled: bool = True, speed_row: int = -1):
        contacts = system.asm.contacts
        labels, self.TCH, self.TCW = contact_channels(contacts.columns)
        if not enabled:
            labels, radial = [], []
            self.TCH, self.TCW = self.TCH[:0], self.TCW[:0]
        self.enabled = bool(enabled)
        self.channels = labels + list(radial)
        # the level edges of each channel (a mesh flank's the tooth force's, a radial
        # bearing force's the planet bearing's; none for the others)
        self.levels: dict[str, np.ndarray] = {}
        for ch, label in enumerate(labels):
            if contacts.kind[int(self.TCH[ch, 0])] == "mesh":
                self.levels[label] = RUN_LEVELS["tooth_force_N"]
        for label in radial:
            self.levels[label] = RUN_LEVELS["planet_bearing_force_N"]
        width = max((len(e) for e in self.levels.values()), default=0)
        # per channel (taylor.LEVEL0): last point's time and value, direction, has one, jump
        # flag, level bin (-1: none yet), number of level edges; in the first row only, the
        # input speed's row among the spring rows (-1: none), the reference speed it adds to
        # (set per call) and the input's revolutions so far (rad); the edges
        self.TS = np.zeros((len(self.channels), LEVEL0 + width))
        self.TS[:, 5] = -1.0
        if len(self.channels):
            self.TS[0, 7] = speed_row
        for ch, label in enumerate(self.channels):
            edges = self.levels.get(label)
            if edges is not None:
                self.TS[ch, 6] = len(edges)
                self.TS[ch, LEVEL0:LEVEL0 + len(edges)] = edges
        # rows: a turning point (time, channel, value, -) or a level change (time,
        # -(channel + 1), bin, the input's revolutions from the start, rad)
        self.TP = np.empty((FIRST_ROOM, 4))
        self.n = 0
        self._kept: list[np.ndarray] = []
        self._kept_levels: list[np.ndarray] = []
        self.finished = False

    def args(self, omega: float = 0.0) -> tuple:
        """The kernel's turning arguments (:func:`~.taylor.taylor_run`) for a call whose
        reference input speed is ``omega`` (rad/s)."""
        if len(self.TS):
            self.TS[0, 8] = omega
        return (self.TCH, self.TCW, self.TS, self.TP, self.n)

    def update(self, TP: np.ndarray, n: int) -> None:
        """What the kernel returned: its (possibly grown) buffer and rows used."""
        self.TP, self.n = TP, int(n)

    def switched(self, contact: int) -> None:
        """Contact ``contact`` switched outside the kernel (a re-basing): its channel's value
        at the next piece's start is a point of its own."""
        for ch in np.flatnonzero((self.TCH == contact).any(axis=1)):
            self.TS[ch, 4] = 1.0

    def drain(self, sink=None, above: int = 0) -> None:
        """The points and level changes found so far to ``sink`` (its ``turns(rows,
        channels)`` and ``levels(rows, channels, levels)``) or kept, the buffer emptied, when
        it holds more than ``above`` rows (a driver drains after each call above
        :data:`DRAIN_ROWS`: a few per call of a co-simulation step would cost more to hand on
        than to find)."""
        if self.n > above:
            rows = self.TP[:self.n]
            self.n = 0
            level = rows[:, 1] < 0.0
            points = rows[~level]
            changes = rows[level]
            changes[:, 1] = -changes[:, 1] - 1.0  # the channel's index
            if sink is not None:
                if len(points):
                    sink.turns(points, self.channels)
                if len(changes):
                    sink.levels(changes, self.channels, self.levels)
            else:
                self._kept.append(points)
                self._kept_levels.append(changes)

    def finish(self, sink=None, t_end: float | None = None) -> None:
        """The run's end (``t_end``, s): each channel's last value (the end of its sequence)
        drained too, and the input's revolutions there (a mark)."""
        if self.finished:
            return
        self.finished = True
        last = [(self.TS[ch, 0], ch, self.TS[ch, 1], np.nan)
                for ch in range(len(self.channels)) if self.TS[ch, 3] and self.TS[ch, 2] != 0.0]
        if t_end is not None and len(self.channels) and self.TS[0, 7] >= 0 and self.TS[0, 3]:
            # the input's revolutions at the run's end (a mark: level_table); the kernel's
            # last piece ended there
            last.append((float(t_end), -(len(self.channels) + 1.0), -1.0, self.TS[0, 9]))
        if last:
            rows = np.array(last, dtype=float)
            if self.n + len(rows) > len(self.TP):
                self.drain(sink)
            self.TP[self.n:self.n + len(rows)] = rows
            self.n += len(rows)
        self.drain(sink)

    def rows(self) -> np.ndarray:
        """The points kept in memory ((n, 4): time, channel index, value, -), run order."""
        return np.concatenate(self._kept) if self._kept else np.empty((0, 4))

    def level_rows(self) -> np.ndarray:
        """The level changes kept in memory ((n, 4): time, channel index, bin, the input's
        revolutions from the start in rad), run order."""
        return np.concatenate(self._kept_levels) if self._kept_levels else np.empty((0, 4))


def level_table(channels: list[str], levels: dict, rows: np.ndarray) -> pd.DataFrame:
    """The level-change table of kernel rows ``rows`` ((n, 4): time, channel index, bin, the
    input's revolutions in rad; ``levels``: each channel's edges): index ``time`` (s), columns
    ``channel``, ``bin`` (the level bin the channel's force is in from that time on:
    ``level_low_N <= F < level_high_N``, the first bin also below it and the last above),
    ``input_revolutions`` (the model input's revolutions from the run's start to that time,
    NaN without an input), in time order (rows of one instant in the order found), each
    channel's first the run's start. Rows of channel :data:`MARK` (bin -1) give the input's
    revolutions at each peak bin's start and at the run's end. ``rows`` are whole calls of the
    kernel (a driver drains between calls), so tables made of successive batches are in time
    order too: :func:`gearmodal.fatigue.level_spectrum` reads them a chunk at a time."""
    rows = rows[np.argsort(rows[:, 0], kind="stable")]  # a piece's channels come one by one
    idx = rows[:, 1].astype(np.int64)
    b = rows[:, 2].astype(np.int64)
    names = np.array([*channels, MARK], dtype=object)[idx]
    low = np.full(len(rows), np.nan)
    high = np.full(len(rows), np.nan)
    for ch in np.unique(idx[b >= 0]):
        edges = levels[channels[ch]]
        sel = idx == ch
        low[sel], high[sel] = edges[b[sel]], edges[b[sel] + 1]
    return pd.DataFrame({"channel": pd.array(names, dtype="str") if _PANDAS_3 else names,
                         "bin": b, "level_low_N": low, "level_high_N": high,
                         "input_revolutions": rows[:, 3] / (2 * np.pi)},
                        index=pd.Index(rows[:, 0], name="time"))


def turn_table(channels: list[str], rows: np.ndarray) -> pd.DataFrame:
    """The turning-point table of kernel rows ``rows`` ((n, >= 3): time, channel index, value):
    index ``time`` (s), columns ``channel`` (its label) and ``force_N``,
    in the order found (each channel's rows in time order: its sequence, what a rainflow
    count reads)."""
    names = np.array(list(channels), dtype=object)[rows[:, 1].astype(np.int64)]
    return pd.DataFrame({"channel": pd.array(names, dtype="str") if _PANDAS_3 else names,
                         "force_N": rows[:, 2]}, index=pd.Index(rows[:, 0], name="time"))
