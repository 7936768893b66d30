"""The mass-scaling rung against the full model over paired turbulence seeds.

Usage::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/rung_ensemble.py --out DIR [--seeds 10]

A single run of the rattling ``clearance`` gearbox cannot measure the rung's error: its peaks
move by several per cent under any change at rounding level (the output step, the order of a
sum), with the full model as with the rung. So this benchmark runs the double-contact study
(``studies/double_contact.py``: reference, clearance and clearance rotated 60 deg; 30 s each)
on ``--seeds`` paired seeds twice, on the rung (``top_frequency_hz`` = 500 Hz, the studies'
default) and on the full model, and gives per case and engineering quantity the geometric-mean
ratio rung / full over the seeds with its 95 % interval (:func:`gearmodal.paired.paired_ratio`,
(C1)) and the largest single-seed deviation. Writes ``DIR/rung_ensemble.csv`` (and the two
studies' stores under ``DIR``); the mean ``cpu_s`` per case of each run (two workers) is in the
last rows.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "studies"))

import pandas as pd  # noqa: E402

from gearmodal.paired import paired_ratio  # noqa: E402

QUANTITIES = ["max_front_force_N", "p99_tooth_force_N", "del_tooth_N",
              "max_planet_bearing_force_N", "p99_planet_bearing_force_N",
              "del_planet_bearing_N", "double_contact_time_s", "peak_load_sharing_factor"]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", required=True)
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--duration", type=float, default=30.0)
    args = ap.parse_args(argv)
    import double_contact

    out = Path(args.out)
    runs = {}
    for name, top in (("rung", 500.0), ("full", None)):
        double_contact.run(out / name, duration=args.duration, seeds=args.seeds, progress=False,
                           top_frequency_hz=top)
        runs[name] = pd.read_csv(out / name / "runs.csv")
    rows = []
    for case in ("reference", "clearance", "clearance_rot60"):
        a = runs["rung"][runs["rung"].case == case].set_index("seed").sort_index()
        b = runs["full"][runs["full"].case == case].set_index("seed").sort_index()
        for q in QUANTITIES:
            if (b[q] <= 0).any():  # (the reference gearbox has no double contact)
                continue
            r = paired_ratio(a[q], b[q])
            rows.append({"case": case, "quantity": q, "ratio": r["ratio"], "low": r["low"],
                         "high": r["high"], "max_seed_deviation": float((a[q] / b[q] - 1).abs()
                                                                        .max()),
                         "seeds": len(a)})
    for name, df in runs.items():
        for case, cpu in df.groupby("case").cpu_s.mean().items():
            rows.append({"case": case, "quantity": f"cpu_s ({name})", "ratio": cpu,
                         "seeds": args.seeds})
    table = pd.DataFrame(rows)
    table.to_csv(out / "rung_ensemble.csv", index=False)
    with pd.option_context("display.width", 160):
        print(table.to_string(index=False))
    return 0


if __name__ == "__main__":
    sys.exit(main())
