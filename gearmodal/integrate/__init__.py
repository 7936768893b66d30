"""Time integration of the piecewise-linear contact model: ``gm.simulate`` (DESIGN 3.2).

One function in front, one driver (:class:`~.driver.Driver`) and interchangeable methods
behind it (:mod:`.driver`):

- ``method="exact"``: event-driven exact propagation (:mod:`.exact`, :mod:`.taylor`), turning
  geometry included (:mod:`.periodic`);
- ``method="newmark"``: Newmark average acceleration, fixed step, events by interpolation
  (:mod:`.newmark`);
- ``method="scipy"``: ``scipy.integrate.solve_ivp`` with event functions (:mod:`.scipy_ref`;
  options ``scipy_method``, ``rtol``, ``atol`` pass through).
"""

from __future__ import annotations

import functools
import math
import time

import numpy as np
import pandas as pd

from ..assembly import Assembly
from ..coupling import Coupled
from ..errors import ModelError, unknown
from ..model import validate as v
from ..model.model import Model
from .azimuth import AzimuthAssembler
from .driver import METHODS, Driver, Method, check_fits, event_rows, get_method
from .loads import LOAD_DT, Harmonic, load_paths
from .peaks import PEAK_BIN, peak_table
from .record import ForceMap, Recorder, event_table
from .result import ELEMENT_COLUMNS, SimulationResult, StoredTables
from .system import PiecewiseLinearSystem
from .turns import level_table, turn_table

#: most output steps of a run (each a row of the result's tables)
MAX_STEPS = 5e7

__all__ = ["LOAD_DT", "METHODS", "PEAK_BIN", "Driver", "Harmonic", "Method", "Recorder",
           "SimulationResult", "build_result", "check_fits", "event_array", "get_method",
           "reconcile", "simulate", "stored_result"]


def _initial(asm: Assembly, values, label: str) -> np.ndarray:
    """The state's half ``label`` (``q0``/``v0``) from ``{DOF name: value}``: any mapping, a
    pandas Series indexed by DOF name (``gm.equilibrium(model, loads).q``), or None."""
    out = np.zeros(asm.n)
    if values is None:
        return out
    if isinstance(values, pd.Series):
        values = values.to_dict()
    if not hasattr(values, "items"):
        raise ModelError(label, f"expected {{DOF name: value}} (a dict, or a Series indexed "
                         f"by DOF name such as gm.equilibrium(...).q), got "
                         f"{type(values).__name__}")
    for name, val in values.items():
        if name not in asm.dof_names:
            raise ModelError(f"{label}.{name}", unknown("DOF", name, asm.dof_names))
        x = v.number(f"{label}.{name}", val, "m or rad" if label == "q0" else "m/s or rad/s")
        out[asm.dof_names.index(name)] = v.plausible(
            f"{label}.{name}", x, "displacement" if label == "q0" else "velocity")
    return out


def _settings_of(values) -> dict:
    """Initial values as the run's settings keep them (JSON: a plain dict of floats)."""
    if values is None:
        return {}
    if isinstance(values, pd.Series):
        values = values.to_dict()
    return {str(k): float(x) if isinstance(x, (int, float, np.floating)) else x
            for k, x in dict(values).items()}


def rotating_geometry(model: Model) -> bool:
    """True when the assembled matrices depend on the input azimuth: bodies in frames that turn
    against each other are connected (e.g. a carrier against a fixed housing or anisotropic
    fixed supports of a rotating body)."""
    a, b = model.assemble(0.0), model.assemble(0.7)

    def same(x, y):
        x, y = np.asarray(x), np.asarray(y)
        if x.shape != y.shape:
            return False
        return np.allclose(x, y, rtol=0, atol=1e-12 * max(np.abs(x).max(initial=0.0), 1e-300))

    if a.contacts.waves is not None and len(a.contacts.waves):
        return True  # offsets turning (run-out, transmission error)
    pairs = [(a.K, b.K), (a.C, b.C), (a.B, b.B), (a.contacts.W, b.contacts.W),
             (a.contacts.offset, b.contacts.offset)]
    for pa, pb in ((a.springs, b.springs), (a.round, b.round)):
        if pa is not None:
            pairs.append((pa.W, pb.W))
    return not all(same(x, y) for x, y in pairs)


