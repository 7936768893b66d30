"""What a case of a study reports: the paper's double-contact quantities of one simulation
(:func:`summarize`), used by :func:`gearmodal.sweep` and the fidelity ladder
(:mod:`gearmodal.auto`)."""

from __future__ import annotations

import math
from collections.abc import Iterable

import numpy as np

from .errors import ModelError

__all__ = ["SUMMARY_COLUMNS", "summarize"]

#: Columns of :func:`summarize` (the double-contact study's ``summary.csv``), in order.
SUMMARY_COLUMNS = ["max_front_force_N", "max_back_force_N", "double_contact_time_s",
                   "double_contact_two_planets_time_s", "max_planet_bearing_force_N",
                   "peak_load_sharing_factor", "max_front_force_sun_planet_N",
                   "max_back_force_sun_planet_N", "max_front_force_ring_planet_N",
                   "max_back_force_ring_planet_N", "k_gamma_sun_planet", "k_gamma_ring_planet",
                   "n_events"]


# -- what a case reports ----------------------------------------------------------------------
def _union_length(intervals: Iterable[tuple[float, float]]) -> float:
    """Total length of a union of intervals (s)."""
    total, end = 0.0, -math.inf
    for a, b in sorted(intervals):
        if b <= end:
            continue
        total += b - max(a, end)
        end = b
    return total


