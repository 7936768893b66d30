"""Exact turning points, level changes and load integrals on the coupled 600 kW turbine: what
they cost, and the DELs, planet-bearing P_eq and load spectra from them against those of the
output rows at four output steps.

Usage::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/exact_fatigue.py --out DIR [--quick]

The double-contact study's two gearboxes (``reference``, ``clearance``) on the scene
``studies/scenes/600kw_turbine_10ms.toml`` (30 s, ``--quick`` 10 s) at the studies' rung
(``top_frequency_hz`` = 500), counted after ``T_SKIP`` s. Writes ``DIR/exact_fatigue.csv``, one
row per gearbox, output step and counting (``exact``: the run's turning points, level changes
and load integrals, ``fatigue.drivetrain_fatigue`` with ``dels_exact`` and ``life_exact``;
``rows``: the same run's rows at that step, the previous approach) with the four DELs, the
planet bearing's P_eq (the most loaded bearing's) and the largest change of a tooth or bearing
spectrum bin (s), each against the exact one at 1 ms; and ``DIR/exact_fatigue_cost.csv``: the
gearbox integration's process time (``stats["cpu_s"]``) with and without the turning points
(best of three, alternating in one process), the number of turning points and level changes
and the size of their Parquet tables.

Process time on one core; the numba kernels are compiled (and cached) by a warm-up run first.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "studies"))

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from gearmodal.fatigue import (  # noqa: E402
    LEVELS,
    WOEHLER,
    damage_equivalent_load,
    drivetrain_fatigue,
    load_duration,
)
from gearmodal.scene import load_scene  # noqa: E402
from gearmodal.turbine import simulate_drivetrain  # noqa: E402

SCENE = "studies/scenes/600kw_turbine_10ms.toml"
TOP = 500.0
T_SKIP = 5.0
DELS = ("del_tooth_N", "del_tooth_flank_N", "del_planet_bearing_N", "del_rotor_torque_Nm")
SPIN = 2.5  # planet revolutions per rotor revolution (any: P_eq does not depend on it)


def row_dels(res) -> dict:
    """The three gearbox DELs of the output rows (what drivetrain_fatigue counted before the
    turning points), as drivetrain_fatigue's channels."""
    sim = res.gearbox
    f = sim.forces[sim.forces.index >= T_SKIP]
    stage = sim.meshes()
    flanks = [f"{m}.{s}" for m in stage if m.startswith(stage[0].split(".")[0] + ".")
              for s in ("front", "back") if f"{m}.{s}" in f.columns]
    bearings = sim.elements_of("planet_bearing")
    radial = {b: (f[f"{b}.x"] ** 2 + f[f"{b}.y"] ** 2) ** 0.5 for b in bearings}
    return {"del_tooth_N": max(damage_equivalent_load(f[c], WOEHLER["tooth_root"])
                               for c in flanks),
            "del_tooth_flank_N": max(damage_equivalent_load(f[c], WOEHLER["tooth_flank"])
                                     for c in flanks),
            "del_planet_bearing_N": max(damage_equivalent_load(r, WOEHLER["bearing"])
                                        for r in radial.values())}


def row_life(res) -> dict:
    """The most loaded planet bearing's P_eq (F3, exponent 10/3) and the tooth and bearing
    LDDs of the output rows: what drivetrain_fatigue computed before the exact level changes
    and load integrals (the rows weighted by their share of time and the turbine's rotor speed
    at the nearest aerodynamic step)."""
    sim, tur = res.gearbox, res.turbine.loads
    f = sim.forces[sim.forces.index >= T_SKIP]
    t = f.index.to_numpy()
    w = np.zeros_like(t)
    w[:-1] += np.diff(t) / 2
    w[1:] += np.diff(t) / 2
    n = w * np.abs(tur["rotor_speed_rpm"].reindex(f.index, method="nearest").to_numpy())
    p = WOEHLER["bearing"]
    peq = {b: float((np.sum(n * np.hypot(f[f"{b}.x"], f[f"{b}.y"]) ** p) / n.sum()) ** (1 / p))
           for b in sim.elements_of("planet_bearing")}
    worst = max(peq, key=peq.get)
    stage = sim.meshes()
    flanks = [f"{m}.{s}" for m in stage if m.startswith(stage[0].split(".")[0] + ".")
              for s in ("front", "back") if f"{m}.{s}" in f.columns]
    teeth = f[flanks].max(axis=1).clip(LEVELS["tooth_force_N"][0], LEVELS["tooth_force_N"][-1])
    radial = np.hypot(f[f"{worst}.x"], f[f"{worst}.y"]).clip(
        LEVELS["planet_bearing_force_N"][0], LEVELS["planet_bearing_force_N"][-1])
    return {"planet_bearing_peq_N": peq[worst],
            "tooth_ldd": load_duration(teeth, LEVELS["tooth_force_N"]).time_s.to_numpy(),
            "bearing_ldd": load_duration(radial, LEVELS["planet_bearing_force_N"])
            .time_s.to_numpy()}


