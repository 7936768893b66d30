"""The NREL 5 MW reference turbine read from its OpenFAST deck (issue 36).

J. Jonkman, S. Butterfield, W. Musial and G. Scott, "Definition of a 5-MW Reference Wind
Turbine for Offshore System Development", NREL/TP-500-38060, 2009. The deck is the one the
``rosco`` wheel ships with the controller tuned for it (``Examples/Test_Cases/NREL-5MW/``:
``NREL-5MW.fst``, ElastoDyn, AeroDyn 15 with its blade file and the eight airfoil polars,
``DISCON.IN`` and the rotor's ``Cp_Ct_Cq.NREL5MW.txt``); ``openfast-io`` (the ``nrel5mw``
extra) reads it. Nothing is copied by hand: every number below comes from those files.

:func:`rotor` builds gearmodal's blade-element momentum rotor (:class:`~.rotor.Rotor`, the one
the 600 kW turbine runs) on the 5 MW blade: AeroDyn's blade nodes between the root and the tip
node are the element centres (the 17 stations of the definition report's Table 2-1; the root
and tip nodes bound the elements), each with its chord, twist and polar, the blades coned by the
deck's precone; :func:`turbine` tilts the shaft by the deck's tilt. :func:`cp_table` and
:func:`ct_table` read NREL's tables to compare with (``docs/guide/turbine.md``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from ..errors import ModelError
from ..integrate.stepper import Stepper
from ..model.bearing import Bearing
from ..model.components import RigidBody
from ..model.model import Model
from ..model.toml_io import load
from ..shipped import find
from .airfoil import Airfoil
from .drivetrain import DrivetrainResult, simulate_drivetrain
from .rosco import Rosco, discon_value, rosco_files
from .rotor import Rotor
from .turbine import Turbine
from .wind import Wind


@dataclass(frozen=True)
class Deck:
    """The parts of the 5 MW deck gearmodal uses (SI units, angles in rad).

    Attributes
    ----------
    tip_radius, hub_radius : m. blades : count. precone, shaft_tilt : rad (ElastoDyn's
    signs; the rotor is coned and the turbine's shaft tilted by them). hub_inertia,
    generator_inertia : kg m^2 (the generator's about its own, high-speed shaft).
    rotor_inertia : kg m^2, the hub's and the blades' (ElastoDyn's blade mass density
    integrated over the span about the shaft).
    gear_ratio : generator per rotor speed.
    drivetrain_stiffness, drivetrain_damping : N m/rad, N m s/rad (the low-speed shaft's
    equivalent). rated_rotor_speed : rad/s (ElastoDyn's initial speed). generator_efficiency :
    0..1. air_density : kg/m^3. hub_height : m. span, chord, twist, airfoil_id : AeroDyn's
    blade nodes (m from the root, m, rad, index into ``airfoils``). airfoils : the polars.
    path : the deck's folder. rotor_mass : kg, the hub's and the blades' (their mass density
    integrated). overhang : m, the hub centre upwind of the yaw axis (ElastoDyn's OverHang,
    negative there for an upwind rotor; given here positive). tower_top_radius : m
    (ElastoDyn's tower file is not read: the tower's top diameter, 3.87 m, from the definition
    report, Table 6-1).
    """

    tip_radius: float
    hub_radius: float
    blades: int
    precone: float
    shaft_tilt: float
    hub_inertia: float
    generator_inertia: float
    rotor_inertia: float
    gear_ratio: float
    drivetrain_stiffness: float
    drivetrain_damping: float
    rated_rotor_speed: float
    generator_efficiency: float
    air_density: float
    hub_height: float
    span: np.ndarray
    chord: np.ndarray
    twist: np.ndarray
    airfoil_id: np.ndarray
    airfoils: tuple
    path: Path
    rotor_mass: float = 0.0
    overhang: float = 0.0
    tower_top_radius: float = 3.87 / 2


def read_deck(path=None) -> Deck:
    """The 5 MW deck at ``path`` (a folder holding ``NREL-5MW.fst``; default: the one the
    ``rosco`` wheel ships), read by ``openfast-io``."""
    if path is None:
        path = rosco_files()[1]
    path = Path(path)
    if not (path / "NREL-5MW.fst").is_file():
        raise ModelError("deck", f"= {str(path)!r}: no NREL-5MW.fst there")
    try:
        from openfast_io.FAST_reader import InputReader_OpenFAST
    except ImportError:
        raise ModelError("deck", "reading an OpenFAST deck needs openfast-io: pip install "
                         "-e '.[nrel5mw]'") from None
    reader = InputReader_OpenFAST()
    reader.FAST_InputFile = "NREL-5MW.fst"
    reader.FAST_directory = str(path)
    try:
        reader.execute()
    except (IndexError, ValueError, KeyError, TypeError, OSError) as e:
        raise ModelError("deck", f"= {str(path)!r}: openfast-io could not read the deck "
                         f"({type(e).__name__}: {e}); a damaged or incomplete file") from None
    vt = reader.fst_vt
    ed, ad, sd = vt["ElastoDyn"], vt["AeroDyn"], vt["ServoDyn"]
    edb = vt["ElastoDynBlade"]
    edb = edb[0] if isinstance(edb, list) else edb
    length = float(ed["TipRad"]) - float(ed["HubRad"])
    s_b = np.asarray(edb["BlFract"], dtype=float) * length
    mass = np.asarray(edb["BMassDen"], dtype=float) * float(edb["AdjBlMs"])
    trapezoid = getattr(np, "trapezoid", None) or np.trapz  # numpy < 2: trapz
    j_blade = float(trapezoid(mass * (float(ed["HubRad"]) + s_b) ** 2, s_b))
    m_blade = float(trapezoid(mass, s_b))
    blade = vt["AeroDynBlade"]
    blade = blade[0] if isinstance(blade, list) else blade
    foils = []
    for i, data in enumerate(ad["af_data"]):
        tab = data[0] if isinstance(data, list) else data
        alpha = np.radians(np.asarray(tab["Alpha"], dtype=float))
        foils.append(Airfoil(alpha, np.asarray(tab["Cl"], dtype=float),
                             np.asarray(tab["Cd"], dtype=float),
                             name=Path(ad["AFNames"][i]).stem))
    deck = Deck(tip_radius=float(ed["TipRad"]), hub_radius=float(ed["HubRad"]),
                blades=int(ed["NumBl"]), precone=math.radians(float(ed["PreCone(1)"])),
                shaft_tilt=math.radians(float(ed["ShftTilt"])),
                hub_inertia=float(ed["HubIner"]), generator_inertia=float(ed["GenIner"]),
                rotor_inertia=float(ed["HubIner"]) + int(ed["NumBl"]) * j_blade,
                gear_ratio=float(ed["GBRatio"]),
                drivetrain_stiffness=float(ed["DTTorSpr"]),
                drivetrain_damping=float(ed["DTTorDmp"]),
                rated_rotor_speed=float(ed["RotSpeed"]) * math.pi / 30,
                generator_efficiency=float(sd["GenEff"]) / 100.0,
                air_density=float(ad["AirDens"]),
                hub_height=float(vt["InflowWind"]["RefHt"]),
                span=np.asarray(blade["BlSpn"], dtype=float),
                chord=np.asarray(blade["BlChord"], dtype=float),
                twist=np.radians(np.asarray(blade["BlTwist"], dtype=float)),
                airfoil_id=np.asarray(blade["BlAFID"], dtype=np.int64) - 1,
                airfoils=tuple(foils), path=path,
                rotor_mass=float(ed["HubMass"]) + int(ed["NumBl"]) * m_blade,
                overhang=-float(ed["OverHang"]))
    _check_deck(deck)
    return deck


def _check_deck(d: Deck) -> None:
    """Every number of the deck finite, and those that must be positive so (a clear error
    naming the field, not a wrong run)."""
    positive = ("tip_radius", "hub_inertia", "generator_inertia", "rotor_inertia", "gear_ratio",
                "drivetrain_stiffness", "air_density", "hub_height", "rotor_mass")
    for f in ("tip_radius", "hub_radius", "precone", "shaft_tilt", "hub_inertia",
              "generator_inertia", "rotor_inertia", "gear_ratio", "drivetrain_stiffness",
              "drivetrain_damping", "rated_rotor_speed", "generator_efficiency", "air_density",
              "hub_height", "rotor_mass", "overhang"):
        v = getattr(d, f)
        if not math.isfinite(v) or (f in positive and v <= 0):
            raise ModelError(f"deck.{f}", f"= {v!r}: must be a finite number"
                             + (" > 0" if f in positive else ""))
    if not 0 < d.generator_efficiency <= 1:
        raise ModelError("deck.generator_efficiency", f"= {d.generator_efficiency!r}: "
                         "ServoDyn's GenEff in (0, 100] %")
    if d.blades < 1:
        raise ModelError("deck.blades", f"= {d.blades!r}: ElastoDyn's NumBl, 1 or more")
    for f in ("span", "chord", "twist"):
        a = getattr(d, f)
        if a.size == 0 or not np.all(np.isfinite(a)):
            raise ModelError(f"deck.{f}", "AeroDyn's blade table needs finite values")


def rotor(deck: Deck | None = None) -> Rotor:
    """The 5 MW rotor for gearmodal's BEM (module docstring): the blade nodes between the
    root and the tip node as element centres."""
    d = read_deck() if deck is None else deck
    inner = slice(1, len(d.span) - 1)
    return Rotor(radius=d.tip_radius, hub_radius=d.hub_radius,
                 r=d.hub_radius + d.span[inner], chord=d.chord[inner], twist=d.twist[inner],
                 blades=d.blades, airfoils=list(d.airfoils), airfoil_id=d.airfoil_id[inner],
                 airfoil=d.airfoils[0], rho=d.air_density, correction="buhl",
                 mass=d.rotor_mass, precone=d.precone)


def cp_table(path=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """NREL's rotor performance table ``(pitch [rad], tip-speed ratio, Cp[tsr, pitch])`` from
    ``Cp_Ct_Cq.NREL5MW.txt`` (default: the rosco wheel's). The ROSCO toolbox made it with
    CCBlade at 11.4 m/s with the deck's precone and tilt, a shear exponent of 0.2 at
    89.56 m (TowerHt + Twr2Shft) and 8 azimuth sectors (``rosco.toolbox.turbine``)."""
    return _performance_table("Power coefficient", path)


def ct_table(path=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """NREL's thrust coefficients ``(pitch [rad], tip-speed ratio, Ct[tsr, pitch])`` from the
    same file as :func:`cp_table`."""
    return _performance_table("Thrust coefficient", path)


def _performance_table(title: str, path=None):
    path = Path(path) if path is not None else rosco_files()[1] / "Cp_Ct_Cq.NREL5MW.txt"
    lines = [ln.strip() for ln in path.read_text().splitlines()]

    def after(title: str, rows: int = 1) -> np.ndarray:
        i = next((k for k, ln in enumerate(lines) if ln.startswith("#") and title in ln), None)
        if i is None:
            raise ModelError("cp_table", f"{path.name} has no '{title}' section")
        vals = [ln for ln in lines[i + 1:] if ln and not ln.startswith("#")][:rows]
        return np.array([[float(x) for x in ln.split()] for ln in vals])

    pitch = np.radians(after("Pitch angle vector")[0])
    tsr = after("TSR vector")[0]
    table = after(title, len(tsr))
    if table.shape != (len(tsr), len(pitch)):
        raise ModelError("cp_table", f"{path.name}: {title} is {table.shape}, not "
                         f"({len(tsr)}, {len(pitch)})")
    return pitch, tsr, table


#: NREL's table's conditions (:func:`cp_table`): shear exponent, its reference height (m)
TABLE_SHEAR = (0.2, 89.56)


def table_conditions(deck: Deck | None = None) -> tuple[Turbine, Wind]:
    """The 5 MW turbine and the wind NREL's table (:func:`cp_table`) was made in: 11.4 m/s,
    shear exponent 0.2 about the hub at 89.56 m, where CCBlade had it (TowerHt + Twr2Shft;
    :data:`TABLE_SHEAR`), no tower shadow. ``turbine.power_coefficient(wind, ...)`` then
    compares with the table."""
    alpha, height = TABLE_SHEAR
    tb = replace(turbine(read_deck() if deck is None else deck), hub_height=height)
    return tb, Wind(mean_speed=11.4, hub_height=height, shear_exponent=alpha,
                    tower_radius=0.0)


def calm(turb: Turbine, wind_speed: float) -> Wind:
    """Steady uniform ``wind_speed`` (m/s) at ``turb``'s hub: no shear, turbulence or tower."""
    return Wind(mean_speed=float(wind_speed), hub_height=turb.hub_height,
                shear_exponent=0.0, tower_radius=0.0)


def drivetrain(deck: Deck | None = None):
    """The 5 MW drivetrain as a gearmodal model on the low-speed side: the rotor (hub and
    blades) and the generator (its inertia times the gear ratio squared) joined by ElastoDyn's
    drivetrain spring and damper; the generator's speed and torque on the high-speed shaft are
    the gear ratio times and over its own."""
    d = read_deck() if deck is None else deck
    m = Model("nrel5mw_drivetrain", input="rotor")
    m.add(RigidBody(name="rotor", mass=1.0, inertia=d.rotor_inertia, dofs="torsional",
                    speed_ratio=1.0))
    m.add(RigidBody(name="generator", mass=1.0, inertia=d.generator_inertia * d.gear_ratio**2,
                    dofs="torsional", speed_ratio=1.0))
    m.add(Bearing(name="drivetrain", a="rotor", b="generator",
                  stiffness={"theta": d.drivetrain_stiffness},
                  damping={"theta": d.drivetrain_damping}))
    return m


def blade_pitch_for_torque(turb: Turbine, wind_speed: float, omega: float,
                           torque: float) -> float:
    """The collective pitch (rad, 0 to 45 deg) at which ``turb``'s aerodynamic torque in
    uniform ``wind_speed`` at ``omega`` is ``torque`` (bisection; 0 when even fine pitch
    gives less): a start near the controller's steady state."""
    wind = calm(turb, wind_speed)

    def q(p):
        return turb.hub_loads(wind, 0.0, omega, 0.0, pitch=p, reset=True)["torque_Nm"]

    lo, hi = 0.0, math.radians(45.0)
    if q(lo) <= torque:
        return 0.0
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if q(mid) > torque else (lo, mid)
    return 0.5 * (lo + hi)


def steady_start(deck: Deck, turb: Turbine, wind_speed: float) -> tuple[float, float, float]:
    """The controller's own steady state in uniform ``wind_speed`` (m/s): ``(rotor speed
    rad/s, pitch rad, generator torque N m)``: its DISCON.IN's optimal tip-speed ratio and
    region-2 gain below rated, its rated torque and the balancing pitch above."""
    discon = deck.path / "DISCON.IN"
    w_rated = deck.rated_rotor_speed
    om0 = min(discon_value("VS_TSRopt", discon) * wind_speed / deck.tip_radius, w_rated)
    t_gen = discon_value("VS_Rgn2K", discon) * (deck.gear_ratio * om0) ** 2  # high-speed shaft
    pitch = 0.0
    if om0 >= w_rated:
        t_gen = discon_value("VS_RtTq", discon)
        pitch = blade_pitch_for_torque(turb, wind_speed, om0, t_gen * deck.gear_ratio)
    return om0, pitch, t_gen


def controlled_run(wind_speed: float, t_end: float = 90.0, *, deck: Deck | None = None,
                   dt: float = 0.00625, aero_dt: float = 0.0125, average: float = 10.0) -> dict:
    """The 5 MW turbine in steady uniform wind ``wind_speed`` (m/s) for ``t_end`` s, ROSCO
    (:class:`~.rosco.Rosco`, the deck's DISCON.IN) setting the generator torque and the
    collective pitch every ``dt`` (its sample time), the drivetrain a :class:`gearmodal.Stepper`
    advanced with the aerodynamic torque of the BEM rotor (evaluated every ``aero_dt``, held;
    the coned rotor on the tilted shaft of :func:`turbine`, blade 1 up).
    Starts at the optimal tip-speed ratio's speed (at most rated) and the pitch that balances
    rated torque above rated. Returns the means over the last ``average`` s: rotor speed
    (rpm), pitch (deg), electrical power (kW: generator torque times speed times the
    generator efficiency), tip-speed ratio, Cp (aerodynamic power over the wind's)."""
    for name, v, lo in (("t_end", t_end, 0.0), ("dt", dt, 0.0), ("aero_dt", aero_dt, 0.0),
                        ("average", average, 0.0), ("wind_speed", wind_speed, 0.0)):
        if not (isinstance(v, (int, float)) and math.isfinite(v) and v > lo):
            raise ModelError(name, f"= {v!r}: must be a finite number > {lo:g}")
    if t_end / dt > 1e8:
        raise ModelError("t_end", f"= {t_end!r} s at dt = {dt!r} s: {t_end / dt:.3g} steps, "
                         "more than 1e8")
    d = read_deck() if deck is None else deck
    tb = turbine(d)
    n, m_aero = round(t_end / dt), max(1, round(aero_dt / dt))
    if not (wind_speed > 0 and n > 0 and average < t_end):
        raise ModelError("wind_speed", f"= {wind_speed!r} m/s, t_end = {t_end!r} s: a wind "
                         "speed > 0 and a run longer than the averaging window")
    om0, pitch, t_gen = steady_start(d, tb, wind_speed)
    wind = calm(tb, wind_speed)
    q = tb.hub_loads(wind, 0.0, om0, 0.0, pitch=pitch, reset=True)["torque_Nm"]
    st = Stepper(drivetrain(d), dt=dt, speed_rpm=om0 * 30 / math.pi,
                 loads={"rotor.torque": q, "generator.torque": -t_gen * d.gear_ratio},
                 q0="equilibrium", reference="follow", rebase_dt=dt, record=False,
                 outputs=["rotor.theta.velocity", "generator.theta.velocity"])
    rows = []
    with Rosco(d.path / "DISCON.IN", dt=dt, pitch0=pitch,
               efficiency=d.generator_efficiency) as ctrl:
        y = st.values()
        for k in range(n):
            t = k * dt
            w_r, w_g = y["rotor.theta.velocity"], y["generator.theta.velocity"]
            if k % m_aero == 0:
                q = tb.hub_loads(wind, t, w_r, 0.0, pitch=pitch)["torque_Nm"]
            t_gen, pitch = ctrl.step(t, d.gear_ratio * w_g, w_r, pitch, t_gen, wind_speed)
            y = st.advance((k + 1) * dt, {"rotor.torque": q,
                                          "generator.torque": -t_gen * d.gear_ratio},
                           hold="hold")
            if t >= t_end - average:
                rows.append((w_r, pitch, t_gen * d.gear_ratio * w_g, q * w_r))
    w_r, p, p_gen, p_aero = np.mean(rows, axis=0)
    return {"wind_speed_mps": float(wind_speed), "rotor_speed_rpm": w_r * 30 / math.pi,
            "pitch_deg": math.degrees(p),
            "power_kW": p_gen * d.generator_efficiency / 1e3,
            "tsr": w_r * d.tip_radius / wind_speed,
            "cp": p_aero / (0.5 * d.air_density * math.pi * (d.tip_radius * math.cos(d.precone))**2
                            * wind_speed**3)}



def turbine(deck: Deck | None = None) -> Turbine:
    """The 5 MW turbine's side for a coupled run with its gearbox (:func:`simulate`): the BEM
    rotor with its weight, no induction generator (ROSCO sets torque and pitch), hub height
    and shaft tilt from the deck. The main bearings are estimates (the deck has none): the
    front one 1.9 m downwind of the hub centre (at ElastoDyn's shaft strain gauge, ShftGagL
    1.912 m), the rear one 2.0 m further (the main shaft of Nejad et al.'s 5 MW drivetrain
    model); the rear one's reaction is the shaft-end force on the gearbox's carrier."""
    d = read_deck() if deck is None else deck
    return Turbine(rotor=rotor(d), generator=None, gear_ratio=d.gear_ratio,
                   inertia=d.rotor_inertia + d.generator_inertia * d.gear_ratio**2,
                   hub_height=d.hub_height, front_bearing=1.9, rear_bearing=3.9,
                   tilt_deg=-math.degrees(d.shaft_tilt), name="nrel5mw")


def wind(mean_speed: float, *, deck: Deck | None = None, **kw) -> Wind:
    """A :class:`~.wind.Wind` for the 5 MW rotor: hub height from the deck, the turbulence
    grid over 1.1 tip radii, the tower's top radius and the rotor's overhang for the tower
    shadow; ``kw`` as :class:`~.wind.Wind` (``turbulence_intensity``, ``seed``,
    ``duration``, ``model``...)."""
    d = read_deck() if deck is None else deck
    kw = {"hub_height": d.hub_height, "half_width": 1.1 * d.tip_radius,
          "tower_radius": d.tower_top_radius, "tower_distance": d.overhang, **kw}
    return Wind(mean_speed=mean_speed, **kw)


def simulate(wind: Wind, t_end: float, *, gearbox=None, deck: Deck | None = None,
             dt: float = 2.5e-3, aero_dt: float = 0.0125, progress=None,
             **settings) -> DrivetrainResult:
    """The NREL 5 MW turbine on its gearbox for ``t_end`` s in ``wind``: the BEM rotor, ROSCO
    (the deck's DISCON.IN, called every ``aero_dt``) and the gearbox's contact dynamics by the
    exact method (:func:`gearmodal.turbine.simulate_drivetrain`, whose ``settings`` apply:
    ``method``, ``top_frequency_hz``, ``out``...). ``gearbox``: a drivetrain model
    (default: ``studies/models/nrel5mw.toml``, the 5 MW reference gearbox). Starts from the
    controller's steady state at the wind's mean speed (:func:`steady_start`)."""
    d = read_deck() if deck is None else deck
    if gearbox is None:
        gearbox = load(find("nrel5mw", "models"))
    tur = turbine(d)
    om0, pitch, _ = steady_start(d, tur, wind.mean_speed)
    settings.setdefault("rotor_speed0_rpm", om0 * 30 / math.pi)
    with Rosco(d.path / "DISCON.IN", dt=aero_dt, pitch0=pitch,
               efficiency=d.generator_efficiency) as ctrl:
        return simulate_drivetrain(tur, wind, gearbox, t_end, dt=dt, aero_dt=aero_dt,
                                   controller=ctrl, progress=progress, **settings)


#: rpm: the rotor's operating range, region 1.5's minimum speed to rated (the definition
#: report, section 7; the drivetrain model's speed_range_rpm)
OPERATING_RPM = (6.9, 12.1)


def elastodyn_file(path=None) -> Path:
    """The ElastoDyn main file of the 5 MW deck at ``path`` (a folder holding
    ``NREL-5MW.fst``; default: the one the ``rosco`` wheel ships), named by its ``EDFile``."""
    from .elastodyn import elastodyn_of

    return elastodyn_of(_fst(path))


def _fst(path=None) -> Path:
    return Path(rosco_files()[1] if path is None else path) / "NREL-5MW.fst"


def flexible(gearbox: Model | None = None, generator: str = "locked", *, deck=None,
             shapes: str = "computed", flap: int = 2, edge: int = 1, fore_aft: int = 2,
             side_to_side: int = 2, yaw: bool = True):
    """The elastic NREL 5 MW turbine built from its OpenFAST deck (issue 56): tower, nacelle,
    shaft, hub and three bending blades (:mod:`gearmodal.turbine.structure`), a model that
    :func:`gearmodal.modal` and :func:`gearmodal.campbell` solve at any rotor speed (the
    operating range 6.9-12.1 rpm marked).

    Parameters
    ----------
    gearbox : None (the deck's two-mass drivetrain: ``DTTorSpr`` between rotor and generator)
        or a drivetrain :class:`~gearmodal.Model`, for instance
        ``gm.load("studies/models/nrel5mw.toml")``, put between rotor and generator.
    generator : ``"locked"`` (the definition report's Table 9-1) or ``"free"``.
    deck : the folder holding ``NREL-5MW.fst`` (default: the ``rosco`` wheel's).
    shapes, flap, edge, fore_aft, side_to_side : the assumed modes
        (:func:`gearmodal.turbine.structure.elastic_turbine`).
    yaw : the nacelle turns on its yaw bearing (ServoDyn's YawSpr 9.03e9 N m/rad and YawDamp
        1.92e7 N m s/rad), as the deck has it (``YawDOF``); False: held in yaw.

    Examples
    --------
    >>> import gearmodal as gm
    >>> res = gm.modal(gm.turbine.nrel5mw.flexible())           # doctest: +SKIP
    >>> res.to_frame()[["frequency_hz", "mode_type"]].head(3)    # doctest: +SKIP
    """
    from .elastodyn import servodyn_yaw
    from .structure import elastic_turbine

    k_yaw, c_yaw = servodyn_yaw(_fst(deck)) if yaw else (None, 0.0)
    return elastic_turbine(elastodyn_file(deck), gearbox=gearbox, generator=generator,
                           flap=flap, edge=edge, fore_aft=fore_aft, side_to_side=side_to_side,
                           shapes=shapes, speed_range_rpm=OPERATING_RPM,
                           yaw_stiffness=k_yaw, yaw_damping=c_yaw)
