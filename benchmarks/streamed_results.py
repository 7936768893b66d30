"""Streamed results against the run held in memory: peak resident memory, process CPU time
against the integration's own, and the output folder, on the shipped 600 kW turbine scene run
through the command line.

Usage::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/streamed_results.py --out DIR [--quick]

Each case is one ``gearmodal simulate studies/scenes/600kw_turbine_10ms.toml --t-end T --out
... --quiet`` process (a fresh interpreter: its peak resident memory is its own), run one at a
time: ``streamed`` (the default, Parquet written while the run goes) for T = 60, 600 and
3 600 s, and ``held`` (``--format csv``: the whole run in memory, then CSV, as every run was
before) for T = 60 and 600 s. ``--quick``: 60 and 120 s. Writes ``DIR/streamed_results.csv``,
one row per case: ``t_end_s``, ``case``, ``peak_rss_mb`` (the child's ``ru_maxrss``),
``process_cpu_s`` (user + system), ``integration_cpu_s`` (``stats.json``'s ``cpu_s``: the
coupled loop, wind box included), ``cpu_ratio`` (process over integration), ``folder_mb``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import pandas as pd

ROOT = Path(__file__).resolve().parent.parent
SCENE = "studies/scenes/600kw_turbine_10ms.toml"
EXE = str(Path(sys.executable).parent / "gearmodal")


def folder_mb(d: Path) -> float:
    return sum(f.stat().st_size for f in d.rglob("*") if f.is_file()) / 1e6


def case(t_end: float, fmt: str) -> dict:
    """One CLI run in a child process; its rusage and what it wrote."""
    wrap = ("import resource, subprocess, sys; r = subprocess.run(sys.argv[1:]); "
            "u = resource.getrusage(resource.RUSAGE_CHILDREN); "
            "print(u.ru_maxrss, u.ru_utime + u.ru_stime); sys.exit(r.returncode)")
    with tempfile.TemporaryDirectory() as td:
        out = Path(td) / "run"
        r = subprocess.run([sys.executable, "-c", wrap, EXE, "simulate", SCENE, "--t-end",
                            str(t_end), "--out", str(out), "--quiet", "--format", fmt],
                           capture_output=True, text=True, cwd=ROOT,
                           env={**os.environ, "OPENBLAS_NUM_THREADS": "1"})
        if r.returncode:
            raise RuntimeError(r.stderr[-500:])
        rss, cpu = r.stdout.split()[-2:]
        stats = json.loads((out / "stats.json").read_text())
        return {"t_end_s": t_end, "case": "streamed" if fmt == "parquet" else "held",
                "peak_rss_mb": int(rss) / 1024.0, "process_cpu_s": float(cpu),
                "integration_cpu_s": stats["cpu_s"],
                "cpu_ratio": float(cpu) / stats["cpu_s"], "folder_mb": folder_mb(out)}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True)
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    plan = ([(60, "parquet"), (120, "parquet"), (60, "csv"), (120, "csv")] if args.quick else
            [(60, "parquet"), (600, "parquet"), (3600, "parquet"), (60, "csv"), (600, "csv")])
    rows = []
    for t_end, fmt in plan:
        rows.append(case(t_end, fmt))
        print(rows[-1], flush=True)
        pd.DataFrame(rows).to_csv(out / "streamed_results.csv", index=False)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
