"""Assembly and Campbell sweep: this checkout against a baseline checkout, in one session.

Usage::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/assembly_speed.py --baseline PATH \
        [--out benchmarks/results] [--repeat 7]

``PATH`` is a checkout of an earlier commit (``git worktree add /tmp/base <commit>``). Each
code runs in its own subprocess, alternating (baseline, this, baseline, this, ...), and each
measurement is the minimum over its repeats of the process time of:

- ``assemble_600kw``: ``model.assemble(azimuth)`` of ``studies/models/600kw.toml`` (72 DOF)
  at 20 azimuths;
- ``assemble_stage_polygon``: the same for ``studies/models/planetary_clearance.toml`` with a
  16-facet polygon carrier clearance (the most contact rows);
- ``campbell_600kw``: ``gm.campbell`` of the 600 kW drivetrain over 40 speeds.

Writes ``OUT/assembly_speed.csv``: ``case``, ``baseline_s``, ``this_s``, ``ratio``
(this / baseline; below 1 is faster), with the command and commits in ``assembly_speed.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
ROOT = Path(__file__).resolve().parent.parent

#: the measurement, run by each checkout's code (its path first on sys.path)
_WORK = r"""
import json, sys, time
sys.path.insert(0, sys.argv[1])
import numpy as np
import gearmodal as gm
root, repeat = sys.argv[2], int(sys.argv[3])
big = gm.load(root + "/studies/models/600kw.toml")
poly = gm.load(root + "/studies/models/planetary_clearance.toml", overrides={
    "planetary_stage.carrier_bearing.clearance_shape": "polygon"})
azimuths = np.linspace(0.0, 6.0, 20)
speeds = np.linspace(0.0, 30.0, 40)
cases = {
    "assemble_600kw": lambda: [big.assemble(azimuth=a) for a in azimuths],
    "assemble_stage_polygon": lambda: [poly.assemble(azimuth=a) for a in azimuths],
    "campbell_600kw": lambda: gm.campbell(big, speeds),
}
out = {}
for name, f in cases.items():
    f()  # warm: kernels compiled and cached
    best = float("inf")
    for _ in range(repeat):
        t0 = time.process_time()
        f()
        best = min(best, time.process_time() - t0)
    out[name] = best
print(json.dumps(out))
"""


def _run(code_path: Path, repeat: int) -> dict:
    res = subprocess.run([sys.executable, "-c", _WORK, str(code_path), str(ROOT), str(repeat)],
                         capture_output=True, text=True, check=True)
    return json.loads(res.stdout.strip().splitlines()[-1])


def _commit(path: Path) -> str:
    return subprocess.run(["git", "-C", str(path), "rev-parse", "--short", "HEAD"],
                          capture_output=True, text=True).stdout.strip()


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--baseline", required=True, type=Path)
    ap.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "results")
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--rounds", type=int, default=3)
    args = ap.parse_args(argv)
    import pandas as pd

    base, this = {}, {}
    for _ in range(args.rounds):  # alternate, so that a change in the machine's load hits both
        for store, path in ((base, args.baseline.resolve()), (this, ROOT)):
            for k, t in _run(path, args.repeat).items():
                store[k] = min(store.get(k, float("inf")), t)
    rows = [{"case": k, "baseline_s": base[k], "this_s": this[k], "ratio": this[k] / base[k]}
            for k in base]
    args.out.mkdir(parents=True, exist_ok=True)
    table = pd.DataFrame(rows)
    table.to_csv(args.out / "assembly_speed.csv", index=False, float_format="%.6g")
    (args.out / "assembly_speed.json").write_text(json.dumps({
        "command": "OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/assembly_speed.py "
                   + " ".join(argv if argv is not None else sys.argv[1:]),
        "this_commit": _commit(ROOT), "baseline_commit": _commit(args.baseline)}, indent=1))
    print(table.to_string(index=False))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