def summarize(result, *, planet: str = "planet1", tables: bool = False,
              loaded_fraction: float = 0.1, fatigue: dict | None = None) -> dict:
    """The quantities of the paper's double-contact study for one simulation.

    ``result`` is a :class:`~gearmodal.SimulationResult` or a turbine run's
    :class:`~gearmodal.turbine.DrivetrainResult`. Forces are N and are the maxima over the
    run of the first planetary stage: the exact maxima of the solution
    (:meth:`~gearmodal.SimulationResult.peaks`: the exact method, never below a sampled
    value, whatever the output step) where the run has them, else over the output times:

    - ``max_front_force_N`` / ``max_back_force_N``: the largest front / back flank force of
      ``planet`` on its sun-planet and ring-planet meshes (also given per mesh:
      ``max_front_force_sun_planet_N``, ...);
    - ``double_contact_time_s``: time during which at least one mesh of the stage has both
      flanks in contact (from the exact event times); ``double_contact_two_planets_time_s``:
      time with double contact on two or more planets at once;
    - ``max_planet_bearing_force_N``: the largest radial planet-bearing force
      ``sqrt(F_x^2 + F_y^2)`` of any planet;
    - ``peak_load_sharing_factor``: the largest ``N_planets * max share`` of the sun-planet
      load (:meth:`~gearmodal.SimulationResult.load_sharing`) over the times at which the
      stage carries at least ``loaded_fraction`` of its largest total load (shares of a
      nearly unloaded, rattling stage are meaningless);
    - ``k_gamma_sun_planet``, ``k_gamma_ring_planet``: the standards' load-sharing factor of
      the stage over the run (:meth:`~gearmodal.SimulationResult.k_gamma`: the largest
      planet's mean mesh load over the mean);
    - ``n_events``; for a turbine run also ``cut_in_time_s`` and ``mean_power_W`` (after
      cut-in).

    With ``fatigue`` (keyword arguments of :func:`gearmodal.fatigue.drivetrain_fatigue`: a
    turbine run's ``bearing_C``, ``planet_spin``, ``t_skip``) the dict also holds that
    function's DELs, 99th percentiles and bearing life (where a name is taken above, this
    function's value stays).

    With ``tables=True`` the dict also holds ``"tables"``: ``events`` (the event log) and
    ``forces`` (planet flank and bearing forces and the load-sharing factor against time), as
    stored by :func:`sweep`.
    """
    sim = result.gearbox
    f = sim.forces
    # the structure the builders recorded (SimulationResult.elements): the meshes of the
    # planet named within its stage, the stage of the first one
    meshes = {kind: [m for m in sim.meshes(f"{kind}_planet") if sim.planet_of(m) == planet]
              for kind in ("sun", "ring")}
    if not meshes["sun"] or not meshes["ring"]:
        raise ModelError("planet", f"= {planet!r}: the result has no sun-planet and ring-planet "
                         "meshes of that planet")
    name = sim.stage_of(meshes["sun"][0])
    stage = f"{name}." if name else ""
    out: dict = {}
    pk = sim.peaks()["peak_force_N"]
    for kind in ("sun", "ring"):
        m = meshes[kind][0]
        out[f"max_front_force_{kind}_planet_N"] = float(pk[f"{m}.front"])
        out[f"max_back_force_{kind}_planet_N"] = float(pk[f"{m}.back"])
    out["max_front_force_N"] = max(out["max_front_force_sun_planet_N"],
                                   out["max_front_force_ring_planet_N"])
    out["max_back_force_N"] = max(out["max_back_force_sun_planet_N"],
                                  out["max_back_force_ring_planet_N"])
    dc = sim.double_contact()
    # single episodes name their mesh ("stage1.ring_planet1"), simultaneous ones their stage
    # ("stage1 (several planets)", or "several planets" for a stage model)
    stage = dc.mesh.map({m: sim.stage_of(m) for m in dc.mesh.unique()})  # (a lookup per mesh)
    single = dc[(dc.n_planets == 1) & (stage == name)]
    multi = dc[(dc.n_planets >= 2)
               & (dc.mesh == (f"{name} (several planets)" if name else "several planets"))]
    out["double_contact_time_s"] = _union_length(zip(single.start, single.end, strict=True))
    out["double_contact_two_planets_time_s"] = _union_length(zip(multi.start, multi.end,
                                                                 strict=True))
    bearings = sorted(b for b in sim.elements_of("planet_bearing") if sim.stage_of(b) == name
                      and f"{b}.x" in f.columns)
    out["max_planet_bearing_force_N"] = (max(float(pk[f"{b}.radial"]) for b in bearings)
                                         if bearings else math.nan)
    ls = sim.load_sharing()
    fac = ls[f"{stage}factor"] if f"{stage}factor" in ls else ls.filter(like="factor").iloc[:, 0]
    sp = [f"{m}.front" for m in sim.meshes("sun_planet") if sim.stage_of(m) == name]
    total = sum(f[c] - f[c[:-len("front")] + "back"] for c in sp)
    loaded = np.abs(total) >= loaded_fraction * float(np.abs(total).max())
    out["peak_load_sharing_factor"] = float(fac[loaded].max())
    kg = sim.k_gamma()
    for role in ("sun_planet", "ring_planet"):
        row = kg[(kg.stage == name) & (kg.mesh == role)]
        out[f"k_gamma_{role}"] = float(row.k_gamma.iloc[0]) if len(row) else math.nan
    out["n_events"] = int(len(sim.events))
    if result.turbine is not None:
        cut = result.turbine.cut_in_time
        out["cut_in_time_s"] = float(cut) if cut is not None else math.nan
        ld = result.turbine.loads
        out["mean_power_W"] = float(ld.loc[ld.index >= cut, "power_W"].mean()) \
            if cut is not None else math.nan
    if fatigue is not None:
        from .fatigue import drivetrain_fatigue

        for key, val in drivetrain_fatigue(result, tables=False, **fatigue).items():
            out.setdefault(key, val)
    if tables:
        cols = [f"{m}.{side}" for k in ("sun", "ring") for m in meshes[k]
                for side in ("front", "back")]
        forces = f[cols].copy()
        for b in bearings:
            forces[f"{b}.radial"] = np.hypot(f[f"{b}.x"], f[f"{b}.y"])
        forces["load_sharing_factor"] = fac
        forces.index.name = "time"
        out["tables"] = {"events": sim.events.copy(), "forces": forces}
    return out
