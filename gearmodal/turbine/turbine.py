"""The turbine: rotor, drivetrain inertia, generator, main-shaft bearings; start-up and operation
in wind (DESIGN 2.5; paper section 5).

The rotor turns as a rigid body at the aerodynamic rate ``dt``::

    J omega' = Q_aero(omega, psi, wind) - ratio T_gen(ratio omega)        (rigid drivetrain)

with ``J`` the drivetrain inertia reduced to the rotor (rotor + gearbox + generator ratio^2).
Explicit midpoint steps; the generator's slip stiffness limits ``dt`` to well below ``J /
(ratio^2 dT/domega)`` (about 0.1 s for the 600 kW machine): a clear error names ``dt`` when it
is too long. The generator cuts in when its speed first reaches synchronous speed.

Shaft-end loads on the gearbox: the main shaft is a rigid beam on the front main bearing (at
``front_bearing`` m downwind of the hub centre) and the gearbox as rear bearing (at
``rear_bearing``). The hub's transverse force ``F`` and moment ``M`` give the rear reaction by
statics of the two-support beam (moments about the front bearing)::

    R_rear_z = (M_y + x_f F_z) / (x_r - x_f),     R_rear_y = (-M_z + x_f F_y) / (x_r - x_f)

and the gearbox carries ``-R_rear`` (``rear_force_y_N``, ``rear_force_z_N``): an overhung rotor's
weight lifts the gearbox end of the shaft.
"""

from __future__ import annotations

import json
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from ..errors import ModelError, SolveError
from ..model.schema import REQUIRED, Field, Table
from ..result_io import (
    VIEW_ROWS,
    copy_table,
    decimated,
    read_table,
    remove_table,
    table_path,
    write_table,
)
from .airfoil import Airfoil
from .generator import InductionGenerator
from .rotor import LOAD_COLUMNS, Rotor
from .wind import Wind

RPM = math.pi / 30
#: columns of a turbine run's loads table (TurbineResult.loads, with "time" the index)
TURBINE_COLUMNS = ["time", "rotor_speed_rpm", "azimuth_deg", "generator_connected",
                   "generator_torque_Nm", "power_W", *LOAD_COLUMNS, "rear_force_y_N",
                   "rear_force_z_N", "pitch_deg"]
#: the unit of each turbine loads column (``power_W``: the generator shaft's power, torque
#: times speed, before the generator's losses)
TURBINE_UNITS = {"time": "s", "rotor_speed_rpm": "rpm", "azimuth_deg": "deg",
                 "generator_connected": "-", "generator_torque_Nm": "N m", "power_W": "W",
                 "thrust_N": "N", "torque_Nm": "N m", "shear_y_N": "N", "shear_z_N": "N",
                 "tilt_Nm": "N m", "yaw_Nm": "N m", "rear_force_y_N": "N",
                 "rear_force_z_N": "N", "pitch_deg": "deg"}
#: OpenFAST's names and units of the turbine channels (ElastoDyn, ServoDyn, AeroDyn output
#: lists): name -> (unit, the gearmodal column, its factor) for :meth:`TurbineResult.openfast`
OPENFAST_CHANNELS = {
    "RotSpeed": ("rpm", "rotor_speed_rpm", 1.0),
    "Azimuth": ("deg", "azimuth_deg", 1.0),
    "BldPitch1": ("deg", "pitch_deg", 1.0),
    "GenTq": ("kN-m", "generator_torque_Nm", 1e-3),
    "RtAeroFxh": ("N", "thrust_N", 1.0),
    "RtAeroMxh": ("N-m", "torque_Nm", 1.0),
}


