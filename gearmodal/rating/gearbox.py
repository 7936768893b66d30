"""The rating of a whole model at a torque: every mesh by ISO 6336, every listed bearing by
ISO 281.

The loads come from the model's static equilibrium (:func:`gearmodal.equilibrium`) under the
torque at its input, balanced at its output, and gravity where the model has it: each mesh's
flank force and each bearing's radial force as the model's own springs carry them (the planets'
load sharing included). Speeds and tooth load cycles follow from the model's kinematics: a gear
turns at its speed relative to the frame its centre sits in (a planet relative to its carrier),
and meets one load cycle per revolution in each mesh of a group (a sun with three planets:
three). A planet's teeth are loaded on both flanks in turn (Y_M = 0.7).

Planets are rated per group (a stage's sun-planet meshes, its ring-planet meshes): on the
group's mean mesh force times K_gamma (``k_gamma="standard"``: IEC 61400-4's values; ``"model"``:
the equilibrium's worst planet over the mean; or a number), the model's own K_gamma reported
beside the standard's.
"""

from __future__ import annotations

import fnmatch
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from ..assembly import as_assembly
from ..errors import ModelError
from ..model import rating_data
from ..model.components import Gear
from ..static import balance, equilibrium
from . import runs
from .iso281 import modified_life, operating_viscosity
from .iso6336 import GearSpec, rate_pair

#: IEC 61400-4:2012's mesh load factor K_gamma by number of planets (its Table 6)
IEC_K_GAMMA = {3: 1.1, 4: 1.25, 5: 1.35, 6: 1.44, 7: 1.47}
G = 9.81


@dataclass
class Rating:
    """A model's ratings: ``gears`` (one row per gear of each mesh group: safety factors S_H and
    S_F, stresses and every factor) and ``bearings`` (one row per bearing: load, speed,
    L10m_h); ``settings`` the inputs that made them; ``spectrum`` the ratings under a run's
    load spectrum (per gear and flank), None without a run."""

    gears: pd.DataFrame
    bearings: pd.DataFrame
    settings: dict = field(default_factory=dict)
    spectrum: pd.DataFrame | None = None

    def to_frame(self) -> pd.DataFrame:
        """The gears' table."""
        return self.gears

    def summary(self) -> pd.DataFrame:
        """The lowest S_H and S_F of each gear, and each bearing's L10m_h."""
        g = self.gears[["mesh", "gear", "S_H", "S_F"]]
        b = self.bearings[["bearing", "L10m_h"]] if len(self.bearings) else None
        return g if b is None else pd.concat([g, b], ignore_index=True)

    def plot(self):
        """Bars of S_H and S_F per gear and of L10m per bearing (a matplotlib Figure)."""
        from .report import plot_rating
        return plot_rating(self)

    def save(self, directory) -> Path:
        """Write ``gears.csv``, ``bearings.csv``, ``rating.png`` and ``index.html`` to
        ``directory`` (the CSVs with a ``#`` header of units and settings)."""
        from .report import write_rating
        return write_rating(self, directory)


def _loads(model, torque: float, gravity: bool) -> dict:
    asm, _ = as_assembly(model)
    inp = f"{model.input}.torque"
    if inp not in asm.load_names:
        raise ModelError("model.input", f"= {model.input!r} has no torque load to rate at")
    out = None
    if model.output and f"{model.output}.torque" in asm.load_names:
        out = f"{model.output}.torque"
    else:  # the fastest other body with a torque load
        cands = [(abs(getattr(b, "speed_ratio", 0.0)), n) for n, b in model.bodies.items()
                 if n != model.input and f"{n}.torque" in asm.load_names]
        if cands:
            out = f"{max(cands)[1]}.torque"
    if out is None:
        raise ModelError("model.output", "no output body with a torque load to balance on")
    loads = {inp: float(torque)}
    if gravity and "gravity" in asm.load_names:
        loads["gravity"] = G
    return balance(model, loads, on=out)


