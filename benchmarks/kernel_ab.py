"""The exact kernel against an earlier checkout's, in one process, timed in alternation.

Usage::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/kernel_ab.py --base REV --out DIR \\
        [--pairs 300] [--turbine-pairs 20] [--cases planet,rattle,planet_peaks,turbine] \\
        [--work WORK] [--compile]

``REV``'s package (``git archive REV gearmodal``) is unpacked as ``gearmodal_base`` under
``WORK/base-REV`` (default: the system's temporary folder; kept, so that its numba cache is
reused by the next run) and imported beside this checkout's ``gearmodal``; every case is
built and run with each package's own API and the two runs are timed in alternation,
``--pairs`` times (the order swapped every pair), process CPU time per run. A ratio per
pair, this code's time over the base's: this VM's speed drifts by 10 % and more between
processes and within minutes, and only times taken side by side are worth comparing.
Reported: each side's minimum and median, the ratio of the minima and the median of the pairs'
ratios, and whether the two runs are the same to the bit (positions, contact states and
events, or the turbine's gearbox positions and forces).

Cases: ``rattle`` and ``planet`` are the work-precision problems (``work_precision.py``: the
gear rattle, 0.3 s, and the planetary stage with carrier clearance, 4 ms, at a quarter of their
output grid, exact method without peaks: the check's rows); ``planet_peaks`` the same with
``gm.simulate``'s default exact peaks; ``turbine`` 2 s of the 600 kW turbine scene at 22.3 rpm,
connected, its gearbox's CPU time (``stats["gearbox_s"]``, ``--turbine-pairs`` pairs).
``--compile``: also each side's compile cost, the process CPU of its first exact run (the
planetary stage, no peaks: the assembly and integrator kernels) in a fresh process with an
empty ``NUMBA_CACHE_DIR``, the two sides one after the other, twice (``DIR/kernel_ab_compile.csv``).
Writes ``DIR/kernel_ab.csv`` (one row per case) and prints it.
"""

from __future__ import annotations

import argparse
import hashlib
import importlib
import io
import os
import statistics
import subprocess
import sys
import tarfile
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd
import work_precision as wp

ROOT = Path(__file__).resolve().parent.parent
SCENE = ROOT / "studies/scenes/600kw_turbine_10ms.toml"


def base_package(rev: str, work: Path) -> str:
    """``rev``'s package unpacked as ``gearmodal_base`` under ``work``; returns its parent."""
    home = work / f"base-{rev}"
    pkg = home / "gearmodal_base"
    if not pkg.exists():
        data = subprocess.run(["git", "archive", rev, "gearmodal"], cwd=ROOT, check=True,
                              capture_output=True).stdout
        tmp = home / "unpack"
        with tarfile.open(fileobj=io.BytesIO(data)) as tar:
            tar.extractall(tmp, filter="data")
        (tmp / "gearmodal").rename(pkg)  # relative imports: the package works under any name
        tmp.rmdir()
    return str(home)


def digest(*arrays) -> str:
    h = hashlib.sha1()
    for a in arrays:
        h.update(np.ascontiguousarray(np.asarray(a, dtype=float)).tobytes())
    return h.hexdigest()[:12]


def problem(gm, name: str):
    """work_precision.py's problem ``name`` built with package ``gm``: (model, loads, t_end,
    dt), ``dt`` a quarter of its output grid."""
    spec = wp.problems(True)[name]
    return spec["model"](gm), spec["loads"](spec["t_end"]), spec["t_end"], spec["grid"] / 4


