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
events and states equal to rounding), but for a curved :class:`SpeedTorque` without
``rebase_dt`` (linearised anew at each call's start).

**Prescribed motion through a spring** (:class:`Drive`): the host's shaft angle and speed
drive one coordinate of the gearbox through a torsional spring-damper (the main shaft's
stiffness), ``T = k (angle - theta) + c (speed - theta')``, returned as ``drive.torque``: the
usual two-way coupling of a drivetrain to an aeroelastic code.

**The reference rotation.** The state is the deflection from a rigid reference rotation of
the drivetrain: the input azimuth ``psi(t)``, every wheel at its ``speed_ratio`` times it.

- ``reference="fixed"`` (default): ``psi = omega t`` at ``speed_rpm``, as
  :func:`gearmodal.simulate` takes it (a run chopped into calls is then one call's run, but
  for a curved :class:`SpeedTorque` without ``rebase_dt``). Without
  a turning geometry the gearbox's rigid rotation (the one motion its stiffness, damping and
  gaps do not see) is moved out of the state into an offset whenever it passes
  :data:`REBASE_ANGLE` at a call's end: exact, since that motion changes no force, and it keeps
  the state's rounding at the size of the deflections however many turns a run makes.
- ``reference="follow"``: the reference follows the drivetrain, as the turbine run's does
  (:mod:`gearmodal.turbine.drivetrain`): at a call's end (taken at the next call's start, so
  that a call's outputs are the state it reached) where the drivetrain's speed has left
  the reference speed by ``rebase_speed`` of it, or its rigid rotation the reference by
  ``rebase_angle``, the reference speed becomes the drivetrain's plus ``phi / REBASE_TAU``
  (the azimuth stays continuous: no jump of the turning geometry), the speed terms are taken
  at it and the velocities re-expressed against it; a contact whose state no longer matches
  its gap switches there, logged. What a host driving a planetary stage through its shaft at a
  varying speed needs: the geometry turns with the carrier. With ``rebase_dt`` it re-bases
  only every ``rebase_dt`` from the start (a call is split there), so that the run does not
  depend on where the calls end, and the times on that grid are whole multiples of
  ``rebase_dt``, so that it does not depend on ``dt`` either (``dt`` only places the rows).
  The state is then the deflection from the drivetrain's rigid rotation; the ``speed_rpm``
  given is the reference's at the start (the result's settings: ``speed0_rpm``).