def _spec(model, name: str, data: dict, reversed_load: bool) -> GearSpec:
    g = model.bodies[name]
    if g.face_width is None:
        raise ModelError(f"{name}.face_width", "missing: the rating needs each gear's face "
                         "width")
    own = _lookup(data["gears"], name)
    return GearSpec(teeth=g.teeth, module=g.module, pressure_angle=g.pressure_angle,
                    helix_angle=g.helix_angle, face_width=g.face_width, internal=g.internal,
                    profile_shift=own.get("profile_shift", 0.0),
                    tip_alteration=own.get("tip_alteration", 0.0),
                    dedendum=own.get("dedendum", 1.25), root_radius=own.get("root_radius", 0.38),
                    sigma_Hlim=own.get("sigma_Hlim", data["sigma_Hlim"]),
                    sigma_Flim=own.get("sigma_Flim", data["sigma_Flim"]),
                    flank_Rz=data["flank_Rz"], root_Rz=data["root_Rz"],
                    reversed_bending=reversed_load)


def _lookup(table: dict, name: str) -> dict:
    """The entry of ``name``, or of the longest key it starts with (``stage1.planet`` for
    ``stage1.planet2``)."""
    if name in table:
        return table[name]
    keys = [k for k in table if name.startswith(k)]
    return table[max(keys, key=len)] if keys else {}


def _speed(model, body: str) -> float:
    """A body's speed relative to the frame its centre sits in, over the input's."""
    b = model.bodies[body]
    return b.speed_ratio - model.frames[b.frame].speed_ratio


def _groups(model) -> dict:
    """Meshes grouped by stage and role: ``{group: [mesh names]}``."""
    out: dict[str, list[str]] = {}
    for n, m in model.meshes.items():
        key = ".".join(x for x in (m.stage, m.role) if x) if m.role else n
        out.setdefault(key, []).append(n)
    return out


def _k_gamma(choice, n_planets: int, model_value: float) -> float:
    if choice == "standard":
        return IEC_K_GAMMA.get(n_planets, 1.0 if n_planets < 3 else 1.47)
    if choice == "model":
        return model_value
    return float(choice)


