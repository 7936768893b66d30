"""One integration driver and the methods behind it (DESIGN 3.2; as scipy's ``OdeSolver``
subclasses behind ``solve_ivp``).

A run is walked through **segments**: intervals over which the system's coefficients are
known functions of time (the whole run for :func:`gearmodal.simulate` at constant speed; the
stretch between two re-basings of the reference rotation for the turbine, advanced one
aerodynamic step at a time with its loads). :class:`Driver` calls the chosen :class:`Method`
on each stretch, keeps the states, logs every event in one format (rows ``time, contact,
before, after, rate, force``, times from the run's start) and builds one
:class:`~gearmodal.integrate.result.SimulationResult`. The turbine co-simulation is a source of
segments and loads for it, not a second loop.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ..errors import ModelError
from .exact import run_exact
from .loads import force_at
from .newmark import run_newmark
from .peaks import PEAK_BIN, PeakTracker
from .scipy_ref import run_scipy
from .stretch import Stretch
from .system import PiecewiseLinearSystem
from .turns import DRAIN_ROWS


class Method:
    """An integration method: ``run(stretch, **options)`` integrates a
    :class:`~gearmodal.integrate.stretch.Stretch` and returns ``(X, S, events, stats)``
    (states and contact states at the ``n_steps + 1`` output times, events as rows or tuples,
    counters); ``options`` are the names it takes. The stretch's ``loads`` (on their own time
    structure): a method that takes them (``takes_loads``) follows them between output times,
    the others get them folded into ``F`` at the output times (Newmark: its steps). Its
    ``peaks``: a method without them (``takes_peaks``) marks them sampled.

    Its ``k_org``: the call continues a run at its output step ``k_org``: ``azimuth0`` and
    the loads' times are then from the run's start, and so are the events' times returned. A
    method that ``chains`` walks the pieces one call would (the exact method); the others are
    given times from the call's start (and ``t_span``'s start for ``k_org dt``)."""

    name = ""
    options: tuple[str, ...] = ()
    takes_loads = False
    takes_peaks = False
    chains = False
    _run = None

    def chains_with(self, options: dict) -> bool:
        """Whether this method, with these options, continues a run across calls
        (:attr:`chains`)."""
        return self.chains

    def run(self, stretch: Stretch, **options):
        """``(X, S, events, stats)`` of ``stretch`` (the class docstring)."""
        if stretch.k_org is not None and not self.chains_with(options):
            # times from the call's start, the events' back from the run's
            t_org = stretch.k_org * stretch.dt if stretch.t_span is None else stretch.t_span[0]
            loads = stretch.loads
            if loads is not None:
                loads = (np.asarray(loads[0], dtype=float) - t_org,) + tuple(loads[1:])
            azimuth0 = stretch.azimuth0 + stretch.system.omega * t_org
            X, S, ev, stats = self.run(replace(stretch, azimuth0=azimuth0, loads=loads,
                                               k_org=None, t_span=None), **options)
            ev = event_rows(ev)
            ev[:, 0] += t_org
            return X, S, ev, stats
        if stretch.peaks is not None and not self.takes_peaks:
            stretch.peaks.exact = False
        if stretch.loads is not None and not self.takes_loads:
            t = np.arange(stretch.n_steps + 1) * stretch.dt
            stretch = replace(stretch, F=stretch.F + force_at(stretch.loads, t), loads=None)
        return type(self)._run(stretch, **options)

    def check(self, options: dict) -> None:
        """Refuse an option this method does not take, naming it and the ones it does, and a
        value outside what it can honour (:data:`OPTION_RANGES`)."""
        for key, val in options.items():
            if key not in self.options:
                allowed = ", ".join(self.options) or "none"
                raise ModelError(key, f"is not an option of method={self.name!r} (its options: "
                                 f"{allowed})")
            _check_option(key, val)


class Exact(Method):
    """Event-driven exact propagation (:func:`gearmodal.integrate.exact.run_exact`)."""

    name = "exact"
    options = ("max_events_per_step", "propagator")
    takes_loads = True
    takes_peaks = True
    chains = True
    _run = staticmethod(run_exact)

    def chains_with(self, options: dict) -> bool:
        """The Taylor propagator chains; ``"expm"`` restarts at every call."""
        return options.get("propagator", "taylor") == "taylor"


class Newmark(Method):
    """Newmark average acceleration (:func:`gearmodal.integrate.newmark.run_newmark`)."""

    name = "newmark"
    options = ()
    _run = staticmethod(run_newmark)


class Scipy(Method):
    """``solve_ivp`` with event functions (:func:`gearmodal.integrate.scipy_ref.run_scipy`)."""

    name = "scipy"
    options = ("scipy_method", "rtol", "atol", "max_events", "max_step", "first_step")
    takes_loads = True
    _run = staticmethod(run_scipy)


#: stats a run keeps the worst of over its stretches (the others add up)
WORST_STATS = ("energy_error",)


#: the methods by name
METHODS: dict[str, Method] = {m.name: m for m in (Exact(), Newmark(), Scipy())}


#: the values each method option takes: (kind, low, high) for numbers and integers, or the
#: choices. A relative tolerance beyond 0.1 is no tolerance (solve_ivp then steps over whole
#: contact episodes: rtol = 1e3 gave 119 events where there is 1); below 1e-13 it is under
#: what float64 rounding lets solve_ivp reach
OPTION_RANGES = {
    "max_events_per_step": ("integer", 1, 10**6),
    "propagator": ("taylor", "expm"),
    "scipy_method": ("RK45", "RK23", "DOP853", "Radau", "BDF", "LSODA"),
    "rtol": ("number", 1e-13, 0.1),
    "atol": ("number", 1e-300, 1.0),
    "max_events": ("integer", 1, 10**8),
    "max_step": ("number", 1e-12, 1e6),
    "first_step": ("number", 1e-15, 1e6),
}


def _check_option(key: str, val) -> None:
    spec = OPTION_RANGES.get(key)
    if spec is None:
        return
    if spec[0] not in ("number", "integer"):
        if not isinstance(val, str) or val not in spec:
            raise ModelError(key, f"= {val!r}: must be one of {', '.join(map(repr, spec))}")
        return
    kind, lo, hi = spec
    if key == "atol" and isinstance(val, (list, tuple, np.ndarray)):
        # solve_ivp's absolute tolerance per state component (its size is solve_ivp's check)
        arr = np.asarray(val)
        if arr.ndim != 1 or arr.size == 0 or arr.dtype.kind not in "iuf" \
                or not (np.all(np.isfinite(arr)) and np.all((arr >= lo) & (arr <= hi))):
            raise ModelError(key, f"= {val!r}: must be a number, or one per state component, "
                             f"in [{lo:g}, {hi:g}]")
        return
    ok = isinstance(val, (int, float, np.integer, np.floating)) and not isinstance(val, bool)
    if ok and kind == "integer":
        ok = float(val) == int(val)
    if not ok or not (math.isfinite(float(val)) and lo <= float(val) <= hi):
        what = "an integer" if kind == "integer" else "a number"
        raise ModelError(key, f"= {val!r}: must be {what} in [{lo:g}, {hi:g}]")


def get_method(name: str, options: dict) -> Method:
    """The method called ``name``, its ``options`` checked."""
    if not isinstance(name, str) or name not in METHODS:
        raise ModelError("method", f"= {name!r}: must be one of {', '.join(map(repr, METHODS))}")
    m = METHODS[name]
    m.check(options)
    return m


class Driver:
    """Walks one run through its segments (module docstring).

    Parameters
    ----------
    name : the method's name; options : its options (checked).
    dt : output step, s. x0, s0 : the state and contact state at time 0.
    peak_bin : width of the exact peaks' bins, s (:class:`~.peaks.PeakTracker`); ``None``:
        none tracked.
    sink : a :class:`~.record.Recorder` the output rows and events go to as the run goes
        (then the driver keeps none of them: :meth:`arrays` has no rows); ``None``: kept.
    turning_points : also the exact turning points (:mod:`.turns`; with ``peak_bin``).
    chained : the calls of :meth:`advance` are one run (:class:`~.stepper.Stepper`): the
        azimuth and the loads' times given from the run's start, and the exact method walks
        the pieces one call would (:class:`Method`'s ``k_org``).
    """

    def __init__(self, name: str, dt: float, x0: np.ndarray, s0: np.ndarray,
                 peak_bin: float | None = PEAK_BIN, sink=None, turning_points: bool = True,
                 chained: bool = False, **options):
        self.method = get_method(name, options)
        self.options = options
        self.dt = float(dt)
        self.x = np.array(x0, dtype=float)
        self.s = np.array(s0, dtype=bool)
        self.s0 = self.s.copy()
        self.k = 0  # output steps done
        self.segments: list[list] = []  # [k0, k1, system] with the system of each stretch
        self._X, self._S, self._events = [self.x[None]], [self.s[None]], []
        self._store = None  # (X, S) of reserve(): the output rows written in place
        self.stats: dict = {}
        self.peak_bin = peak_bin
        self.turning_points = bool(turning_points)
        self.peaks: PeakTracker | None = None  # made with the first system
        self.sink = sink
        self.chained = bool(chained)
        self.n_events = 0
        self.audits: dict = {}  # the reference methods' energy audit, continued call to call

    def reserve(self, n_steps: int) -> None:
        """Hold the run's ``n_steps`` output steps in one array written as the run goes, so
        that :meth:`arrays` needs no copy of the history (a 600 s turbine run: 0.3 GB)."""
        X = np.empty((n_steps + 1, self.x.size))
        S = np.empty((n_steps + 1, self.s.size), dtype=bool)
        k = self.k
        X[:k + 1], S[:k + 1] = np.concatenate(self._X), np.concatenate(self._S)
        self._store = (X, S)
        self._X = self._S = None

    def advance(self, system: PiecewiseLinearSystem, n_steps: int, F: np.ndarray,
                azimuth0: float = 0.0, loads=None, azimuths: np.ndarray | None = None,
                t_span: tuple | None = None) -> None:
        """Advance ``n_steps`` output steps with ``system`` and the force grid ``F``
        (``n_steps + 1`` rows), the input azimuth ``azimuth0`` (rad) at the first; ``loads``
        (times from this call's start) as :class:`Method`. ``azimuths``: the input azimuth
        at each of the ``n_steps + 1`` times, for the sink's force rows (alternating
        meshes). ``t_span``: the call's start and end times (chained; default ``k dt``)."""
        if self.peaks is None and self.peak_bin is not None:
            self.peaks = PeakTracker(system, self.peak_bin, turns=self.turning_points)
        X, S, ev, st = self.method.run(
            Stretch(system, self.dt, n_steps, F, self.x, self.s, azimuth0=azimuth0, loads=loads,
                    peaks=self.peaks, t0=self.k * self.dt if t_span is None else t_span[0],
                    k_org=self.k if self.chained else None,
                    t_span=t_span if self.chained else None, audits=self.audits),
            **self.options)
        ev = event_rows(ev)
        if not self.chained:
            ev[:, 0] += self.k * self.dt
        self._event(ev)
        if self.peaks is not None:
            self.peaks.turns.drain(self.sink, DRAIN_ROWS)
        new = not self.segments or self.segments[-1][2] is not system
        if self.sink is not None:
            a = 0 if self.k == 0 else 1  # the first call writes the initial row too
            seg_k0 = self.k if new else self.segments[-1][0]
            self.sink.rows(self.k + a, X[a:], S[a:], system, seg_k0,
                           None if azimuths is None else azimuths[a:])
        elif self._store is not None:
            if self.k + n_steps >= len(self._store[0]):
                raise ValueError(f"Driver: {self.k + n_steps} steps exceed the "
                                 f"{len(self._store[0]) - 1} reserved")
            self._store[0][self.k + 1:self.k + n_steps + 1] = X[1:]
            self._store[1][self.k + 1:self.k + n_steps + 1] = S[1:]
        else:
            self._X.append(X[1:])
            self._S.append(S[1:])
        self.x, self.s = X[-1].copy(), S[-1].copy()
        if new:
            if self.sink is not None and len(self.segments) > 1:
                # its rows are written: a stretch's system (thousands on a long turbine run,
                # 76 kB each) is not kept, but the first's (the run's structure)
                self.segments[-1][2] = None
            self.segments.append([self.k, self.k, system])
        self.k += n_steps
        self.segments[-1][1] = self.k
        for key, val in st.items():
            if key in WORST_STATS:
                self.stats[key] = max(self.stats.get(key, 0.0), float(val))
            elif isinstance(val, (int, float)):
                self.stats[key] = self.stats.get(key, 0) + val

    def rebase(self, system: PiecewiseLinearSystem, x: np.ndarray, azimuth: float) -> None:
        """Continue from state ``x`` (the reference rotation re-based: :func:`reconcile`) with
        ``system``; contacts whose state no longer matches their gap switch now, logged."""
        from . import reconcile

        events: list = []
        self.x = np.array(x, dtype=float)
        self.s = reconcile(system, self.x, self.s, self.k * self.dt, events, azimuth)
        if events:
            ev = event_rows(events)
            if self.peaks is not None and self.peaks.exact:  # the episodes it ends, begins
                for row in ev:
                    row[6:8] = self.peaks.switched(int(row[1]), row[3] > 0.5, row[5], row[0])
            self._event(ev)
        self.stats["rebase_switches"] = self.stats.get("rebase_switches", 0) + len(events)

    def _event(self, ev: np.ndarray) -> None:
        self.n_events += len(ev)
        if self.sink is not None:
            self.sink.events(ev)
        else:
            self._events.append(ev)

    def arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(X, S, events)`` of the run so far (with a sink: the rows and events went to it,
        ``X`` and ``S`` are None and no events are returned)."""
        if self.sink is not None:
            return None, None, np.empty((0, 8))
        if self._store is not None:
            X, S = self._store[0][:self.k + 1], self._store[1][:self.k + 1]
        else:
            X, S = np.concatenate(self._X), np.concatenate(self._S)
        ev = np.concatenate(self._events) if self._events else np.empty((0, 8))
        return X, S, ev


def available_memory() -> float | None:
    """Bytes of memory the machine has available (Linux ``MemAvailable``), or None."""
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return float(line.split()[1]) * 1024.0
    except OSError:
        pass
    return None


def check_fits(rows: int, values: int, advice: str, field: str = "t_end",
               what: str = "the run") -> None:
    """Refuse a run whose ``rows`` output rows of ``values`` float64 values each would not fit
    in the memory the machine has available (with the run's other arrays: taken as twice the
    rows), naming ``field``, what it would need and ``advice`` (how to reduce it)."""
    need = 2.0 * rows * values * 8.0
    have = available_memory()
    if have is not None and need > 0.8 * have:
        raise ModelError(field, f"{what} would hold {rows:,} output rows of {values} values "
                         f"in memory, about {need / 1e9:.3g} GB; this machine has "
                         f"{have / 1e9:.3g} GB available: {advice}")


def event_rows(ev) -> np.ndarray:
    """Event rows as an (n, 8) array: the six of every method, then the peak of the episode a
    row ends and its time (NaN where a method gives none)."""
    a = np.asarray(ev, dtype=float)
    if a.size == 0:
        return np.empty((0, 8))
    a = a.reshape(len(a), -1) if a.ndim == 2 else a.reshape(-1, 6)
    if a.shape[1] == 8:
        return a
    return np.hstack([a.reshape(-1, 6), np.full((len(a), 2), np.nan)])