def case_run(gm, case: str):
    """(a function running the case once with package ``gm`` and returning (cpu s, digest))."""
    if case == "turbine":
        sc = importlib.import_module(gm.__name__ + ".scene").load_scene(
            SCENE, {"scene.t_end": 2.0, "turbine.rotor_speed0_rpm": 22.3,
                    "turbine.connected": True})
        sim = importlib.import_module(gm.__name__ + ".turbine").simulate_drivetrain

        def run():
            r = sim(sc.turbine, sc.wind, sc.model, sc.t_end, dt=sc.dt, **sc.drivetrain)
            return r.stats["gearbox_s"], digest(r.gearbox.q.to_numpy(),
                                                r.gearbox.forces.to_numpy())
        return run
    model, loads, t_end, dt = problem(gm, "gear_rattle" if case == "rattle"
                                      else "planetary_clearance")
    asm = model.assemble()
    opts = {} if case == "planet_peaks" else {"peak_bin": None}

    def run():
        t0 = time.process_time()
        s = gm.simulate(asm, t_end, dt=dt, loads=loads, method="exact", **opts)
        cpu = time.process_time() - t0
        return cpu, digest(s.q.to_numpy(), s.contact_state.to_numpy(),
                           s.events.select_dtypes("number").to_numpy())
    return run


_COMPILE = r"""
import sys, time
sys.path[:0] = [sys.argv[2], sys.argv[3]]
sys.path.insert(0, sys.argv[4])
import importlib
gm = importlib.import_module(sys.argv[1])
import kernel_ab
model, loads, t_end, dt = kernel_ab.problem(gm, "planetary_clearance")
asm = model.assemble()
t = time.process_time()
gm.simulate(asm, t_end, dt=dt, loads=loads, method="exact", peak_bin=None)
print(time.process_time() - t)
"""


def compile_seconds(package: str, home: str) -> float:
    """The first exact run's CPU time of ``package`` (found in ``home``) in a fresh process
    compiling every kernel (an empty numba cache)."""
    with tempfile.TemporaryDirectory() as cache:
        r = subprocess.run([sys.executable, "-c", _COMPILE, package, home, str(ROOT),
                            str(ROOT / "benchmarks")], capture_output=True, text=True,
                           check=True, env={**os.environ, "NUMBA_CACHE_DIR": cache})
    return float(r.stdout.split()[-1])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--base", required=True, help="git revision of the kernel to compare with")
    ap.add_argument("--out", required=True)
    ap.add_argument("--pairs", type=int, default=300)
    ap.add_argument("--turbine-pairs", type=int, default=20)
    ap.add_argument("--cases", default="planet,rattle,planet_peaks,turbine")
    ap.add_argument("--work", default=str(Path(tempfile.gettempdir()) / "gearmodal-kernel-ab"))
    ap.add_argument("--compile", action="store_true", help="also time a fresh compile")
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    home = base_package(args.base, Path(args.work))
    if args.compile:
        comp = [{"round": i, "side": side, "compile_run_cpu_s": compile_seconds(pkg, where)}
                for i in range(2) for side, pkg, where in (("this", "gearmodal", str(ROOT)),
                                                          ("base", "gearmodal_base", home))]
        pd.DataFrame(comp).to_csv(out / "kernel_ab_compile.csv", index=False)
        print(pd.DataFrame(comp).to_string(index=False), flush=True)
    sys.path.insert(0, home)
    sys.path.insert(0, str(ROOT))
    import gearmodal_base as base

    import gearmodal as this

    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT,
                            capture_output=True, text=True).stdout.strip()
    rows = []
    for case in args.cases.split(","):
        runs = {"this": case_run(this, case), "base": case_run(base, case)}
        same = {k: (f(), f())[1][1] for k, f in runs.items()}  # compiled, warm, its digest
        times = {"this": [], "base": []}
        pairs = args.turbine_pairs if case == "turbine" else args.pairs
        for i in range(pairs):
            for k in (("this", "base") if i % 2 == 0 else ("base", "this")):
                times[k].append(runs[k]()[0])
        ratios = [a / b for a, b in zip(times["this"], times["base"], strict=True)]
        rows.append({"case": case, "pairs": pairs,
                     "this_min_s": min(times["this"]), "base_min_s": min(times["base"]),
                     "this_median_s": statistics.median(times["this"]),
                     "base_median_s": statistics.median(times["base"]),
                     "ratio_of_minima": min(times["this"]) / min(times["base"]),
                     "median_pair_ratio": statistics.median(ratios),
                     "same_to_the_bit": same["this"] == same["base"],
                     "commit": commit, "base": args.base})
        pd.DataFrame(rows).to_csv(out / "kernel_ab.csv", index=False)
        print(pd.DataFrame(rows[-1:]).to_string(index=False), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