@dataclass
class Turbine:
    """A turbine. rotor : :class:`Rotor`. generator : :class:`InductionGenerator` (a
    stall-regulated, fixed-speed machine), or None when a controller sets the generator torque
    and the pitch (a coupled run's ``controller``, e.g. :class:`~.rosco.Rosco` for the NREL
    5 MW turbine: :func:`gearmodal.turbine.nrel5mw.turbine`). gear_ratio : generator / rotor
    speed. inertia : drivetrain
    inertia at the rotor, kg m^2. hub_height, front_bearing, rear_bearing : m.
    mounting_azimuth_deg : azimuth of planet 1 relative to blade 1 (deg). tilt_deg : shaft
    tilt, the rotor end up (deg): the rotor's inflow (:meth:`blade_wind`) and the direction of
    gravity on the gearbox's bodies in a turbine run (the gearbox model's own ``tilt_deg`` is
    replaced by it)."""

    rotor: Rotor
    generator: InductionGenerator | None
    gear_ratio: float
    inertia: float
    hub_height: float = 40.0
    front_bearing: float = 1.0
    rear_bearing: float = 2.6
    mounting_azimuth_deg: float = 0.0
    tilt_deg: float = 0.0
    name: str = "turbine"

    def __post_init__(self):
        if not self.rear_bearing > self.front_bearing > 0:
            raise ModelError("turbine.rear_bearing", f"= {self.rear_bearing!r}: need "
                             f"rear_bearing > front_bearing > 0 m")
        if not self.inertia > 0 or not self.gear_ratio > 0:
            raise ModelError("turbine.inertia", "inertia and gear_ratio must be > 0")

    def blade_wind(self, wind: Wind, t: float, psi: float):
        """Wind at the blade elements at time ``t`` (s) and blade-1 azimuth ``psi`` (rad):
        ``(u, vt)``, normal to the coned blades and in plane along the blade motion, m/s,
        each (blades, n), for :meth:`Rotor.loads` (:mod:`.rotor`'s docstring). The shaft,
        tilted by ``tilt_deg`` (the rotor end up), has the axis ``x_s = (cos, 0, -sin)`` and
        the normal ``z_s = (sin, 0, cos)`` in the wind's axes; an element at ``(x, y, z)`` in
        the shaft's axes stands ``z cos(tilt) - x sin(tilt)`` above the hub and
        ``x cos(tilt) + z sin(tilt)`` downwind of it, which its tower shadow takes (at least
        just outside the tower)."""
        rot = self.rotor
        y, z, psib = rot.positions(psi)
        tau = math.radians(self.tilt_deg)
        ct, st = math.cos(tau), math.sin(tau)
        height = z + self.hub_height if tau == 0.0 else \
            self.hub_height + z * ct - rot.r_axial[None, :] * st
        if wind.tower_radius > 0 and (tau != 0.0 or rot.precone != 0.0):
            # the tower shadow at each element's own distance upwind of the tower: the rotor
            # plane's, less the element's downwind offset x cos(tilt) + z sin(tilt)
            gap = wind.tower_distance - (rot.r_axial[None, :] * ct + z * st)
            vel = wind.velocity(t, y, height, np.maximum(gap, 1.001 * wind.tower_radius))
        else:
            vel = wind.velocity(t, y, height)
        sp, cp = np.sin(psib)[:, None], np.cos(psib)[:, None]
        if tau == 0.0:
            ux, uz = vel[0], vel[2]
        else:
            ux, uz = vel[0] * ct - vel[2] * st, vel[0] * st + vel[2] * ct
        vt = -vel[1] * cp - uz * sp
        if rot.precone == 0.0:
            return ux, vt
        ur = -vel[1] * sp + uz * cp  # along the blade's radial direction e_r
        return ux * math.cos(rot.precone) - ur * math.sin(rot.precone), vt

    def hub_loads(self, wind: Wind, t: float, omega: float, psi: float, *,
                  pitch: float | None = None, reset: bool = False) -> dict:
        """The rotor's hub loads (:meth:`Rotor.loads`) in ``wind`` at time ``t`` (s), rotor
        speed ``omega`` (rad/s) and blade-1 azimuth ``psi`` (rad), the shaft tilted by
        ``tilt_deg``."""
        return self.rotor.loads(omega, psi, *self.blade_wind(wind, t, psi), reset=reset,
                                pitch=pitch, tilt=math.radians(self.tilt_deg))

    def power_coefficient(self, wind: Wind, omega: float, pitch: float | None = None, *,
                          azimuths: int = 8) -> tuple[float, float]:
        """``(Cp, Ct)`` in a steady ``wind`` (its shear, no turbulence; tower shadow as the
        wind has it) at rotor speed ``omega`` (rad/s) and ``pitch`` (rad): the loads averaged
        over ``azimuths`` rotor positions evenly spread over one blade passage, relative to
        the wind's hub speed on the swept area ``pi (R cos(precone))^2`` (as CCBlade, whose
        ``nSector`` averages the same way)."""
        if wind.turbulent:
            raise ModelError("wind.turbulence_intensity", f"= {wind.turbulence_intensity}: "
                             "the power coefficient needs a steady wind")
        if not (isinstance(azimuths, int) and 1 <= azimuths <= 360):
            raise ModelError("azimuths", f"= {azimuths!r}: an integer in [1, 360]")
        step = 2 * math.pi / self.rotor.blades / azimuths
        sums = {"torque_Nm": 0.0, "thrust_N": 0.0}
        for k in range(azimuths):
            ld = self.hub_loads(wind, 0.0, omega, k * step, pitch=pitch, reset=True)
            for key in sums:
                sums[key] += ld[key] / azimuths
        return self.rotor.coefficients(sums, wind.mean_speed, omega)

    def rear_force(self, ld: dict) -> tuple[float, float]:
        """``(y, z)`` force of the shaft end on the gearbox, N (module docstring)."""
        xf, xr = self.front_bearing, self.rear_bearing
        rz = (ld["tilt_Nm"] + xf * ld["shear_z_N"]) / (xr - xf)
        ry = (-ld["yaw_Nm"] + xf * ld["shear_y_N"]) / (xr - xf)
        return -ry, -rz


