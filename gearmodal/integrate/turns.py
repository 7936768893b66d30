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

__all__ = ["TurnPoints", "turn_table", "TURN_COLUMNS"]

#: the columns of the turning-point table (its index is ``time``)
TURN_COLUMNS = ("channel", "force_N")
#: rows of the kernel's first point buffer (it grows as a run needs)
FIRST_ROOM = 4096
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

    def __init__(self, system, radial: list[str], enabled: bool = True):
        labels, self.TCH, self.TCW = contact_channels(system.asm.contacts.columns)
        if not enabled:
            labels, radial = [], []
            self.TCH, self.TCW = self.TCH[:0], self.TCW[:0]
        self.enabled = bool(enabled)
        self.channels = labels + list(radial)
        # per channel: last point's time and value, direction, has one, jump flag
        self.TS = np.zeros((len(self.channels), 5))
        self.TP = np.empty((FIRST_ROOM, 3))
        self.n = 0
        self._kept: list[np.ndarray] = []
        self.finished = False

    def args(self) -> tuple:
        """The kernel's turning arguments (:func:`~.taylor.taylor_run`)."""
        return (self.TCH, self.TCW, self.TS, self.TP, self.n)

    def update(self, TP: np.ndarray, n: int) -> None:
        """What the kernel returned: its (possibly grown) buffer and rows used."""
        self.TP, self.n = TP, int(n)

    def switched(self, contact: int) -> None:
        """Contact ``contact`` switched outside the kernel (a re-basing): its channel's value
        at the next piece's start is a point of its own."""
        for ch in np.flatnonzero((self.TCH == contact).any(axis=1)):
            self.TS[ch, 4] = 1.0

    def drain(self, sink=None) -> None:
        """The points found so far to ``sink`` (its ``turns(rows, channels)``) or kept; the
        buffer emptied."""
        if self.n:
            rows = self.TP[:self.n].copy()
            self.n = 0
            if sink is not None:
                sink.turns(rows, self.channels)
            else:
                self._kept.append(rows)

    def finish(self, sink=None) -> None:
        """The run's end: each channel's last value (the end of its sequence) drained too."""
        if self.finished:
            return
        self.finished = True
        last = [(self.TS[ch, 0], ch, self.TS[ch, 1]) for ch in range(len(self.channels))
                if self.TS[ch, 3] and self.TS[ch, 2] != 0.0]
        if last:
            rows = np.array(last, dtype=float)
            if self.n + len(rows) > len(self.TP):
                self.drain(sink)
            self.TP[self.n:self.n + len(rows)] = rows
            self.n += len(rows)
        self.drain(sink)

    def rows(self) -> np.ndarray:
        """The points kept in memory ((n, 3): time, channel index, value), run order."""
        return np.concatenate(self._kept) if self._kept else np.empty((0, 3))


def turn_table(channels: list[str], rows: np.ndarray) -> pd.DataFrame:
    """The turning-point table of kernel rows ``rows`` ((n, 3): time, channel index, value):
    index ``time`` (s), columns ``channel`` (its label) and ``force_N``,
    in the order found (each channel's rows in time order: its sequence, what a rainflow
    count reads)."""
    names = np.array(list(channels), dtype=object)[rows[:, 1].astype(np.int64)]
    return pd.DataFrame({"channel": pd.array(names, dtype="str") if _PANDAS_3 else names,
                         "force_N": rows[:, 2]}, index=pd.Index(rows[:, 0], name="time"))
