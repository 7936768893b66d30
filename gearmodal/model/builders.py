"""Builders: gear pairs, planetary and parallel stages, Lin & Parker stages, drivetrains.

Sign convention (all builders): every rotation is positive counter-clockwise about +z; ``q = 0``
is the front flanks touching with zero force, and a positive torque on the driving member (the
pinion of a pair, the carrier of a planetary stage, the input of a drivetrain) closes the front
flanks. Back flanks touch when the relative rotation, measured along their line of action,
exceeds the backlash.
"""

from __future__ import annotations

import copy
import dataclasses
import math
from typing import Annotated

from ..errors import ModelError
from . import spec as sp
from . import validate as v
from .bearing import Bearing, Shaft
from .components import DOF_LEVELS, Frame, Gear, RigidBody
from .mesh import Mesh
from .model import Model
from .schema import REQUIRED, Field, Table

_CENTRAL = ("carrier", "ring", "sun")

# -- the builders' parameters as their files have them (gearmodal.model.spec) ----------------
_MF, _RB = Mesh.SCHEMA.by_key(), RigidBody.SCHEMA.by_key()
_DOFS = sp.key("choice", choices=DOF_LEVELS, doc="DOF level of the bodies")
_MESH_K = sp.like(_MF["stiffness"], doc="mesh stiffness on the line of action")
_BACKLASH = sp.like(_MF["backlash"])
_MESH_C = sp.like(_MF["damping"])
_ALTERNATION = sp.key("alternation", default=False,
                      doc="true, or a table of contact_ratio, stiffness_ratio, phase: the mesh "
                          "stiffness alternates between single and double tooth-pair contact")
_PIN_ERRORS = sp.key("pairs", "m", limits="gap",
                     doc="per planet [radial, tangential] carrier pinhole position error")
_THICKNESS_ERRORS = sp.key("vector", "m", limits="gap",
                           doc="per planet tooth thickness error on the line of action "
                               "(positive: thicker)")
_BODIES4 = (*_CENTRAL, "planet")
#: Lin & Parker's tables (:func:`lin_parker_stage`): a value per body, per central body, per
#: mesh kind, and the pressure angles per mesh kind (in degrees in a file)
LIN_PARKER_BODIES = Table("lin_parker_stage per body", tuple(
    Field(b, "number", default=REQUIRED, doc=b) for b in _BODIES4),
    "A value per body (`mass`, `inertia_over_r2`, `bearing`).")
LIN_PARKER_CENTRAL = Table("lin_parker_stage per central body", tuple(
    Field(b, "number", default=REQUIRED, doc=b) for b in _CENTRAL),
    "A value per central body (`torsional`).")
PER_MESH = Table("per mesh (sun_planet, ring_planet)", (
    dataclasses.replace(_MF["stiffness"], key="sun_planet", doc="sun-planet meshes"),
    dataclasses.replace(_MF["stiffness"], key="ring_planet", doc="ring-planet meshes")),
    "A value per mesh kind.")
PER_MESH_ANGLE = Table("lin_parker_stage pressure angles", tuple(
    Field(k, "number", "deg", low=math.degrees(1e-6), high=60.0, high_open=True,
          default=REQUIRED, doc=f"{k.replace('_', '-')} meshes", deg_floor=10.0)
    for k in ("sun_planet", "ring_planet")),
    "Lin & Parker's pressure angles per mesh kind, in degrees.")
#: a torsional shaft's stiffness and damping (a drivetrain's main and high-speed shafts)
SHAFT_K = Field("stiffness", "number", "N m/rad", low=0.0, default=REQUIRED,
                doc="torsional stiffness", limits="stiffness")
SHAFT_C = Field("damping", "number", "N m s/rad", low=0.0, default=0.0,
                doc="torsional damping", limits="damping")
_CENTRE = sp.key("number", "m", low=0.0, low_open=True,
                 doc="operating centre distance of profile-shifted gears (default: the "
                     "standard one); each mesh at its operating pressure angle")


def _gear(g: Gear, field: str, name: str, dofs: str) -> Gear:
    if not isinstance(g, Gear):
        raise ModelError(field, f"expected a gm.Gear, got {type(g).__name__}")
    out = copy.deepcopy(g)
    out.name = name
    out.dofs = dofs
    out.coordinate_names = dict(g.coordinate_names)
    return out


def _same_tooth_system(field: str, a: Gear, b: Gear, internal: bool = False) -> None:
    """Gears that can mesh: one module and pressure angle, helix angles of one size and of
    opposite hands on an external pair, the same hand on an internal one (ring)."""
    if not math.isclose(a.module, b.module, rel_tol=1e-12):
        raise ModelError(field, f"modules differ ({a.name}: {a.module:g} m, {b.name}: "
                                f"{b.module:g} m); meshing gears need the same module")
    if not math.isclose(a.pressure_angle, b.pressure_angle, rel_tol=1e-12):
        raise ModelError(field, f"pressure angles differ ({_angle(a.pressure_angle)} vs "
                                f"{_angle(b.pressure_angle)})")
    if not math.isclose(abs(a.helix_angle), abs(b.helix_angle), rel_tol=1e-12, abs_tol=1e-15):
        raise ModelError(field, f"helix angles differ in size ({_angle(a.helix_angle)} vs "
                                f"{_angle(b.helix_angle)})")
    if a.helix_angle != 0.0 and (a.helix_angle == b.helix_angle) != internal:
        need = "the same hand (an internal pair)" if internal else "opposite hands (an " \
            "external pair)"
        raise ModelError(f"{field}.helix_angle", f"= {_angle(b.helix_angle)} against "
                         f"{a.name}'s {_angle(a.helix_angle)}: helical gears mesh with {need}")


def _angle(rad: float) -> str:
    """An angle for a message, in both units (the API's radians, a file's degrees)."""
    return f"{rad:g} rad ({math.degrees(rad):.6g} deg)"