def exact_life(row: dict) -> dict:
    """The same three from drivetrain_fatigue's row (exact where ``life_exact``)."""
    sp = row["tables"]["spectra"]
    return {"planet_bearing_peq_N": row["planet_bearing_peq_N"],
            "tooth_ldd": sp[sp.quantity == "tooth_force_N"].time_s.to_numpy(),
            "bearing_ldd": sp[sp.quantity == "planet_bearing_force_N"].time_s.to_numpy()}


def main(argv=None) -> int:
    from double_contact import CLEARANCE

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--out", required=True)
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    t_end = 10.0 if args.quick else 30.0
    rows, cost = [], []
    for name, over in (("reference", {}),
                       ("clearance", {"model.stages.0.carrier_bearing": CLEARANCE})):
        sc = load_scene(ROOT / SCENE, {**over, "scene.t_end": t_end})
        kw = {**sc.drivetrain, "top_frequency_hz": TOP}
        simulate_drivetrain(sc.turbine, sc.wind, sc.model, 0.5, dt=sc.dt, **kw)  # compile
        cpu = {}
        for _ in range(3):
            for on in (False, True):
                r = simulate_drivetrain(sc.turbine, sc.wind, sc.model, t_end, dt=sc.dt,
                                        turning_points=on, **kw)
                cpu[on] = min(cpu.get(on, float("inf")), r.gearbox.stats["cpu_s"])
        with tempfile.TemporaryDirectory() as td:
            r = simulate_drivetrain(sc.turbine, sc.wind, sc.model, t_end, dt=sc.dt, out=td,
                                    **kw)

            def size(name):
                return sum(p.stat().st_size for p in Path(td).glob(f"{name}.parquet*")
                           if p.is_file()) + sum(p.stat().st_size for p in
                                                 Path(td).glob(f"{name}.parquet/*"))
            tp_bytes, lc_bytes = size("turning_points"), size("level_changes")
            n_tp = len(r.gearbox.turning_points)
            n_lc = len(r.gearbox.level_changes)
        cost.append({"gearbox": name, "t_end_s": t_end, "cpu_without_s": cpu[False],
                     "cpu_with_s": cpu[True], "cost": cpu[True] / cpu[False] - 1.0,
                     "turning_points": n_tp, "table_bytes": tp_bytes,
                     "level_changes": n_lc, "level_table_bytes": lc_bytes})
        runs = {}
        for dt in (5e-4, 1e-3, 2e-3, 4e-3):
            res = simulate_drivetrain(sc.turbine, sc.wind, sc.model, t_end, dt=dt, **kw)
            row = drivetrain_fatigue(res, bearing_C=2e6, planet_spin=SPIN, t_skip=T_SKIP)
            runs[dt] = (row, row_dels(res), exact_life(row), row_life(res))
        ref, ref_life = runs[1e-3][0], runs[1e-3][2]
        for dt, (ex, sampled, life, rlife) in runs.items():
            assert ex["dels_exact"] and ex["life_exact"]
            for label, vals, lv in (("exact", ex, life),
                                    ("rows", {**sampled, "del_rotor_torque_Nm":
                                              ex["del_rotor_torque_Nm"]}, rlife)):
                rows.append({"gearbox": name, "dt_s": dt, "counting": label,
                             **{k: vals[k] for k in DELS},
                             **{f"{k}_vs_exact": vals[k] / ref[k] - 1.0 for k in DELS},
                             "planet_bearing_peq_N": lv["planet_bearing_peq_N"],
                             "peq_vs_exact": lv["planet_bearing_peq_N"]
                             / ref_life["planet_bearing_peq_N"] - 1.0,
                             "tooth_ldd_max_diff_s": float(np.abs(
                                 lv["tooth_ldd"] - ref_life["tooth_ldd"]).max()),
                             "bearing_ldd_max_diff_s": float(np.abs(
                                 lv["bearing_ldd"] - ref_life["bearing_ldd"]).max())})
    pd.DataFrame(rows).to_csv(out / "exact_fatigue.csv", index=False)
    pd.DataFrame(cost).to_csv(out / "exact_fatigue_cost.csv", index=False)
    print(pd.DataFrame(cost).to_string())
    print(pd.DataFrame(rows).to_string())
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