def simulate(model, t_end: float, *, dt: float, loads: dict | None = None,
             q0: dict | None = None, v0: dict | None = None, method: str = "exact",
             speed_rpm: float = 0.0, load_dt: float = LOAD_DT,
             peak_bin: float | None = PEAK_BIN, turning_points: bool = True, out=None,
             **options) -> SimulationResult:
    """Simulate the nonlinear contact dynamics of ``model`` from 0 to ``t_end`` (s).

    Parameters
    ----------
    model : :class:`gearmodal.Model` (or an :class:`Assembly`).
    t_end : end time, s. dt : output step, s: it places the output rows; the exact method's
        solution does not depend on it (every state change inside a step is found, the loads
        keep their own time structure); for ``"newmark"`` it is the integration step too.
    loads : ``{load name: value}``, N or N m, each a constant, a :class:`gm.Harmonic
        <gearmodal.integrate.loads.Harmonic>` (integrated exactly by the exact method), a
        pandas Series indexed by time (linear between its own knots, ends held) or any other
        callable of time (sampled every ``load_dt``, linear in between). A load is fixed in
        its body's axes; a body turning against the ground carries it round.
    load_dt : sampling step of callable loads, s (default 1e-4 s, whatever ``dt`` is).
    peak_bin : width of the bins of the exact peaks, s (:meth:`SimulationResult.peaks`: a
        peak over any whole number of bins is exact); ``None``: no exact peaks (the sampled
        ones; they cost the exact method 28-30 % more CPU on the turbine runs).
    turning_points : the exact turning points of the force channels
        (:attr:`SimulationResult.turning_points`: what exact DELs count,
        :func:`gearmodal.fatigue.turning_dels`), their level changes
        (:attr:`SimulationResult.level_changes`: exact load spectra,
        :func:`gearmodal.fatigue.level_spectrum`) and the planet bearings' load integrals
        (in :attr:`SimulationResult.peak_bins`: exact ISO 281 lives,
        :func:`gearmodal.fatigue.equivalent_loads`); exact method, with ``peak_bin``. False:
        none (a run that needs no fatigue count saves their cost, 82-90 % more integration
        CPU on the 600 kW turbine runs).
    q0, v0 : initial displacements and velocities by DOF name (others 0). The initial contact
        state follows from ``q0`` (a contact is closed when it penetrates).
    out : a directory the result's tables are written to as Parquet while the run goes (as
        :meth:`SimulationResult.save` writes them); the result then reads them from there
        when first asked for. ``None``: the tables stay in memory.
    method : ``"exact"``, ``"newmark"`` or ``"scipy"``.
    speed_rpm : input speed (either sense) at which gyroscopic/centripetal terms are taken;
        the input azimuth turns at it from 0. Where frames turn against each other (a carrier
        against the housing, a rotating body on anisotropic ground supports or in a clearance
        given in ground axes) the system is time-periodic and every method integrates it as
        such: the exact method sums the series of the time-varying system and finds crossings
        of the turning gaps on it (:mod:`gearmodal.integrate.periodic`); ``"scipy"`` and
        ``"newmark"`` evaluate the matrices at each instant's (step's) azimuth.
    options : method options: ``max_events_per_step`` and ``propagator`` (``"taylor"``,
        the default, or ``"expm"``; see :func:`gearmodal.integrate.exact.run_exact`) for the
        exact method; ``scipy_method``, ``rtol``, ``atol``, ``max_events``, ``max_step``,
        ``first_step`` (scipy; the last two go to ``solve_ivp``). Any other option is refused.

    Examples
    --------
    >>> import math, gearmodal as gm
    >>> p = gm.Gear(20, 0.004, math.radians(20), mass=1.0, inertia=1e-3)
    >>> w = gm.Gear(40, 0.004, math.radians(20), mass=4.0, inertia=1.6e-2)
    >>> pair = gm.gear_pair(p, w, mesh_stiffness=2e8, backlash=1e-4)
    >>> sim = gm.simulate(pair, 0.01, dt=1e-4, v0={"pinion.theta": 1.0})
    >>> sim.events[["element", "contact", "state_after"]].head(2).values.tolist()
    [['mesh', 'front', 'closed'], ['mesh', 'front', 'open']]
    """
    get_method(method, options)  # the name and its options checked
    n_steps = _output_steps(t_end, dt, speed_rpm, load_dt)
    check = getattr(model, "check_simulation", None)
    if callable(check):  # a model that is not simulated at every speed says so
        check(speed_rpm)
    omega = float(speed_rpm) * 2 * math.pi / 60  # the input azimuth is omega t
    asm, name, casm, geo = _assembly_of(model, omega, speed_rpm)
    nc = len(asm.contacts.element) if asm.contacts is not None else 0
    check_fits(n_steps + 1, 2 * asm.n + nc + (len(asm.springs) if asm.springs is not None
                                               else 0),
               "a longer dt (with the exact method it only places the rows) or a shorter "
               "t_end")
    t = np.arange(n_steps + 1) * dt
    cpu = time.process_time()
    # the loads on their own time structure (constants, knots, harmonics), as values of the
    # load map's columns (fixed in their bodies' axes: a turning map carries them round)
    paths = load_paths(asm.load_names, loads, float(n_steps * dt), float(load_dt))
    used = paths.used()
    system = PiecewiseLinearSystem(asm, speed_rpm, geometry=geo, load_columns=used)
    if casm is None:
        x = np.concatenate([_initial(asm, q0, "q0"), _initial(asm, v0, "v0")])
    else:
        x = np.concatenate([_initial_coupled(casm, q0, "q0"), _initial_coupled(casm, v0, "v0")])
    s = system.penetration(x) > 0
    s_init = s.copy()
    part = paths.columns(used)
    if system.turning:  # loads fixed in their bodies' axes, the map turning: load values
        F = np.tile(np.append(part.constant, 1.0), (n_steps + 1, 1))  # the last: f_const
        basis = np.eye(len(used) + 1, len(used))
    else:
        basis = asm.B[:, used]
        F = np.tile(basis @ part.constant + system.f_const, (n_steps + 1, 1))
    timed = None
    if part.time_varying:  # knots and harmonics acting through the force rows ``basis``
        timed = (part.knot_t, part.knot_u, part.harmonic_u, part.harmonic_nu, basis)
    sink = None
    if out is not None:
        if casm is not None:
            raise ModelError("out", "a coupled system's run is not streamed (its constraint "
                             "forces need the whole run): simulate it, then result.save(DIR)")
        sink = Recorder(out, system, dt,
                        mesh_k=lambda sy, az: mesh_stiffness(system, az))
    if not isinstance(turning_points, bool):
        raise ModelError("turning_points", f"= {turning_points!r}: True or False")
    run = Driver(method, dt, x, s, peak_bin=peak_bin, sink=sink,
                 turning_points=turning_points, **options)
    run.advance(system, n_steps, F, azimuth0=0.0, loads=timed, azimuths=omega * t)
    X, S, events = run.arrays()
    stats = {**run.stats, "cpu_s": time.process_time() - cpu, "n_events": run.n_events,
             "n_steps": n_steps}
    settings = {"model": name, "method": method, "t_end": t_end, "dt": dt,
                "speed_rpm": speed_rpm, "load_dt": load_dt, "peak_bin": peak_bin,
                "turning_points": turning_points,
                "options": options,
                "loads": {k: (v if isinstance(v, (int, float)) else type(v).__name__)
                          for k, v in (loads or {}).items()},
                "q0": _settings_of(q0), "v0": _settings_of(v0)}
    if sink is not None:
        return stored_result(sink, system, s_init, stats, settings, (0.0, float(t[-1])),
                             peaks=run.peaks)
    result = build_result([tuple(sg) for sg in run.segments], t, X, S, events, s_init, stats,
                          mesh_stiffness(system, omega * t), settings, peaks=run.peaks)
    if casm is not None:
        _expand_coupled(result, model, casm, [(0, n_steps, system, casm, paths.values(t))], X,
                        S, speed_rpm)
    return result