def _alternation(field: str, spec, key: str | None = None, phase: float = 0.0) -> dict:
    """:class:`Mesh` keywords of a builder's ``mesh_alternation`` (None/False, True or a table
    of ``contact_ratio`` (per mesh kind ``key`` if a table), ``stiffness_ratio``, ``phase``);
    ``phase`` is added to the table's."""
    if spec is None or spec is False:
        return {}
    if spec is True:
        spec = {}
    if not isinstance(spec, dict):
        raise ModelError(field, f"= {spec!r}: expected true/false or a table of contact_ratio, "
                         "stiffness_ratio, phase")
    bad = set(spec) - {"contact_ratio", "stiffness_ratio", "phase"}
    if bad:
        raise ModelError(f"{field}.{sorted(bad)[0]}", "unknown key; allowed: contact_ratio, "
                         "stiffness_ratio, phase")
    out = {"alternation": True, "phase": v.number(f"{field}.phase", spec.get("phase", 0.0))
           + phase}
    eps = spec.get("contact_ratio")
    if isinstance(eps, dict):
        if key is None or key not in eps:
            raise ModelError(f"{field}.contact_ratio", f"= {eps!r}: expected a number"
                             + (f" or a table with {key!r}" if key else ""))
        eps = eps[key]
    if eps is not None:
        out["contact_ratio"] = eps
    if "stiffness_ratio" in spec:
        out["stiffness_ratio"] = spec["stiffness_ratio"]
    return out


def _support(field: str, spec, dofs: str) -> dict:
    """Normalise a bearing spec: a number (translational stiffness, N/m) or a table with
    ``stiffness``, ``damping``, ``clearance`` tables keyed by direction and optionally
    ``clearance_shape`` (``axes``/``polygon``/``round``), ``facets`` and ``ramps``
    (:class:`Bearing`)."""
    if spec is None:
        return {"stiffness": {}, "damping": {}, "clearance": {}}
    if not isinstance(spec, dict):
        k = v.nonnegative(field, spec, "N/m")
        keys = ("x", "y", "z") if dofs == "full" else ("x", "y")
        return {"stiffness": dict.fromkeys(keys, k), "damping": {}, "clearance": {}}
    unknown = set(spec) - {"stiffness", "damping", "clearance", "clearance_shape", "facets",
                         "ramps"}
    if unknown:
        raise ModelError(f"{field}.{sorted(unknown)[0]}", "unknown key; allowed: stiffness, "
                         "damping, clearance, clearance_shape, facets, ramps")
    out = {k: spec[k] for k in ("clearance_shape", "facets", "ramps") if k in spec}
    for key in ("stiffness", "damping", "clearance"):
        sub = spec.get(key, {})
        if not isinstance(sub, dict):
            raise ModelError(f"{field}.{key}", f"= {sub!r}: expected a table keyed by "
                             "direction (x, y, z, rx, ry, theta)")
        out[key] = dict(sub)
    return out


@sp.checked
def gear_pair(pinion: Annotated[Gear, sp.GEAR], wheel: Annotated[Gear, sp.GEAR],
              mesh_stiffness: Annotated[float, _MESH_K], backlash: Annotated[float, _BACKLASH],
              mesh_damping: Annotated[float, _MESH_C] = 0.0,
              dofs: Annotated[str, _DOFS] = "torsional",
              bearing_stiffness: Annotated[object, sp.key(
                  "support", file="bearing",
                  doc="both wheels to the ground (required unless torsional)")] = None,
              mesh_alternation: Annotated[object, _ALTERNATION] = None) -> Model:
    """Two external gears on fixed bearings, free to rotate.

    Parameters
    ----------
    pinion, wheel : :class:`Gear` (same module and pressure angle, opposite helix hands).
    mesh_stiffness : N/m along the line of action. backlash : m along the line of action.
    mesh_damping : N s/m.
    dofs : DOF level of both wheels. At ``planar``/``full`` the wheels float on bearings of
        ``bearing_stiffness`` (N/m, or a table as for :class:`Bearing`) to the ground.
    mesh_alternation : None/False (constant mesh stiffness), True or a table of
        ``contact_ratio``, ``stiffness_ratio``, ``phase``: the stiffness alternates between
        single and double tooth-pair contact at the mesh frequency (:class:`Mesh`).

    Notes
    -----
    DOFs are ``"pinion.theta"``, ``"wheel.theta"`` (plus ``.x``, ``.y``...); loads
    ``"pinion.torque"``, ``"wheel.torque"`` (N m). The pinion is the input and sits at the
    origin, the wheel on +x at the standard centre distance. A positive pinion torque closes the
    front flank.

    Examples
    --------
    >>> import math, gearmodal as gm
    >>> p = gm.Gear(20, 0.004, math.radians(20), mass=1.0, inertia=1e-3)
    >>> w = gm.Gear(40, 0.004, math.radians(20), mass=4.0, inertia=1.6e-2)
    >>> gm.gear_pair(p, w, mesh_stiffness=2e8, backlash=1e-4).dof_names
    ['pinion.theta', 'wheel.theta']
    """
    p = _gear(pinion, "gear_pair.pinion", "pinion", dofs)
    w = _gear(wheel, "gear_pair.wheel", "wheel", dofs)
    if p.internal or w.internal:
        raise ModelError("gear_pair", "both gears of a gear_pair must be external")
    _same_tooth_system("gear_pair.wheel", p, w)
    centre = (p.base_radius + w.base_radius) / math.cos(p.transverse_pressure_angle)
    p.position, p.speed_ratio, p.role = (0.0, 0.0, 0.0), 1.0, "pinion"
    w.position, w.speed_ratio, w.role = (centre, 0.0, 0.0), -p.teeth / w.teeth, "wheel"
    m = Model("gear_pair", input="pinion")
    m.add(p)
    m.add(w)
    m.add(Mesh("mesh", "pinion", "wheel", mesh_stiffness, backlash, mesh_damping, side=1,
               role="mesh", **_alternation("gear_pair.mesh_alternation", mesh_alternation)))
    if dofs != "torsional":
        if bearing_stiffness is None:
            raise ModelError("gear_pair.bearing_stiffness", f"required for dofs={dofs!r} "
                             "(N/m): the wheels' centres need a support")
        for g in ("pinion", "wheel"):
            s = _support("gear_pair.bearing_stiffness", bearing_stiffness, dofs)
            m.add(Bearing(f"{g}_bearing", g, None, role=f"{g}_bearing", **s))
    return m.check()


