"""The turbine and the gearbox in one run: aerodynamics, generator and the gearbox's contact
dynamics together (DESIGN 2.5, paper section 5; issue 5's multirate scheme), as a
co-simulation over the public stepping API.

The gearbox model (``600kw.toml``: rotor inertia, main shaft, stages, generator, housing on its
suspension) carries the whole drivetrain, so its free rotation is the turbine's rotation. The
run is a short loop: the turbine's side (:class:`~gearmodal.turbine.plant.TurbinePlant`:
wind, blade-element aerodynamics, generator and cut-in, shaft-end force) on the aerodynamic
step ``aero_dt``, the gearbox a :class:`gearmodal.Stepper` advanced to each aerodynamic
step's end with the loads over it (``aero_hold``, :mod:`gearmodal.turbine.plant`), its
outputs (the rotor's azimuth and speed, the generator's speed) read back. Two rates:

- **aerodynamic step** ``aero_dt``: the wind sampled at the rotating blade elements, the
  blade-element momentum loads evaluated (their hold's error against evaluating at every
  gearbox step is measured in ``benchmarks/turbine_speed.py``);
- **gearbox step** ``dt``: the exact piecewise-linear integrator (or any ``method`` of
  :func:`gearmodal.simulate`) with every contact event; the loads are piecewise linear on the
  aerodynamic knots, so the output step only places rows.

The stepper's state is the deflection from a rigid reference rotation ``psi_ref(t) = psi_f +
Omega_f (t - t_f)`` that follows the drivetrain (``reference="follow"``): re-based on the
aerodynamic grid only where the speed drifts (by ``rebase_speed`` of the reference speed),
the drivetrain's rigid rotation ``phi = r^T M q / r^T M r`` (``r`` the free rotation mode)
leaves it by ``rebase_angle``, or the generator cuts in. The reference azimuth stays
continuous: the turning geometry never jumps (moving ``phi`` into the azimuth at once would
move every turning gap by ``phi`` times a deflection: a kick to the carrier floating in its
clearance). The new reference speed is the drivetrain's plus ``phi / REBASE_TAU``, so the
rigid rotation left in ``q`` is taken up smoothly; the speed terms and the generator tangent
are taken at the new speed, and the velocities re-expressed against it exactly. The gearbox
geometry turns with the reference azimuth and is integrated exactly as the time-periodic
system it is (:mod:`gearmodal.integrate.periodic`).

The induction generator enters the linear gearbox equations as its tangent (a
:class:`gearmodal.SpeedTorque`): over each aerodynamic step, torque
``T(w_k) + (dT/dw)(w_t) (w - w_k)`` with ``w_k`` the generator's speed at the step's start,
a constant load plus a viscous damper ``dT/dw`` on the generator's rotation, taken at its
speed ``w_t`` at the last re-basing (or anew where its speed has moved by ``rebase_speed``
since: :class:`gearmodal.SpeedTorque`), so its strong slip damping is implicit (no step limit)
and the torque is the curve's at every aerodynamic step's start (the torque the turbine's
table reports).
The run starts from the drivetrain accelerating rigidly under the first loads (the stepper's
``q0="equilibrium"``).

Loads on the gearbox: the rotor's aerodynamic torque on ``rotor.torque``, the generator torque
on ``generator.torque`` and the shaft-end force on the first planetary carrier
(``stageN.carrier.force_x`` = global ``y``, ``force_y`` = global ``z``; not modelled when the
carrier has no translation, a torsional stage): the rear main-bearing reaction of
:meth:`gearmodal.turbine.Turbine.rear_force` (rotor weight, thrust, tilt and yaw moments,
shear forces). Gravity on every body of the gearbox (the load ``gravity``, on by default:
``gravity=False`` turns it off) is a constant ground-axes force, which the turning geometry
maps onto the carrier frame exactly, as it does the shaft-end force.

The mounting azimuth ``Turbine.mounting_azimuth_deg`` is the angle from blade 1 to planet 1 in
the direction of rotation: 0 puts planet 1 on blade 1's radius.
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd
import scipy.linalg as sla

from ..errors import ModelError
from ..integrate import (
    PEAK_BIN,
    SimulationResult,
    get_method,
)
from ..integrate.stepper import Stepper
from ..model.components import G_STANDARD
from ..result_io import (
    HEADER,
    digests,
    read_header,
    refuses_damage,
    replacing,
    verify_digests,
    write_header,
)
from .plant import HOLDS, Step, TurbinePlant
from .turbine import RPM, Turbine, TurbineResult, mark_cut_in
from .wind import Wind

#: layout version of :meth:`DrivetrainResult.save` (``drivetrain.json``): 2 Parquet or CSV
#: tables, 1 CSV only (still read)
SAVE_VERSION = 2



@dataclass
class DrivetrainResult:
    """A turbine + gearbox run.

    turbine : :class:`TurbineResult` at the aerodynamic rate (rotor speed and azimuth are the
        gearbox model's rotor, rigid reference plus deflection).
    gearbox : :class:`gearmodal.SimulationResult` at the gearbox step: forces, event log,
        double contact, load sharing. Its ``q``, ``v`` are elastic deflections: the rigid
        drivetrain rotation is removed (it is in ``turbine.loads``).
    stats : CPU seconds split into ``aero_s`` (blade-element momentum), ``wind_s`` (wind
        sampling; ``wind_setup_s`` the turbulence box), ``gearbox_s`` (the
        gearbox integration), with ``cpu_s`` total and ``realtime_ratio`` (simulated s per CPU s,
        without the one-off turbulence box).
    """

    turbine: TurbineResult
    gearbox: SimulationResult
    stats: dict = field(default_factory=dict)

    @property
    def cut_in_time(self) -> float | None:
        return self.turbine.cut_in_time

    @property
    def choice(self) -> None:
        """No fidelity choice made this run (:class:`gearmodal.run.RunResult`)."""
        return None

    def to_frame(self) -> pd.DataFrame:
        """The turbine loads at the aerodynamic rate, their units in ``attrs["units"]``."""
        return self.turbine.to_frame()

    def openfast(self, gear_ratio: float, efficiency: float = 1.0,
                 shaft: str = "main_shaft") -> pd.DataFrame:
        """:meth:`TurbineResult.openfast` (OpenFAST's channel names and units) with
        ``LSShftTq`` kN-m, the low-speed shaft's structural torque: the gearbox model's
        ``shaft`` element (the torsional spring and damper from the rotor into the gearbox) at
        the turbine's times (rows the gearbox's output holds, or linear between them),
        positive as the rotor drives the gearbox, as OpenFAST's."""
        out = self.turbine.openfast(gear_ratio, efficiency)
        col = f"{shaft}.theta"
        columns = self.gearbox.force_columns()
        if col not in columns:
            shafts = sorted({c.rsplit(".", 1)[0] for c in columns if c.endswith(".theta")})
            raise ModelError("shaft", f"= {shaft!r}: no torsional element of that name in the "
                             "gearbox's forces; torsional elements: " + ", ".join(shafts))
        f = self.gearbox.forces[col]
        t = out.index.to_numpy()
        out["LSShftTq"] = np.interp(t, f.index.to_numpy(dtype=float), f.to_numpy()) * 1e-3
        out.attrs["units"] = {**out.attrs["units"], "LSShftTq": "kN-m"}
        return out

    def plot(self):
        """Rotor speed, power and the planet-1 tooth forces against time; returns the Figure."""
        import matplotlib.pyplot as plt

        fig, axs = plt.subplots(3, 1, sharex=True, figsize=(9, 8))
        d = self.turbine.view(["rotor_speed_rpm", "power_W"])
        axs[0].plot(d.index, d["rotor_speed_rpm"])
        axs[0].set_ylabel("rotor speed [rpm]")
        axs[1].plot(d.index, d["power_W"] / 1e3)
        axs[1].set_ylabel("generator shaft power [kW]")
        self.gearbox.plot(ax=axs[2])
        mark_cut_in(axs, self.cut_in_time)
        fig.tight_layout()
        return fig

    def save(self, directory, format: str = "parquet") -> Path:
        """Write the turbine loads (``turbine_loads``, ``turbine.json``), the gearbox results
        (``forces``, ``events``, ``q``, ``v``, ``settings.json``...: as
        :meth:`SimulationResult.save`; Parquet, or CSV with ``format="csv"``) and
        ``stats.json``: what :meth:`load` reads back. Saving over an earlier result replaces
        it whole (it stays readable until the new one is complete); the headers hold every
        file's SHA-256, which :meth:`load` checks."""
        d = Path(directory)
        stored = self.gearbox.stored
        if stored is not None and d.is_dir() and d.resolve() == Path(stored).resolve():
            self._write(d, format)  # streamed here: the rest beside it
            return d
        with replacing(d, (HEADER, "drivetrain.json")) as target:
            self._write(target, format)
        return d

    def _write(self, d: Path, format: str) -> None:
        self.turbine.save(d, format)
        self.gearbox.save(d, format)
        (d / "stats.json").write_text(json.dumps(self.stats, indent=2))
        write_header(d, "DrivetrainResult", SAVE_VERSION, header="drivetrain.json",
                     sha256=digests(d, [f"turbine_loads.{format}", "turbine.json",
                                        "stats.json"]))

    @classmethod
    @refuses_damage
    def load(cls, directory) -> DrivetrainResult:
        """The run :meth:`save` wrote to ``directory``: turbine loads and the gearbox result,
        floats exact; an older layout is refused naming the directory."""
        d = Path(directory)
        head = read_header(d, "DrivetrainResult", (1, SAVE_VERSION), header="drivetrain.json")
        verify_digests(d, head.get("sha256") or {})
        return cls(turbine=TurbineResult.load(d), gearbox=SimulationResult.load(d),
                   stats=json.loads((d / "stats.json").read_text()))


def unrestrained(asm, modes: np.ndarray, share: float = 0.1) -> list[str]:
    """Names of the DOFs that move most in the free ``modes`` (mass-orthonormal columns) once
    the drivetrain rotation (the combination that moves ``rotor.theta`` most) is taken out,
    largest first, for an error message. Translations and tilts are named before rotations
    about the wheel axes: an unsupported tilt of a helical wheel lets the chain behind it turn,
    and the tilt is the cause. A DOF is named when its kinetic-energy share is at least
    ``share`` of the largest one's."""
    if "rotor.theta" in asm.dof_names:
        a = modes[asm.dof_names.index("rotor.theta")]
        if np.any(a):  # an orthonormal basis of the combinations that leave the rotor still
            modes = modes @ sla.null_space(a[None, :])
    s = np.sqrt(np.abs(np.diag(asm.M)))[:, None] * modes
    e = np.sum(s * s, axis=1)
    lateral = np.array([n.rsplit(".", 1)[-1] in ("x", "y", "z", "rx", "ry")
                        for n in asm.dof_names])
    if e[lateral].sum() > 1e-6 * e.sum():
        e = np.where(lateral, e, 0.0)
    order = np.argsort(-e)
    return [asm.dof_names[i] for i in order if e[i] > 0 and e[i] >= share * e[order[0]]]


def rigid_rotation(asm) -> np.ndarray:
    """The free rotation mode ``r`` of the drivetrain (every wheel turning at its speed ratio),
    normalised to 1 on the rotor; raises when the gearbox has no such mode."""
    c = asm.contacts
    Kc = asm.K + (c.W.T * c.stiffness) @ c.W  # all flanks closed: the stiffest connection
    w, V = sla.eigh(Kc, asm.M)
    # zero modes sit at rounding level (~1e-16 of the largest eigenvalue); a physical mode
    # 1e-10 below the stiffest one would be below 0.05 Hz against a 5 kHz top frequency
    free = np.abs(w) <= 1e-10 * np.abs(w).max()
    if not free.any():
        raise ModelError("gearbox", "has no free drivetrain rotation: the rotor and generator "
                         "must be free to turn (no torsional support to ground)")
    if free.sum() > 1:
        raise ModelError("gearbox", f"has {int(free.sum())} free motions where only the "
                         "drivetrain rotation may be free: nothing resists "
                         + ", ".join(unrestrained(asm, V[:, free])) + ". Give those "
                         "supports a stiffness in these directions (a support given as a "
                         "number has x, y and, at the full level, z; tilts rx/ry need a "
                         "stiffness table)")
    r = V[:, int(np.flatnonzero(free)[0])]
    i = asm.dof_names.index("rotor.theta")
    if asm.M[i, i] * r[i] ** 2 < 1e-6:  # r is mass-normalised: the rotor's energy share
        raise ModelError("gearbox", "has one free motion, but it leaves the rotor still: "
                         "nothing resists " + ", ".join(unrestrained(asm, r[:, None])))
    return r / r[i]


@dataclass
class Coupling:
    """A coupled turbine run set up (:func:`couple`): the turbine's side ``plant``, the
    gearbox's :class:`gearmodal.Stepper`, the loads over the first aerodynamic step ``first``
    (then :meth:`TurbinePlant.step` from the stepper's outputs at each step's start),
    ``n_aero`` aerodynamic steps of ``aero_dt`` s, the run's ``settings``, the directory it
    streams to ``out`` (or None)."""

    plant: TurbinePlant
    stepper: Stepper
    first: Step
    n_aero: int
    aero_dt: float
    settings: dict
    out: Path | None = None

    def result(self, cpu0: float) -> DrivetrainResult:
        """The run's result, its clock from ``cpu0`` (``time.process_time()`` at its start):
        the gearbox's, the turbine loads, the timings."""
        plant = self.plant
        cpu = time.process_time() - cpu0
        clock = dict(plant.clock)
        clock["gearbox_s"] = cpu - sum(clock.values())
        stats = {**clock, "cpu_s": cpu, "realtime_ratio": self.n_aero * self.aero_dt
                 / max(cpu - clock["wind_setup_s"], 1e-12)}
        sim = self.stepper.result(settings=self.settings, stats=stats)
        out = self.out
        tres = TurbineResult(loads=plant.close(), cut_in_time=plant.cut_in,
                             settings=self.settings, stored=out)
        res = DrivetrainResult(turbine=tres, gearbox=sim, stats=sim.stats)
        if out is not None:
            res.save(out)  # the headers and the small tables beside the streamed ones
        return res


def simulate_drivetrain(turbine: Turbine, wind: Wind, gearbox, t_end: float, *,
                        progress=None, **settings) -> DrivetrainResult:
    """Run turbine and gearbox together for ``t_end`` s: the run :func:`couple` sets up (its
    ``settings``: ``dt``, ``aero_dt``, ``method``, ``out``...) walked over its aerodynamic
    steps. ``progress``: ``progress(i, n)`` per aerodynamic step (the solver never prints)."""
    cpu0 = time.process_time()
    c = couple(turbine, wind, gearbox, t_end, **settings)
    plant, st, step = c.plant, c.stepper, c.first
    for k in range(1, c.n_aero + 1):
        y = st.advance(k * c.aero_dt, step.loads, hold=step.hold, start=step.start)
        if progress is not None:
            progress(k, c.n_aero)
        if k < c.n_aero:  # the next step's loads from the gearbox's outputs
            step = plant.step(k, *y.values())
            if plant.switched:
                st.set_speed_torque(plant.generator())
    return c.result(cpu0)


def couple(turbine: Turbine, wind: Wind, gearbox, t_end: float, *, dt: float = 2e-3,
           aero_dt: float = 0.02, aero_hold: str = "interpolate",
           rotor_speed0_rpm: float = 6.0, azimuth0_deg: float = 0.0, connected: bool = False,
           rebase_speed: float = 0.01, rebase_angle: float = 5e-4, method: str = "exact",
           gravity: bool | float = True, top_frequency_hz: float | None = None,
           peak_bin: float | None = PEAK_BIN, turning_points: bool = True, out=None,
           controller=None, **options) -> Coupling:
    """Turbine and gearbox set up to run together from ``rotor_speed0_rpm`` for ``t_end`` s
    (:func:`simulate_drivetrain` runs them; a host's own loop over the public API may).

    Parameters
    ----------
    turbine : :class:`Turbine` (rotor, generator, main-shaft geometry, mounting azimuth).
    wind : :class:`Wind`.
    gearbox : :class:`gearmodal.Model` of the drivetrain with bodies ``rotor`` and
        ``generator`` and a planetary stage (``studies/models/600kw.toml``).
    t_end : s. dt : gearbox output step, s (the exact method finds every contact event inside
        it). aero_dt : aerodynamic step, s (a whole multiple of ``dt``). aero_hold :
        ``"interpolate"``, ``"hold"`` or ``"linear"`` (module docstring).
    rotor_speed0_rpm, azimuth0_deg : initial rotor speed and blade-1 azimuth.
    connected : start with the generator on the grid (else it cuts in at synchronous speed).
    rebase_speed : relative drift of the rotor speed from the reference that re-bases the
        reference rotation (module docstring). rebase_angle : rigid rotation (rad) of the
        drivetrain against the reference that re-bases it: the turning geometry is taken at
        the reference azimuth, so this bounds how far it lags the true carrier angle.
    method : ``"exact"``, ``"newmark"`` or ``"scipy"``; ``options`` go to it (refused if it
        does not take them). A method that diverges (a gearbox state entry above
        :data:`gearmodal.integrate.stepper.DIVERGED`) stops the run with a
        :class:`gearmodal.SolveError` naming it and the time.
    gravity : the weight of every gearbox body (the model's load ``gravity``, along the
        turbine's ``tilt_deg``): True (standard gravity, 9.80665 m/s^2), False, or g in m/s^2.
    top_frequency_hz : the mass-scaling rung (:mod:`gearmodal.massscale`): the gearbox's
        modes above this frequency are slowed to it by added mass along them (stiffness,
        gaps, loads exact), so the exact method's pieces are longer. ``None`` (default): the
        full model. Its error on the engineering quantities is measured in
        ``benchmarks/turbine_speed.py``.
    peak_bin : width of the bins of the exact peaks, s, as :func:`gearmodal.simulate`'s;
        ``None``: no exact peaks (the sampled ones, about 22 % less integration CPU).
    turning_points : the exact turning points, level changes and load integrals of the
        gearbox's force channels, as :func:`gearmodal.simulate`'s (what
        :func:`gearmodal.fatigue.drivetrain_fatigue`'s exact DELs, spectra and lives come
        from); False: none (about 45 % less integration CPU).
    out : a directory the run streams to as it goes (:meth:`DrivetrainResult.save`'s layout:
        Parquet row groups of the gearbox rows and of the turbine loads); the result reads
        its tables from there when first asked for, so the run's memory does not grow with
        its duration. ``None``: every row is held in memory.
    controller : for a turbine whose ``generator`` is None, what sets the generator torque and
        the pitch every ``aero_dt`` (:class:`gearmodal.turbine.rosco.Rosco`, or any object
        with its ``step`` and ``pitch``: :class:`~gearmodal.turbine.plant.TurbinePlant`); the
        caller owns it (opens and closes it).
    """
    if not isinstance(turning_points, bool):
        raise ModelError("turning_points", f"= {turning_points!r}: True or False")
    for label, val in (("t_end", t_end), ("dt", dt), ("aero_dt", aero_dt),
                       ("rebase_speed", rebase_speed), ("rebase_angle", rebase_angle)):
        if not (isinstance(val, (int, float)) and math.isfinite(val) and val > 0):
            raise ModelError(label, f"= {val!r}: must be a finite number > 0")
    m_sub = round(aero_dt / dt)
    if m_sub < 1 or abs(m_sub * dt - aero_dt) > 1e-9 * aero_dt:
        raise ModelError("aero_dt", f"= {aero_dt!r}: must be a whole multiple of dt = {dt!r}")
    if aero_hold not in HOLDS:
        raise ModelError("aero_hold", f"= {aero_hold!r}: must be one of {HOLDS}")
    get_method(method, options)  # the name and its options checked
    if isinstance(gravity, bool):
        g = G_STANDARD if gravity else 0.0
    elif isinstance(gravity, (int, float)) and math.isfinite(gravity) and 0 <= gravity <= 100:
        g = float(gravity)
    else:
        raise ModelError("gravity", f"= {gravity!r}: true, false or g in m/s^2 (0 to 100)")
    if not (isinstance(rotor_speed0_rpm, (int, float)) and rotor_speed0_rpm >= 0):
        raise ModelError("rotor_speed0_rpm", f"= {rotor_speed0_rpm!r}: must be >= 0 rpm")
    if wind.turbulent and wind.duration < t_end:
        raise ModelError("wind.duration", f"= {wind.duration}: shorter than t_end = {t_end}")
    if g and getattr(gearbox, "tilt_deg", 0.0) != turbine.tilt_deg:
        gearbox = gearbox.copy()  # gravity along the turbine's shaft tilt
        gearbox.tilt_deg = turbine.tilt_deg
    _check_drivetrain(gearbox)
    if out is not None:
        Path(out).mkdir(parents=True, exist_ok=True)
    plant = TurbinePlant(turbine, wind, gearbox, aero_dt=aero_dt, aero_hold=aero_hold,
                         gravity=g, connected=connected, out=out, controller=controller)
    n_aero = int(math.ceil(t_end / aero_dt - 1e-9))
    # -- the coupled loop, on the public stepping API: the plant reads the gearbox's outputs
    # at each aerodynamic step's start and gives the loads over it; the stepper re-bases its
    # reference rotation on the aerodynamic grid (the gearbox's geometry turns with it)
    om0, psi0 = rotor_speed0_rpm * RPM, math.radians(azimuth0_deg)
    step = plant.step(0, psi0 + plant.mount, om0, om0 * gearbox.bodies["generator"].speed_ratio)
    st = Stepper(gearbox, dt=dt, method=method, speed_rpm=rotor_speed0_rpm,
                 azimuth0=psi0 + plant.mount, loads={**step.now, **plant.constant_loads()},
                 speed_torque=plant.generator(), q0="equilibrium", reference="follow",
                 rebase_speed=rebase_speed, rebase_angle=rebase_angle, rebase_dt=aero_dt,
                 top_frequency_hz=top_frequency_hz, peak_bin=peak_bin,
                 turning_points=turning_points, out=out,
                 outputs=["rotor.theta", "rotor.theta.velocity", "generator.theta.velocity"],
                 **options)
    st.reserve(n_aero * m_sub * dt)
    settings = {"turbine": turbine.name, "gearbox": getattr(gearbox, "name", ""),
                "t_end": t_end, "dt": dt, "aero_dt": aero_dt, "aero_hold": aero_hold,
                "rotor_speed0_rpm": rotor_speed0_rpm, "azimuth0_deg": azimuth0_deg,
                "mounting_azimuth_deg": turbine.mounting_azimuth_deg,
                "rebase_speed": rebase_speed, "rebase_angle": rebase_angle,
                "method": method, "options": options, "gravity_mps2": g,
                "turning_points": turning_points, "top_frequency_hz": top_frequency_hz,
                "controller": None if controller is None else type(controller).__name__,
                "mass_scaling": st.settings["mass_scaling"], "speed_rpm": None,
                "shaft_end_force": "on the carrier" if plant.bending else "not modelled (the "
                "first stage's carrier has no translation)",
                "wind": {k: v for k, v in vars(wind).items() if not k.startswith("_")}}
    return Coupling(plant, st, step, n_aero, m_sub * dt, settings,
                    None if out is None else Path(out))


def _check_drivetrain(gearbox) -> None:
    """Refuse a gearbox the coupled run cannot take, naming what is missing: the bodies
    ``rotor`` and ``generator``, one free drivetrain rotation, piecewise-linear contacts (the
    start is a static equilibrium)."""
    asm = gearbox.assemble()
    asm.require_piecewise_linear("the turbine co-simulation (its start is a static "
                                 "equilibrium)")
    for name in ("rotor.theta", "generator.theta"):
        if name not in asm.dof_names:
            raise ModelError("gearbox", f"has no DOF {name!r}: the drivetrain model needs "
                             "bodies 'rotor' and 'generator' (see studies/models/600kw.toml)")
    rigid_rotation(asm)
    ratio = gearbox.bodies["rotor"].speed_ratio
    if ratio != 1.0:
        raise ModelError("gearbox.rotor.speed_ratio", f"= {ratio!r}: the rotor is the "
                         "drivetrain's input, 1 (its azimuth is the blades')")