def _output_steps(t_end, dt, speed_rpm, load_dt) -> int:
    """The number of output steps of a run of ``t_end`` s at ``dt``, its arguments checked
    (:func:`simulate`)."""
    for label, val in (("t_end", t_end), ("dt", dt)):
        if not isinstance(val, (int, float)) or isinstance(val, bool) or not math.isfinite(val) \
                or val <= 0:
            raise ModelError(label, f"= {val!r}: must be a finite number > 0 s")
    if not isinstance(speed_rpm, (int, float)) or isinstance(speed_rpm, bool) \
            or not math.isfinite(speed_rpm):
        raise ModelError("speed_rpm", f"= {speed_rpm!r}: must be a finite number (rpm)")
    v.plausible("speed_rpm", float(speed_rpm), "speed_rpm")
    v.plausible("t_end", float(t_end), "time")
    v.plausible("dt", float(dt), "time")
    if not isinstance(load_dt, (int, float)) or isinstance(load_dt, bool) \
            or not math.isfinite(load_dt) or load_dt <= 0:
        raise ModelError("load_dt", f"= {load_dt!r}: must be a finite number > 0 s")
    if dt > t_end:
        raise ModelError("dt", f"= {dt!r}: must be at most t_end = {t_end!r} s (the run would "
                         f"end at {dt!r} s)")
    if t_end / dt > MAX_STEPS:
        raise ModelError("dt", f"= {dt!r}: t_end / dt = {t_end / dt:.3g} output steps; at most "
                         f"{MAX_STEPS:.0e} (a longer dt, or a shorter t_end = {t_end!r} s)")
    return int(math.ceil(t_end / dt - 1e-9))