@sp.checked
def lin_parker_stage(
        n_planets: Annotated[int, sp.key(
            "integer", low=1, high=v.MAX_PLANETS, doc="number of planets",
            note="wind-turbine gearboxes have 3 to 7")],
        mass: Annotated[dict, sp.key(
            "table", "kg", doc="carrier, ring, sun, planet", table=LIN_PARKER_BODIES)],
        inertia_over_r2: Annotated[dict, sp.key(
            "table", "kg", doc="carrier, ring, sun, planet", table=LIN_PARKER_BODIES)],
        bearing: Annotated[dict, sp.key(
            "table", "N/m", doc="carrier, ring, sun, planet", table=LIN_PARKER_BODIES)],
        torsional: Annotated[dict, sp.key(
            "table", "N/m", doc="carrier, ring, sun (on u = r theta)",
            table=LIN_PARKER_CENTRAL)],
        mesh: Annotated[dict, sp.key(
            "table", "N/m", doc="sun_planet, ring_planet", table=PER_MESH)],
        pressure_angle: Annotated[object, sp.key(
            "per_mesh", "deg", file="pressure_angle_deg", table=PER_MESH_ANGLE,
            doc="pressure angle, a number or {sun_planet, ring_planet}")],
        planet_angles: Annotated[object, sp.key(
            "vector", "rad", degrees=True, doc="planet positions (default equally spaced)")]
        = None, *,
        backlash: Annotated[float, _BACKLASH] = 0.0,
        mesh_damping: Annotated[float, _MESH_C] = 0.0,
        pin_errors: Annotated[object, _PIN_ERRORS] = None,
        tooth_thickness_errors: Annotated[object, _THICKNESS_ERRORS] = None) -> Model:
    """Lin & Parker (1999) planar planetary stage in the frame rotating with the carrier.

    Parameters (SI, Lin & Parker's convention)
    ----------
    n_planets : number of planets (>= 1).
    mass : kg, keyed ``carrier``, ``ring``, ``sun``, ``planet``.
    inertia_over_r2 : ``I / r**2`` in kg, same keys (``r`` is the base radius; the carrier's is
        the radius of the planet pins).
    bearing : translational support stiffness of ``carrier``, ``ring``, ``sun`` (to ground) and
        ``planet`` (planet bearing, radial and tangential), N/m.
    torsional : torsional support stiffness of ``carrier``, ``ring``, ``sun`` in N/m acting on
        ``u = r theta``.
    mesh : mesh stiffness ``sun_planet``, ``ring_planet``, N/m.
    pressure_angle : rad, a number or a table ``sun_planet``, ``ring_planet``.
    planet_angles : planet positions ``psi_n`` in rad (default equally spaced from 0).
    backlash : m, both meshes (the back flanks; 0 = none). mesh_damping : N s/m.
    pin_errors : per planet ``[radial_m, tangential_m]``, the carrier pinhole position error
        (the planet's ``position_error``). tooth_thickness_errors : per planet, m along the
        line of action (positive: thicker; each of its flanks closes by half of it).

    DOFs are ``carrier.x, carrier.y, carrier.u, ring.x, ..., sun.u, planet1.zeta, planet1.eta,
    planet1.u, ...`` with ``zeta``/``eta`` the planet's radial/tangential displacement and ``u``
    the rotational coordinate ``r theta`` (m). Front flanks follow Lin & Parker's mesh
    deflections ``delta_sn``, ``delta_rn`` (compressed by a positive sun rotation).
    """
    for label, table, keys in (("mass", mass, (*_CENTRAL, "planet")),
                               ("inertia_over_r2", inertia_over_r2, (*_CENTRAL, "planet")),
                               ("bearing", bearing, (*_CENTRAL, "planet")),
                               ("torsional", torsional, _CENTRAL),
                               ("mesh", mesh, ("sun_planet", "ring_planet"))):
        if not isinstance(table, dict):
            raise ModelError(f"lin_parker_stage.{label}", f"expected a table with keys "
                                                          f"{', '.join(keys)}, got {table!r}")
        for k in keys:
            if k not in table:
                raise ModelError(f"lin_parker_stage.{label}.{k}", "missing")
        for k in table:
            if k not in keys:
                raise ModelError(f"lin_parker_stage.{label}.{k}", "unknown key; allowed: "
                                 + ", ".join(keys))
    if isinstance(pressure_angle, dict):
        a_s = pressure_angle.get("sun_planet")
        a_r = pressure_angle.get("ring_planet")
    else:
        a_s = a_r = pressure_angle
    a_s = v.angle("lin_parker_stage.pressure_angle.sun_planet", a_s, low=1e-6, high=math.pi / 3)
    a_r = v.angle("lin_parker_stage.pressure_angle.ring_planet", a_r, low=1e-6,
                  high=math.pi / 3)
    psi = _planet_angles("lin_parker_stage.planet_angles", planet_angles, n_planets)
    errors = _errors("lin_parker_stage", n_planets, pin_errors, tooth_thickness_errors)
    _check_backlash("lin_parker_stage", backlash, errors)

    # Radii cancel from Lin & Parker's matrices (u = r theta, I / r^2); pick a consistent
    # geometry: pin radius 1 m, planet base radius 1/4 m, sun and ring base radii from the
    # pressure angles so that both lines of action are tangent to the base circles.
    r_c, r_p = 1.0, 0.25
    radius = {"carrier": r_c, "sun": r_c * math.cos(a_s) - r_p,
              "ring": r_c * math.cos(a_r) + r_p, "planet": r_p}
    m = Model("lin_parker_stage", input="carrier")
    m.add(Frame("carrier", 1.0))
    for b in _CENTRAL:
        r = radius[b]
        m.add(RigidBody(name=b, mass=mass[b], inertia=_iorr(f"{b}", inertia_over_r2[b], r),
                        dofs="planar", frame="carrier", rotation_scale=r, speed_ratio=1.0,
                        role=b))
    for n, p in enumerate(psi, start=1):
        m.add(RigidBody(name=f"planet{n}", mass=mass["planet"],
                        inertia=_iorr("planet", inertia_over_r2["planet"], r_p),
                        dofs="planar", frame="carrier", rotation_scale=r_p, speed_ratio=1.0,
                        position=(r_c * math.cos(p), r_c * math.sin(p), 0.0), orientation=p,
                        coordinate_names={"x": "zeta", "y": "eta"}, role="planet",
                        **errors[n - 1]))
    for b in _CENTRAL:
        k = v.nonnegative(f"lin_parker_stage.bearing.{b}", bearing[b], "N/m")
        ku = v.nonnegative(f"lin_parker_stage.torsional.{b}", torsional[b], "N/m")
        m.add(Bearing(f"{b}_support", b, None,
                      stiffness={"x": k, "y": k, "theta": ku * radius[b] ** 2},
                      role=f"{b}_support"))
    kp = v.nonnegative("lin_parker_stage.bearing.planet", bearing["planet"], "N/m")
    ksp = v.nonnegative("lin_parker_stage.mesh.sun_planet", mesh["sun_planet"], "N/m")
    krp = v.nonnegative("lin_parker_stage.mesh.ring_planet", mesh["ring_planet"], "N/m")
    for n, p in enumerate(psi, start=1):
        pl = f"planet{n}"
        m.add(Bearing(f"{pl}_bearing", pl, "carrier", stiffness={"x": kp, "y": kp},
                      axes_angle=p, role="planet_bearing", planet=pl))
        m.add(Mesh(f"sun_{pl}", "sun", pl, ksp, backlash, mesh_damping, side=1,
                   pressure_angle=a_s, base_radii=(radius["sun"], r_p), helix_angle=0.0,
                   internal=False, role="sun_planet", planet=pl))
        m.add(Mesh(f"ring_{pl}", "ring", pl, krp, backlash, mesh_damping, side=1,
                   pressure_angle=a_r, base_radii=(radius["ring"], r_p), helix_angle=0.0,
                   internal=True, role="ring_planet", planet=pl))
    m.groups["planets"] = [f"planet{n}" for n in range(1, n_planets + 1)]
    return m.check()


