"""A gearbox advanced call by call: the public stepping API of a co-simulation (DESIGN 3.2).

An aeroelastic code (or any host) owns the rotor, the tower and the controller and advances
the gearbox one communication step at a time. :class:`Stepper` holds what carries over from
one call to the next (the exact state, the contact state, the input azimuth, the loads at the
call's end, the exact peaks and turning points) and walks the one integration driver
(:class:`~gearmodal.integrate.driver.Driver`) over each call::

    st = gm.Stepper(model, dt=1e-4, loads={"wheel.torque": -40.0},
                    drive=gm.Drive("pinion.theta", stiffness=2e4, damping=2.0))
    for k in range(1, 101):
        out = st.advance(k * 1e-3, drive_angle=..., drive_speed=...)   # the host's shaft
        torque = out["drive.torque"]                                      # back to the host
    result = st.result()                                                  # a SimulationResult

Inputs between calls are **ramped** (default: linear from the values at the last call's end
to the ones given for this call's end) or **held** (``hold="hold"``: the values given act over
the whole call, a step at its start). Both are integrated exactly as :func:`gearmodal.simulate`
integrates a load Series: the exact method's pieces end at the call boundaries, and a run
advanced in chunks is the run of one call with load knots there (``tests/test_stepper.py``:
events and states equal to rounding).

**Prescribed motion through a spring** (:class:`Drive`): the host's shaft angle and speed
drive one coordinate of the gearbox through a torsional spring-damper (the main shaft's
stiffness), ``T = k (angle - theta) + c (speed - theta')``, returned as ``drive.torque``: the
usual two-way coupling of a drivetrain to an aeroelastic code.

**Unbounded rotation.** Without a turning geometry the gearbox's rigid rotation (the one
motion its stiffness, damping and gaps do not see) is moved out of the state into an offset
whenever it passes :data:`REBASE_ANGLE` at a call's end: exact, since that motion changes no
force, and it keeps the state's rounding at the size of the deflections however many turns a
run makes. Angles in and out (``drive_angle``, a DOF's output, the result's ``q``) are
absolute. A turning system (frames turning against each other at ``speed_rpm``) keeps its
rotation relative to the reference rotation at ``speed_rpm`` in the state, as
:func:`gearmodal.simulate` does.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
import pandas as pd
import scipy.linalg as sla

from ..errors import ModelError, unknown
from ..model import validate as v
from ..model.model import Model
from . import (
    _initial,
    build_result,
    mesh_stiffness,
    rotating_geometry,
    stored_result,
)
from .azimuth import AzimuthAssembler
from .driver import Driver, get_method
from .peaks import PEAK_BIN
from .record import ForceMap, Recorder
from .result import SimulationResult
from .system import PiecewiseLinearSystem

__all__ = ["HOLDS", "REBASE_ANGLE", "Drive", "Stepper"]

#: how inputs act between two calls' ends
HOLDS = ("ramp", "hold")
#: rigid rotation (rad) beyond which a call's end moves it out of the state (module docstring)
REBASE_ANGLE = 2 * math.pi
#: a call's end this close to a whole number of output steps is on the grid (of ``dt``)
GRID_TOL = 1e-9


@dataclass(frozen=True)
class Drive:
    """A host's shaft driving coordinate ``dof`` (a rotation, e.g. ``"carrier.theta"``)
    through a spring ``stiffness`` (N m/rad, > 0) and damper ``damping`` (N m s/rad, >= 0): the
    torque ``T = stiffness (angle - theta) + damping (speed - theta')`` acts on the gearbox
    and is returned as the output ``drive.torque`` (the host's shaft takes ``-T``).
    ``angle0``, ``speed0``: the host's shaft at time 0 (rad, rad/s, absolute); default: the
    coordinate's own initial angle and speed (the spring relaxed)."""

    dof: str
    stiffness: float
    damping: float = 0.0
    angle0: float | None = None
    speed0: float | None = None


class Stepper:
    """A gearbox integrated one call at a time (module docstring).

    Parameters
    ----------
    model : :class:`gearmodal.Model`.
    dt : output step, s: a call's end must be a whole number of them from the start. The
        exact method's solution does not depend on it.
    loads : ``{load name: value}`` at time 0, N or N m: the loads the host sets between
        calls (:meth:`advance` refuses others) and constant ones alike.
    drive : a :class:`Drive` (or None): the host's shaft angle and speed acting through a
        spring.
    outputs : names :meth:`advance` returns at each call's end (default: every one,
        :attr:`output_names`): a DOF name (its displacement, m or rad; rotations absolute),
        ``"<DOF>.velocity"``, a force column of the result (``"ring_planet1.front"``,
        ``"carrier_bearing.x"``: N), ``"drive.torque"`` (N m).
    method, options : the integration method and its options (:func:`gearmodal.simulate`).
    speed_rpm : input speed: gyroscopic and centrifugal terms, and the input azimuth turning
        at it (a turning geometry is integrated exactly, as :func:`gearmodal.simulate` does).
    q0, v0 : initial displacements and velocities by DOF name.
    peak_bin, turning_points : as :func:`gearmodal.simulate` (the exact peaks, turning points).
    out : a directory the result's tables stream to (:func:`gearmodal.simulate`'s ``out``):
        memory stays flat however long the host runs.
    record : False: no rows, events or turning points are kept (:meth:`result` refused), only
        the state and the exact peaks: a host that reads the outputs alone (an FMU without a
        result directory) runs in constant memory.
    """

    def __init__(self, model: Model, *, dt: float, loads: dict | None = None,
                 drive: Drive | None = None, outputs: list[str] | None = None,
                 method: str = "exact", speed_rpm: float = 0.0, q0: dict | None = None,
                 v0: dict | None = None, peak_bin: float | None = PEAK_BIN,
                 turning_points: bool = True, out=None, record: bool = True, **options):
        get_method(method, options)
        if not isinstance(model, Model):
            raise TypeError(f"expected a gm.Model, got {type(model).__name__}")
        self.dt = _positive("dt", dt, "time")
        if not isinstance(speed_rpm, (int, float)) or isinstance(speed_rpm, bool) \
                or not math.isfinite(speed_rpm):
            raise ModelError("speed_rpm", f"= {speed_rpm!r}: must be a finite number (rpm)")
        v.plausible("speed_rpm", float(speed_rpm), "speed_rpm")
        if not isinstance(turning_points, bool):
            raise ModelError("turning_points", f"= {turning_points!r}: True or False")
        self.model = model
        self.omega = float(speed_rpm) * 2 * math.pi / 60
        asm = model.assemble()
        self.asm = asm
        geo = AzimuthAssembler(model) if self.omega and rotating_geometry(model) else None
        names = list(asm.load_names)
        loads = dict(loads or {})
        for name, val in loads.items():
            if name not in names:
                raise ModelError(f"loads.{name}", unknown("load", name, names))
            _number(f"loads.{name}", val)
        self.drive = drive
        cols = {names.index(nm) for nm in loads}
        grounded = ()
        if drive is not None:
            self._i_drive, j = self._drive_column(drive)
            cols.add(j)
            grounded = ((self._i_drive, float(drive.stiffness), float(drive.damping)),)
        self.columns = sorted(cols)
        self.load_index = {names[j]: i for i, j in enumerate(self.columns)}
        self.u = np.zeros(len(self.columns))
        for name, val in loads.items():
            self.u[self.load_index[name]] = float(val)
        cpu = time.process_time()
        system = PiecewiseLinearSystem(asm, speed_rpm, geometry=geo, grounded=grounded)
        system.azimuth0 = 0.0
        self.system = system
        n = asm.n
        self.n = n
        x = np.concatenate([_initial(asm, q0, "q0"), _initial(asm, v0, "v0")])
        s = system.penetration(x) > 0
        self.s_init = s.copy()
        if system.turning:  # load values through the turning load map, f_const last
            system.use_loads(self.columns)
            self._F = np.append(np.zeros(len(self.columns)), 1.0)
            self._basis = np.eye(len(self.columns) + 1, len(self.columns))
        else:
            self._basis = asm.B[:, self.columns]
            self._F = system.f_const.copy()
        # the rigid rotation moved out of the state (module docstring): the one motion no
        # stiffness, damping or gap sees; none on a turning system
        self.rigid = None if system.turning else _rigid_motion(system, grounded)
        self.offset = 0.0  # rigid rotation moved out so far, in units of ``rigid``
        self._rebases: list[tuple[int, float]] = []  # (output step, offset from then on)
        if drive is not None:
            i = self._i_drive
            ratio = self._reference_ratio(drive.dof)
            self._ref = ratio * self.omega  # the DOF's reference speed, rad/s
            a0 = x[i] if drive.angle0 is None else _number("drive.angle0", drive.angle0)
            w0 = x[n + i] + self._ref if drive.speed0 is None else _number("drive.speed0",
                                                                           drive.speed0)
            self._host = np.array([a0, w0])  # absolute
        self.sink = None
        self.record = bool(record)
        if not self.record:
            self.sink = _Discard()
        elif out is not None:
            self.sink = Recorder(out, system, self.dt, elastic=self._absolute,
                                 mesh_k=lambda sy, az: mesh_stiffness(system, az))
        self.run = Driver(method, self.dt, x, s, peak_bin=peak_bin, sink=self.sink,
                          turning_points=turning_points, chained=True, **options)
        self.fmap = ForceMap(system)
        self.settings = {"model": model.name, "method": method, "dt": self.dt,
                         "speed_rpm": speed_rpm, "peak_bin": peak_bin,
                         "turning_points": turning_points, "options": options,
                         "loads": {k: float(x) for k, x in loads.items()},
                         "drive": None if drive is None else {
                             "dof": drive.dof, "stiffness": float(drive.stiffness),
                             "damping": float(drive.damping)},
                         "stepped": True}
        self.output_names = (list(asm.dof_names) + [f"{d}.velocity" for d in asm.dof_names]
                             + list(self.fmap.labels)
                             + (["drive.torque"] if drive is not None else []))
        if outputs is None:
            outputs = self.output_names
        for name in outputs:
            if name not in self.output_names:
                raise ModelError(f"outputs.{name}", unknown("output", name,
                                                            self.output_names))
        self.outputs = list(outputs)
        self._cpu = time.process_time() - cpu
        self._done = None

    # -- the host's calls -------------------------------------------------------------------

    @property
    def time(self) -> float:
        """The time the gearbox has reached, s."""
        return self.run.k * self.dt

    def advance(self, t: float, loads: dict | None = None, *, hold: str = "ramp",
                drive_angle: float | None = None,
                drive_speed: float | None = None) -> dict[str, float]:
        """Advance to time ``t`` (s; a whole number of output steps ``dt`` from 0, after the
        time reached) and return the outputs there (:attr:`outputs`).

        ``hold``: how the inputs act over the call:

        - ``"ramp"`` (default): the values given are those at ``t``; every input is linear
          from its value at the last call's end to them. ``drive_angle``, ``drive_speed``:
          the host's shaft at ``t`` (rad, rad/s, absolute; default: the angle the last speed
          reaches, the last speed).
        - ``"hold"`` (an FMU's inputs, set at the step's start): the loads given act over the
          whole call (a step at its start); ``drive_angle``, ``drive_speed`` are the shaft at
          the call's start, turning at that speed over the call.

        ``loads``: ``{load name: value}`` for loads given at construction (others keep their
        last value).
        """
        if self._done is not None:
            raise ModelError("advance", "the run is finished: result() was called")
        if hold not in HOLDS:
            raise ModelError("hold", f"= {hold!r}: must be one of {', '.join(map(repr, HOLDS))}")
        t = _number("t", t)
        k1 = round(t / self.dt)
        if abs(k1 * self.dt - t) > GRID_TOL * max(abs(t), self.dt) or k1 <= self.run.k:
            raise ModelError("t", f"= {t!r}: must be after the time reached ({self.time!r} "
                             f"s) by a whole number of output steps dt = {self.dt!r} s")
        k0, n_steps = self.run.k, k1 - self.run.k
        span = k1 * self.dt - k0 * self.dt
        given = self.u.copy()
        for name, val in (loads or {}).items():
            if name not in self.settings["loads"]:
                raise ModelError(f"loads.{name}", unknown(
                    "load set between calls (give it at construction, loads=...)", name,
                    list(self.settings["loads"])))
            given[self.load_index[name]] = _number(f"loads.{name}", val)
        host0 = host1 = None
        if self.drive is not None:
            a0, w0 = self._host
            w1 = w0 if drive_speed is None else _number("drive_speed", drive_speed)
            if hold == "hold":  # the shaft from the given angle at the given speed
                a = a0 if drive_angle is None else _number("drive_angle", drive_angle)
                host0, host1 = (a, w1), (a + w1 * span, w1)
            else:
                a1 = (a0 + 0.5 * (w0 + w1) * span if drive_angle is None
                      else _number("drive_angle", drive_angle))
                host0, host1 = tuple(self._host), (a1, w1)
        u1 = self._load_values(k1, given, host1)
        u0 = self._load_values(k0, given if hold == "hold" else self.u, host0)
        cpu = time.process_time()
        start = u0
        # knots at the call's ends, from the run's start (k dt: as a load Series on the same
        # times gives them to one call)
        timed = (np.array([k0 * self.dt, k1 * self.dt]), np.vstack([start, u1]),
                 np.empty((0, len(u1))), np.empty(0), self._basis)
        F = np.tile(self._F, (n_steps + 1, 1))
        self.run.advance(self.system, n_steps, F, azimuth0=0.0, loads=timed,
                         azimuths=self.omega * np.arange(k0, k1 + 1) * self.dt)
        self.u = given
        if host1 is not None:
            self._host = np.array(host1)
        self._rebase()
        self._cpu += time.process_time() - cpu
        return self.values()

    def values(self) -> dict[str, float]:
        """The outputs (:attr:`outputs`) at the time reached."""
        x = self.run.x
        q, qd = self._absolute(x[None, :])
        out = dict(zip(self.asm.dof_names, q[0], strict=True))
        out.update({f"{d}.velocity": val for d, val in zip(self.asm.dof_names, qd[0],
                                                            strict=True)})
        t = self.time
        K = mesh_stiffness(self.system, np.array([self.omega * t]))
        f = self.fmap.rows(self.system, x[None, :], self.run.s[None, :], np.array([t]), K)
        out.update(zip(self.fmap.labels, f[0], strict=True))
        if self.drive is not None:
            out["drive.torque"] = self._drive_torque()
        return {name: float(out[name]) for name in self.outputs}

    @property
    def state(self) -> tuple[pd.Series, pd.Series]:
        """``(q, v)`` at the time reached, by DOF name (rotations absolute)."""
        q, qd = self._absolute(self.run.x[None, :])
        return (pd.Series(q[0], index=self.asm.dof_names, name="q"),
                pd.Series(qd[0], index=self.asm.dof_names, name="v"))

    @property
    def contact_state(self) -> pd.Series:
        """Each contact's state (True: closed) at the time reached."""
        return pd.Series(self.run.s.copy(), index=self.system.names, name="closed")

    def result(self) -> SimulationResult:
        """The run so far as a :class:`~gearmodal.SimulationResult` (the one
        :func:`gearmodal.simulate` builds: rows at every ``dt``, the event log, exact peaks
        and turning points); the run ends here."""
        if self._done is not None:
            return self._done
        if not self.record:
            raise ModelError("record", "= False: the run kept no rows; make the stepper with "
                             "record=True (or out=DIR) to build its result")
        if self.run.k == 0:
            raise ModelError("result", "nothing was run yet: call advance(t) first")
        run = self.run
        stats = {**run.stats, "cpu_s": self._cpu, "n_events": run.n_events,
                 "n_steps": run.k, "n_rebases": len(self._rebases)}
        t_end = run.k * self.dt
        settings = {**self.settings, "t_end": t_end}
        if self.sink is not None:
            self._done = stored_result(self.sink, self.system, self.s_init, stats, settings,
                                       (0.0, t_end), peaks=run.peaks)
            return self._done
        X, S, events = run.arrays()
        Q = None  # rotations absolute; the forces from the states (no rounding of the turns)
        if self._rebases:
            Q = self._absolute(X, rows=np.arange(len(X)))[0]
        t = np.arange(run.k + 1) * self.dt
        self._done = build_result([tuple(sg) for sg in run.segments], t, X, S, events,
                                  self.s_init, stats, mesh_stiffness(self.system,
                                                                     self.omega * t),
                                  settings, peaks=run.peaks, displacements=Q)
        return self._done

    # -- bookkeeping -----------------------------------------------------------------------

    def _drive_column(self, drive: Drive) -> tuple[int, int]:
        """The driven coordinate and the load column acting on it alone (its torque)."""
        asm = self.asm
        if not isinstance(drive, Drive):
            raise TypeError(f"drive: expected a gm.Drive, got {type(drive).__name__}")
        if drive.dof not in asm.dof_names:
            raise ModelError("drive.dof", unknown("DOF", drive.dof, asm.dof_names))
        _positive("drive.stiffness", drive.stiffness, "rotational_stiffness")
        c = _number("drive.damping", drive.damping)
        if c < 0:
            raise ModelError("drive.damping", f"= {c!r}: must be >= 0 N m s/rad")
        i = asm.dof_names.index(drive.dof)
        for j in range(asm.B.shape[1]):
            col = asm.B[:, j]
            if col[i] == 1.0 and np.count_nonzero(col) == 1:
                self._drive_col, self._drive_name = j, asm.load_names[j]
                return i, j
        raise ModelError("drive.dof", f"= {drive.dof!r}: no load acts on it alone (a torque "
                         "load such as 'carrier.torque'); drive a wheel's rotation")

    def _reference_ratio(self, dof: str) -> float:
        """The DOF's reference speed per input speed (its body's ``speed_ratio``), for a
        rotation; 0 for a translation."""
        body, _, coord = dof.rpartition(".")
        if coord != "theta" or body not in self.model.bodies:
            return 0.0
        return float(self.model.bodies[body].speed_ratio)

    def _load_values(self, k: int, given: np.ndarray, host) -> np.ndarray:
        """The load columns' values at output step ``k``: the loads ``given`` plus, with a
        drive, ``stiffness angle + damping speed`` of the host's shaft ``host`` (absolute)
        taken against the state's reference: the DOF's reference rotation and the rigid
        rotation moved out of the state so far (the spring's other end is in the state)."""
        u = given.copy()
        if host is not None:
            d = self.drive
            rel = host[0] - self._ref * k * self.dt - self.offset * self._rigid_i()
            u[self.load_index[self._drive_name]] += (d.stiffness * rel
                                                     + d.damping * (host[1] - self._ref))
        return u

    def _drive_torque(self) -> float:
        """The drive's torque on the gearbox now, from the state (rebased: no rounding of
        the turns made)."""
        d, n, i = self.drive, self.n, self._i_drive
        a, w = self._host
        rel = a - self._ref * self.time - self.offset * self._rigid_i()
        return d.stiffness * (rel - self.run.x[i]) + d.damping * (w - self._ref
                                                                  - self.run.x[n + i])

    def _rigid_i(self) -> float:
        return 0.0 if self.rigid is None else float(self.rigid[self._i_drive])

    def _rebase(self) -> None:
        """Move the rigid rotation out of the state at this call's end when it passed
        :data:`REBASE_ANGLE` (module docstring); the drive's load re-expressed against it."""
        if self.rigid is None:
            return
        n, r = self.n, self.rigid
        phi = float(self._Mr @ self.run.x[:n]) / self._J
        if abs(phi) <= REBASE_ANGLE:
            return
        k = self.run.k
        self.run.x[:n] -= r * phi
        self.offset += phi
        self._rebases.append((k, self.offset))

    @property
    def _Mr(self) -> np.ndarray:
        return self.asm.M @ self.rigid

    @property
    def _J(self) -> float:
        return float(self.rigid @ self._Mr)

    def _absolute(self, X: np.ndarray, rows: np.ndarray | None = None):
        """``(q, v)`` of state rows ``X`` with the rigid rotation moved out added back:
        ``rows`` their output steps (default: every row at the time reached)."""
        q = np.array(X[:, :self.n])
        if self.rigid is not None and self._rebases:
            if rows is None:
                off = np.full(len(X), self.offset)
            else:
                off = np.zeros(len(X))
                for kk, val in self._rebases:
                    off[rows > kk] = val
            q += np.outer(off, self.rigid)
        return q, X[:, self.n:]


class _Discard:
    """A driver's sink that keeps nothing (``record=False``)."""

    def rows(self, *args) -> None:
        pass

    def events(self, ev) -> None:
        pass

    def turns(self, rows, channels) -> None:
        pass


def _rigid_motion(system: PiecewiseLinearSystem, grounded) -> np.ndarray | None:
    """The one motion of a frozen system that no stiffness, damping or gap sees (a free
    drivetrain rotation), normalised to 1 on its largest rotation; None without one (or with
    several: then nothing is moved)."""
    K, C = system.K0.copy(), system.C0.copy()
    for dof, kg, cg in grounded:  # the drive's own spring does see it: taken up by the drive
        K[dof, dof] -= kg
        C[dof, dof] -= cg
    A = np.vstack([K, C, system.W])
    scale = float(np.abs(A).max(initial=0.0))
    if scale == 0.0:
        return None
    null = sla.null_space(A, rcond=1e-10)
    if null.shape[1] != 1:
        return None
    r = null[:, 0]
    return r / r[int(np.argmax(np.abs(r)))]


def _number(label: str, val) -> float:
    if not isinstance(val, (int, float, np.integer, np.floating)) or isinstance(val, bool) \
            or not math.isfinite(float(val)):
        raise ModelError(label, f"= {val!r}: must be a finite number")
    return float(val)


def _positive(label: str, val, kind: str) -> float:
    x = _number(label, val)
    if x <= 0:
        raise ModelError(label, f"= {val!r}: must be > 0")
    return x
