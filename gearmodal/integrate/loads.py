"""Loads on their own time structure (DESIGN 2.4): what :func:`gearmodal.simulate` gives the
integrator so that the output step only places output rows.

- a number is constant;
- a :class:`Harmonic` (``mean + amplitude sin(2 pi frequency_hz t + phase)``) is carried
  exactly by the exact method, as the turning geometry is (its Taylor series in every piece);
- a pandas Series indexed by time is piecewise linear on its own knots (ends held);
- any other callable of time is sampled on the load step ``load_dt`` the caller states and
  is linear in between (the one approximation, independent of the output step).

:func:`load_paths` turns a run's ``loads`` into :class:`LoadPaths`: the constant values, the
knot table and the harmonics, by load column; :meth:`LoadPaths.values` gives the loads at any
times (the output rows, the reference methods' steps).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pandas as pd

from ..errors import ModelError, unknown
from ..model import validate as v

__all__ = ["LOAD_DT", "Harmonic", "LoadPaths", "force_at", "load_paths"]

#: default load step of a callable load, s: a 1.1 Hz sine sampled on it is within 6e-8 of its
#: amplitude between samples ((2 pi f dt)^2 / 8), an 80 Hz one within 3e-4
LOAD_DT = 1e-4
#: a knot whose two sides' slopes agree to this fraction of the load is no kink: left out
#: (a straight stretch of samples, a constant callable, ends no pieces)
LINE_TOL = 1e-12
#: most knots of a run's load table (every callable sample and series knot in the run)
MAX_KNOTS = 5e7


@dataclass(frozen=True)
class Harmonic:
    """A load ``mean + amplitude sin(2 pi frequency_hz t + phase)``: N or N m, Hz, ``phase``
    in rad. A callable of time (s) like any load, but the exact method integrates it exactly
    (no load step).

    Examples
    --------
    >>> import gearmodal as gm
    >>> gm.Harmonic(mean=1.0, amplitude=2.0, frequency_hz=0.25)(1.0)
    3.0
    """

    mean: float
    amplitude: float
    frequency_hz: float
    phase: float = 0.0

    def __call__(self, t):
        x = self.mean + self.amplitude * np.sin(2 * math.pi * self.frequency_hz
                                                * np.asarray(t, dtype=float) + self.phase)
        return float(x) if np.ndim(x) == 0 else x


@dataclass
class LoadPaths:
    """A run's loads by load column (``m`` columns), from time 0 of the run.

    ``constant`` (m,): the constant part; ``knot_t`` (nk,) and ``knot_u`` (nk, m): the
    piecewise-linear part (zero columns where a load has none; empty when no load has one),
    held beyond its ends; ``harmonic_u`` (nh, m) complex and ``harmonic_nu`` (nh,) rad/s: the
    harmonic part ``Re sum_j harmonic_u_j exp(i harmonic_nu_j t)``."""

    constant: np.ndarray
    knot_t: np.ndarray
    knot_u: np.ndarray
    harmonic_u: np.ndarray
    harmonic_nu: np.ndarray

    @property
    def time_varying(self) -> bool:
        return len(self.knot_t) > 0 or len(self.harmonic_nu) > 0

    def values(self, t: np.ndarray) -> np.ndarray:
        """The loads (len(t), m) at times ``t`` (s)."""
        t = np.asarray(t, dtype=float)
        return self.constant[None, :] + _timed(self.knot_t, self.knot_u, self.harmonic_u,
                                               self.harmonic_nu, t, len(self.constant))

    def columns(self, cols: list[int]) -> LoadPaths:
        """The same loads on the columns ``cols`` only (in that order)."""
        return LoadPaths(self.constant[cols], self.knot_t, self.knot_u[:, cols],
                         self.harmonic_u[:, cols], self.harmonic_nu)

    def used(self) -> list[int]:
        """The columns with a nonzero load."""
        return [j for j in range(len(self.constant))
                if self.constant[j] != 0.0 or np.any(self.knot_u[:, j])
                or np.any(self.harmonic_u[:, j])]


def force_at(loads, t: np.ndarray) -> np.ndarray:
    """The force rows (len(t), mF) at times ``t`` (s, from the call's start) of a call's
    ``loads = (knot_t, knot_u, harmonic_u, harmonic_nu, basis)``: load values (mL columns) on
    knots and harmonics (:class:`LoadPaths`' parts) acting through the force rows ``basis``
    (mF, mL) of the force grid (the form the integration methods take)."""
    kt, ku, hu, hnu, basis = loads
    t = np.atleast_1d(np.asarray(t, dtype=float))
    return _timed(kt, ku, hu, hnu, t, np.shape(basis)[1]) @ np.asarray(basis).T


def _timed(kt, ku, hu, hnu, t: np.ndarray, m: int) -> np.ndarray:
    """The knots' and harmonics' part (len(t), m) of loads at times ``t``."""
    U = np.zeros((len(t), m))
    if len(kt):
        for j in np.flatnonzero(np.any(ku != 0.0, axis=0)):
            U[:, j] += np.interp(t, kt, ku[:, j])
    for u, nu in zip(hu, hnu, strict=True):
        U += (np.exp(1j * nu * t)[:, None] * np.asarray(u)[None, :]).real
    return U


def _series(name: str, val: pd.Series) -> tuple[np.ndarray, np.ndarray]:
    """A Series load's knots: its index in seconds (numbers; a datetime or timedelta index
    would be read in nanoseconds: refused, naming the conversion) and its numeric values."""
    if not pd.api.types.is_numeric_dtype(val.index.dtype) \
            or pd.api.types.is_bool_dtype(val.index.dtype):
        hint = " (a time index: give seconds, e.g. s.index = (s.index - s.index[0])" \
            ".total_seconds())" if isinstance(val.index, (pd.DatetimeIndex,
                                                           pd.TimedeltaIndex)) else ""
        raise ModelError(f"loads.{name}", f"a Series must be indexed by time in s, got an "
                         f"index of {val.index.dtype}{hint}")
    if not pd.api.types.is_numeric_dtype(val.dtype) or pd.api.types.is_bool_dtype(val.dtype):
        raise ModelError(f"loads.{name}", f"a Series of {val.dtype} values: expected numbers "
                         "(N or N m)")
    idx = np.asarray(val.index, dtype=float)
    if not np.all(np.isfinite(idx)):
        bad = float(idx[~np.isfinite(idx)][0])
        raise ModelError(f"loads.{name}", f"a Series whose time index holds {bad!r}: every "
                         "time must be a finite number of s")
    if len(idx) < 1 or np.any(np.diff(idx) <= 0):
        raise ModelError(f"loads.{name}", "a Series must be indexed by increasing time")
    return idx, val.to_numpy(dtype=float)


def _probe(name: str, f) -> None:
    """Call a load function once at t = 0 before the run: a clear error naming the load when
    it takes no time argument or does not give one finite number."""
    try:
        y = f(0.0)
    except TypeError as err:
        raise ModelError(f"loads.{name}", f"the callable must take the time in s: {err}") \
            from None
    if isinstance(y, (bool, np.bool_)) or not isinstance(y, (int, float, np.number)) \
            and not (isinstance(y, np.ndarray) and y.shape == ()):
        raise ModelError(f"loads.{name}", f"the callable gave {type(y).__name__} {y!r:.60} at "
                         "t = 0: it must give one number (N or N m) per time")


def load_paths(names: list[str], loads: dict | None, t_end: float,
               load_dt: float = LOAD_DT) -> LoadPaths:
    """The :class:`LoadPaths` of ``loads`` (``{name: value}``, module docstring) over a run
    from 0 to ``t_end`` s, by the columns ``names``; a callable is sampled every ``load_dt``
    s (and at ``t_end``). Errors name the load."""
    m = len(names)
    if loads is not None and not hasattr(loads, "items"):
        raise ModelError("loads", f"expected {{load name: value}} (a dict), got "
                         f"{type(loads).__name__}")
    const = np.zeros(m)
    harm_u, harm_nu = [], []
    series: dict[int, tuple[np.ndarray, np.ndarray]] = {}
    knots = [np.array([0.0, float(t_end)])]
    for name, val in (loads or {}).items():
        if name not in names:
            raise ModelError(f"loads.{name}", unknown("load", name, names))
        j = names.index(name)
        if isinstance(val, Harmonic):
            parts = {"mean": val.mean, "amplitude": val.amplitude,
                     "frequency_hz": val.frequency_hz, "phase": val.phase}
            for key, x in parts.items():
                x = v.number(f"loads.{name}.{key}", x, "N or N m" if key != "phase" else "rad")
                if key == "frequency_hz" and x < 0:
                    raise ModelError(f"loads.{name}.frequency_hz", f"= {x!r}: must be >= 0 Hz")
                if key == "frequency_hz":
                    v.plausible(f"loads.{name}.frequency_hz", x, "frequency")
            v.plausible(f"loads.{name}", abs(val.mean) + abs(val.amplitude), "load")
            const[j] += val.mean
            if val.frequency_hz == 0.0:
                const[j] += val.amplitude * math.sin(val.phase)
            elif val.amplitude != 0.0:
                u = np.zeros(m, dtype=complex)
                # sin(x) = Re exp(i (x - pi / 2))
                u[j] = val.amplitude * np.exp(1j * (val.phase - math.pi / 2))
                harm_u.append(u)
                harm_nu.append(2 * math.pi * val.frequency_hz)
            continue
        if isinstance(val, pd.Series):
            idx, y = _series(name, val)
        elif callable(val):
            n = int(math.ceil(t_end / load_dt - 1e-9))
            if n > MAX_KNOTS:
                raise ModelError("load_dt", f"= {load_dt!r}: {n:.3g} samples of loads.{name}; "
                                 f"at most {MAX_KNOTS:.0e} (a longer load_dt)")
            idx = np.arange(n + 1) * load_dt  # the last at or after the end
            _probe(name, val)
            try:
                y = np.array([float(val(tt)) for tt in idx])
            except (TypeError, ValueError) as err:
                raise ModelError(f"loads.{name}", f"the callable did not give a number: {err}") \
                    from None
        else:
            try:
                const[j] += float(val)
            except (TypeError, ValueError):
                raise ModelError(f"loads.{name}", f"= {val!r}: expected a number (N or N m), a "
                                 "gm.Harmonic, a callable of time or a pandas Series") from None
            if not math.isfinite(const[j]):
                raise ModelError(f"loads.{name}", "has non-finite values")
            v.plausible(f"loads.{name}", abs(const[j]), "load")
            continue
        if not np.all(np.isfinite(y)):
            raise ModelError(f"loads.{name}", "has non-finite values")
        v.plausible(f"loads.{name}", float(np.abs(y).max(initial=0.0)), "load")
        series[j] = (idx, y)
        knots.append(idx[(idx > 0.0) & (idx < t_end)])
    nh = len(harm_nu)
    hu = np.array(harm_u, dtype=complex).reshape(nh, m)
    hnu = np.array(harm_nu, dtype=float)
    if not series:
        return LoadPaths(const, np.empty(0), np.empty((0, m)), hu, hnu)
    kt = np.unique(np.concatenate(knots))
    ku = np.zeros((len(kt), m))
    for j, (idx, y) in series.items():
        ku[:, j] = np.interp(kt, idx, y)
    # only the kinks end pieces: a knot whose sides' slopes agree (a straight stretch) is
    # left out, which leaves the piecewise-linear load as it is
    if len(kt) > 2:
        s = np.diff(ku, axis=0) / np.diff(kt)[:, None]
        scale = np.abs(ku).max(axis=0) + 1e-300
        kink = np.any(np.abs(s[1:] - s[:-1]) * (kt[2:] - kt[:-2])[:, None]
                      > LINE_TOL * scale, axis=1)
        keep = np.concatenate([[True], kink, [True]])
        kt, ku = kt[keep], ku[keep]
    return LoadPaths(const, kt, ku, hu, hnu)