def mark_cut_in(axs, cut_in_time: float | None) -> None:
    """A dashed vertical line at the generator's cut-in on each of ``axs``."""
    if cut_in_time is not None:
        for a in axs:
            a.axvline(cut_in_time, color="0.6", ls="--", lw=0.8)


#: the tables of a turbine file (:mod:`gearmodal.model.schema`); section -> (table, required)
TURBINE_FILE = {
    "turbine": (Table("turbine", (
        Field("name", "string", doc="turbine name (default: the file name)"),
        Field("gear_ratio", "number", low=0.0, low_open=True, default=REQUIRED,
              doc="generator over rotor speed"),
        Field("inertia", "number", "kg m^2", low=0.0, low_open=True, default=REQUIRED,
              doc="drivetrain inertia at the rotor (turbine-only runs)"),
        Field("hub_height", "number", "m", low=0.0, low_open=True, default=REQUIRED,
              doc="hub height"),
        Field("front_bearing", "number", "m", low=0.0, low_open=True, default=REQUIRED,
              doc="front main bearing downwind of the hub centre"),
        Field("rear_bearing", "number", "m", low=0.0, low_open=True, default=REQUIRED,
              doc="rear main bearing (the gearbox), beyond the front one"),
        Field("mounting_azimuth_deg", "number", "deg", default=0.0,
              doc="planet 1 relative to blade 1"),
        Field("tilt_deg", "number", "deg", low=-30.0, high=30.0, default=0.0,
              doc="shaft tilt, rotor end up: the rotor's inflow and the direction of "
                  "gravity on the gearbox bodies")), "The turbine."), True),
    "rotor": (Table("rotor", (
        Field("radius", "number", "m", low=0.0, low_open=True, default=REQUIRED,
              doc="tip radius"),
        Field("hub_radius", "number", "m", low=0.0, low_open=True, default=REQUIRED,
              doc="hub radius"),
        Field("blades", "integer", low=1, high=10, default=3, doc="number of blades"),
        Field("pitch_deg", "number", "deg", low=-90.0, high=90.0, default=0.0,
              doc="fixed blade pitch"),
        Field("mass", "number", "kg", low=0.0, default=REQUIRED, doc="rotor mass"),
        Field("air_density", "number", "kg/m^3", low=0.0, low_open=True, default=1.225,
              doc="air density")), "The rotor."), True),
    "blade": (Table("blade", (
        Field("r", "vector", "m", low=0.0, default=REQUIRED,
              doc="element radii, increasing, inside (hub_radius, radius)"),
        Field("chord", "vector", "m", low=0.0, low_open=True, default=REQUIRED,
              doc="chord per element"),
        Field("twist_deg", "vector", "deg", default=REQUIRED, doc="twist per element")),
        "The blade's elements (the same length each)."), True),
    "airfoil": (Table("airfoil", (
        Field("lift_slope", "number", "1/rad", low=1.0, high=8.0, default=6.2,
              doc="pre-stall lift slope"),
        Field("alpha0_deg", "number", "deg", low=-20.0, high=20.0, default=-2.6,
              doc="zero-lift angle"),
        Field("stall_deg", "number", "deg", low=4.0, high=30.0, default=12.0,
              doc="stall angle"),
        Field("cd0", "number", low=0.0, high=0.1, default=0.008, doc="pre-stall drag"),
        Field("k_drag", "number", low=0.0, high=10.0, default=0.6,
              doc="pre-stall drag growth (alpha in rad)"),
        Field("aspect_ratio", "number", low=1.0, high=1e3, default=12.0,
              doc="blade length over mean chord (sets the post-stall maximum drag)"),
        Field("name", "string", default="NACA 63-415 (Viterna)", doc="airfoil name")),
        "The airfoil: pre-stall data and Viterna-Corrigan post-stall."), False),
    "generator": (Table("generator", (
        Field("rated_power", "number", "W", low=1.0, high=1e9, default=600e3,
              doc="rated power"),
        Field("sync_speed_rpm", "number", "rpm", low=1.0, high=1e5, default=1800.0,
              doc="synchronous speed of the generator"),
        Field("rated_slip", "number", low=1e-4, high=0.2, default=0.02,
              doc="slip at rated power"),
        Field("pullout_ratio", "number", low=1.05, high=10.0, default=2.5,
              doc="pull-out over rated torque")), "The induction generator."), True),
}