def rate(model, torque: float | None = None, *, speed_rpm: float | None = None,
         life_h: float | None = None, application_factor: float | None = None,
         k_gamma=None, dynamic_factor: float | None = None, gravity: bool = True,
         result=None, t_from: float = 0.0) -> Rating:
    """ISO 6336 and ISO 281 ratings of ``model`` at a steady ``torque`` (N m at its input;
    default the ``[rating]`` table's ``input_torque``) and speed (rpm; default the model's rated
    speed), over ``life_h`` hours (default the table's, 20 years).

    ``application_factor`` (K_A) and ``k_gamma`` override the table's; ``dynamic_factor`` a
    K_v for every mesh instead of ISO 6336-1's method B (e.g. 1 where a dynamic model's loads
    are given, or the peaks of a run over its static loads). ``gravity``: the
    weights in the loads where the model has a gravity load (the bearings' loads).

    With ``result`` (a run of this model: :func:`gearmodal.simulate`, a turbine run) the rating
    adds ISO 6336-6's under the run's exact load spectrum from ``t_from`` (s) on, the run
    standing for the whole life (:mod:`gearmodal.rating.runs`): ``Rating.spectrum`` (per gear
    and flank: damages and equivalent safety factors ``S_H_spectrum``, ``S_F_spectrum``, and
    ``peak_over_steady``, the run's largest flank force over the steady rating's largest
    mesh force: what the dynamics and double contact add to the standard's K factors) and
    the planet bearings' lives from their exact equivalent loads (``L10m_h_spectrum``).

    Examples
    --------
    >>> import gearmodal as gm
    >>> r = gm.rate(gm.load("studies/models/nrel5mw.toml"))
    >>> print(r.gears[["mesh", "gear", "S_H", "S_F"]].head(4).round(2).to_string(index=False))
                  mesh          gear  S_H  S_F
     stage1.sun_planet stage1.planet 1.42 3.07
     stage1.sun_planet    stage1.sun 1.39 4.13
    stage1.ring_planet stage1.planet 1.93 3.45
    stage1.ring_planet   stage1.ring 1.93 3.72
    """
    data = model.rating if model.rating is not None else rating_data.defaults()
    torque = data.get("input_torque") if torque is None else torque
    if torque is None:
        raise ModelError("rating.input_torque", "missing: give the model's [rating] "
                         "input_torque or rate(model, torque=...)")
    speed = model.rated_speed_rpm if speed_rpm is None else speed_rpm
    if speed is None or not speed > 0:
        raise ModelError("model.rated_speed_rpm", f"= {speed!r}: the rating needs the input "
                         "speed (the model's rated_speed_rpm or speed_rpm=)")
    life = data["life_h"] if life_h is None else life_h
    k_a = data["application_factor"] if application_factor is None else application_factor
    kg_choice = data["k_gamma"] if k_gamma is None else k_gamma
    loads = _loads(model, torque, gravity)
    eq = equilibrium(model, loads, speed_rpm=speed)  # the centrifugal loads in
    c = eq.contacts
    force = c.groupby("element")["force_N"].sum()
    rows, spectrum = [], []
    sim = runs.simulation_of(result) if result is not None else None
    for pair in _pairs(model, data):
        names, (sp, sw) = pair["meshes"], pair["specs"]
        f = np.array([abs(float(force.get(n, 0.0))) for n in names])
        worst = names[int(np.argmax(f))]
        n_pl = pair["planets"]
        kg_model = float(f.max() / f.mean()) if f.mean() > 0 else 1.0
        kg = _k_gamma(kg_choice, n_pl, kg_model) if n_pl else 1.0
        torque_p = float(f.mean()) * pair["force_to_torque"]  # per mesh, the group's mean
        n_p, n_w = (x * speed for x in pair["speed_ratio"])
        cyc = tuple(abs(n) * 60.0 * life * k for n, k in zip((n_p, n_w), pair["count"],
                                                            strict=True))
        r = rate_pair(sp, sw, pair["centre"], torque_p, n_p, cycles=cyc,
                      application_factor=k_a, k_gamma=kg,
                      accuracy_grade=data["accuracy_grade"],
                      lubricant_viscosity_40=data["lubricant_viscosity_40"],
                      tip_relief=data["tip_relief"], long_life=data["long_life"],
                      reduced_mass=pair["reduced_mass"], dynamic_factor=dynamic_factor)
        if sim is not None:
            new = runs.spectrum_rows(sim, pair, names, life_h=life, t_from=t_from, data=data)
            for row in new:  # the run's dynamic peak against the steady rating's load
                row["peak_over_steady"] = row["peak_force_N"] / float(f.max()) if f.max() > 0 \
                    else math.nan
            spectrum += new
        for k, g in enumerate(r.gears):
            rows.append({"mesh": pair["group"], "gear": pair["labels"][k],
                         "member": ("pinion", "wheel")[k], "worst_mesh": worst,
                         "S_H": g["S_H"], "S_F": g["S_F"],
                         **{x: v for x, v in g.items() if x not in ("S_H", "S_F")},
                         **r.pair, "K_gamma_model": kg_model})
    if sim is not None and not spectrum:
        raise ModelError("result", "has no force of this model's mesh flanks (a run of another "
                         "model?)")
    gears = pd.DataFrame(rows)
    bearings = _bearings(model, eq, data, speed, life)
    if sim is not None and len(bearings):
        rated = [(n, data["bearings"][p]) for n, p in zip(bearings.bearing, bearings.pattern,
                                                           strict=True)]
        extra = pd.DataFrame(runs.bearing_rows(sim, model, data, t_from=t_from, life_h=life,
                                               bearings=rated))
        if len(extra):
            bearings = bearings.merge(extra, on="bearing", how="left")
    settings = {"model": model.name, "input_torque_Nm": float(torque), "speed_rpm": speed,
                "life_h": life, "application_factor": k_a, "k_gamma": kg_choice,
                "gravity": "gravity" in loads, "loads": loads,
                "standards": "ISO 6336-1:2006 (K_v B, K_Hbeta C, K_Halpha B), ISO 6336-2:2019, "
                             "ISO 6336-3:2019 (method B), ISO 1328-1:1995, ISO 281:2007"}
    if sim is not None:
        settings["run"] = {"t_from_s": t_from, "t_end_s": sim.time_span()[1],
                           "factors": "K_A = K_gamma = K_v = 1 (the dynamics in the run's "
                                      "loads), the standard's K_Hbeta, K_Halpha"}
    return Rating(gears, bearings, settings,
                  pd.DataFrame(spectrum) if sim is not None else None)


