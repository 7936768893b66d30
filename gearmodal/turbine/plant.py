"""The turbine around the gearbox, on its own step: wind, blade-element aerodynamics, the
generator and its cut-in, the shaft-end force (DESIGN 2.5, paper section 5; issue 5's
multirate scheme).

A :class:`TurbinePlant` is what an aeroelastic code is to a co-simulated gearbox: at each
aerodynamic step it reads the gearbox's outputs (the rotor's azimuth and speed, the
generator's speed), samples the wind at the rotating blade elements, evaluates the
blade-element momentum loads and gives the loads the gearbox takes over the step (the rotor
torque, the shaft-end force, the generator's torque-speed law). The coupled run
(:func:`gearmodal.turbine.simulate_drivetrain`) is a loop of it over the public stepping API
(:class:`gearmodal.Stepper`).

Loads across an aerodynamic step (``aero_hold``):

- ``"interpolate"`` (default): linear to the loads at the step's end, evaluated at the azimuth
  predicted there with the current speed: continuous;
- ``"hold"``: the loads at the step's start held over it (a jump at every step, which rings
  the gearbox);
- ``"linear"``: extrapolated from the last two samples (also discontinuous).

The induction generator is a :class:`gearmodal.SpeedTorque` (its torque-slip curve, taken
implicitly: at the generator's speed at each aerodynamic step's start, its slope at the
last re-basing's or where the speed has since moved by ``rebase_speed``; the stiff slip
damping sets no step limit); it is off the
grid (no torque) until the generator reaches synchronous speed, unless ``connected``.

A controlled turbine (``Turbine.generator`` None, a ``controller`` given: ROSCO for the NREL
5 MW turbine) is called once per aerodynamic step, at its start, with the gearbox's measured
generator and rotor speeds, the pitch and torque it last demanded and the hub-height wind
(:meth:`gearmodal.turbine.rosco.Rosco.step`'s signature); its generator torque is the load
``generator.torque`` (with the other loads across the step, ``aero_hold``) and its pitch is
the blades' from that step on. It is on the grid from the start.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
import pandas as pd

from ..errors import ModelError
from ..integrate.stepper import SpeedTorque
from ..model.components import GRAVITY
from ..result_io import TableWriter
from .rotor import LOAD_COLUMNS
from .turbine import RPM, TURBINE_COLUMNS, Turbine
from .wind import Wind

#: how the loads act across an aerodynamic step (module docstring)
HOLDS = ("interpolate", "hold", "linear")
#: turbine-load rows kept before a streamed run writes them
ROWS_PER_WRITE = 1000


@dataclass
class Step:
    """What the gearbox takes over one aerodynamic step: the loads at its end (``"ramp"``:
    from ``start`` or the last step's end) or over it (``"hold"``); ``now``: the loads
    evaluated at its start (a run's first loads)."""

    loads: dict
    now: dict
    hold: str = "ramp"
    start: dict | None = None


class TurbinePlant:
    """The turbine's side of the coupled run (module docstring).

    Parameters
    ----------
    turbine, wind : the :class:`Turbine` and its :class:`Wind`.
    gearbox : the drivetrain :class:`gearmodal.Model` (bodies ``rotor`` and ``generator``,
        a planetary carrier for the shaft-end force).
    aero_dt : aerodynamic step, s. aero_hold : ``"interpolate"``, ``"hold"``, ``"linear"``.
    gravity : g, m/s^2 (0: none), on every gearbox body (the load ``gravity``).
    connected : the generator on the grid from the start.
    out : a directory the turbine loads stream to (``turbine_loads``), or None (in memory).
    controller : for a turbine without an induction generator: an object with
        ``step(t, generator_speed, rotor_speed, pitch, generator_torque, wind_speed) ->
        (generator_torque, pitch)`` (N m on the high-speed shaft, rad; module docstring)
        called every ``aero_dt``, and ``pitch`` (rad), the pitch it starts from.
    """

    def __init__(self, turbine: Turbine, wind: Wind, gearbox, *, aero_dt: float,
                 aero_hold: str = "interpolate", gravity: float = 0.0,
                 connected: bool = False, out=None, controller=None):
        if aero_hold not in HOLDS:
            raise ModelError("aero_hold", f"= {aero_hold!r}: must be one of {HOLDS}")
        self.turbine, self.wind = turbine, wind
        self.aero_dt, self.hold, self.g = float(aero_dt), aero_hold, float(gravity)
        names = gearbox.assemble().load_names
        # the first stage's carrier takes the shaft-end force; a torsional one has no
        # translation, so the force is not modelled (the loads table still reports it)
        carrier = next((b.name for b in gearbox.bodies.values() if b.role == "carrier"), None)
        if carrier is None:
            raise ModelError("gearbox", "has no planetary carrier (a body of role 'carrier', "
                             "as gm.planetary_stage makes) to carry the shaft-end force")
        self.carrier = (f"{carrier}.force_x", f"{carrier}.force_y")
        self.bending = self.carrier[0] in names
        ratio = float(gearbox.bodies["generator"].speed_ratio)
        self.sg = math.copysign(1.0, ratio)  # the generator's forward sense
        # the mounting: the input azimuth is planet 1's, blade 1's plus this
        self.mount = math.radians(turbine.mounting_azimuth_deg) + 0.5 * math.pi
        if (turbine.generator is None) == (controller is None):
            raise ModelError("controller", "a turbine with an induction generator takes no "
                             "controller" if controller is not None else "required: the "
                             "turbine has no induction generator (Turbine.generator is None)")
        self.controller = controller
        self.pitch = float(controller.pitch) if controller is not None else turbine.rotor.pitch
        self.tilt = math.radians(turbine.tilt_deg)  # the rotor's weight in the shaft's axes
        self._hub = (np.zeros(1), np.full(1, float(turbine.hub_height)))  # the hub point
        self.t_gen = 0.0  # the controller's last torque demand, N m
        self.on = bool(connected) or controller is not None
        self.cut_in = 0.0 if self.on else None
        self.switched = False
        self.clock = {"aero_s": 0.0, "wind_s": 0.0, "wind_setup_s": 0.0}
        self.rows: list[tuple] = []
        self.writer = None
        if out is not None:
            self.writer = TableWriter(out, "turbine_loads", TURBINE_COLUMNS[1:], dtype=None)
        self._next = None  # "interpolate": the loads at the step's end
        self._prev = None  # "linear": the last step's load values
        if wind.turbulent:
            tw = time.process_time()
            wind._turbulence()
            self.clock["wind_setup_s"] = time.process_time() - tw

    def generator(self) -> SpeedTorque:
        """The generator's torque on ``generator.theta`` as a function of its speed: the
        torque-slip curve on the grid, none off it."""
        gen, sg, on = self.turbine.generator, self.sg, self.on

        def law(w: float) -> tuple[float, float]:
            if not on or gen is None:  # a controller's torque is a load (module docstring)
                return 0.0, 0.0
            t, c = gen.tangent(sg * w)  # forward speed; torque against the rotation
            return -sg * t, -c

        return SpeedTorque("generator.theta", law)

    def loads(self, u: np.ndarray) -> dict:
        """The gearbox loads of values ``u`` (rotor torque, shaft-end force y and z, and with
        a controller the generator torque on the high-speed shaft)."""
        out = {"rotor.torque": float(u[0])}
        if self.bending:
            out.update({self.carrier[0]: float(u[1]), self.carrier[1]: float(u[2])})
        if self.controller is not None:
            out["generator.torque"] = -self.sg * float(u[3])
        return out

    def constant_loads(self) -> dict:
        """The loads the gearbox takes unchanged: its weight."""
        return {GRAVITY: self.g} if self.g else {}

    def step(self, k: int, azimuth: float, speed: float, generator_speed: float) -> Step:
        """Aerodynamic step ``k`` from the gearbox's input ``azimuth`` (rad, planet 1's),
        rotor ``speed`` and ``generator_speed`` (rad/s, signed as the model's) at its start:
        the turbine loads row, the cut-in, and the loads over the step. ``switched``: the
        generator went on the grid here (its law changed: :meth:`generator`)."""
        t = k * self.aero_dt
        psi = azimuth - self.mount  # blade 1
        turbine = self.turbine
        w_gen = self.sg * generator_speed  # forward positive
        if self.controller is not None:  # its demands from the measured speeds
            hub = self.wind.velocity(t, *self._hub)[0][0]
            self.t_gen, self.pitch = self.controller.step(t, w_gen, speed, self.pitch,
                                                          self.t_gen, float(hub))
        # aerodynamics at the rotor's actual azimuth and speed ("interpolate": also at the
        # end of the step, predicted with the current speed)
        if self.hold == "interpolate":
            ld = self._aero(t, psi, speed, True) if k == 0 else self._next
            self._next = self._aero(t + self.aero_dt, psi + speed * self.aero_dt, speed, False)
        else:
            ld = self._aero(t, psi, speed, k == 0)
        fy, fz = turbine.rear_force(ld)
        gen = turbine.generator
        if gen is None:
            self.switched, tg = False, self.t_gen
        else:
            self.switched = not self.on and w_gen >= gen.omega_sync
            if self.switched:
                self.on, self.cut_in = True, t
            tg = gen.torque(w_gen) if self.on else 0.0
        self.rows.append((t, speed / RPM, math.degrees(psi) % 360.0, self.on, tg, tg * w_gen,
                          *(ld[c] for c in LOAD_COLUMNS), fy, fz, math.degrees(self.pitch)))
        if self.writer is not None and len(self.rows) >= ROWS_PER_WRITE:
            self.writer.append_frame(self.table())
            self.rows = []
        u = np.array([ld["torque_Nm"], fy, fz, tg])
        now = self.loads(u)
        prev, self._prev = self._prev, u
        if self.hold == "interpolate":
            nxt = self._next
            return Step(self.loads(np.array([nxt["torque_Nm"], *turbine.rear_force(nxt),
                                             tg])), now)
        if self.hold == "linear" and prev is not None:
            return Step(self.loads(u + (u - prev)), now, start=now)
        return Step(now, now, hold="hold")

    def table(self) -> pd.DataFrame:
        """The turbine loads rows kept (:data:`TURBINE_COLUMNS`), indexed by time."""
        return pd.DataFrame(self.rows, columns=TURBINE_COLUMNS).set_index("time")

    def close(self) -> pd.DataFrame | None:
        """The turbine loads table (None when streamed: the last rows written)."""
        if self.writer is None:
            return self.table()
        self.writer.append_frame(self.table())
        self.writer.close()
        return None

    def _aero(self, ta: float, psi: float, om: float, reset: bool) -> dict:
        """Hub loads at time ``ta``, blade-1 azimuth ``psi``, speed ``om``; timed."""
        tw = time.process_time()
        bw = self.turbine.blade_wind(self.wind, ta, psi)
        tv = time.process_time()
        out = self.turbine.rotor.loads(om, psi, *bw, reset=reset, pitch=self.pitch,
                                       tilt=self.tilt)
        self.clock["wind_s"] += tv - tw
        self.clock["aero_s"] += time.process_time() - tv
        return out