def load_turbine(path) -> Turbine:
    """A :class:`Turbine` from a TOML file (``studies/turbines/600kw_turbine.toml``); every
    table and key is checked (``docs/file-format.md``) and errors name the key and the file."""
    p = Path(path)
    try:
        d = tomllib.loads(p.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError, RecursionError) as err:
        raise ModelError("path", f"= {str(path)!r}: cannot read the turbine file "
                         f"({type(err).__name__}: {err})") from None
    try:
        return _turbine(d, p.stem)
    except ModelError as e:
        raise ModelError(e.field, f"{e.message} (in {p})") from None


def _turbine(d: dict, default_name: str) -> Turbine:
    for key in d:
        if key not in TURBINE_FILE:
            raise ModelError(key, "unknown section; allowed: " + ", ".join(TURBINE_FILE))
    v = {}
    for key, (table, required) in TURBINE_FILE.items():
        if key not in d and required:
            raise ModelError(key, f"missing section [{key}]")
        v[key] = table.read(key, d.get(key, {}))
    t, ro, bl, af, ge = v["turbine"], v["rotor"], v["blade"], v["airfoil"], v["generator"]
    rotor = Rotor(radius=ro["radius"], hub_radius=ro["hub_radius"],
                  r=np.asarray(bl["r"], dtype=float),
                  chord=np.asarray(bl["chord"], dtype=float),
                  twist=np.radians(np.asarray(bl["twist_deg"], dtype=float)),
                  blades=ro["blades"], pitch=math.radians(ro["pitch_deg"]),
                  airfoil=Airfoil.viterna(**af), mass=ro["mass"], rho=ro["air_density"])
    return Turbine(rotor=rotor, generator=InductionGenerator(**ge),
                   gear_ratio=t["gear_ratio"], inertia=t["inertia"],
                   hub_height=t["hub_height"], front_bearing=t["front_bearing"],
                   rear_bearing=t["rear_bearing"],
                   mounting_azimuth_deg=t["mounting_azimuth_deg"], tilt_deg=t["tilt_deg"],
                   name=t.get("name", default_name))