def _assembly_of(model, omega: float, speed_rpm):
    """``(assembly solved, model name, coupled assembly or None, turning geometry or None)``
    of what :func:`simulate` was given: a coupled system is solved in its constrained
    coordinates ``q = N z``; frames turning against each other at ``omega`` (rad/s) get
    their geometry's assembler."""
    casm = geo = None
    if isinstance(model, Assembly):
        asm, name = model, ""
        red, N = model.reduction()
        if N is not None:  # a coupled assembly: solved in its constrained coordinates
            casm, asm = model, red
    elif isinstance(model, (Model, Coupled)):
        asm, name = model.assemble(), model.name
        if isinstance(model, Coupled):
            casm, asm = asm, asm.reduced()
        if omega != 0.0 and rotating_geometry(model):
            if casm is not None:
                raise ModelError("speed_rpm", f"= {speed_rpm!r}: a coupled system whose frames "
                                 "turn against each other is not integrated yet (its "
                                 "constraint forces need the turning geometry too); run it at "
                                 "0 rpm or simulate the gearbox alone")
            geo = AzimuthAssembler(model)
    else:
        raise TypeError(f"expected a gm.Model or gm.Coupled, got {type(model).__name__}")
    return asm, name, casm, geo


def event_array(chunks) -> np.ndarray:
    """One (n, 8) float array of event rows from a list of arrays and single-event tuples
    (:func:`reconcile` appends tuples of 6), in the order given (:func:`.driver.event_rows`)."""
    parts = [event_rows(c) for c in chunks]
    return np.concatenate(parts) if parts else np.empty((0, 8))


def reconcile(system: PiecewiseLinearSystem, x: np.ndarray, s: np.ndarray, t: float,
              events: list, azimuth: float | None = None) -> np.ndarray:
    """Contact state after a re-basing of the reference rotation (the turbine run): the rigid
    rotation moved into the reference azimuth moves the turning gaps by second-order terms
    (angle times deflection), so a contact whose state no longer matches its penetration
    switches at time ``t`` and is logged in ``events`` (gaps and force at input azimuth
    ``azimuth``, rad, if given). Returns the new state."""
    p, r = system.penetration(x, azimuth), system.rate(x, azimuth)
    wv = system.velocity_term(x, azimuth)
    k = system.stiffness_at(azimuth) if azimuth is not None else system.k
    s = s.copy()
    for e in np.flatnonzero((p > 0) != s):
        s[e] = not s[e]
        force = k[e] * max(p[e], 0.0) + system.c[e] * wv[e] if s[e] else 0.0
        events.append((t, int(e), not s[e], bool(s[e]), float(r[e]), float(force)))
    return s


def _initial_coupled(casm, values, label: str) -> np.ndarray:
    """Independent coordinates ``z`` of initial values given in the original coordinates;
    they must satisfy the (linearised) constraints."""
    full = _initial(casm, values, label)
    z = full[casm.independent]
    miss = full - casm.expand(z)
    scale = max(np.abs(full).max(), 1e-300)
    if np.abs(miss).max() > 1e-9 * scale:
        bad = casm.dof_names[int(np.argmax(np.abs(miss)))]
        raise ModelError(label, f"violates the constraints at {bad!r}: give values that "
                         "satisfy them, e.g. only for the independent coordinates "
                         + ", ".join(casm.dof_names[i] for i in casm.independent[:8])
                         + (" ..." if len(casm.independent) > 8 else ""))
    return z