Angles and speeds out (a rotation DOF's output) are absolute: the wheel's reference rotation
plus its deflection.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import pandas as pd
import scipy.linalg as sla

from ..errors import ModelError, SolveError, unknown
from ..massscale import scaled_mass
from ..model import validate as v
from ..model.model import Model
from ..static import equilibrium
from . import (
    _initial,
    build_result,
    mesh_stiffness,
    rotating_geometry,
    stored_result,
)
from .azimuth import AzimuthAssembler
from .driver import Driver, check_fits, get_method
from .exact import shared_bounds
from .peaks import PEAK_BIN
from .record import ForceMap, Recorder
from .result import SimulationResult
from .rigid import elastic
from .system import RPM, PiecewiseLinearSystem

__all__ = ["HOLDS", "REBASE_ANGLE", "Drive", "SpeedTorque", "Stepper"]

#: how inputs act between two calls' ends
HOLDS = ("ramp", "hold")
#: how the reference rotation moves (module docstring)
REFERENCES = ("fixed", "follow")
#: time (s) over which a re-based reference speed takes up the rigid rotation left in the state
#: (``reference="follow"``; the turbine run's value)
REBASE_TAU = 0.1
#: rigid rotation (rad) beyond which a call's end moves it out of the state (module docstring)
REBASE_ANGLE = 2 * math.pi
#: bytes below which a call's arrays are not checked against the memory available
SIZE_CHECKED = 1e8
#: a call's end this close to a whole number of output steps is on the grid (of ``dt``)
GRID_TOL = 1e-9
#: a state entry beyond this (m, rad, m/s, rad/s of deflection from the reference rotation)
#: means the integration method diverged
DIVERGED = 1e6


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


@dataclass(frozen=True)
class SpeedTorque:
    """A torque on rotation ``dof`` that depends on its speed: ``law(speed)`` returns the
    torque on the DOF (N m, in its positive sense) and its derivative by the speed (N m s/rad)
    at ``speed`` (rad/s, absolute). An induction generator's torque-slip curve is one: its
    slip damping is stiff, so the stepper takes it **implicitly**, linearised: over a stretch
    (a call; with ``rebase_dt``, a stretch of that grid, calls split there) that starts at the
    DOF's speed ``w_k``, ``law(w_k) + law'(w_t) (w - w_k)``, a constant torque (exact at the
    stretch's start) and a damper ``-law'(w_t)`` in the equations. The slope is the law's at
    ``w_t``, the DOF's speed when the tangent was last taken: at the start (the reference
    speed), at every re-basing (``reference="follow"``), at
    :meth:`Stepper.set_speed_torque`, and wherever the speed has left ``w_t`` by
    ``rebase_speed`` of it and the slope has changed (a new system; the slope's change acts
    explicitly over a stretch, so it is kept to that of such a drift). A linear law is taken
    exactly; a curved one converges with the stretch, to second order
    (``tests/test_stepper.py``; on the 600 kW turbine, ``benchmarks/RESULTS.md``, "The
    generator's tangent"). A run chopped into calls between the points of ``rebase_dt``'s
    grid is then the run of one call per point; without ``rebase_dt`` it depends on the
    calls through this linearisation only.
    """

    dof: str
    law: object


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
    q0, v0 : initial displacements and velocities by DOF name. ``q0="equilibrium"``: the
        static equilibrium under the loads at time 0 (the speed torque's included) at
        ``azimuth0`` and ``speed_rpm``; a drivetrain free to turn (one rigid rotation) is
        taken accelerating rigidly under them, so that the teeth take up the first torque
        without an impact (:meth:`_equilibrium`).
    peak_bin, turning_points : as :func:`gearmodal.simulate` (the exact peaks, turning points).
    out : a directory the result's tables stream to (:func:`gearmodal.simulate`'s ``out``):
        memory stays flat however long the host runs.
    record : False: no rows, events or turning points are kept (:meth:`result` refused), only
        the state and the exact peaks: a host that reads the outputs alone (an FMU without a
        result directory) runs in constant memory.
    reference : ``"fixed"`` or ``"follow"`` (module docstring); ``rebase_speed`` (relative)
        and ``rebase_angle`` (rad): when ``"follow"`` re-bases (``rebase_speed`` also: where
        a speed torque's tangent is taken anew); ``rebase_dt`` (s): where it may, and where a
        speed torque is taken anew, every ``rebase_dt`` from the start (the calls split there,
        their inputs linear across), so that the run does not depend on the call ends; None:
        at every call's end
        (then it does, at the level of the re-basing).
    azimuth0 : the input azimuth at time 0, rad (a turning geometry's start; the reference
        rotation's origin).
    speed_torque : a :class:`SpeedTorque` (a generator), linearised at each stretch's start
        (its docstring).
    top_frequency_hz : the mass-scaling rung (:mod:`gearmodal.massscale`): the modes above
        this frequency slowed to it by added mass along them; ``None``: the full model.
    """

    def __init__(self, model: Model, *, dt: float, loads: dict | None = None,
                 drive: Drive | None = None, outputs: list[str] | None = None,
                 method: str = "exact", speed_rpm: float = 0.0, q0: dict | None = None,
                 v0: dict | None = None, peak_bin: float | None = PEAK_BIN,
                 turning_points: bool = True, out=None, record: bool = True,
                 reference: str = "fixed", rebase_speed: float = 0.01,
                 rebase_angle: float = 5e-4, rebase_dt: float | None = None,
                 azimuth0: float = 0.0, speed_torque: SpeedTorque | None = None,
                 top_frequency_hz: float | None = None, **options):
        get_method(method, options)
        self._reference_settings(reference, rebase_speed, rebase_angle, rebase_dt, dt)
        if not isinstance(model, Model):
            raise TypeError(f"expected a gm.Model, got {type(model).__name__}")
        self.dt = _positive("dt", dt)
        if not isinstance(speed_rpm, (int, float)) or isinstance(speed_rpm, bool) \
                or not math.isfinite(speed_rpm):
            raise ModelError("speed_rpm", f"= {speed_rpm!r}: must be a finite number (rpm)")
        v.plausible("speed_rpm", float(speed_rpm), "speed_rpm")
        if not isinstance(turning_points, bool):
            raise ModelError("turning_points", f"= {turning_points!r}: True or False")
        self.model = model
        self.omega = float(speed_rpm) * 2 * math.pi / 60
        psi0 = _number("azimuth0", azimuth0)
        turns = rotating_geometry(model) if (self.omega or self.follow) else False
        geo = AzimuthAssembler(model) if (turns or top_frequency_hz is not None) else None
        self.mass_scaling = None
        if top_frequency_hz is not None:
            Ms, self.mass_scaling = scaled_mass(geo, top_frequency_hz)
            geo = geo.with_mass(Ms)
        asm = model.assemble() if geo is None else geo.template
        self.asm = asm
        self.geo = geo if turns else None
        loads = dict(loads or {})
        grounded = self._inputs(asm, loads, drive, speed_torque)
        # every rotation's reference speed per input speed (its body's speed_ratio)
        self.ratio = np.array([self._reference_ratio(d) for d in asm.dof_names])
        self.ref = _Reference(self.omega, psi0)
        self.rigid = None
        if self.follow:  # the drivetrain's rigid rotation, per input speed
            self.rigid = self._follow_motion(asm)
        self._drive_grounded = grounded
        self._tau = 0.0  # the speed torque's constant part, N m
        grounded = self._grounded()
        cpu = time.process_time()
        system = PiecewiseLinearSystem(asm, speed_rpm, geometry=self.geo, grounded=grounded,
                                       load_columns=self.columns, azimuth0=psi0)
        self.system = system
        self.grounded = grounded
        self._om_rho = self.omega  # the speed of the last full spectral bound (follow)
        n = asm.n
        self.n = n
        if isinstance(q0, str):
            if q0 != "equilibrium":
                raise ModelError("q0", f"= {q0!r}: {{DOF name: value}} or 'equilibrium'")
            if drive is not None:
                raise ModelError("q0", "= 'equilibrium' with a drive: give q0 (the drive's "
                                 "spring holds the state where the host's shaft is)")
            q0 = self._equilibrium(psi0, float(speed_rpm))
        x = np.concatenate([_initial(asm, q0, "q0"), _initial(asm, v0, "v0")])
        s = system.penetration(x, psi0) > 0
        self.s_init = s.copy()
        if system.turning:  # load values through the turning load map, f_const last
            self._F = np.append(np.zeros(len(self.columns)), 1.0)
            self._basis = np.eye(len(self.columns) + 1, len(self.columns))
        else:
            self._basis = asm.B[:, self.columns]
            self._F = system.f_const.copy()
        # fixed: the rigid rotation moved out of the state (module docstring), the one motion
        # no stiffness, damping or gap sees; none on a turning system
        if not self.follow and not system.turning:
            self.rigid = _rigid_motion(asm.M, system.K0, system.C0, system.W, system.k,
                                       grounded)
        if self.rigid is not None:  # its mass-weighted row and inertia, for its share of x
            self._Mr = asm.M @ self.rigid
            self._J = float(self.rigid @ self._Mr)
        self.offset = 0.0  # rigid rotation moved out so far, in units of ``rigid``
        self._rebases: list[tuple[int, float]] = []  # (output step, offset from then on)
        if drive is not None:
            i = self._i_drive
            a0 = x[i] if drive.angle0 is None else _number("drive.angle0", drive.angle0)
            w0 = (x[n + i] + self.ratio[i] * self.omega if drive.speed0 is None
                  else _number("drive.speed0", drive.speed0))
            self._host = np.array([a0, w0])  # absolute
        self.sink = None
        self.record = bool(record)
        if not self.record:
            self.sink = _Discard()
        elif out is not None:
            self.sink = Recorder(out, system, self.dt, elastic=self._tables,
                                 mesh_k=lambda sy, az: mesh_stiffness(system, az))
        self.run = Driver(method, self.dt, x, s, peak_bin=peak_bin, sink=self.sink,
                          turning_points=turning_points, chained=True, **options)
        self.fmap = ForceMap(system)
        self.settings = {"model": model.name, "method": method, "dt": self.dt,
                         "speed_rpm": None if self.follow else speed_rpm,
                         "speed0_rpm": speed_rpm, "peak_bin": peak_bin,
                         "turning_points": turning_points, "options": options,
                         "loads": {k: float(x) for k, x in loads.items()},
                         "drive": None if drive is None else {
                             "dof": drive.dof, "stiffness": float(drive.stiffness),
                             "damping": float(drive.damping)},
                         "reference": reference, "stepped": True,
                         "azimuth0": psi0, "top_frequency_hz": top_frequency_hz,
                         "mass_scaling": self.mass_scaling}
        if self.follow or self.speed_torque is not None:
            self.settings["rebase_speed"] = self.rebase_speed
        if self.follow:
            self.settings["rebase_angle"] = self.rebase_angle
        if self.rebase_steps:
            self.settings["rebase_dt"] = self._rebase_dt
        self._outputs(asm, outputs, drive)
        self._qv_names = self.output_names[:2 * len(asm.dof_names)]  # q, then velocities
        self._force_rebase = False  # set_speed_torque: re-base at the next call's start
        self._tangents = 0  # the speed torque's tangents taken anew (_retake_torque)
        self._t_sys = 0.0  # the time the system was made at: its turning geometry's zero
        self._reserved = None  # reserve(): the output steps held
        self._cpu = time.process_time() - cpu
        self._done = None

    def _reference_settings(self, reference, rebase_speed, rebase_angle, rebase_dt,
                            dt) -> None:
        """``reference`` and its re-basing settings, checked (:class:`Stepper`)."""
        if reference not in REFERENCES:
            raise ModelError("reference", f"= {reference!r}: must be one of "
                             + ", ".join(map(repr, REFERENCES)))
        self.follow = reference == "follow"
        self.rebase_speed = _positive("rebase_speed", rebase_speed)
        self.rebase_angle = _positive("rebase_angle", rebase_angle)
        self.rebase_steps = 0  # "follow" may re-base at every call's end
        if rebase_dt is not None:
            self._rebase_dt = _positive("rebase_dt", rebase_dt)
            self.rebase_steps = round(self._rebase_dt / float(dt))
            if self.rebase_steps < 1 or abs(self.rebase_steps * dt - rebase_dt) \
                    > GRID_TOL * rebase_dt:
                raise ModelError("rebase_dt", f"= {rebase_dt!r}: must be a whole number of "
                                 f"output steps dt = {dt!r} s")

    def _inputs(self, asm, loads: dict, drive, speed_torque) -> tuple:
        """The load columns the host sets (``loads``, the drive's and the speed torque's),
        checked; returns the drive's grounded spring (:class:`Stepper`)."""
        names = list(asm.load_names)
        for name, val in loads.items():
            if name not in names:
                raise ModelError(f"loads.{name}", unknown("load", name, names))
            _number(f"loads.{name}", val)
        self.drive = drive
        cols = {names.index(nm) for nm in loads}
        grounded = ()
        if drive is not None:
            if not isinstance(drive, Drive):
                raise TypeError(f"drive: expected a gm.Drive, got {type(drive).__name__}")
            self._i_drive, j = self._torque_column(drive.dof, "drive")
            cols.add(j)
            self._drive_name = names[j]
            _positive("drive.stiffness", drive.stiffness)
            c = _number("drive.damping", drive.damping)
            if c < 0:
                raise ModelError("drive.damping", f"= {c!r}: must be >= 0 N m s/rad")
            grounded = ((self._i_drive, float(drive.stiffness), float(drive.damping)),)
        self.speed_torque = None
        if speed_torque is not None:
            self._check_speed_torque(speed_torque)
            i, j = self._torque_column(speed_torque.dof, "speed_torque")
            self._st_index = (i, j)
            cols.add(j)
            self.speed_torque = speed_torque
        self.columns = sorted(cols)
        self.load_index = {names[j]: i for i, j in enumerate(self.columns)}
        self.u = np.zeros(len(self.columns))
        for name, val in loads.items():
            self.u[self.load_index[name]] = float(val)
        return grounded

    def _outputs(self, asm, outputs, drive) -> None:
        """The outputs a call returns (:attr:`outputs`; default every one), checked."""
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
        # the force rows cost a mesh stiffness and a force map per call: only when asked for
        self._forces = any(name in self.fmap.labels for name in self.outputs)

    @classmethod
    def from_scene(cls, scene, **kwargs) -> Stepper:
        """A stepper of a gearbox scene (:func:`gearmodal.scene.load_scene`): its model,
        ``dt``, method and options, ``speed_rpm`` and initial state (``start = "equilibrium"``
        included); its loads' values at time 0 as the loads the host sets from then on (a
        wave or series is the host's to follow). ``kwargs`` (``drive``, ``outputs``,
        ``reference``...) go to the stepper and override the scene's
        (:meth:`gearmodal.scene.Scene.stepper_settings`: the scene knows its own fields)."""
        try:
            settings = scene.stepper_settings
        except AttributeError:
            raise TypeError(f"expected a gearmodal.scene.Scene, got "
                            f"{type(scene).__name__}") from None
        return cls(scene.model, **{**settings(), **kwargs})

    # -- the host's calls -------------------------------------------------------------------

    @property
    def time(self) -> float:
        """The time the gearbox has reached, s."""
        return self._t(self.run.k)

    def _t(self, k: int) -> float:
        """The run's time at output step ``k``: ``k dt``; with ``rebase_dt``, the whole
        re-basing steps in ``rebase_dt`` and the rest in ``dt``, so that the times on the
        re-basing grid (a turbine's aerodynamic steps, where its calls end) and with them the
        pieces do not depend on ``dt`` (``dt`` only places the rows)."""
        if not self.rebase_steps:
            return k * self.dt
        q, r = divmod(k, self.rebase_steps)
        return q * self._rebase_dt + r * self.dt if r else q * self._rebase_dt

    def advance(self, t: float, loads: dict | None = None, *, hold: str = "ramp",
                start: dict | None = None, drive_angle: float | None = None,
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
        last value). ``start`` (with ``"ramp"``): values of some of them at the call's start
        instead of at the last call's end (a step there, then the ramp to ``loads``: a host
        extrapolating its last samples).
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
        k0 = self.run.k
        self._check_size(t, k0, k1)
        if self._reserved is not None and k1 > self._reserved:
            raise ModelError("t", f"= {t!r}: beyond the rows reserved (reserve(t_end) up to "
                             f"{self._t(self._reserved)!r} s)")
        span = self._t(k1) - self._t(k0)
        given = self._given(self.u, loads, "loads")
        if start is not None and hold != "ramp":
            raise ModelError("start", "is the loads at a ramp's start: give it with "
                             "hold='ramp'")
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
        # the given loads at the call's start
        g0 = given if hold == "hold" else self._given(self.u, start, "start")
        cpu = time.process_time()
        # the call's stretches: to each point of the re-basing grid inside it (where
        # "follow" may re-base and a speed torque is taken anew), then its end
        ends = [k1]
        if self.rebase_steps and (self.follow or self.speed_torque is not None):
            m = self.rebase_steps
            ends = list(range((k0 // m + 1) * m, k1, m)) + [k1]
        ka = k0
        for kb in ends:
            on_grid = not self.rebase_steps or ka % self.rebase_steps == 0
            if self._force_rebase or (ka and self.follow and on_grid):
                self._follow(force=self._force_rebase)
            if self.speed_torque is not None and on_grid:
                self._retake_torque()
            # the inputs linear over the call (its ends' values exactly at its ends)
            ga, ha = _between(ka, k0, k1, g0, given), _between(ka, k0, k1, host0, host1)
            gb, hb = _between(kb, k0, k1, g0, given), _between(kb, k0, k1, host0, host1)
            ua, ub = self._load_values(ka, ga, ha), self._load_values(kb, gb, hb)
            # knots at the stretch's ends, from the run's start (_t(k): k dt as a load Series
            # on the same times gives them to one call, or on the re-basing grid)
            ta, tb = self._t(ka), self._t(kb)
            timed = (np.array([ta, tb]), np.vstack([ua, ub]),
                     np.empty((0, len(ub))), np.empty(0), self._basis)
            F = np.tile(self._F, (kb - ka + 1, 1))
            self.run.advance(self.system, kb - ka, F, azimuth0=self.ref.origin(), loads=timed,
                             azimuths=self.ref.at(np.arange(ka, kb + 1) * self.dt),
                             t_span=(ta, tb) if self.rebase_steps else None)
            self._diverged(kb)
            ka = kb
        self.u = given
        if host1 is not None:
            self._host = np.array(host1)
        if not self.follow:
            self._rebase()
        self._cpu += time.process_time() - cpu
        return self.values()

    def _check_size(self, t: float, k0: int, k1: int) -> None:
        """Refuse (naming the size) a call whose arrays would not fit in memory before they
        are made: the call's state rows, force grid and azimuths, and the history when the
        rows are kept in memory (``record=True`` without ``out``)."""
        n_c = len(self.asm.contacts.element)
        n_sp = len(self.asm.springs) if self.asm.springs is not None else 0
        if (k1 + 1) * (4 * self.n + n_c + n_sp + self._F.size + 1) * 16 < SIZE_CHECKED:
            return  # a host's usual call: no need to ask the machine (a file read per call)
        advice = ("advance in shorter calls (the host's communication step) or take a longer "
                  "dt")
        check_fits(k1 - k0 + 1, 2 * self.n + n_c + self._F.size + 1, advice, field="t",
                   what=f"advancing to t = {t!r} s ({k1 - k0:,} output steps in one call)")
        if self.record and self.sink is None and self._reserved is None:
            check_fits(k1 + 1, 4 * self.n + n_c + n_sp, "give out=DIR (the rows go to disk as "
                       "the run goes), record=False, a longer dt or a shorter run", field="t",
                       what=f"advancing to t = {t!r} s with the rows kept (record=True)")

    def values(self) -> dict[str, float]:
        """The outputs (:attr:`outputs`) at the time reached."""
        x = self.run.x
        q, qd = self._absolute(x[None, :])
        # rotations absolute: the reference rotation at each wheel's ratio added
        q = q[0] + self.ratio * self.ref.at(self.time)
        qd = qd[0] + self.ratio * self.ref.om_f
        out = dict(zip(self._qv_names, np.concatenate([q, qd]).tolist(), strict=True))
        t = self.time
        if self._forces:
            K = mesh_stiffness(self.system, np.array([self.ref.at(t)]))
            f = self.fmap.rows(self.system, x[None, :], self.run.s[None, :],
                               np.array([t - self._t_sys]), K)
            out.update(zip(self.fmap.labels, f[0].tolist(), strict=True))
        if self.drive is not None:
            out["drive.torque"] = float(self._drive_torque())
        return {name: out[name] for name in self.outputs}

    @property
    def state(self) -> tuple[pd.Series, pd.Series]:
        """``(q, v)`` at the time reached, by DOF name: the result's last row (deflections from
        the reference rotation; ``"follow"``: the rigid rotation taken out, as the turbine's
        tables)."""
        q, qd = self._tables(self.run.x[None, :])
        return (pd.Series(q[0], index=self.asm.dof_names, name="q"),
                pd.Series(qd[0], index=self.asm.dof_names, name="v"))

    @property
    def contact_state(self) -> pd.Series:
        """Each contact's state (True: closed) at the time reached."""
        return pd.Series(self.run.s.copy(), index=self.system.names, name="closed")

    def reserve(self, t_end: float) -> None:
        """Hold the rows up to ``t_end`` (s) in one array written as the run goes, so that
        :meth:`result` needs no copy of the history; refuses (naming the memory) a run whose
        rows would not fit. Nothing to do when the rows stream to ``out`` or are not kept."""
        if self.sink is not None:
            return
        if self._reserved is not None:
            raise ModelError("reserve", f"was called already (up to step {self._reserved})")
        n_steps = round(_positive("t_end", t_end) / self.dt)
        if n_steps <= self.run.k:
            raise ModelError("t_end", f"= {t_end!r}: must be after the time reached "
                             f"({self.time!r} s); reserve the run's end")
        nsp = len(self.asm.springs) if self.asm.springs is not None else 0
        check_fits(n_steps + 1, 4 * self.n + len(self.asm.contacts.element) + nsp,
                   "give out=DIR (the rows go to disk as the run goes; gearmodal simulate "
                   "does), a longer dt or a shorter t_end")
        self.run.reserve(n_steps)
        self._reserved = n_steps

    def set_speed_torque(self, speed_torque: SpeedTorque) -> None:
        """Replace the speed-dependent torque (same DOF; a generator switched onto the grid)
        from the time reached: the reference is re-based at the next call's start (before the
        first call: now), its tangent taken there and the spectral bounds anew. With
        ``rebase_dt``, call it at a call end on the re-basing grid: elsewhere the run then
        re-bases where the call ends (and depends on it)."""
        if self.speed_torque is None:
            raise ModelError("speed_torque", "the stepper was made without one: give "
                             "speed_torque= at construction")
        self._check_speed_torque(speed_torque)
        if speed_torque.dof != self.speed_torque.dof:
            raise ModelError("speed_torque.dof", f"= {speed_torque.dof!r}: the stepper's is "
                             f"{self.speed_torque.dof!r}")
        self.speed_torque = speed_torque
        self._force_rebase = True
        if self.run.k == 0:  # the start's system made anew (nothing integrated with it yet)
            self._follow(force=True, move=False)

    def result(self, settings: dict | None = None,
               stats: dict | None = None) -> SimulationResult:
        """The run so far as a :class:`~gearmodal.SimulationResult` (the one
        :func:`gearmodal.simulate` builds: rows at every ``dt``, the event log, exact peaks
        and turning points); the run ends here. ``settings``, ``stats``: entries added to the
        result's (a host's own: its plant, its clock)."""
        if self._done is not None:
            return self._done
        if not self.record:
            raise ModelError("record", "= False: the run kept no rows; make the stepper with "
                             "record=True (or out=DIR) to build its result")
        if self.run.k == 0:
            raise ModelError("result", "nothing was run yet: call advance(t) first")
        run = self.run
        stats = {**run.stats, "cpu_s": self._cpu, "n_events": run.n_events,
                 "n_steps": run.k,
                 "n_rebases": len(self.ref.stretches) - 1 if self.follow else len(self._rebases),
                 "speed_torque_tangents": self._tangents,
                 **(stats or {})}
        t_end = self._t(run.k)
        settings = {**self.settings, "t_end": t_end, **(settings or {})}
        if self.sink is not None:
            self._done = stored_result(self.sink, self.system, self.s_init, stats, settings,
                                       (0.0, t_end), peaks=run.peaks)
            return self._done
        X, S, events = run.arrays()
        Q = V = None  # the tables' rows; the forces from the states (no rounding of turns)
        if self.follow:
            Q, V = self._tables(X)
        elif self._rebases:
            Q = self._absolute(X, rows=np.arange(len(X)))[0]
        t = np.arange(run.k + 1) * self.dt
        az = self.ref.grid(run.k, self.dt)
        self._done = build_result([tuple(sg) for sg in run.segments], t, X, S, events,
                                  self.s_init, stats,
                                  mesh_stiffness(run.segments[0][2] or self.system, az),
                                  settings, peaks=run.peaks, displacements=Q, velocities=V)
        return self._done

    # -- bookkeeping -----------------------------------------------------------------------

    def _torque_column(self, dof: str, label: str) -> tuple[int, int]:
        """Coordinate ``dof`` and the load column acting on it alone (its torque)."""
        asm = self.asm
        if not isinstance(dof, str) or dof not in asm.dof_names:
            raise ModelError(f"{label}.dof", unknown("DOF", dof, asm.dof_names))
        i = asm.dof_names.index(dof)
        for j in range(asm.B.shape[1]):
            col = asm.B[:, j]
            if col[i] == 1.0 and np.count_nonzero(col) == 1:
                return i, j
        raise ModelError(f"{label}.dof", f"= {dof!r}: no load acts on it alone (a torque "
                         "load such as 'carrier.torque'); give a wheel's rotation")

    @staticmethod
    def _check_speed_torque(speed_torque) -> None:
        if not isinstance(speed_torque, SpeedTorque):
            raise TypeError(f"speed_torque: expected a gm.SpeedTorque, got "
                            f"{type(speed_torque).__name__}")
        if not callable(speed_torque.law):
            raise ModelError("speed_torque.law", f"= {speed_torque.law!r}: must be a function "
                             "of the speed returning (torque, dtorque/dspeed)")

    def _given(self, u: np.ndarray, loads: dict | None, label: str) -> np.ndarray:
        """Load values ``u`` with the host's ``loads`` (by name) put in."""
        out = u.copy()
        if loads is not None and not isinstance(loads, Mapping):
            raise ModelError(label, f"expected {{load name: value}} (a dict), got "
                             f"{type(loads).__name__} {loads!r:.60}")
        for name, val in (loads or {}).items():
            if name not in self.settings["loads"]:
                raise ModelError(f"{label}.{name}", unknown(
                    "load set between calls (give it at construction, loads=...)", name,
                    list(self.settings["loads"])))
            out[self.load_index[name]] = _number(f"{label}.{name}", val)
        return out

    def _equilibrium(self, psi0: float, speed_rpm: float) -> dict:
        """``q0="equilibrium"``: the static equilibrium (:func:`gearmodal.equilibrium`) under
        the loads at time 0 at input azimuth ``psi0``. A drivetrain with one free rigid
        rotation ``r`` cannot be in equilibrium under a net torque: it is taken accelerating
        rigidly, the d'Alembert force ``-M r alpha`` added with ``alpha = r^T F / r^T M r``
        (together the loads do no work on ``r``), and the rigid rotation taken out of the
        result."""
        asm = self.geo.assemble(psi0) if self.geo is not None else self.asm
        loads = {asm.load_names[j]: float(u) for j, u in
                 zip(self.columns, self._load_values(0, self.u, None), strict=True)}
        r = self.rigid if self.rigid is not None else _rigid_motion(
            asm.M, asm.K, asm.C, asm.contacts.W, asm.contacts.stiffness, damped=False)
        if r is None:
            q = equilibrium(asm, loads, speed_rpm).q.to_numpy()
        else:
            Mr = asm.M @ r
            alpha = float(r @ asm.load_vector(loads)) / float(r @ Mr)
            ext = dataclasses.replace(asm, B=np.column_stack([asm.B, -Mr]),
                                      load_names=[*asm.load_names, "rigid_acceleration"])
            q = equilibrium(ext, {**loads, "rigid_acceleration": alpha},
                            speed_rpm).q.to_numpy()
            q = q - r * float(Mr @ q) / float(r @ Mr)
        return dict(zip(asm.dof_names, q, strict=True))

    def _follow_motion(self, asm) -> np.ndarray:
        """The drivetrain's rigid rotation scaled to the speed ratio of the wheel it turns
        most (``"follow"``'s reference motion)."""
        r = _rigid_motion(asm.M, asm.K, asm.C, asm.contacts.W, asm.contacts.stiffness,
                          damped=False)
        if r is None:
            raise ModelError("reference", "= 'follow' needs one free rigid rotation of the "
                             "drivetrain (a gearbox whose wheels turn freely together); "
                             "this model has none or several")
        j = int(np.argmax(np.abs(r) * (self.ratio != 0)))
        if self.ratio[j] == 0:
            raise ModelError("reference", "= 'follow': the free rotation turns no wheel "
                             "with a speed_ratio")
        return r * (self.ratio[j] / r[j])

    def _grounded(self, speed: float | None = None) -> tuple:
        """The springs and dampers to ground: the drive's, and the speed torque's tangent
        (:class:`SpeedTorque`) at its DOF's ``speed`` (rad/s, absolute; None: the reference
        speed), a damper on the deflection's velocity whose constant torque goes to
        ``_tau``."""
        out = self._drive_grounded
        self._tau = 0.0
        if self.speed_torque is not None:
            i = self._st_index[0]
            w_f = float(self.ratio[i]) * self.ref.om_f
            w_t = w_f if speed is None else speed
            tau, dtau = self._law(w_t)
            self._tau = tau - dtau * (w_t - w_f)
            self._tangent = (w_t, dtau)
            if dtau:
                out = out + ((i, 0.0, -dtau),)
        return out

    def _st_speed(self, x: np.ndarray, om: float) -> tuple[float, float]:
        """The speed torque's DOF's reference speed at reference speed ``om`` and its speed
        in state ``x`` (deflections from that reference), rad/s, absolute."""
        i = self._st_index[0]
        w_f = float(self.ratio[i]) * om
        return w_f, w_f + float(x[self.n + i])

    def _law(self, w: float) -> tuple[float, float]:
        """The speed torque's ``(torque, dtorque/dspeed)`` at speed ``w`` (rad/s), checked."""
        try:
            out = self.speed_torque.law(w)
        except Exception as err:  # the user's law failed: say so, its own error chained
            raise ModelError("speed_torque.law", f"raised {type(err).__name__} at {w!r} "
                             f"rad/s: {err}") from err
        try:
            tau, dtau = out
        except (TypeError, ValueError):
            raise ModelError("speed_torque.law", f"at {w!r} rad/s: must return (torque, "
                             f"dtorque/dspeed), two numbers; got {out!r:.60}") from None
        return (_number("speed_torque.law's torque", tau),
                _number("speed_torque.law's derivative", dtau))

    def _retake_torque(self) -> None:
        """The speed torque taken anew at its DOF's speed now, ``w_k`` (the reference's
        ``w_f`` plus the deflection's): its constant part ``law(w_k) - s (w_k - w_f)``, so
        that over the stretch that starts here the torque is ``law(w_k) + s (w - w_k)``,
        exact at its start, with the slope ``s`` of the last tangent (taken at ``w_t``, in
        the equations as a damper). Where the law's slope has changed and ``w_k`` has left
        ``w_t`` by ``rebase_speed`` of it, the tangent is taken anew at ``w_k`` (a new system,
        the reference kept): the slope's error, explicit over a stretch, stays that of a
        drift of ``rebase_speed`` (:class:`SpeedTorque`)."""
        w_t, dtau = self._tangent
        w_f, w = self._st_speed(self.run.x, self.ref.om_f)
        tau, slope = self._law(w)
        if slope != dtau and abs(w - w_t) > self.rebase_speed * max(abs(w_t), 1e-3):
            self._follow(force=True, move=False)
            self._tangents += 1
            return
        self._tau = tau - dtau * (w - w_f)

    def _follow(self, force: bool = False, move: bool = True) -> None:
        """Re-base the reference rotation at the time reached where the drivetrain has left
        it (``reference="follow"``: module docstring; as the turbine run's re-basing), or
        (``force``) take the speed torque's tangent anew; ``move=False``: at the reference
        as it is (the start)."""
        n, ref, t = self.n, self.ref, self.time
        self._force_rebase = False
        x = self.run.x
        if self.follow and move:
            r, Mr, J = self.rigid, self._Mr, self._J
            phi, dom = float(Mr @ x[:n]) / J, float(Mr @ x[n:]) / J
            if not (force or abs(dom) > self.rebase_speed * max(abs(ref.om_f), 1e-3)
                    or abs(phi) > self.rebase_angle):
                return
            om_new = ref.om_f + dom + phi / REBASE_TAU
            x = x.copy()
            x[n:] -= r * (om_new - ref.om_f)
            ref.rebase(self.run.k, t, om_new)
        # the spectral bounds anew once the speed has moved by its own size since they last
        # were (and with a new speed torque); in between the last ones serve, with the
        # integrator's margin (the turbine's)
        om = ref.om_f
        fresh = force or abs(om - self._om_rho) > max(abs(self._om_rho), 1e-3)
        rho, sb = (None, None) if fresh else shared_bounds(self.system)
        speed = None if self.speed_torque is None else self._st_speed(x, om)[1]
        self.grounded = self._grounded(speed)
        # the stretch's start azimuth: its tables' times count from there (as the driver
        # takes it: the origin plus the system's speed times the run's output time)
        speed_rpm = om / RPM
        az0 = ref.origin() + float(speed_rpm) * RPM * self.run.k * self.dt
        system = PiecewiseLinearSystem(
            self.asm, speed_rpm, geometry=self.geo, grounded=self.grounded,
            spectral_bound=rho, state_bound=sb, load_columns=self.columns, azimuth0=az0)
        if fresh:
            self._om_rho = om
        if not system.turning:
            self._F = system.f_const.copy()
        self.system, self._t_sys = system, t
        self.run.rebase(system, x, ref.at(t))

    def _diverged(self, k: int) -> None:
        """Stop with a :class:`~gearmodal.SolveError` when the state at output step ``k`` is
        not finite or beyond :data:`DIVERGED`: the method diverged (named, with the time)."""
        x = self.run.x
        big = float(np.abs(x).max(initial=0.0))
        if math.isfinite(big) and big <= DIVERGED:
            return
        method = self.settings["method"]
        hint = {"newmark": "Newmark switches contacts at step ends, which is unstable with "
                           "stiff meshes and a clearance (benchmarks/RESULTS.md, stability "
                           "map): use method='exact'",
                "exact": "the exact method solves the equations as given, so they grow: look "
                         "for a negative stiffness or damping in the model, or a speed torque "
                         "that rises with the speed"}.get(method, "reduce dt or use "
                                                                  "method='exact'")
        raise SolveError(
            "method", f"= {method!r}: the gearbox state diverged in the step ending at t = "
            f"{self._t(k):.3f} s (largest entry {big:.3g}, above {DIVERGED:g}); {hint}")

    def _tables(self, X: np.ndarray):
        """``(q, v)`` rows of the result's tables from state rows ``X`` at the time reached
        (``"follow"``: the rigid rotation taken out, column by column, as the turbine's
        tables; else :meth:`_absolute`)."""
        if not self.follow:
            return self._absolute(X)
        Mr = self.asm.M @ self.rigid
        return elastic(X, self.n, self.rigid, Mr, float(self.rigid @ Mr))

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
        if self.speed_torque is not None:  # its tangent's constant torque
            u[self.load_index[self.asm.load_names[self._st_index[1]]]] += self._tau
        if host is not None:
            d, rho = self.drive, self.ratio[self._i_drive]
            rel = host[0] - rho * self.ref.at(self._t(k)) - self.offset * self._rigid_i()
            u[self.load_index[self._drive_name]] += (
                d.stiffness * rel + d.damping * (host[1] - rho * self.ref.om_f))
        return u

    def _drive_torque(self) -> float:
        """The drive's torque on the gearbox now, from the state (rebased: no rounding of
        the turns made)."""
        d, n, i = self.drive, self.n, self._i_drive
        a, w = self._host
        rho = self.ratio[i]
        rel = a - rho * self.ref.at(self.time) - self.offset * self._rigid_i()
        return d.stiffness * (rel - self.run.x[i]) + d.damping * (
            w - rho * self.ref.om_f - self.run.x[n + i])

    def _rigid_i(self) -> float:
        """The driven DOF's part of the rigid rotation moved out (``"fixed"``)."""
        if self.rigid is None or self.follow:
            return 0.0
        return float(self.rigid[self._i_drive])

    def _rebase(self) -> None:
        """Move the rigid rotation out of the state at this call's end when it passed
        :data:`REBASE_ANGLE` (module docstring); the drive's load re-expressed against it."""
        if self.rigid is None or self.follow:
            return
        n, r = self.n, self.rigid
        phi = float(self._Mr @ self.run.x[:n]) / self._J
        if abs(phi) <= REBASE_ANGLE:
            return
        k = self.run.k
        self.run.x[:n] -= r * phi
        self.offset += phi
        self._rebases.append((k, self.offset))


    def _absolute(self, X: np.ndarray, rows: np.ndarray | None = None):
        """``(q, v)`` of state rows ``X`` with the rigid rotation moved out added back:
        ``rows`` their output steps (default: every row at the time reached)."""
        q = np.array(X[:, :self.n])
        if self.rigid is not None and self._rebases and not self.follow:
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

    def levels(self, rows, channels, levels) -> None:
        pass


class _Reference:
    """The reference input azimuth ``psi(t) = psi_f + om_f (t - t_f)`` (rad), re-based
    between calls (``reference="follow"``); ``stretches``: ``(k, psi_f, om_f, t_f)`` from each
    re-basing's output step on."""

    def __init__(self, omega: float, psi0: float = 0.0):
        self.psi_f, self.om_f, self.t_f = float(psi0), float(omega), 0.0
        self.stretches = [(0, self.psi_f, self.om_f, 0.0)]

    def at(self, t):
        """The azimuth at time(s) ``t`` of the current stretch."""
        return self.psi_f + self.om_f * (t - self.t_f)

    def origin(self) -> float:
        """The current stretch's azimuth extended back to time 0 (the kernel's times are the
        run's)."""
        return self.psi_f - self.om_f * self.t_f

    def rebase(self, k: int, t: float, om: float) -> None:
        """A new stretch from output step ``k`` (time ``t``) at speed ``om``, the azimuth
        continuous."""
        self.psi_f, self.t_f, self.om_f = self.at(t), t, float(om)
        self.stretches.append((k, self.psi_f, self.om_f, self.t_f))

    def grid(self, k_end: int, dt: float) -> np.ndarray:
        """The azimuth at every output step ``0 .. k_end``."""
        out = np.empty(k_end + 1)
        ks = [s[0] for s in self.stretches] + [k_end + 1]
        for (k0, psi, om, tf), k1 in zip(self.stretches, ks[1:], strict=True):
            out[k0:k1] = psi + om * (np.arange(k0, k1) * dt - tf)
        return out


def _between(k: int, k0: int, k1: int, a, b):
    """Values linear from ``a`` at step ``k0`` to ``b`` at ``k1``, at step ``k`` (the ends'
    exactly; None stays None)."""
    if a is None:
        return None
    if k == k0:
        return np.asarray(a, dtype=float)
    if k == k1:
        return np.asarray(b, dtype=float)
    f = (k - k0) / (k1 - k0)
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return a + f * (b - a)


def _rigid_motion(M: np.ndarray, K: np.ndarray, C: np.ndarray, W: np.ndarray, k: np.ndarray,
                  grounded=(), damped: bool = True) -> np.ndarray | None:
    """The one free motion of stiffness ``K`` with every contact (rows ``W``, stiffness
    ``k``) closed: a drivetrain's rigid rotation, normalised to 1 on its largest entry (the
    eigenvector of zero eigenvalue of ``(K + W^T k W, M)``, as the turbine's
    ``rigid_rotation``); None without one, with several, or (``damped``) when the damping ``C``
    sees it. ``grounded``: the drive's springs in ``K``, ``C``, left out (the drive takes that
    motion up, with the host's angle)."""
    K, C = np.array(K, dtype=float), np.array(C, dtype=float)
    for dof, kg, cg in grounded:
        K[dof, dof] -= kg
        C[dof, dof] -= cg
    Kc = K + (W.T * k) @ W
    w, V = sla.eigh(Kc, M)
    free = np.abs(w) <= 1e-10 * max(np.abs(w).max(initial=0.0), 1e-300)
    if free.sum() != 1:
        return None
    r = V[:, int(np.flatnonzero(free)[0])]
    if damped and np.abs(C @ r).max(initial=0.0) > 1e-10 * np.abs(C).max(initial=0.0) \
            * np.abs(r).max():
        return None
    return r / r[int(np.argmax(np.abs(r)))]


def _number(label: str, val) -> float:
    if not isinstance(val, (int, float, np.integer, np.floating)) or isinstance(val, bool) \
            or not math.isfinite(float(val)):
        raise ModelError(label, f"= {val!r}: must be a finite number")
    return float(val)


def _positive(label: str, val) -> float:
    x = _number(label, val)
    if x <= 0:
        raise ModelError(label, f"= {val!r}: must be > 0")
    return x