@dataclass
class TurbineResult:
    """Time series of a turbine run: ``loads`` DataFrame indexed by time (s) with
    ``rotor_speed_rpm``, ``azimuth_deg`` (blade 1), ``generator_connected``,
    ``generator_torque_Nm`` (on the generator shaft), ``power_W`` (the generator shaft's:
    torque times speed, before the generator's losses), the hub loads
    ``thrust_N, torque_Nm, shear_y_N, shear_z_N, tilt_Nm, yaw_Nm`` and the shaft-end force on
    the gearbox ``rear_force_y_N, rear_force_z_N``."""

    loads: pd.DataFrame | None
    cut_in_time: float | None
    settings: dict = field(default_factory=dict)
    #: the directory a streamed or loaded run's ``turbine_loads`` table is read from
    stored: Path | None = field(default=None, repr=False, compare=False)

    def __post_init__(self):
        if self.stored is not None:
            self.stored = Path(self.stored)
        elif self.loads is None:
            raise TypeError("TurbineResult needs loads (or stored=DIR)")

    def to_frame(self) -> pd.DataFrame:
        """The loads table, its units in ``attrs["units"]`` (:data:`TURBINE_UNITS`)."""
        frame = self.loads
        frame.attrs["units"] = {c: TURBINE_UNITS[c] for c in frame.columns
                                if c in TURBINE_UNITS}
        return frame

    def openfast(self, gear_ratio: float, efficiency: float = 1.0) -> pd.DataFrame:
        """The run in OpenFAST's channel names and units, column for column with an
        OpenFAST output (``attrs["units"]``): ``RotSpeed`` rpm, ``Azimuth`` deg,
        ``BldPitch1`` deg, ``GenSpeed`` rpm (the rotor's times ``gear_ratio``), ``GenTq``
        kN-m (on the generator shaft), ``GenPwr`` kW (electrical: the shaft power times
        ``efficiency``, ServoDyn's ``GenEff``), ``RtAeroFxh`` N and ``RtAeroMxh`` N-m (the
        rotor's aerodynamic thrust and torque, AeroDyn's). Indexed by ``Time`` (s). The shaft's
        structural torque ``LSShftTq`` needs the gearbox: a coupled run's
        :meth:`gearmodal.turbine.DrivetrainResult.openfast`."""
        for name, v, lo, hi in (("gear_ratio", gear_ratio, 0.0, 1e4),
                                ("efficiency", efficiency, 0.0, 1.0)):
            if not (isinstance(v, (int, float)) and not isinstance(v, bool) and lo < v <= hi):
                raise ModelError(name, f"= {v!r}: a number in ({lo:g}, {hi:g}]")
        d = self.view(list(dict.fromkeys([c for _, c, _ in OPENFAST_CHANNELS.values()]
                                         + ["rotor_speed_rpm", "power_W"])), max_rows=None)
        out = pd.DataFrame(index=pd.Index(d.index.to_numpy(), name="Time"))
        units = {}
        for name, (unit, col, factor) in OPENFAST_CHANNELS.items():
            out[name] = d[col].to_numpy() * factor
            units[name] = unit
        out["GenSpeed"] = d["rotor_speed_rpm"].to_numpy() * float(gear_ratio)
        out["GenPwr"] = d["power_W"].to_numpy() * float(efficiency) * 1e-3
        units.update(GenSpeed="rpm", GenPwr="kW")
        out.attrs["units"] = {"Time": "s", **units}
        return out

    def view(self, columns: list[str], max_rows: int | None = VIEW_ROWS) -> pd.DataFrame:
        """``columns`` of :attr:`loads` for a figure (a stored run's read decimated, every
        bucket keeping its extremes: :func:`gearmodal.result_io.decimated`; ``max_rows=None``:
        every row of them, read without the other columns)."""
        if self.stored is not None and self.__dict__.get("_loads") is None:
            return decimated(self.stored, "turbine_loads", list(columns), max_rows)
        return self.loads[list(columns)]

    def plot(self):
        """Rotor speed, power and shaft-end force against time; returns the Figure."""
        import matplotlib.pyplot as plt

        fig, axs = plt.subplots(3, 1, sharex=True, figsize=(8, 7))
        d = self.view(["rotor_speed_rpm", "power_W", "torque_Nm", "rear_force_y_N",
                       "rear_force_z_N"])
        axs[0].plot(d.index, d["rotor_speed_rpm"])
        axs[0].set_ylabel("rotor speed [rpm]")
        axs[1].plot(d.index, d["power_W"] / 1e3, label="generator shaft")
        axs[1].plot(d.index, d["torque_Nm"] * d["rotor_speed_rpm"] * RPM / 1e3, lw=0.7,
                    label="aerodynamic")
        axs[1].set_ylabel("power [kW]")
        axs[1].legend(fontsize=8)
        axs[2].plot(d.index, d["rear_force_y_N"] / 1e3, label="y")
        axs[2].plot(d.index, d["rear_force_z_N"] / 1e3, label="z")
        axs[2].set_ylabel("shaft-end force on gearbox [kN]")
        axs[2].legend(fontsize=8)
        axs[2].set_xlabel("time [s]")
        mark_cut_in(axs, self.cut_in_time)
        fig.tight_layout()
        return fig

    def save(self, directory, format: str = "parquet") -> Path:
        """Write ``turbine_loads`` (Parquet, or CSV with ``format="csv"``) and
        ``turbine.json`` (settings, cut-in time): what :meth:`load` reads back."""
        d = Path(directory)
        d.mkdir(parents=True, exist_ok=True)
        src = None
        if self.stored is not None and self.__dict__.get("_loads") is None:
            src = table_path(self.stored, "turbine_loads")
        if src is not None and src.suffix == f".{format}":
            if src.resolve() != (d / src.name).resolve():
                copy_table(src, d)
        else:
            write_table(self.loads, d, "turbine_loads", format)
        remove_table(d / f"turbine_loads.{'csv' if format == 'parquet' else 'parquet'}")
        (d / "turbine.json").write_text(json.dumps(
            {**self.settings, "cut_in_time": self.cut_in_time}, indent=2, default=str))
        return d

    @classmethod
    def load(cls, directory) -> TurbineResult:
        """The result :meth:`save` wrote to ``directory`` (floats exact)."""
        d = Path(directory)
        table_path(d, "turbine_loads")  # there (a missing table named now, not later)
        meta = json.loads((d / "turbine.json").read_text())
        cut = meta.pop("cut_in_time", None)
        return cls(loads=None, cut_in_time=cut, settings=meta, stored=d)

    def gearbox_loads(self, ratio: float | None = None) -> dict:
        """Loads for :func:`gearmodal.simulate` on the drivetrain model (``600kw.toml``):
        ``rotor.torque`` (aerodynamic), ``generator.torque`` (the generator's braking torque,
        negative) and the shaft-end force on the first stage's carrier in the gearbox plane
        (``x`` = shaft ``y``, ``y`` = shaft ``z``, global axes)."""
        d = self.loads
        idx = pd.Index(d.index.to_numpy(dtype=float), name="time")
        return {"rotor.torque": pd.Series(d["torque_Nm"].to_numpy(), index=idx),
                "generator.torque": pd.Series(-d["generator_torque_Nm"].to_numpy(), index=idx),
                "stage1.carrier.force_x": pd.Series(d["rear_force_y_N"].to_numpy(), index=idx),
                "stage1.carrier.force_y": pd.Series(d["rear_force_z_N"].to_numpy(), index=idx)}