def _pairs(model, data: dict):
    """Each mesh group's pair as the ratings need it, from the model alone: its meshes, pinion
    and wheel (the external gear with fewer teeth is the pinion), their ISO 6336 specs, labels
    (a stage's planets as one), centre distance, reduced mass, the factor from a flank force
    to the pinion's torque, speeds against their frame over the input's, load cycles per
    revolution (meshes of the group each gear is in) and the stage's number of planets."""
    planets_of: dict[str, set] = {}
    roles: dict[str, set] = {}
    for m in model.meshes.values():
        if m.planet:
            planets_of.setdefault(m.stage, set()).add(m.planet)
        for g in (m.gear_a, m.gear_b):
            roles.setdefault(g, set()).add(m.role or m.name)
    for group, names in _groups(model).items():
        m0 = model.meshes[names[0]]
        A, B = model.bodies[m0.gear_a], model.bodies[m0.gear_b]
        if not (isinstance(A, Gear) and isinstance(B, Gear)):
            continue
        if A.internal or (not B.internal and B.teeth <= A.teeth):
            pin, whl = m0.gear_b, m0.gear_a
        else:
            pin, whl = m0.gear_a, m0.gear_b
        P, W = model.bodies[pin], model.bodies[whl]
        sp = _spec(model, pin, data, len(roles[pin]) > 1)
        sw = _spec(model, whl, data, len(roles[whl]) > 1)
        count = {g: sum(1 for n in names if g in (model.meshes[n].gear_a,
                                                  model.meshes[n].gear_b))
                 for g in (pin, whl)}
        yield {"group": group, "meshes": names, "names": (pin, whl),
               "labels": [_collapsed(x, m0.stage) if m0.planet else x for x in (pin, whl)],
               "specs": (sp, sw),
               "centre": float(np.linalg.norm(np.subtract(P.position, W.position)[:2])),
               "reduced_mass": _reduced_mass(model, pin, whl, count, sp, sw),
               "force_to_torque": math.cos(P.base_helix_angle) * P.base_radius,
               "speed_ratio": (_speed(model, pin), _speed(model, whl)),
               "count": (count[pin], count[whl]),
               "planets": len(planets_of.get(m0.stage, ())) if m0.planet else 0}


def rate_spectrum(model, spectrum: pd.DataFrame, *, meshes: list[str] | None = None,
                  hours: float | None = None, flank: str = "front") -> pd.DataFrame:
    """ISO 6336-6 ratings of mesh groups under a lifetime load spectrum of their flank force:
    ``spectrum`` with ``level_low``, ``level_high`` (N, the contact force on a flank, as the
    model's mesh forces and a run's force columns give it) and ``revolutions`` (the model
    input's, over the whole life), e.g. a fatigue study's lifetime load revolution
    distribution of the largest tooth force. ``meshes``: the groups to rate
    (``"stage1.sun_planet"``...; default every group), each with the same spectrum;
    ``hours`` the life the spectrum stands for (its input's mean speed, for Z_v; default the
    ``[rating]`` table's life). One row per gear: damages and equivalent safety factors
    (:mod:`gearmodal.rating.spectrum`), K_A = K_gamma = K_v = 1 (the dynamics in the loads)."""
    data = model.rating if model.rating is not None else rating_data.defaults()
    for col in ("level_low", "level_high", "revolutions"):
        if col not in spectrum:
            raise ModelError("spectrum", f"has no column {col!r} (level_low, level_high, "
                             "revolutions)")
    pairs = {p["group"]: p for p in _pairs(model, data)}
    chosen = list(pairs) if meshes is None else list(meshes)
    for g in chosen:
        if g not in pairs:
            raise ModelError("meshes", f"{g!r}: no such mesh group; groups: "
                             + ", ".join(pairs))
    life_h = data["life_h"] if hours is None else hours
    used = spectrum[spectrum.revolutions > 0]
    top = float(used.level_high.max()) if len(used) else 0.0
    mean_rpm = float(spectrum.revolutions.sum()) / (life_h * 60.0)
    rows = []
    for g in chosen:
        rows += runs.rate_flank(spectrum, pairs[g], flank, 1.0, mean_rpm, data, top)
    return pd.DataFrame(rows)