def _expand_coupled(result, model, casm, seg_systems, X, S, speed_rpm) -> None:
    """Coupled runs: states back to the original coordinates, constraint forces (the
    multipliers, from the reduced accelerations) and the exact constraint residual."""
    n = seg_systems[0][2].n
    om = float(speed_rpm) * 2 * math.pi / 60
    idx = result.q.index
    Q = casm.expand(X[:, :n])
    V = casm.expand(X[:, n:])
    LAM = np.empty((len(X), casm.Gc.shape[0]))
    for k0, k1, _system, seg_casm, U in seg_systems:
        red = seg_casm.reduced()
        Z, Zd, Ss = X[k0:k1 + 1, :n], X[k0:k1 + 1, n:], S[k0:k1 + 1]
        c = red.contacts
        K = c.stiffness
        if c.variation is not None and len(c.variation):  # alternating meshes: k(t)
            K = c.variation.table(c.stiffness, om * result.t[k0:k1 + 1], om < 0)
        Fc = np.where(Ss, K * (Z @ c.W.T - c.offset) + c.damping * (Zd @ c.W.T), 0.0)
        rhs = (U @ red.B.T + om**2 * red.f_cent - Zd @ (red.C + om * red.G).T
               - Z @ (red.K + om**2 * red.K_cent + om * red.K_speed).T - Fc @ c.W)
        Zdd = np.linalg.solve(red.M, rhs.T).T
        LAM[k0:k1 + 1] = seg_casm.multipliers(Q[k0:k1 + 1], V[k0:k1 + 1],
                                              seg_casm.expand(Zdd), U, Ss, om,
                                              contact_forces=Fc)
    result.q = pd.DataFrame(Q, index=idx, columns=casm.dof_names)
    result.v = pd.DataFrame(V, index=idx, columns=casm.dof_names)
    result.constraint_forces = pd.DataFrame(LAM, index=idx, columns=casm.constraint_names)
    if isinstance(model, Coupled):
        result.constraint_residual = model.constraint_residual(result.q)
        result.stats["max_constraint_residual"] = float(
            np.abs(result.constraint_residual.to_numpy()).max(initial=0.0))


def mesh_stiffness(system: PiecewiseLinearSystem, azimuth: np.ndarray):
    """Every contact's stiffness at the output times' input azimuths (len(t), contacts), or
    None without alternating meshes (the result's forces use it)."""
    if not system.alternating:
        return None
    return system.variation.table(system.k, azimuth, system.omega < 0)


def build_result(seg_systems, t, X, S, events, s0, stats, mesh_k, settings,
                 peaks=None, displacements=None, velocities=None) -> SimulationResult:
    """The :class:`SimulationResult` of a run: its tables are built on first read
    (:class:`_Tables`). ``events``: (n, 6 or 8) rows or a list of tuples
    (:func:`event_array`). ``mesh_k``: :func:`mesh_stiffness` of the run. ``peaks``: the run's
    :class:`~gearmodal.integrate.peaks.PeakTracker` (the exact peaks, where it has them).
    ``displacements``, ``velocities``: the ``q``, ``v`` tables' rows when they are not the
    states' halves (the stepper's absolute rotations, its rigid rotation taken out; the forces
    still come from the states)."""
    system = seg_systems[0][2]
    init = {system.names[e]: bool(s0[e]) for e in range(len(s0))}
    tables = _Tables(seg_systems, t, X, S, event_array([events]), mesh_k, displacements,
                     velocities)
    bins = turning = levels = None
    if peaks is not None:
        bins = peak_table(peaks, system.asm.contacts.columns, float(t[-1]))
        settings = {**settings, "peak_bin": peaks.bin}
        if bins is not None and peaks.turns.enabled:  # the exact kernel throughout
            tp = peaks.turns
            tp.finish(t_end=float(t[-1]))
            turning = turn_table(tp.channels, tp.rows())
            rows = tp.level_rows()
            levels = level_table(tp.channels, tp.levels, rows) if len(rows) else None
    return SimulationResult(t=t, settings=settings, initial_state=init, stats=stats,
                            tables=tables, peak_bins=bins, turning_points=turning,
                            level_changes=levels,
                            elements=functools.partial(elements_table, system.asm))