def _loads_property() -> property:
    """:attr:`TurbineResult.loads`: a stored run's table is read when first asked for."""

    def get(self):
        d = self.__dict__
        if d.get("_loads") is None and d.get("stored") is not None:
            df = read_table(d["stored"], "turbine_loads")
            if "generator_connected" in df:
                df["generator_connected"] = df["generator_connected"].astype(bool)
            d["_loads"] = df
        return d.get("_loads")

    def set_(self, val):
        self.__dict__["_loads"] = val

    return property(get, set_, doc="The turbine's time series at the aerodynamic rate.")


TurbineResult.loads = _loads_property()


def simulate_turbine(turbine: Turbine, wind: Wind, t_end: float, *, dt: float = 0.02,
                     rotor_speed0_rpm: float = 6.0, azimuth0_deg: float = 0.0,
                     connected: bool = False, progress=None) -> TurbineResult:
    """Run the turbine from ``rotor_speed0_rpm`` for ``t_end`` s at the aerodynamic rate ``dt``.

    The generator is disconnected until its speed first reaches synchronous speed (set
    ``connected=True`` to start on the grid). ``progress(i, n)`` is called per step (the
    solver never prints)."""
    for label, val, lo in (("t_end", t_end, 0.0), ("dt", dt, 0.0)):
        if not (isinstance(val, (int, float)) and math.isfinite(val) and val > lo):
            raise ModelError(label, f"= {val!r}: must be a finite number > 0 s")
    gen = turbine.generator
    if gen is None:
        raise ModelError("turbine.generator", "= None: a turbine-only run needs the induction "
                         "generator; a controlled turbine runs coupled to its gearbox "
                         "(simulate_drivetrain with a controller)")
    ratio = turbine.gear_ratio
    # generator slip stiffness at the rotor: ratio^2 dT/domega at synchronous speed
    c_gen = ratio**2 * gen.tangent(gen.omega_sync)[1]
    if dt > turbine.inertia / c_gen:
        raise ModelError("dt", f"= {dt!r}: longer than the generator's slip time constant "
                         f"{turbine.inertia / c_gen:.3g} s; the explicit step would be unstable")
    if wind.turbulent and wind.duration < t_end:
        raise ModelError("wind.duration", f"= {wind.duration}: shorter than t_end = {t_end}")
    rot = turbine.rotor
    n = int(math.ceil(t_end / dt - 1e-9))
    omega = rotor_speed0_rpm * RPM
    psi = math.radians(azimuth0_deg)
    on = bool(connected)
    cut_in = 0.0 if on else None
    rows = []

    def aero(t, om, ps, reset=False):
        return turbine.hub_loads(wind, t, om, ps, reset=reset)

    def gen_torque(om):
        return gen.torque(om * ratio) if on else 0.0

    for k in range(n + 1):
        t = k * dt
        ld = aero(t, omega, psi, reset=(k == 0))
        tg = gen_torque(omega)
        fy, fz = turbine.rear_force(ld)
        rows.append((t, omega / RPM, math.degrees(psi) % 360.0, on, tg, tg * omega * ratio,
                     *(ld[c] for c in LOAD_COLUMNS), fy, fz, math.degrees(rot.pitch)))
        if k == n:
            break
        # explicit midpoint on (psi, omega)
        acc = (ld["torque_Nm"] - ratio * tg) / turbine.inertia
        om_m = omega + 0.5 * dt * acc
        ps_m = psi + 0.5 * dt * omega
        ld_m = aero(t + 0.5 * dt, om_m, ps_m)
        acc_m = (ld_m["torque_Nm"] - ratio * gen_torque(om_m)) / turbine.inertia
        psi += dt * om_m
        omega += dt * acc_m
        if not on and omega * ratio >= gen.omega_sync:
            on = True
            cut_in = t + dt
        if not math.isfinite(omega):
            raise SolveError("simulate_turbine", f"rotor speed not finite at t = {t:.3f} s")
        if progress is not None:
            progress(k + 1, n)
    df = pd.DataFrame(rows, columns=TURBINE_COLUMNS).set_index("time")
    return TurbineResult(loads=df, cut_in_time=cut_in,
                         settings={"turbine": turbine.name, "t_end": t_end, "dt": dt,
                                   "rotor_speed0_rpm": rotor_speed0_rpm,
                                   "wind": {k: v for k, v in vars(wind).items()
                                            if not k.startswith("_")}})
