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

import math

import numpy as np
import pandas as pd

from .errors import ModelError

#: default Woehler exponents (F1)
WOEHLER = {"tooth_root": 8.7, "tooth_flank": 13.2, "bearing": 10.0 / 3.0}
#: default reference number of cycles of a DEL (F1)
N_REF = 1e7


def _series(name: str, values) -> np.ndarray:
    x = np.asarray(values, dtype=float).ravel()
    if x.size < 2 or not np.all(np.isfinite(x)):
        raise ModelError(name, "needs at least two finite values")
    return x


def rainflow_cycles(load) -> pd.DataFrame:
    """Rainflow cycles of ``load`` (a sequence or Series): ``range``, ``mean``, ``count`` (1
    for a full cycle, 0.5 for a half cycle), one row per cycle, in the order counted."""
    import rainflow

    x = _series("load", load)
    rows = [(rng, mean, count) for rng, mean, count, _, _ in rainflow.extract_cycles(x)]
    return pd.DataFrame(rows, columns=["range", "mean", "count"])


def damage_equivalent_load(load, m: float, n_ref: float = N_REF) -> float:
    """The damage-equivalent load range (F1) of ``load`` for Woehler exponent ``m`` at
    ``n_ref`` cycles (same unit as the load)."""
    if not (isinstance(m, (int, float)) and 1.0 <= m <= 50.0):
        raise ModelError("m", f"= {m!r}: a Woehler exponent from 1 to 50")
    if not (isinstance(n_ref, (int, float)) and n_ref > 0 and math.isfinite(n_ref)):
        raise ModelError("n_ref", f"= {n_ref!r}: a number of cycles > 0")
    c = rainflow_cycles(load)
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
    k = np.clip(np.searchsorted(edges, x, side="right") - 1, 0, len(edges) - 2)
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
    k = np.clip(np.searchsorted(edges, x, side="right") - 1, 0, len(edges) - 2)
    revs = np.bincount(k, weights=_weights(t) * np.abs(n) / 60.0, minlength=len(edges) - 1)
    return pd.DataFrame({"level_low": edges[:-1], "level_high": edges[1:],
                         "revolutions": revs})


def rating_life(load: pd.Series, speed_rpm, C: float, p: float = WOEHLER["bearing"]) -> dict:
    """ISO 281 basic rating life (F3) of a bearing of dynamic load rating ``C`` (N) under the
    radial load ``load`` (N, on a time index, s) at ``speed_rpm``: ``equivalent_load_N``,
    ``l10_million_revolutions``, ``l10_h``."""
    if not (isinstance(C, (int, float)) and C > 0 and math.isfinite(C)):
        raise ModelError("C", f"= {C!r}: the dynamic load rating, N > 0")
    if not (isinstance(p, (int, float)) and 1.0 <= p <= 10.0):
        raise ModelError("p", f"= {p!r}: the life exponent (3 ball, 10/3 roller bearings)")
    x = np.abs(_series("load", load))
    t = np.asarray(load.index, dtype=float)
    n = np.abs(np.broadcast_to(np.asarray(speed_rpm, dtype=float), x.shape))
    revs = _weights(t) * n / 60.0
    total = float(revs.sum())
    if not total > 0:
        raise ModelError("speed_rpm", "the bearing makes no revolution over the load history")
    p_eq = float((np.sum(revs * x**p) / total) ** (1.0 / p))
    l10 = (C / p_eq) ** p if p_eq > 0 else math.inf
    n_mean = total * 60.0 / float(t[-1] - t[0])
    return {"equivalent_load_N": p_eq, "l10_million_revolutions": l10,
            "l10_h": l10 * 1e6 / (60.0 * n_mean)}
