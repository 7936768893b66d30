"""Exact peaks of a run's forces (DESIGN 3.2: load statistics from the exact solution, not from
the sampled rows).

The exact method's Taylor propagator knows each piece's series, so every contact force (while
closed) and every spring force is a known polynomial over the piece; the kernel finds its true
maximum there (:func:`gearmodal.integrate.taylor.poly_max`: the ends and every interior
maximum, none missed, located to rounding) wherever a bound of the series does not keep it
below what is known already. :class:`PeakTracker` holds what the kernel accumulates: the
largest value and its time per **peak bin** (``bin_s``, 1 s by default: a statistic over any
whole number of bins, e.g. after a start-up of 5 s, is exact) for each contact and spring
channel, and each contact's open episode (whose peak the event log gets on the row that ends
it). Its memory grows with the run's duration by one row of bins per ``bin_s``.

Channels: every contact (mesh flanks, bearing clearance sides) and the radial force
``sqrt(F_x^2 + F_y^2)`` of every planet bearing (``<element>.radial``) whose rows do not turn.
The other springs' peaks are the largest sampled values (:meth:`SimulationResult.peaks` says
which are exact): tracking every spring row costs about as much as the integration itself on
the 600 kW drivetrain.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from ..errors import ModelError
from ..fatigue import LOAD_INTEGRALS
from .bundles import Peaks, Search
from .turns import TurnPoints

__all__ = ["PEAK_BIN", "PeakTracker", "peak_table"]

#: default width of the peak bins, s
PEAK_BIN = 1.0
#: most terms of a piece's series (taylor.terms_for's cap)
MAX_TERMS = 200
#: the spring elements whose radial force is tracked exactly (the loads of the paper's and the
#: standards' bearing statistics)
RADIAL_ROLES = ("planet_bearing",)


def _spring_rows(system) -> list[int]:
    """The spring rows whose geometry does not turn (their ``W`` row is the assembled one)."""
    sp = system.asm.springs
    if sp is None or not len(sp):
        return []
    rows = list(range(len(sp)))
    geo = system.geometry
    if geo is not None and "springs.W" in geo.coef:
        a, b = geo.coef["springs.W"]
        hs = np.asarray(geo.harmonics)
        # a row turns when its harmonics are more than the rounding of their fit
        scale = np.abs(np.asarray(a)).max(axis=(0, 2)) + 1e-300
        turning = np.zeros(len(sp), dtype=bool)
        for h, ah, bh in zip(hs, a, b, strict=True):
            if h != 0:
                turning |= np.maximum(np.abs(ah).max(axis=1), np.abs(bh).max(axis=1)) \
                    > 1e-12 * scale
        rows = [r for r in rows if not turning[r]]
    return rows


class PeakTracker:
    """What the exact kernel accumulates for the exact peaks (module docstring) of one run.

    Parameters
    ----------
    system : the run's (first) :class:`~gearmodal.integrate.system.PiecewiseLinearSystem`
        (its contacts and springs; re-based systems of the same model share them).
    bin_s : width of the peak bins, s (> 0).
    turns : also the exact turning points of the same channels (:mod:`.turns`).
    """

    def __init__(self, system, bin_s: float = PEAK_BIN, turns: bool = True):
        if not (isinstance(bin_s, (int, float)) and math.isfinite(bin_s) and bin_s > 0):
            raise ModelError("peak_bin", f"= {bin_s!r}: must be a finite number > 0 s")
        self.bin = float(bin_s)
        self.names = list(system.names)  # contacts
        nc = len(self.names)
        sp = system.asm.springs
        rows = _spring_rows(system)
        W = sp.W[rows] if rows else np.zeros((0, system.n))
        r_, c_ = np.nonzero(W)
        self.sptr = np.zeros(len(rows) + 1, dtype=np.int64)
        np.cumsum(np.bincount(r_, minlength=len(rows)), out=self.sptr[1:])
        self.sidx = c_.astype(np.int64)
        self.sval = np.ascontiguousarray(W[r_, c_], dtype=float)
        self.sk = np.array([sp.stiffness[r] for r in rows], dtype=float)
        self.sc = np.array([sp.damping[r] for r in rows], dtype=float)
        # the input speed's row after the springs' (the load integrals' revolutions)
        speed = system.asm.input_speed
        self.speed_row = -1
        if speed is not None and np.any(speed):
            j = np.flatnonzero(speed)
            self.speed_row = len(rows)
            self.sptr = np.append(self.sptr, self.sptr[-1] + len(j))
            self.sidx = np.append(self.sidx, j).astype(np.int64)
            self.sval = np.append(self.sval, speed[j])
            self.sk = np.append(self.sk, 0.0)
            self.sc = np.append(self.sc, 1.0)
        # the planet bearings' radial forces (the other springs' peaks are sampled)
        chans, labels = [], []
        local = {(sp.element[r], sp.contact[r]): i for i, r in enumerate(rows)}
        for el in dict.fromkeys(sp.element[r] for r in rows
                                if sp.role[r] in RADIAL_ROLES):
            if (el, "x") in local and (el, "y") in local:
                chans.append((local[el, "x"], local[el, "y"]))
                labels.append(f"{el}.radial")
        self.chp = np.array(chans, dtype=np.int64).reshape(-1, 2)
        self.channels = labels

        self.EP = np.empty((nc, 2))
        self.EP[:, 0], self.EP[:, 1] = -np.inf, np.nan
        # per bin and channel: peak, its time, a radial channel's load integrals
        self.PB = np.empty((0, nc + len(labels), 5))
        # each channel's pending piece (taylor._offer): its terms (a radial channel's square
        # has up to twice the series' terms), (bound, start, length, end, bin), count
        width = 2 * MAX_TERMS
        self.PC = np.zeros((nc + len(labels), width))
        self.PM = np.full((nc + len(labels), 5), -np.inf)
        self.PN = np.zeros(nc + len(labels), dtype=np.int64)
        #: every piece so far went through the exact kernel (else the peaks are sampled)
        self.exact = True
        #: the exact turning points of the same channels (:mod:`.turns`)
        self.turns = TurnPoints(system, labels, enabled=turns, speed_row=self.speed_row)

    def ensure(self, t_end: float) -> None:
        """Bins up to absolute time ``t_end`` (s)."""
        nb = int(t_end // self.bin) + 1
        if nb > len(self.PB):
            grown = np.empty((nb, self.PB.shape[1], 5))
            grown[:, :, 0], grown[:, :, 1], grown[:, :, 2:] = -np.inf, np.nan, 0.0
            grown[:len(self.PB)] = self.PB
            self.PB = grown

    def args(self) -> tuple:
        """The kernel's peak fields (:data:`~.bundles.Peaks` but its call's start
        ``t_call``)."""
        return (True, self.EP, self.PB, self.bin, self.PC, self.PM, self.PN)

    def flush(self) -> None:
        """Search every pending piece (the run's end, a re-basing): the bins and episodes then
        hold their exact maxima."""
        from .taylor import DEPTH, resolve_all

        if not np.any(self.PM[:, 0] != -np.inf):
            return
        w = self.PC.shape[1]
        resolve_all(len(self.names), Peaks(*self.args(), 0.0),
                    Search(np.zeros(w), np.zeros(w), np.empty((DEPTH + 5) * w),
                           np.empty((2, DEPTH + 1))), np.zeros(7, dtype=np.int64))

    def rows(self) -> tuple:
        return (self.sptr, self.sidx, self.sval, self.sk, self.sc, self.chp)

    def switched(self, e: int, closed: bool, force: float, t: float) -> tuple[float, float]:
        """Contact ``e`` switched outside the kernel (a re-basing) at time ``t`` with ``force``:
        the episode's ``(peak, time)`` if it opened (NaN otherwise), its new episode begun if
        it closed."""
        self.flush()
        self.turns.switched(e)
        if closed:
            self.EP[e] = (force, t)
            return math.nan, math.nan
        out = (float(self.EP[e, 0]), float(self.EP[e, 1]))
        self.EP[e] = (-np.inf, np.nan)
        return out if out[0] > -np.inf else (math.nan, math.nan)


def peak_table(tracker: PeakTracker, columns: list, t_end: float) -> pd.DataFrame | None:
    """The exact peaks of ``tracker`` by force-table column and bin (long format: columns
    ``bin_start_s``, ``channel``, ``peak_force_N``, ``time_s``, and a radial channel's load
    integrals over the bin ``int_F3_dN``, ``int_F10_3_dN`` (``int F^p dN``, N^p, ``N`` the
    model input's revolutions) and ``input_revolutions``, with the turning points and an
    input; NaN for the others); ``columns`` are the contacts' force columns
    (``Contacts.columns``: ``((column, weight), ...)`` per contact). A column is exact when
    it is one contact (weight 1) or a dead band's two sides (+1 and -1, never closed
    together; its peak the larger side's); springs as the tracker's channels. ``None`` when
    the run did not go through the exact kernel throughout."""
    if not tracker.exact or not len(tracker.PB):
        return None
    tracker.flush()
    nb = min(len(tracker.PB), int(t_end // tracker.bin) + 1)
    PB = tracker.PB[:nb]
    nc = len(tracker.names)
    by_col: dict[str, list[int]] = {}
    weights: dict[str, list[float]] = {}
    for e, parts in enumerate(columns):
        for key, w in parts:
            by_col.setdefault(key, []).append(e)
            weights.setdefault(key, []).append(float(w))
    cols, vals, times = [], [], []
    for key, es in by_col.items():
        w = sorted(weights[key])
        if not (w == [1.0] or w == [-1.0, 1.0]):
            continue  # a combination of several contacts (a polygon's facets): sampled
        v = PB[:, es, 0]
        j = np.argmax(v, axis=1)
        cols.append(key)
        vals.append(v[np.arange(nb), j])
        times.append(PB[np.arange(nb), np.array(es)[j], 1])
    n_contact_cols = len(cols)
    for i, key in enumerate(tracker.channels):
        cols.append(key)
        vals.append(PB[:, nc + i, 0])
        times.append(PB[:, nc + i, 1])
    names = [*LOAD_INTEGRALS.values(), "input_revolutions"]
    if not cols:
        return pd.DataFrame(columns=["bin_start_s", "channel", "peak_force_N", "time_s",
                                     *names])
    V, T = np.array(vals).T, np.array(times).T  # (bins, channels)
    # a bin no piece reached (an open contact throughout): no force, at the bin's start; a
    # contact whose largest k p + c p' in a bin is negative (damping just before it opens) was
    # open in that bin too, where its force is 0 (the force column's value)
    starts = np.arange(nb) * tracker.bin
    empty = ~np.isfinite(V)
    empty[:, :n_contact_cols] |= V[:, :n_contact_cols] < 0.0
    V = np.where(empty, 0.0, V)
    T = np.where(empty, starts[:, None], T)
    out = {"bin_start_s": np.repeat(starts, len(cols)),
           "channel": np.tile(np.array(cols, dtype=object), nb),
           "peak_force_N": V.ravel(), "time_s": T.ravel()}
    # the radial channels' load integrals over the input's revolutions (with the turning
    # points and an input; NaN elsewhere): rad to revolutions
    for k, name in enumerate(names):
        I = np.full((nb, len(cols)), np.nan)
        if tracker.turns.enabled and tracker.speed_row >= 0:
            I[:, n_contact_cols:] = PB[:, nc:nc + len(tracker.channels), 2 + k] / (2 * np.pi)
        out[name] = I.ravel()
    return pd.DataFrame(out)
