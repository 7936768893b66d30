"""The turbine and the gearbox in one run: aerodynamics, generator and the gearbox's contact
dynamics together (DESIGN 2.5, paper section 5; issue 5's multirate scheme).

The gearbox model (``600kw.toml``: rotor inertia, main shaft, stages, generator, housing on its
suspension) carries the whole drivetrain, so its free rotation is the turbine's rotation. Its
coordinates ``q`` are deflections from a rigid reference rotation ``psi_ref(t) = psi_f +
Omega_f (t - t_f)`` re-based at time ``t_f``; the rotor's azimuth and speed are
``psi_ref + q_rotor`` and ``Omega_f + v_rotor``. Two rates:

- **aerodynamic step** ``aero_dt`` (the turbine's own rate): the wind is sampled at the rotating
  blade elements and the blade-element momentum loads evaluated. Across the gearbox steps of an
  aerodynamic step the loads are ``aero_hold="interpolate"`` (default): interpolated linearly
  to the loads at the step's end, evaluated at the azimuth predicted there with the current
  speed, so the load is continuous; ``"hold"``: evaluated at the step's start and held (a
  jump at every aerodynamic step, which rings the gearbox); ``"linear"``: extrapolated from
  the last two samples (also discontinuous). Their error against evaluating at every gearbox
  step is measured in ``benchmarks/turbine_speed.py``.
- **gearbox step** ``dt``: the exact piecewise-linear integrator (or any ``method`` of
  :func:`gearmodal.simulate`) with every contact event. The shaft-end force (global axes) is
  mapped onto the rotating carrier at each gearbox step's azimuth, exactly.

The induction generator enters the linear gearbox equations as its tangent at the reference
speed: torque ``T(w_f) + (dT/dw) (w - w_f)``, i.e. a constant load plus a viscous damper
``dT/dw`` on the generator's rotation, so its strong slip damping is implicit (no step
limit). The gearbox geometry turns with the reference azimuth and is integrated exactly as the
time-periodic system it is (:mod:`gearmodal.integrate.periodic`): there is no refreeze. The
reference is **re-based** only where the speed drifts (by ``rebase_speed`` of the reference
speed), the drivetrain's rigid rotation ``phi = r^T M q / r^T M r`` (``r`` the free rotation
mode) leaves it by ``rebase_angle``, or the generator cuts in. The reference azimuth stays
continuous: the turning geometry never jumps (moving ``phi`` into the azimuth at once would
move every turning gap by ``phi`` times a deflection: a kick to the carrier floating in its
clearance). The new reference speed is the drivetrain's plus ``phi / REBASE_TAU``, so the
rigid rotation left in ``q`` is taken up smoothly; the speed terms and the generator tangent
are taken at the new speed, and the velocities re-expressed against it exactly.

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

import dataclasses
import functools
import json
import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd
import scipy.linalg as sla

from ..errors import ModelError, SolveError
from ..integrate import (
    PEAK_BIN,
    Driver,
    Recorder,
    SimulationResult,
    build_result,
    check_fits,
    get_method,
    mesh_stiffness,
    stored_result,
)
from ..integrate.azimuth import AzimuthAssembler
from ..integrate.rigid import elastic as take_out_rigid
from ..integrate.system import PiecewiseLinearSystem
from ..massscale import scaled_mass
from ..model.components import G_STANDARD, GRAVITY
from ..result_io import (
    HEADER,
    TableWriter,
    digests,
    read_header,
    replacing,
    verify_digests,
    write_header,
)
from ..static import equilibrium
from .rotor import LOAD_COLUMNS
from .turbine import RPM, TURBINE_COLUMNS, Turbine, TurbineResult, mark_cut_in
from .wind import Wind

#: layout version of :meth:`DrivetrainResult.save` (``drivetrain.json``): 2 Parquet or CSV
#: tables, 1 CSV only (still read)
SAVE_VERSION = 2

HOLDS = ("interpolate", "hold", "linear")
#: time (s) over which a re-based reference speed takes up the drivetrain's rigid rotation
REBASE_TAU = 0.1
#: a gearbox state entry beyond this (m, rad, m/s, rad/s from the re-based rotation) means the
#: integration method diverged
DIVERGED = 1e6


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

    def to_frame(self) -> pd.DataFrame:
        """The turbine loads at the aerodynamic rate."""
        return self.turbine.loads

    def plot(self):
        """Rotor speed, power and the planet-1 tooth forces against time; returns the Figure."""
        import matplotlib.pyplot as plt

        fig, axs = plt.subplots(3, 1, sharex=True, figsize=(9, 8))
        d = self.turbine.view(["rotor_speed_rpm", "power_W"])
        axs[0].plot(d.index, d["rotor_speed_rpm"])
        axs[0].set_ylabel("rotor speed [rpm]")
        axs[1].plot(d.index, d["power_W"] / 1e3)
        axs[1].set_ylabel("electrical power [kW]")
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
    def load(cls, directory) -> DrivetrainResult:
        """The run :meth:`save` wrote to ``directory``: turbine loads and the gearbox result,
        floats exact; an older layout is refused naming the directory."""
        d = Path(directory)
        head = read_header(d, "DrivetrainResult", (1, SAVE_VERSION), header="drivetrain.json")
        verify_digests(d, head.get("sha256") or {})
        return cls(turbine=TurbineResult.load(d), gearbox=SimulationResult.load(d),
                   stats=json.loads((d / "stats.json").read_text()))


def _first_mesh_k(system0, _system, azimuth):
    """The stiffness rows of the force table at ``azimuth``: the first stretch's system's, as
    the run held in memory takes them (:func:`gearmodal.integrate.mesh_stiffness`)."""
    return mesh_stiffness(system0, azimuth)


def _accelerating_equilibrium(asm, r: np.ndarray, speed_rpm: float, loads: dict) -> np.ndarray:
    """Deflections of the drivetrain accelerating rigidly under ``loads``: the static
    equilibrium under the loads plus the d'Alembert force ``-M r alpha`` with ``alpha = r^T F /
    r^T M r``, which together do no work on the free rotation. The start of a run: no
    artificial impact when the teeth take up the initial torque."""
    Mr = asm.M @ r
    alpha = float(r @ asm.load_vector(loads)) / float(r @ Mr)
    ext = dataclasses.replace(asm, B=np.column_stack([asm.B, -Mr]),
                              load_names=[*asm.load_names, "rigid_acceleration"])
    q = equilibrium(ext, {**loads, "rigid_acceleration": alpha}, speed_rpm).q.to_numpy()
    return q - r * float(Mr @ q) / float(r @ Mr)


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


def simulate_drivetrain(turbine: Turbine, wind: Wind, gearbox, t_end: float, *,
                        dt: float = 2e-3, aero_dt: float = 0.02, aero_hold: str = "interpolate",
                        rotor_speed0_rpm: float = 6.0, azimuth0_deg: float = 0.0,
                        connected: bool = False, rebase_speed: float = 0.01,
                        rebase_angle: float = 5e-4,
                        method: str = "exact", gravity: bool | float = True,
                        top_frequency_hz: float | None = None,
                        peak_bin: float | None = PEAK_BIN, turning_points: bool = True,
                        progress=None, out=None, **options) -> DrivetrainResult:
    """Run turbine and gearbox together from ``rotor_speed0_rpm`` for ``t_end`` s.

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
        :data:`DIVERGED`) stops the run with a :class:`gearmodal.ModelError` naming it and the
        time.
    gravity : the weight of every gearbox body (the model's load ``gravity``, along the
        turbine's ``tilt_deg``): True (standard gravity, 9.80665 m/s^2), False, or g in m/s^2.
    top_frequency_hz : the mass-scaling rung (:mod:`gearmodal.massscale`): the gearbox's
        modes above this frequency are slowed to it by added mass along them (stiffness,
        gaps, loads exact), so the exact method's pieces are longer. ``None`` (default): the
        full model. Its error on the engineering quantities is measured in
        ``benchmarks/turbine_speed.py``.
    peak_bin : width of the bins of the exact peaks, s, as :func:`gearmodal.simulate`'s;
        ``None``: no exact peaks (the sampled ones, about 22 % less integration CPU).
    turning_points : the exact turning points of the gearbox's force channels, as
        :func:`gearmodal.simulate`'s (what :func:`gearmodal.fatigue.drivetrain_fatigue`'s
        exact DELs count); False: none (up to about 65 % less integration CPU).
    progress : ``progress(i, n)`` per aerodynamic step (the solver never prints).
    out : a directory the run streams to as it goes (:meth:`DrivetrainResult.save`'s layout:
        Parquet row groups of the gearbox rows and of the turbine loads); the result reads
        its tables from there when first asked for, so the run's memory does not grow with
        its duration. ``None``: every row is held in memory.
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
    cpu0 = time.process_time()
    clock = {"aero_s": 0.0, "wind_s": 0.0, "wind_setup_s": 0.0}
    if wind.turbulent:
        tw = time.process_time()
        wind._turbulence()
        clock["wind_setup_s"] = time.process_time() - tw

    if g and getattr(gearbox, "tilt_deg", 0.0) != turbine.tilt_deg:
        gearbox = gearbox.copy()  # gravity along the turbine's shaft tilt
        gearbox.tilt_deg = turbine.tilt_deg
    geo = AzimuthAssembler(gearbox)
    mass_scaling = None
    if top_frequency_hz is not None:
        Ms, mass_scaling = scaled_mass(geo, top_frequency_hz)
        geo = geo.with_mass(Ms)
    # the start is a static equilibrium and the gearbox runs piecewise linear
    geo.template.require_piecewise_linear("the turbine co-simulation (its start is a static "
                                          "equilibrium)")
    asm0 = geo.template
    for name in ("rotor.theta", "generator.theta"):
        if name not in asm0.dof_names:
            raise ModelError("gearbox", f"has no DOF {name!r}: the drivetrain model needs "
                             "bodies 'rotor' and 'generator' (see studies/models/600kw.toml)")
    # the first stage's carrier takes the shaft-end force; a torsional one has no
    # translation, so the force is not modelled (the turbine's loads table still reports it)
    carrier = next((b.name for b in gearbox.bodies.values() if b.role == "carrier"), None)
    if carrier is None:
        raise ModelError("gearbox", "has no planetary carrier (a body of role 'carrier', as "
                         "gm.planetary_stage makes) to carry the shaft-end force")
    carrier_x = f"{carrier}.force_x"
    bending = carrier_x in asm0.load_names
    n = asm0.n
    i_rot, i_gen = asm0.dof_names.index("rotor.theta"), asm0.dof_names.index("generator.theta")
    names = ["rotor.torque", "generator.torque"]
    if bending:
        names += [carrier_x, carrier_x[:-1] + "y"]
    if g:
        names.append(GRAVITY)
    cols = [asm0.load_names.index(c) for c in names]
    r = rigid_rotation(asm0)
    Mr = asm0.M @ r
    J = float(r @ Mr)
    g_ratio = float(r[i_gen])  # generator speed per rotor speed, signed
    sg = math.copysign(1.0, g_ratio)
    gen = turbine.generator
    rot = turbine.rotor

    def elastic(X):
        """Elastic deflections and rates of states ``X`` (rows): the rigid rotation (re-based
        at each re-basing) taken out, column by column."""
        return take_out_rigid(X, n, r, Mr, J)

    mount = math.radians(turbine.mounting_azimuth_deg) + 0.5 * math.pi  # planet 1 on blade 1

    def aero(ta, psi, om, reset):
        """Hub loads at time ``ta``, blade-1 azimuth ``psi``, speed ``om``; timed."""
        tw = time.process_time()
        bw = turbine.blade_wind(wind, ta, psi)
        tv = time.process_time()
        out = rot.loads(om, psi, *bw, reset=reset)
        clock["wind_s"] += tv - tw
        clock["aero_s"] += time.process_time() - tv
        return out

    def reference(om_ref, on_grid, prev=None):
        """The gearbox system turning at ``om_ref`` (rad/s) with the generator's tangent;
        ``prev``: the last system, whose spectral bounds (over all states and per state) are
        reused when only the speed drifted
        (by ``rebase_speed``: the speed terms are soft against the meshes; the integrator adds
        a margin, and the series' tail check halves any piece it makes too long)."""
        T0_, c_gen = gen.tangent(sg * g_ratio * om_ref) if on_grid else (0.0, 0.0)
        sy = PiecewiseLinearSystem(
            asm0, om_ref / RPM, geometry=geo,
            spectral_bound=None if prev is None else getattr(prev, "rho_bound", None),
            state_bound=None if prev is None else getattr(prev, "state_bound", None))
        if c_gen:
            sy.add_damping(i_gen, c_gen)  # the generator's tangent slip damping
        sy.use_loads(cols)  # load values in, the turning load map followed exactly
        return sy, T0_

    n_aero = int(math.ceil(t_end / aero_dt - 1e-9))
    n_steps = n_aero * m_sub
    if out is None:
        nsp = len(asm0.springs) if asm0.springs is not None else 0
        check_fits(n_steps + 1, 4 * n + len(asm0.contacts.element) + nsp,
                   "give out=DIR (the rows go to disk as the run goes; gearmodal simulate "
                   "does), a longer dt or a shorter t_end")
    om_f = rotor_speed0_rpm * RPM  # reference speed and azimuth at the last re-basing
    psi_f = math.radians(azimuth0_deg)
    t_f = 0.0
    x = np.zeros(2 * n)
    s = None
    on = bool(connected)
    cut_in = 0.0 if on else None
    system, T0 = None, 0.0
    om_rho = om_f  # the speed of the last full spectral bound
    rows = []
    loads_out = None  # the turbine loads' writer of a streamed run
    if out is not None:
        Path(out).mkdir(parents=True, exist_ok=True)
        loads_out = TableWriter(out, "turbine_loads", TURBINE_COLUMNS[1:], dtype=None)
    run = None  # the integration Driver, from the start state on
    stats: dict = {"n_rebases": 0}
    prev = ld_next = None
    # reference input azimuth (with the mounting) at each step: a run held in memory
    az_grid = np.zeros(n_steps + 1) if out is None else None
    # the output times from an aerodynamic step's start, and the fraction of the step, j / m:
    # at half the output step the shared times get the same load and azimuth to the bit (not
    # (t + tau) - t, rounded with t), so the exact method's solution does not depend on it
    tau = dt * np.arange(m_sub + 1)
    frac = np.arange(m_sub + 1) / m_sub
    for k in range(n_aero):
        t = k * aero_dt
        psi = psi_f + om_f * (t - t_f) + x[i_rot]
        om = om_f + x[n + i_rot]
        # -- aerodynamics at the rotor's actual azimuth and speed ("interpolate": also at
        # the end of the step, predicted with the current speed)
        if aero_hold == "interpolate":
            if k == 0:
                ld = aero(t, psi, om, True)
            else:
                ld = ld_next
            ld_next = aero(t + aero_dt, psi + om * aero_dt, om, False)
        else:
            ld = aero(t, psi, om, k == 0)
        fy, fz = turbine.rear_force(ld)
        w_gen = sg * (g_ratio * om_f + x[n + i_gen])  # generator speed, forward positive
        switched = False
        if not on and w_gen >= gen.omega_sync:
            on, cut_in, switched = True, t, True
        tg = gen.torque(w_gen) if on else 0.0
        rows.append((t, om / RPM, math.degrees(psi) % 360.0, on, tg, tg * w_gen,
                     *(ld[c] for c in LOAD_COLUMNS), fy, fz))
        if loads_out is not None and len(rows) >= 1000:
            loads_out.append_frame(pd.DataFrame(rows, columns=TURBINE_COLUMNS)
                                   .set_index("time"))
            rows = []
        # -- loads on the gearbox over this aerodynamic step (held or extrapolated)
        u_now = np.array([ld["torque_Nm"], fy, fz])
        if aero_hold == "interpolate":
            u_next = np.array([ld_next["torque_Nm"], *turbine.rear_force(ld_next)])
            u = u_now[None, :] + np.outer(frac, u_next - u_now)
        elif aero_hold == "linear" and prev is not None:
            u = u_now[None, :] + np.outer(frac, u_now - prev)
        else:
            u = np.repeat(u_now[None, :], m_sub + 1, axis=0)
        prev = u_now
        kk = k * m_sub  # gearbox step index
        # -- re-basing: rigid rotation into the reference; speed terms, generator tangent
        phi, dom = float(Mr @ x[:n]) / J, float(Mr @ x[n:]) / J
        if (system is None or switched or abs(dom) > rebase_speed * max(abs(om_f), 1e-3)
                or abs(phi) > rebase_angle):
            # the reference azimuth stays continuous (no jump of the turning geometry); its
            # new speed is the drivetrain's plus phi / REBASE_TAU, which steers the rigid
            # rotation left in q back towards zero
            om_new = om_f + dom + phi / REBASE_TAU if system is not None else om_f
            psi_f, t_f = psi_f + om_f * (t - t_f), t
            x[n:] -= r * (om_new - om_f)
            om_f = om_new
            # the spectral bound is computed anew at the start, at cut-in and once the speed
            # has moved by its own size since it last was; in between the last one serves
            # (with a 1 % margin: on the 600 kW drivetrain the bound moves by 1e-5 from 6 to
            # 22.5 rpm)
            fresh = (system is None or switched
                     or abs(om_f - om_rho) > max(abs(om_rho), 1e-3))
            system, T0 = reference(om_f, on, None if fresh else system)
            if fresh:
                om_rho = om_f
            if s is None:
                # the drivetrain accelerating rigidly under the first loads, at the initial
                # azimuth's geometry
                loads0 = {"rotor.torque": u[0, 0], "generator.torque": -sg * T0}
                if bending:
                    loads0.update({names[2]: u[0, 1], names[3]: u[0, 2]})
                if g:
                    loads0[GRAVITY] = g
                x[:n] = _accelerating_equilibrium(geo.assemble(psi_f + mount), r, om_f / RPM,
                                                  loads0)
                s = system.penetration(x, psi_f + mount) > 0
                sink = None
                if out is not None:
                    sink = Recorder(out, system, dt, elastic=elastic,
                                    mesh_k=functools.partial(_first_mesh_k, system))
                run = Driver(method, dt, x, s, peak_bin=peak_bin, sink=sink,
                             turning_points=turning_points, **options)
                if sink is None:
                    run.reserve(n_steps)
            else:
                run.rebase(system, x, psi_f + mount)
                stats["n_rebases"] += 1
        az0 = psi_f + om_f * (t - t_f) + mount
        # load values: rotor torque, generator torque (its tangent's constant part), the
        # shaft-end force in ground axes (zero when no carrier translation takes it), 1 for
        # the centrifugal force
        F = np.column_stack([u[:, 0], np.full(m_sub + 1, -sg * T0)]
                            + ([u[:, 1], u[:, 2]] if bending else [])
                            + ([np.full(m_sub + 1, g)] if g else [])
                            + [np.ones(m_sub + 1)])
        a0 = 0 if kk == 0 else 1
        if az_grid is not None:
            az_grid[kk + a0:kk + m_sub + 1] = az0 + om_f * tau[a0:]
        run.advance(system, m_sub, F, azimuth0=az0, azimuths=az0 + om_f * tau)
        x = run.x.copy()
        if not (math.isfinite(om) and np.abs(x).max() <= DIVERGED):
            # no gearbox state reaches this (deflections from the re-based rotation, in m and
            # rad, and their rates): the method has diverged, and the next aerodynamic step
            # would fail somewhere less clear (the generator's slip overflows)
            raise SolveError(
                "method", f"= {method!r}: the gearbox state diverged in the aerodynamic step "
                f"ending at t = {t + aero_dt:.3f} s (largest entry {np.abs(x).max():.3g}, "
                f"above {DIVERGED:g}); "
                + ("Newmark switches contacts at step ends, which is unstable with stiff "
                   "meshes and a clearance (benchmarks/RESULTS.md, stability map): use "
                   "method='exact'" if method == "newmark" else "reduce dt or use "
                   "method='exact'"))
        if progress is not None:
            progress(k + 1, n_aero)
    X, S, events = run.arrays()
    segs = run.segments
    stats.update(run.stats)
    cpu = time.process_time() - cpu0
    clock["gearbox_s"] = cpu - clock["aero_s"] - clock["wind_s"] - clock["wind_setup_s"]
    stats.update(clock)
    stats.update(cpu_s=cpu, n_events=run.n_events, n_steps=n_steps,
                 realtime_ratio=n_aero * aero_dt / max(cpu - clock["wind_setup_s"], 1e-12))
    settings = {"turbine": turbine.name, "gearbox": getattr(gearbox, "name", ""),
                "t_end": t_end, "dt": dt, "aero_dt": aero_dt, "aero_hold": aero_hold,
                "rotor_speed0_rpm": rotor_speed0_rpm, "azimuth0_deg": azimuth0_deg,
                "mounting_azimuth_deg": turbine.mounting_azimuth_deg,
                "rebase_speed": rebase_speed, "rebase_angle": rebase_angle,
                "method": method, "options": options, "gravity_mps2": g,
                "turning_points": turning_points,
                "top_frequency_hz": top_frequency_hz, "mass_scaling": mass_scaling,
                "shaft_end_force": "on the carrier" if bending else "not modelled (the first "
                "stage's carrier has no translation)",
                "wind": {k: v for k, v in vars(wind).items() if not k.startswith("_")}}
    if out is not None:
        sim = stored_result(run.sink, segs[0][2], run.s0, stats, settings,
                            (0.0, n_steps * dt), peaks=run.peaks)
        loads_out.append_frame(pd.DataFrame(rows, columns=TURBINE_COLUMNS).set_index("time"))
        loads_out.close()
        tres = TurbineResult(loads=None, cut_in_time=cut_in, settings=settings, stored=out)
        res = DrivetrainResult(turbine=tres, gearbox=sim, stats=stats)
        res.save(out)  # the headers and the small tables beside the streamed ones
        return res
    t_grid = np.arange(n_steps + 1) * dt
    sim = build_result([tuple(sg_) for sg_ in segs], t_grid, X, S, events, run.s0, stats,
                       mesh_stiffness(segs[0][2], az_grid), settings, peaks=run.peaks)
    # elastic deflections: the rigid rotation (re-based at each re-basing) taken out, column
    # by column (no run-length temporaries: a 600 s run has 600 001 rows)
    idx = pd.Index(t_grid, name="time")
    q, v = elastic(X)
    for name, block in (("q", q), ("v", v)):
        setattr(sim, name, pd.DataFrame(block, index=idx, columns=asm0.dof_names,
                                        copy=False))
    loads = pd.DataFrame(rows, columns=TURBINE_COLUMNS).set_index("time")
    tres = TurbineResult(loads=loads, cut_in_time=cut_in, settings=settings)
    return DrivetrainResult(turbine=tres, gearbox=sim, stats=stats)