def _collapsed(name: str, stage: str) -> str:
    """``stage1.planet2`` -> ``stage1.planet`` (the planets rated together)."""
    prefix = f"{stage}.planet" if stage else "planet"
    return prefix if name.startswith(prefix) else name


def _reduced_mass(model, pin: str, whl: str, count: dict, sp: GearSpec,
                  sw: GearSpec) -> float:
    """The pair's reduced mass per face width, kg/m, from the model's inertias (ISO 6336-1,
    6.3.2: m* = J / (r_b^2 b)); a gear in several meshes of the group (a sun and its planets)
    shares its mass among them, a gear fixed to the housing (a ring) is infinitely heavy."""
    def m_star(name, spec):
        g = model.bodies[name]
        if spec.internal or g.speed_ratio == 0.0:
            return math.inf
        return g.inertia / (g.base_radius ** 2 * g.face_width) / count[name]
    m1, m2 = m_star(pin, sp), m_star(whl, sw)
    if math.isinf(m2):
        return m1
    if math.isinf(m1):
        return m2
    return m1 * m2 / (m1 + m2)


def _bearings(model, eq, data: dict, speed: float, life: float) -> pd.DataFrame:
    asm, _ = as_assembly(model)
    sp = asm.springs
    q = eq.q.reindex(asm.dof_names).to_numpy()
    f = (sp.W @ q) * sp.stiffness
    table = sp.to_frame()
    nu = operating_viscosity(data["lubricant_viscosity_40"], data["lubricant_viscosity_100"],
                             data["oil_temperature_C"])
    rows = []
    for pattern, spec in data["bearings"].items():
        for name in fnmatch.filter(model.bearings, pattern):
            el = model.bearings[name]
            sel = (table["element"] == name).to_numpy()
            comp = dict(zip(table.loc[sel, "contact"], f[sel], strict=True))
            radial = math.hypot(comp.get("x", 0.0), comp.get("y", 0.0))
            sa = model.bodies[el.a].speed_ratio
            sb = model.bodies[el.b].speed_ratio if el.b else 0.0
            n = abs(sa - sb) * speed
            field_ = f"rating.bearings.{pattern}"
            if "pitch_diameter" not in spec:
                raise ModelError(f"{field_}.pitch_diameter", "missing: ISO 281's rated "
                                 "viscosity needs the bearing's pitch diameter (m)")
            if radial <= 0.0 or n <= 0.0:
                raise ModelError(field_, f"{name} carries {radial:.3g} N at {n:.3g} rpm in the "
                                 "rating's equilibrium: nothing to rate")
            cu = spec.get("C_u", spec["C"] / 10.0)
            life_ = modified_life(spec["C"], radial, n, C_u=cu,
                                  pitch_diameter=spec["pitch_diameter"], kind=spec["kind"],
                                  contamination=data["contamination"], viscosity=nu,
                                  reliability=data["reliability"])
            rows.append({"bearing": name, "pattern": pattern, "label": spec.get("label", ""),
                         "radial_load_N": radial, "speed_rpm": n, "C_N": spec["C"],
                         "C_u_N": cu, "viscosity_mm2_s": nu, **life_,
                         "L10m_over_required": life_["L10m_h"] / life})
    return pd.DataFrame(rows)
