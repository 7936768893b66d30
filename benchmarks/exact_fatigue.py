"""Exact turning points on the coupled 600 kW turbine: what they cost, and the DELs counted
from them against the DELs of the output rows at four output steps.

Usage::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/exact_fatigue.py --out DIR [--quick]

The double-contact study's two gearboxes (``reference``, ``clearance``) on the scene
``studies/scenes/600kw_turbine_10ms.toml`` (30 s, ``--quick`` 10 s) at the studies' rung
(``top_frequency_hz`` = 500), counted after ``T_SKIP`` s. Writes ``DIR/exact_fatigue.csv``, one
row per gearbox, output step and counting (``exact``: the run's turning points,
``fatigue.drivetrain_fatigue`` with ``dels_exact``; ``rows``: the same run's rows at that
step, the previous approach) with the four DELs and their relative difference from the exact
count at 1 ms; and ``DIR/exact_fatigue_cost.csv``: the gearbox integration's process time
(``stats["cpu_s"]``) with and without the turning points (best of three, alternating in one
process), the number of turning points and the size of their Parquet table.

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

import pandas as pd  # noqa: E402

from gearmodal.fatigue import WOEHLER, damage_equivalent_load, drivetrain_fatigue  # noqa: E402
from gearmodal.scene import load_scene  # noqa: E402
from gearmodal.turbine import simulate_drivetrain  # noqa: E402

SCENE = "studies/scenes/600kw_turbine_10ms.toml"
TOP = 500.0
T_SKIP = 5.0
DELS = ("del_tooth_N", "del_tooth_flank_N", "del_planet_bearing_N", "del_rotor_torque_Nm")


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
            size = sum(p.stat().st_size for p in Path(td).glob("turning_points.parquet*")
                       if p.is_file()) + sum(p.stat().st_size for p in
                                             Path(td).glob("turning_points.parquet/*"))
            n_tp = len(r.gearbox.turning_points)
        cost.append({"gearbox": name, "t_end_s": t_end, "cpu_without_s": cpu[False],
                     "cpu_with_s": cpu[True], "cost": cpu[True] / cpu[False] - 1.0,
                     "turning_points": n_tp, "table_bytes": size})
        runs = {}
        for dt in (5e-4, 1e-3, 2e-3, 4e-3):
            res = simulate_drivetrain(sc.turbine, sc.wind, sc.model, t_end, dt=dt, **kw)
            runs[dt] = (drivetrain_fatigue(res, bearing_C=2e6, planet_spin=2.5,
                                           t_skip=T_SKIP, tables=False), row_dels(res))
        ref = runs[1e-3][0]
        for dt, (ex, sampled) in runs.items():
            assert ex["dels_exact"]
            for label, vals in (("exact", ex), ("rows", {**sampled, "del_rotor_torque_Nm":
                                                         ex["del_rotor_torque_Nm"]})):
                rows.append({"gearbox": name, "dt_s": dt, "counting": label,
                             **{k: vals[k] for k in DELS},
                             **{f"{k}_vs_exact": vals[k] / ref[k] - 1.0 for k in DELS}})
    pd.DataFrame(rows).to_csv(out / "exact_fatigue.csv", index=False)
    pd.DataFrame(cost).to_csv(out / "exact_fatigue_cost.csv", index=False)
    print(pd.DataFrame(cost).to_string())
    print(pd.DataFrame(rows).to_string())
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
