"""Ratings under the exact load spectrum of a run (ISO 6336-6, ISO 281 with P_eq).

Each mesh group's spectrum is the exact load revolution distribution of its flank forces
(:func:`gearmodal.fatigue.level_spectrum` on the run's own level edges: the time and the
model input's revolutions in each force bin, summed over the exact solution's level changes,
independent of the output step), the largest planet's at every instant (conservative for the
group). A front and a back flank are rated apart: a back flank loaded by double contact is
the other flank of the same teeth. Cycles: the input's revolutions in a bin times the gear's
load cycles per input revolution (its speed against its frame, times its meshes in the group),
scaled from the run's duration to the required life (the run stands for the life). A planet
bearing's life takes its exact ISO 281 equivalent load (:func:`gearmodal.fatigue.
equivalent_loads`, p = 10/3 or 3) over its own revolutions.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..errors import ModelError
from ..fatigue import equivalent_loads, level_spectrum
from .iso281 import modified_life, operating_viscosity
from .iso6336 import rate_pair
from .spectrum import damage, equivalent_safety


def simulation_of(result):
    """The :class:`gearmodal.SimulationResult` of ``result`` (a turbine run's gearbox)."""
    sim = getattr(result, "gearbox", result)
    if not hasattr(sim, "level_chunks"):
        raise ModelError("result", f"a {type(result).__name__} is not a run of the gearbox "
                         "(gm.simulate, a turbine run)")
    return sim


def spectrum_rows(sim, pair: dict, names: list[str], *, life_h: float, t_from: float,
                  data: dict) -> list[dict]:
    """The spectrum ratings of one mesh group (``pair``: its gears' specs, speeds, counts and
    centre distance from :func:`gearmodal.rating.gearbox.rate`), one row per gear and flank."""
    t0, t1 = sim.time_span()
    duration = t1 - t_from
    if not duration > 0:
        raise ModelError("t_from", f"= {t_from!r}: must be before the run's end, {t1!r} s")
    scale = life_h * 3600.0 / duration
    columns = set(sim.force_columns())
    peaks = sim.peaks(t_from)
    rows = []
    for flank in ("front", "back"):
        channels = [f"{n}.{flank}" for n in names if f"{n}.{flank}" in columns]
        if not channels:
            continue
        top = float(peaks.loc[channels, "peak_force_N"].max())
        if not top > 0:
            continue  # a flank that never touched: nothing to rate
        spec = level_spectrum(sim, channels, t_from=t_from, edges="run")
        if spec is None:
            raise ModelError("result", "the run has no exact level changes (the exact "
                             "method's Taylor propagator with turning_points) to rate on")
        # the peak lies in the highest bin with time in it, unless the table clipped it (a
        # force beyond its top edge, or a run recorded on narrower edges)
        edge = float(spec.level_high[spec.time_s > 0].max())
        if top > edge * (1 + 1e-9):
            raise ModelError("result", f"{channels[0]!r} reaches {top:.4g} N, beyond the run's "
                             f"level table ({edge:.4g} N): its spectrum is clipped")
        n_in = float(spec.revolutions.sum()) / duration * 60.0
        rows += rate_flank(spec, pair, flank, scale, n_in, data, top)
    return rows


def rate_flank(spec: pd.DataFrame, pair: dict, flank: str, scale: float, n_in: float,
               data: dict, top: float) -> list[dict]:
    """One flank of a mesh group under ``spec`` (level bins with the input's revolutions,
    times ``scale`` for the life; ``n_in`` the input's mean speed, rpm; ``top`` the largest
    force): a row per gear."""
    used = spec[(spec.revolutions > 0) & (spec.level_high > 0)]
    sp, sw = pair["specs"]
    sig_h, sig_f, ref_h, ref_f = [], [], None, None
    for f in used.level_high.to_numpy():
        torque = f * pair["force_to_torque"]
        r = rate_pair(sp, sw, pair["centre"], torque, pair["speed_ratio"][0] * n_in,
                      cycles=(1e9, 1e9), application_factor=1.0, k_gamma=1.0,
                      accuracy_grade=data["accuracy_grade"],
                      lubricant_viscosity_40=data["lubricant_viscosity_40"],
                      tip_relief=data["tip_relief"], long_life=data["long_life"],
                      reduced_mass=pair["reduced_mass"], dynamic_factor=1.0)
        sig_h.append([g["sigma_H_MPa"] for g in r.gears])
        sig_f.append([g["sigma_F_MPa"] for g in r.gears])
        if ref_h is None:  # the permissible stresses without their life factors
            ref_h = [g["sigma_HG_MPa"] / g["Z_NT"] for g in r.gears]
            ref_f = [g["sigma_FG_MPa"] / g["Y_NT"] for g in r.gears]
    sig_h, sig_f = np.array(sig_h).reshape(-1, 2), np.array(sig_f).reshape(-1, 2)
    optimum = data["long_life"] == "optimum"
    out = []
    for k, member in enumerate(("pinion", "wheel")):
        per_rev = abs(pair["speed_ratio"][k]) * pair["count"][k]
        cyc = used.revolutions.to_numpy() * scale * per_rev
        row = {"mesh": pair["group"], "gear": pair["labels"][k], "member": member,
               "flank": flank, "peak_force_N": top, "life_cycles": float(cyc.sum())}
        if len(cyc):
            row.update(
                S_H_spectrum=equivalent_safety(sig_h[:, k], cyc, ref_h[k], "pitting", optimum),
                damage_H=damage(sig_h[:, k], cyc, ref_h[k], "pitting", optimum),
                S_F_spectrum=equivalent_safety(sig_f[:, k], cyc, ref_f[k], "bending", optimum),
                damage_F=damage(sig_f[:, k], cyc, ref_f[k], "bending", optimum))
        out.append(row)
    return out


def bearing_rows(sim, model, data: dict, *, t_from: float, life_h: float,
                 bearings: list[tuple[str, dict]]) -> list[dict]:
    """The ISO 281 lives of the rated bearings the run tracks (planet bearings' radial forces)
    from their exact equivalent loads."""
    out = []
    t1 = sim.time_span()[1]
    duration = t1 - t_from
    nu = operating_viscosity(data["lubricant_viscosity_40"], data["lubricant_viscosity_100"],
                             data["oil_temperature_C"])
    tables = {}
    for name, spec in bearings:
        p = 10.0 / 3.0 if spec["kind"] == "roller" else 3.0
        if p not in tables:
            tables[p] = equivalent_loads(sim, p, t_from=t_from)
        eq = tables[p]
        ch = f"{name}.radial"
        if eq is None or ch not in eq.index:
            continue
        el = model.bearings[name]
        sa = model.bodies[el.a].speed_ratio
        sb = model.bodies[el.b].speed_ratio if el.b else 0.0
        revs = float(eq.loc[ch, "revolutions"]) * abs(sa - sb)
        n = revs / duration * 60.0
        if not (n > 0 and eq.loc[ch, "equivalent_load_N"] > 0):
            continue
        life = modified_life(spec["C"], float(eq.loc[ch, "equivalent_load_N"]), n,
                             C_u=spec.get("C_u", spec["C"] / 10.0),
                             pitch_diameter=spec["pitch_diameter"], kind=spec["kind"],
                             contamination=data["contamination"], viscosity=nu,
                             reliability=data["reliability"])
        out.append({"bearing": name, "P_eq_N": float(eq.loc[ch, "equivalent_load_N"]),
                    "mean_speed_rpm": n, "L10m_h_spectrum": life["L10m_h"],
                    "a_ISO_spectrum": life["a_ISO"],
                    "L10m_spectrum_over_required": life["L10m_h"] / life_h})
    return out