def _errors(name: str, n: int, pin_errors, tooth_thickness_errors) -> list[dict]:
    """Per planet: ``position_error`` (radial, tangential pinhole error, m) and
    ``thickness_error`` (m) from the builders' ``pin_errors`` and ``tooth_thickness_errors``
    (None: no errors), each given for every planet."""
    out = [{} for _ in range(n)]
    if pin_errors is not None:
        f = f"{name}.pin_errors"
        if not isinstance(pin_errors, (list, tuple)) or len(pin_errors) != n:
            raise ModelError(f, f"= {pin_errors!r}: expected one [radial_m, tangential_m] "
                             f"per planet ({n})")
        for i, e in enumerate(pin_errors):
            if not isinstance(e, (list, tuple)) or len(e) != 2:
                raise ModelError(f"{f}[{i}]", f"= {e!r}: expected [radial_m, tangential_m]")
            out[i]["position_error"] = tuple(v.plausible(f"{f}[{i}]", v.number(
                f"{f}[{i}]", x, "m"), "gap") for x in e)
    if tooth_thickness_errors is not None:
        f = f"{name}.tooth_thickness_errors"
        if not isinstance(tooth_thickness_errors, (list, tuple)) \
                or len(tooth_thickness_errors) != n:
            raise ModelError(f, f"= {tooth_thickness_errors!r}: expected one value (m) per "
                             f"planet ({n})")
        for i, t in enumerate(tooth_thickness_errors):
            out[i]["thickness_error"] = v.plausible(f"{f}[{i}]", v.number(f"{f}[{i}]", t, "m"),
                                                    "gap")
    return out


def _runout(name: str, runout, bodies=("sun", "ring", "carrier")) -> dict:
    """``{body: (e_m, phase_rad)}`` from the builders' ``runout`` table (None: none)."""
    if runout is None:
        return {}
    f = f"{name}.runout"
    if not isinstance(runout, dict):
        raise ModelError(f, f"= {runout!r}: expected a table {{sun = [e_m, phase], ...}} of "
                         + ", ".join(bodies))
    out = {}
    for k, val in runout.items():
        if k not in bodies:
            raise ModelError(f"{f}.{k}", "unknown body; allowed: " + ", ".join(bodies))
        if not isinstance(val, (list, tuple)) or len(val) != 2:
            raise ModelError(f"{f}.{k}", f"= {val!r}: expected [eccentricity_m, phase]")
        e = v.plausible(f"{f}.{k}", v.nonnegative(f"{f}.{k}", val[0], "m"), "gap")
        out[k] = (e, v.number(f"{f}.{k}", val[1], "rad"))
    return out


def _te(name: str, te) -> tuple:
    """A mesh's ``transmission_error`` pairs ``[(amplitude_m, phase_rad), ...]`` (None: none)."""
    if te is None:
        return ()
    f = f"{name}.transmission_error"
    if not isinstance(te, (list, tuple)) or not all(isinstance(x, (list, tuple))
                                                    and len(x) == 2 for x in te):
        raise ModelError(f, f"= {te!r}: expected [[amplitude_m, phase], ...], one pair per "
                         "harmonic of the mesh frequency")
    return tuple((v.plausible(f"{f}[{i}]", v.nonnegative(f"{f}[{i}]", a, "m"), "gap"),
                  v.number(f"{f}[{i}]", ph, "rad")) for i, (a, ph) in enumerate(te))


def _check_backlash(name: str, backlash: float, errors: list[dict]) -> None:
    for i, e in enumerate(errors):
        t = e.get("thickness_error", 0.0)
        if t > 0.0 and t > backlash:
            raise ModelError(f"{name}.tooth_thickness_errors[{i}]", f"= {t!r} m: thicker than "
                             f"the backlash ({backlash!r} m) allows; the teeth would jam")


def _iorr(field: str, value, r: float) -> float:
    return v.positive(f"lin_parker_stage.inertia_over_r2.{field}", value, "kg") * r * r


def _planet_angles(field: str, angles, n: int) -> list[float]:
    if angles is None:
        return [2 * math.pi * i / n for i in range(n)]
    angles = list(angles)
    if len(angles) != n:
        raise ModelError(field, f"gives {len(angles)} angles for {n} planets")
    return [v.number(f"{field}[{i}]", a, "rad") for i, a in enumerate(angles)]


