"""gm.modal at one speed against ROSS's Rotor.run_modal at an equal number of DOFs (issue 23).

gearmodal: the shipped 600 kW drivetrain (`studies/models/600kw.toml`, 35 DOF), `gm.modal`
at 22.1 rpm plus a small step per call (no call repeats a speed). ROSS: a steel shaft of 5
Timoshenko elements (6 nodes x 6 DOF = 36 DOF), a disk, two anisotropic bearings,
`rotor.run_modal(speed)` at 200 rad/s plus a step per call (ROSS caches a repeated speed).
ROSS runs in its own virtual environment (`--ross-python`: it pins plotly < 6, which the
project does not), in a subprocess; each side times the first call (compilation, caches) and
the median and minimum of ``--repeat`` further calls in its own process.

    python3 -m venv /tmp/rossenv && /tmp/rossenv/bin/pip install ross-rotordynamics "plotly<6"
    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/modal_speed.py \
        --ross-python /tmp/rossenv/bin/python

Writes benchmarks/results/modal_speed.csv (or ``--out``).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent

ROSS_SCRIPT = r"""
import json, sys, time, warnings
warnings.filterwarnings("ignore")
import numpy as np
import ross as rs
repeat = int(sys.argv[1])
steel = rs.Material(name="Steel", rho=7810, E=211e9, G_s=81.2e9)
shaft = [rs.ShaftElement(L=0.25, idl=0.0, odl=0.05, material=steel, shear_effects=True,
                         rotary_inertia=True, gyroscopic=True) for _ in range(5)]
disks = [rs.DiskElement.from_geometry(n=2, material=steel, width=0.07, i_d=0.05, o_d=0.28)]
bearings = [rs.BearingElement(n=0, kxx=1e6, kyy=8e5, cxx=10.0),
            rs.BearingElement(n=5, kxx=1e6, kyy=8e5, cxx=10.0)]
rotor = rs.Rotor(shaft, disks, bearings)
t0 = time.perf_counter(); rotor.run_modal(speed=200.0); first = time.perf_counter() - t0
ts = []
for k in range(repeat):
    t0 = time.perf_counter(); rotor.run_modal(speed=200.0 + 0.37 * (k + 1))
    ts.append(time.perf_counter() - t0)
print(json.dumps({"n_dofs": int(rotor.ndof), "first_s": first,
                  "median_s": float(np.median(ts)), "min_s": float(min(ts)),
                  "version": rs.__version__}))
"""


def gearmodal_times(repeat: int) -> dict:
    import gearmodal as gm

    model = gm.load(HERE.parent / "studies" / "models" / "600kw.toml")
    t0 = time.perf_counter()
    gm.modal(model, 22.1)
    first = time.perf_counter() - t0
    ts = []
    for k in range(repeat):
        t0 = time.perf_counter()
        gm.modal(model, 22.1 + 0.01 * (k + 1))
        ts.append(time.perf_counter() - t0)
    return {"n_dofs": model.n_dofs, "first_s": first, "median_s": float(np.median(ts)),
            "min_s": float(min(ts)), "version": gm.__version__}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--ross-python", required=True, help="python of a venv with ROSS")
    ap.add_argument("--repeat", type=int, default=30)
    ap.add_argument("--out", default=str(HERE / "results" / "modal_speed.csv"))
    a = ap.parse_args(argv)
    ross = json.loads(subprocess.run([a.ross_python, "-c", ROSS_SCRIPT, str(a.repeat)],
                                     capture_output=True, text=True, check=True)
                      .stdout.strip().splitlines()[-1])
    gmt = gearmodal_times(a.repeat)
    import pandas as pd

    table = pd.DataFrame([{"code": "gearmodal gm.modal", **gmt},
                          {"code": "ROSS run_modal", **ross}])
    ratio = gmt["median_s"] / ross["median_s"]
    print(table.to_string(index=False))
    print(f"ratio gearmodal / ROSS (median per call): {ratio:.2f}")
    Path(a.out).parent.mkdir(parents=True, exist_ok=True)
    table.assign(ratio_median=ratio).to_csv(a.out, index=False)
    return 0


if __name__ == "__main__":
    sys.exit(main())