def stored_result(recorder: Recorder, system, s0, stats, settings, span,
                  peaks=None) -> SimulationResult:
    """The :class:`SimulationResult` of a run streamed to ``recorder``'s directory (closed
    here; its ``result.json`` and small tables written): its tables are read from there
    when first asked for. ``span``: the first and last output time, s."""
    if peaks is not None and peaks.exact and peaks.turns.enabled:
        peaks.turns.finish(recorder, float(span[1]))  # each channel's last value, to its table
    d = recorder.close()
    init = {system.names[e]: bool(s0[e]) for e in range(len(s0))}
    bins = None
    if peaks is not None:
        bins = peak_table(peaks, system.asm.contacts.columns, float(span[1]))
        settings = {**settings, "peak_bin": peaks.bin}
    result = SimulationResult(t=None, settings=settings, initial_state=init, stats=stats,
                              tables=StoredTables(d), stored=d, span=tuple(span),
                              peak_bins=bins, elements=elements_table(system.asm))
    result.save(d)  # the header and the small tables beside the streamed ones
    return result


def elements_table(asm: Assembly) -> pd.DataFrame:
    """One row per element with contact, spring or round-clearance rows (index ``element``):
    ``kind``, ``stage``, ``role``, ``planet`` (:attr:`SimulationResult.elements`)."""
    rows = {}
    for part in (asm.contacts, asm.springs, asm.round):
        if part is None:
            continue
        for el, kind, st, role, pl in zip(part.element, part.kind, part.stage, part.role,
                                          part.planet, strict=True):
            rows.setdefault(el, (kind, st, role, pl))
    out = pd.DataFrame(list(rows.values()), index=pd.Index(list(rows), name="element"),
                       columns=ELEMENT_COLUMNS, dtype=object)
    return out.astype(str)


class _Tables:
    """Builds a run's tables from its arrays (:class:`SimulationResult` asks for each when it is
    first read): ``q``, ``v``, ``forces``, ``events``, ``contact_state``."""

    def __init__(self, seg_systems, t, X, S, events: np.ndarray, mesh_k=None,
                 displacements=None, velocities=None):
        self.seg_systems, self.t, self.X, self.S, self.ev = seg_systems, t, X, S, events
        self.Q, self.V = displacements, velocities
        self.mesh_k = mesh_k
        self.system = seg_systems[0][2]
        self._index = None
        self.force_arrays = None
        if len(seg_systems) > 1:
            # a refrozen run: its segments' systems (thousands on the turbine) are not kept
            # alive by the result; the force values are computed now, the table when read
            self.force_arrays = self._force_arrays()
            self.seg_systems = None

    def __call__(self, name: str) -> pd.DataFrame:
        return getattr(self, name)()

    @property
    def index(self) -> pd.Index:
        """The tables' time index (built with the first table: a run need not pay for it)."""
        if self._index is None:
            self._index = pd.Index(self.t, name="time")
        return self._index

    def q(self) -> pd.DataFrame:
        sy = self.system
        # a view of the run's array (copy-on-write keeps it safe): not a second copy
        Q = self.X[:, :sy.n] if self.Q is None else self.Q
        return pd.DataFrame(Q, index=self.index, columns=sy.asm.dof_names, copy=False)

    def v(self) -> pd.DataFrame:
        sy = self.system
        V = self.X[:, sy.n:] if self.V is None else self.V
        return pd.DataFrame(V, index=self.index, columns=sy.asm.dof_names, copy=False)

    def contact_state(self) -> pd.DataFrame:
        return pd.DataFrame(self.S, index=self.index, columns=self.system.names)

    def events(self) -> pd.DataFrame:
        return event_table(self.system, self.ev)

    def forces(self) -> pd.DataFrame:
        data, labels = self.force_arrays or self._force_arrays()
        return pd.DataFrame(data, index=self.index, columns=labels)

    def _force_arrays(self) -> tuple[np.ndarray, list[str]]:
        """The force table's values and labels, built segment by segment into the one output
        array (no temporaries of the run's length: a 600 s turbine run has 600 001 rows)."""
        fmap = ForceMap(self.system)
        t = self.t
        out = np.empty((len(t), len(fmap.labels)))
        for k0, k1, sy in self.seg_systems:  # each segment with its geometry (turning: exact)
            # a segment's rows after its first: the row where a re-basing starts it holds the
            # state before the re-basing, the last of the stretch before (as the driver's
            # sink writes it)
            a = k0 + 1 if k0 > 0 else 0
            sl = slice(a, k1 + 1)
            K = None if self.mesh_k is None else self.mesh_k[sl]
            fmap.rows(sy, self.X[sl], self.S[sl], t[sl] - t[k0], K, out=out[sl])
        return out, fmap.labels