def _planets_fit(name: str, given: bool, psi: list, centre: float, planet: Gear,
                 teeth: int) -> None:
    """Planets that can be built: no two whose tip circles (radius pitch + one module)
    intersect, and each at an angle from planet 1 where the teeth of sun and ring let it in,
    a multiple of ``2 pi / (z_sun + z_ring)`` (the assembly condition)."""
    field = f"{name}.planet_angles" if given else f"{name}.n_planets"
    tip = planet.pitch_radius + planet.module
    for i in range(len(psi)):
        for j in range(i):
            d = 2.0 * centre * abs(math.sin(0.5 * (psi[i] - psi[j])))
            if d < 2.0 * tip * (1.0 - 1e-9):
                where = f"{field}[{i}]" if given else field
                raise ModelError(where, f"planets {j + 1} and {i + 1} overlap: their centres "
                                 f"are {d:.4g} m apart, their tip circles need {2 * tip:.4g} m")
    if given:
        pitch = 2.0 * math.pi / teeth
        for i in range(1, len(psi)):
            k = (psi[i] - psi[0]) / pitch
            if abs(k - round(k)) > 1e-6:
                raise ModelError(f"{field}[{i}]", f"= {psi[i]:.6g} rad: the teeth cannot "
                                 f"assemble planet {i + 1} there: its angle from planet 1 must "
                                 f"be a multiple of 2 pi / (sun + ring teeth) = {pitch:.6g} rad "
                                 f"({360.0 / teeth:.6g} deg); {k:.4f} pitches is not")


def _operating_angle(field: str, a: float, rb_sum: float, pair: str) -> float:
    """The operating transverse pressure angle of a pair at centre distance ``a`` (m):
    ``cos(alpha_w) = rb_sum / a``, ``rb_sum`` the base radii's sum (external pair) or
    difference (internal pair) (ISO 21771, the operating pressure angle of profile-shifted
    gears; the line of action stays tangent to both base circles)."""
    c = rb_sum / a
    if not math.cos(math.pi / 4) < c < 1.0:
        raise ModelError(field, f"= {a!r} m: with base radii {pair} = {rb_sum:.6g} m the "
                         f"operating pressure angle acos({c:.6g}) is outside (0, 45) deg; the "
                         f"centre distance must lie in ({rb_sum:.6g}, "
                         f"{rb_sum / math.cos(math.pi / 4):.6g}) m")
    return math.acos(c)


def _centre(name: str, centre_distance, a: Gear, b: Gear, pairs: dict) -> tuple[float, dict]:
    """The centre distance of external gears ``a`` and ``b`` and each pair's operating
    pressure angle (``pairs``: key -> (base radii's sum or difference, its label)): without
    ``centre_distance`` the standard distance of unshifted gears and None (the gears' own
    angle) for every pair."""
    if centre_distance is None:
        return ((a.base_radius + b.base_radius) / math.cos(a.transverse_pressure_angle),
                dict.fromkeys(pairs))
    field = f"{name}.centre_distance"  # (its range checked with the builder's arguments)
    return centre_distance, {key: _operating_angle(field, centre_distance, rb, label)
                             for key, (rb, label) in pairs.items()}


def _needs_contact_ratio(field: str, spec: dict) -> None:
    """With a centre distance (profile-shifted gears) the default contact ratio, computed for
    standard gears, does not apply: an alternating mesh must state its own."""
    if spec.get("alternation") and "contact_ratio" not in spec:
        raise ModelError(f"{field}.contact_ratio", "required with centre_distance: the default "
                         "is computed for standard gears without profile shift")


@sp.checked
def planetary_stage(
        sun: Annotated[Gear, sp.GEAR], planet: Annotated[Gear, sp.GEAR],
        ring: Annotated[Gear, sp.RING], *,
        n_planets: Annotated[int, sp.key(
            "integer", low=1, high=v.MAX_PLANETS, doc="number of planets",
            note="wind-turbine gearboxes have 3 to 7")] = 3,
        carrier_mass: Annotated[float, sp.like(_RB["mass"], file="carrier.mass")],
        carrier_inertia: Annotated[float, sp.like(_RB["inertia"], file="carrier.inertia")],
        mesh_stiffness: Annotated[object, sp.like(_MF["stiffness"], type="per_mesh",
                                                  doc="mesh stiffness on the line of action")],
        backlash: Annotated[float, _BACKLASH] = 0.0,
        mesh_damping: Annotated[float, _MESH_C] = 0.0,
        planet_bearing: Annotated[object, sp.key(
            "support", doc="each planet on its carrier pin")] = None,
        carrier_bearing: Annotated[object, sp.key("support", doc="carrier to the housing")] = None,
        sun_support: Annotated[object, sp.key("support", doc="sun to the housing")] = None,
        ring_support: Annotated[object, sp.key("support", doc="ring to the housing")] = None,
        dofs: Annotated[str, _DOFS] = "planar",
        planet_angles: Annotated[object, sp.key(
            "vector", "rad", degrees=True, doc="planet positions (default equally spaced)")]
        = None,
        carrier_inertia_diametral: Annotated[float | None, sp.like(
            _RB["inertia_diametral"], file="carrier.inertia_diametral")] = None,
        name: str = "planetary_stage",
        mesh_alternation: Annotated[object, _ALTERNATION] = None,
        pin_errors: Annotated[object, _PIN_ERRORS] = None,
        tooth_thickness_errors: Annotated[object, _THICKNESS_ERRORS] = None,
        runout: Annotated[object, sp.key(
            "table", phase_deg=True, doc="{sun = [e_m, phase_deg], ring = ..., carrier = ...}: "
            "eccentricity turning with the body")] = None,
        transmission_error: Annotated[object, sp.key(
            "any", phase_deg=True, doc="[[amplitude_m, phase_deg], ...] harmonics of the mesh "
            "frequency, or {sun_planet = [...], ring_planet = [...]}")] = None,
        centre_distance: Annotated[float | None, _CENTRE] = None) -> Model:
    """A planetary stage with carrier input and the ring held (the wind-turbine layout).

    Parameters
    ----------
    sun, planet, ring : :class:`Gear` (``ring.internal = True``; ring teeth = sun + 2 planet
        unless ``centre_distance`` is given).
    n_planets : number of planets; equally spaced unless ``planet_angles`` (rad) is given.
    carrier_mass : kg. carrier_inertia : kg m^2 about the axis.
    mesh_stiffness : N/m, a number or a table ``sun_planet``, ``ring_planet``.
    backlash : m along the line of action (both meshes). mesh_damping : N s/m.
    planet_bearing, carrier_bearing, sun_support, ring_support : N/m or a table of
        ``stiffness``/``damping``/``clearance`` tables keyed by direction (see
        :class:`Bearing`); the planet bearing's axes are radial/tangential, the others'
        are fixed. Supports go to the ground (to the housing inside a drivetrain).
    dofs : DOF level of every body.
    mesh_alternation : None/False (constant mesh stiffness), True or a table of
        ``contact_ratio`` (a number or a table ``sun_planet``, ``ring_planet``) and
        ``stiffness_ratio``: every mesh alternates between single and double tooth-pair
        contact at the mesh frequency (:class:`Mesh`), planet n's meshes phased by the planet
        spacing (Parker & Lin 2004); the sun-ring phase is taken as 0.
    pin_errors : per planet ``[radial_m, tangential_m]``: the carrier pinhole position error
        (the planet's ``position_error``; tangential positive in the sense of the carrier's
        positive rotation). tooth_thickness_errors : per planet, m along the line of action
        (positive: thicker; each of its flanks closes by half of it, the backlash by all).
    runout : ``{"sun": (e_m, phase_rad), "ring": ..., "carrier": ...}``: the eccentricity of a
        wheel's teeth turning with it (``Body.runout``); the carrier's moves every planet pin by
        the same vector (a common pinhole error, constant in the carrier frame).
    transmission_error : ``[(amplitude_m, phase_rad), ...]`` harmonics of the mesh frequency
        on every mesh (or a table ``sun_planet``, ``ring_planet``), planet n's phased by the
        planet spacing as ``mesh_alternation`` is (:class:`Mesh`).
    centre_distance : m, the operating centre distance of profile-shifted gears (sun to
        planet = planet to ring); each mesh then runs at its own operating pressure angle,
        ``cos(alpha_w) = (r_b,sun + r_b,planet) / a`` and ``(r_b,ring - r_b,planet) / a``, and
        the ring's teeth need not be sun + 2 planet (the speed ratios stay the tooth counts'). An
        alternating mesh then needs its ``contact_ratio``. Default: the standard centre
        distance of unshifted gears.

    Notes
    -----
    All bodies' coordinates are expressed in the frame rotating with the carrier (Lin & Parker
    1999). Bodies: ``carrier``, ``sun``, ``ring``, ``planet1..N`` (planet translations ``zeta``
    radial, ``eta`` tangential). The carrier is the input (speed ratio 1), the sun turns at
    ``1 + z_ring/z_sun``. A positive carrier torque closes the front flanks.
    """
    s = _gear(sun, f"{name}.sun", "sun", dofs)
    p = _gear(planet, f"{name}.planet", "planet", dofs)
    r = _gear(ring, f"{name}.ring", "ring", dofs)
    if not r.internal:
        raise ModelError(f"{name}.ring.internal", "= false: the ring must be an internal gear")
    if s.internal or p.internal:
        raise ModelError(f"{name}.sun.internal", "sun and planet must be external gears")
    _same_tooth_system(f"{name}.planet", s, p)
    _same_tooth_system(f"{name}.ring", p, r, internal=True)
    if centre_distance is None and r.teeth != s.teeth + 2 * p.teeth:
        raise ModelError(f"{name}.ring.teeth", f"= {r.teeth}: ring teeth must equal sun + 2 * "
                         f"planet ({s.teeth} + 2 * {p.teeth} = {s.teeth + 2 * p.teeth}), or "
                         "give the stage's centre_distance (profile-shifted gears)")
    if planet_angles is None and (s.teeth + r.teeth) % n_planets:
        raise ModelError(f"{name}.n_planets", f"= {n_planets}: planets cannot be equally "
                         f"spaced, (sun + ring teeth) = {s.teeth + r.teeth} is not divisible "
                         f"by {n_planets}; give planet_angles")
    psi = _planet_angles(f"{name}.planet_angles", planet_angles, n_planets)
    errors = _errors(name, n_planets, pin_errors, tooth_thickness_errors)
    _check_backlash(name, backlash, errors)
    ro = _runout(name, runout)
    if isinstance(transmission_error, dict):
        unknown = set(transmission_error) - {"sun_planet", "ring_planet"}
        if unknown:
            raise ModelError(f"{name}.transmission_error.{sorted(unknown)[0]}",
                             "unknown mesh kind; allowed: sun_planet, ring_planet")
        te = {k: _te(name, transmission_error.get(k)) for k in ("sun_planet", "ring_planet")}
    else:
        te = dict.fromkeys(("sun_planet", "ring_planet"), _te(name, transmission_error))
    if isinstance(mesh_stiffness, dict):
        k_sp = mesh_stiffness.get("sun_planet")
        k_rp = mesh_stiffness.get("ring_planet")
        if k_sp is None or k_rp is None:
            raise ModelError(f"{name}.mesh_stiffness", "needs sun_planet and ring_planet")
    else:
        k_sp = k_rp = mesh_stiffness
    centre, alpha_w = _centre(name, centre_distance, s, p, {
        "sun_planet": (s.base_radius + p.base_radius, "sun + planet"),
        "ring_planet": (r.base_radius - p.base_radius, "ring - planet")})
    _planets_fit(name, planet_angles is not None, psi, centre, p, s.teeth + r.teeth)

    m = Model(name, input="carrier")
    m.add(Frame("carrier", 1.0))
    carrier = RigidBody(name="carrier", mass=carrier_mass, inertia=carrier_inertia,
                        inertia_diametral=carrier_inertia_diametral, dofs=dofs,
                        frame="carrier", speed_ratio=1.0, role="carrier")
    for g, ratio in ((s, 1.0 + r.teeth / s.teeth), (r, 0.0)):
        g.frame, g.speed_ratio, g.role = "carrier", ratio, g.name
        g.runout = ro.get(g.name, (0.0, 0.0))
    m.add(carrier)
    m.add(s)
    m.add(r)
    for n, a in enumerate(psi, start=1):
        pl = copy.deepcopy(p)
        pl.name, pl.frame, pl.speed_ratio = f"planet{n}", "carrier", 1.0 - r.teeth / p.teeth
        pl.position = (centre * math.cos(a), centre * math.sin(a), 0.0)
        pl.orientation = a
        pl.coordinate_names = {"x": "zeta", "y": "eta"}
        pl.pinned_to = "carrier"  # a torsional planet rides on its carrier pin
        pl.role = "planet"
        pe = errors[n - 1].get("position_error", (0.0, 0.0))
        if "carrier" in ro:  # the pin circle off the carrier's axis: every pin moves by e
            e, ph = ro["carrier"]
            pe = (pe[0] + e * math.cos(ph - a), pe[1] + e * math.sin(ph - a))
        pl.position_error = pe
        pl.thickness_error = errors[n - 1].get("thickness_error", 0.0)
        m.add(pl)
    for label, spec, body in (("carrier_bearing", carrier_bearing, "carrier"),
                              ("sun_support", sun_support, "sun"),
                              ("ring_support", ring_support, "ring")):
        sup = _support(f"{name}.{label}", spec, dofs)
        if sup["stiffness"]:
            m.add(Bearing(label, body, None, role=label, **sup))
    for n, a in enumerate(psi, start=1):
        pl = f"planet{n}"
        sup = _support(f"{name}.planet_bearing", planet_bearing, dofs)
        if sup["stiffness"]:
            m.add(Bearing(f"{pl}_bearing", pl, "carrier", axes_angle=a,
                          role="planet_bearing", planet=pl, **sup))
        # Carrier input: the planets drive the sun and push on the ring on the flanks that a
        # positive carrier rotation closes, i.e. Lin & Parker's mirrored line of action.
        # mesh phases of planet n relative to planet 1 (Parker & Lin 2004): the ring's teeth
        # pass planet n's position z_r psi_n / 2 pi periods later, the sun's z_s psi_n / 2 pi
        # earlier (mesh_stiffness M3)
        alt = f"{name}.mesh_alternation"
        for kind, gear, frac in (("sun_planet", "sun", -s.teeth * a / (2 * math.pi)),
                                 ("ring_planet", "ring", r.teeth * a / (2 * math.pi))):
            spec = _alternation(alt, mesh_alternation, kind, frac)
            if centre_distance is not None:
                _needs_contact_ratio(alt, spec)
            if te[kind]:
                spec.setdefault("phase", frac)  # also the transmission error's phase
            m.add(Mesh(f"{gear}_{pl}", gear, pl, k_sp if kind == "sun_planet" else k_rp,
                       backlash, mesh_damping, side=-1, role=kind, planet=pl,
                       transmission_error=te[kind], pressure_angle=alpha_w[kind], **spec))
    m.groups["planets"] = [f"planet{n}" for n in range(1, n_planets + 1)]
    m.output = "sun"
    return m.check()


@sp.checked
def parallel_stage(gear: Annotated[Gear, sp.GEAR], pinion: Annotated[Gear, sp.GEAR], *,
                   mesh_stiffness: Annotated[float, _MESH_K],
                   backlash: Annotated[float, _BACKLASH] = 0.0,
                   mesh_damping: Annotated[float, _MESH_C] = 0.0,
                   gear_bearing: Annotated[object, sp.key(
                       "support", doc="gear to the housing")] = None,
                   pinion_bearing: Annotated[object, sp.key(
                       "support", doc="pinion to the housing")] = None,
                   dofs: Annotated[str, _DOFS] = "planar",
                   position: Annotated[tuple, sp.key(
                       "vector", "m", lengths=(2,), doc="[x, y] centre of the gear")] = (0.0, 0.0),
                   angle: Annotated[float, sp.key(
                       "angle", "rad", degrees=True,
                       doc="direction from the gear to the pinion")] = 0.0,
                   name: str = "parallel_stage",
                   mesh_alternation: Annotated[object, _ALTERNATION] = None,
                   centre_distance: Annotated[float | None, _CENTRE] = None) -> Model:
    """A parallel (speed-increasing) stage: ``gear`` (input, the large wheel) drives ``pinion``.

    ``position`` (m) is the centre of ``gear`` in the housing plane and ``angle`` (rad) the
    direction from it to the pinion. Bearings (N/m or tables, see :class:`Bearing`) go to the
    ground, or to the housing inside a drivetrain. A positive torque on ``gear`` closes the front
    flank. ``mesh_alternation``: as for :func:`gear_pair`. ``centre_distance`` (m): the
    operating centre distance of profile-shifted gears, the mesh then at its operating pressure
    angle ``cos(alpha_w) = (r_b,gear + r_b,pinion) / a`` (default: the standard one).
    """
    g = _gear(gear, f"{name}.gear", "gear", dofs)
    p = _gear(pinion, f"{name}.pinion", "pinion", dofs)
    if g.internal or p.internal:
        raise ModelError(f"{name}", "gears of a parallel stage must be external")
    _same_tooth_system(f"{name}.pinion", g, p)
    x0, y0 = position
    alt = _alternation(f"{name}.mesh_alternation", mesh_alternation)
    centre, alpha_w = _centre(name, centre_distance, g, p, {
        "mesh": (g.base_radius + p.base_radius, "gear + pinion")})
    if centre_distance is not None:
        alt["pressure_angle"] = alpha_w["mesh"]
        _needs_contact_ratio(f"{name}.mesh_alternation", alt)
    g.position, g.speed_ratio, g.role, p.role = (x0, y0, 0.0), 1.0, "gear", "pinion"
    p.position = (x0 + centre * math.cos(angle), y0 + centre * math.sin(angle), 0.0)
    p.speed_ratio = -g.teeth / p.teeth
    m = Model(name, input="gear")
    m.add(g)
    m.add(p)
    m.add(Mesh("mesh", "gear", "pinion", mesh_stiffness, backlash, mesh_damping, side=1,
               role="mesh", **alt))
    for label, spec, body in (("gear_bearing", gear_bearing, "gear"),
                              ("pinion_bearing", pinion_bearing, "pinion")):
        sup = _support(f"{name}.{label}", spec, dofs)
        if sup["stiffness"]:
            m.add(Bearing(label, body, None, role=label, **sup))
    m.output = "pinion"
    return m.check()


@sp.checked
def drivetrain(
        rotor: Annotated[RigidBody, sp.body("the rotor (input)", "torsional")], stages: list, *,
        main_shaft_stiffness: Annotated[float, sp.like(SHAFT_K, file="main_shaft.stiffness")],
        main_shaft_damping: Annotated[float, sp.like(SHAFT_C, file="main_shaft.damping")]
        = 0.0,
        couplings=None,
        generator: Annotated[RigidBody | None, sp.body("the generator rotor", "torsional")]
        = None,
        hss_stiffness: Annotated[float | None, sp.like(SHAFT_K, file="hss_shaft.stiffness")]
        = None,
        hss_damping: Annotated[float, sp.like(SHAFT_C, file="hss_shaft.damping")] = 0.0,
        housing: Annotated[RigidBody | None, sp.body("the gearbox housing", "planar")] = None,
        suspension: Annotated[object, sp.key("support", doc="the housing to the ground")]
        = None,
        shaft_bending: Annotated[object, sp.key(
            "support", doc="the first stage's input to the ground (the main bearing)")] = None,
        name: str = "drivetrain", stage_names=None) -> Model:
    """Chain a rotor, gear stages, a generator and a housing on its suspension.

    Parameters
    ----------
    rotor : the rotor (input, speed ratio 1), usually ``dofs="torsional"``.
    stages : stage models from :func:`planetary_stage` / :func:`parallel_stage`, input first;
        each stage's input is coupled to the previous stage's output and placed coaxially.
    main_shaft_stiffness : N m/rad, rotor to first stage input. couplings : N m/rad between
        consecutive stages (a number or a list; default rigid-ish 1e9).
    generator, hss_stiffness : generator rotor and its coupling to the last stage, N m/rad.
    housing : gearbox housing body (planar/full); the stages' supports attach to it, and it
        rests on ``suspension`` (N/m or a table, see :class:`Bearing`) to the ground.
    shaft_bending : translational support of the first stage input (the main shaft end, seen
        through the main bearing), N/m or a table.

    Stage bodies are named ``stage<k>.<body>`` (or with ``stage_names``). Speed ratios are
    chained so that every body's ratio is relative to the rotor; a stage whose input turns
    backwards has its mesh sides flipped so that rotor torque closes every front flank.
    """
    if not isinstance(rotor, RigidBody):
        raise ModelError(f"{name}.rotor", "expected a gm.RigidBody")
    if not stages:
        raise ModelError(f"{name}.stages", "at least one stage is needed")
    names = list(stage_names or [f"stage{k}" for k in range(1, len(stages) + 1)])
    if len(names) != len(stages):
        raise ModelError(f"{name}.stage_names", "one name per stage")
    if couplings is None or not isinstance(couplings, (list, tuple)):
        couplings = [couplings if couplings is not None else 1e9] * (len(stages) - 1)
    if len(couplings) != len(stages) - 1:
        raise ModelError(f"{name}.couplings", f"gives {len(couplings)} stiffnesses for "
                         f"{len(stages) - 1} couplings between {len(stages)} stages")
    m = Model(name, input="rotor")
    rot = copy.deepcopy(rotor)
    rot.name = rot.name or "rotor"
    if rot.name != "rotor":
        raise ModelError(f"{name}.rotor.name", "the drivetrain input body is named 'rotor'")
    rot.speed_ratio, rot.role = 1.0, "rotor"
    m.add(rot)
    support = None
    if housing is not None:
        h = copy.deepcopy(housing)
        h.name = "housing"
        h.speed_ratio, h.role = 0.0, "housing"
        m.add(h)
        support = "housing"
    ratio, prev_out, prev_centre = 1.0, "rotor", (0.0, 0.0)
    for k, (sname, st) in enumerate(zip(names, stages, strict=True)):
        if not isinstance(st, Model) or getattr(st, "output", None) is None:
            raise ModelError(f"{name}.stages[{k}]", "expected a stage model from "
                             "gm.planetary_stage or gm.parallel_stage")
        st = st.copy()
        inp = st.bodies[st.input]
        dx, dy = prev_centre[0] - inp.position[0], prev_centre[1] - inp.position[1]
        for b in st.bodies.values():
            b.speed_ratio *= ratio
            if st.frames[b.frame].speed_ratio == 0.0:
                b.position = (b.position[0] + dx, b.position[1] + dy, b.position[2])
            elif (dx, dy) != (0.0, 0.0):
                raise ModelError(f"{name}.stages[{k}]", "a rotating-frame stage must be "
                                 "coaxial with the rotor")
        for fr in st.frames.values():
            fr.speed_ratio *= ratio
        if ratio < 0:
            for mesh in st.meshes.values():
                mesh.side = -mesh.side
        m.merge(st, sname, ground=support)
        a = f"{sname}.{st.input}"
        if k == 0:
            m.add(Shaft("main_shaft", "rotor", a, main_shaft_stiffness, main_shaft_damping))
            m.bearings["main_shaft"].role = "main_shaft"
            if shaft_bending is not None:
                dofs = m.bodies[a].dofs
                m.add(Bearing("shaft_bending", a, None, role="shaft_bending",
                              **_support(f"{name}.shaft_bending", shaft_bending, dofs)))
        else:
            m.add(Shaft(f"coupling{k}", prev_out, a, couplings[k - 1]))
            m.bearings[f"coupling{k}"].role = "coupling"
        out = st.bodies[st.output]
        ratio = out.speed_ratio
        prev_out = f"{sname}.{st.output}"
        prev_centre = out.position[:2]
    if generator is not None:
        g = copy.deepcopy(generator)
        g.name = "generator"
        g.speed_ratio, g.role = ratio, "generator"
        m.add(g)
        if hss_stiffness is None:
            raise ModelError(f"{name}.hss_stiffness", "required with a generator (N m/rad)")
        m.add(Shaft("hss_shaft", prev_out, "generator", hss_stiffness, hss_damping))
        m.bearings["hss_shaft"].role = "hss_shaft"
    if housing is not None:
        if suspension is None:
            raise ModelError(f"{name}.suspension", "required with a housing")
        m.add(Bearing("suspension", "housing", None, role="suspension",
                      **_support(f"{name}.suspension", suspension, m.bodies["housing"].dofs)))
    m.output = "generator" if generator is not None else prev_out
    m.gear_ratio = ratio
    return m.check()
