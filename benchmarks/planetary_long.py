"""A longer, event-dense planetary run: exact method against RK45 (RESULTS.md, work-precision).

Usage::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/planetary_long.py [--damping 3000]
        [--t-end 0.1] [--ripple 0.3] [--freq 20] [--rtol 1e-7 1e-8]

The stage of ``work_precision.py``'s ``planetary_clearance`` with mesh damping raised to a
realistic value (3000 N s/m is ~10 % of critical) and the torque rippled by
``1 + ripple sin(2 pi freq t)``, sampled every 40 us (linear in between, the same forcing for
every method). Prints: exact runs at two ``dt`` and their difference (the problem is regular
when they agree to rounding), event count, then RK45 at the given tolerances with their error
against the fine exact run and the CPU ratio. Process time, numba compile excluded.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
from work_precision import planetary_clearance_model  # noqa: E402

import gearmodal as gm  # noqa: E402


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--damping", type=float, default=3000.0)
    ap.add_argument("--t-end", type=float, default=0.1)
    ap.add_argument("--ripple", type=float, default=0.3)
    ap.add_argument("--freq", type=float, default=20.0)
    ap.add_argument("--rtol", type=float, nargs="*", default=[1e-7, 1e-8])
    a = ap.parse_args(argv)
    m = planetary_clearance_model()
    for mesh in m.meshes.values():
        mesh.damping = a.damping
    asm = gm.assemble(m)
    knot, T = 4e-5, a.t_end
    tk = np.arange(int(round(T / knot)) + 1) * knot
    rip = 1 + a.ripple * np.sin(2 * np.pi * a.freq * tk)
    loads = {"carrier.force_u": pd.Series(2e3 * rip, index=tk),
             "sun.force_u": pd.Series(-2e3 * rip, index=tk), "carrier.force_y": -3e3}
    gm.simulate(asm, 1e-3, dt=knot, loads={"carrier.force_y": -3e3})  # compile
    gm.simulate(asm, 1e-3, dt=knot, loads={"carrier.force_y": -3e3}, method="scipy",
                scipy_method="RK45", rtol=1e-6)
    runs = {}
    for prop in ("expm", "taylor"):  # the default last: its runs are the ones compared
        for dt in (knot, knot / 16):
            t0 = time.process_time()
            runs[dt] = gm.simulate(asm, T, dt=dt, loads=loads, propagator=prop)
            c = time.process_time() - t0
            st = runs[dt].stats
            print(f"exact ({prop}) dt={dt:.3g} s: cpu {c:.3f} s, events "
                  f"{len(runs[dt].events)}, exponentials {st.get('exponentials')}, pieces "
                  f"{st.get('pieces')}")
            if dt == knot:
                cpu_exact = c
    ref = runs[knot / 16].q.to_numpy()[::16]
    scale = np.abs(ref).max()
    print(f"exact dt vs dt/16: {np.abs(runs[knot].q.to_numpy() - ref).max() / scale:.2e}")
    vs = np.abs(runs[knot / 16].v.to_numpy()).max()
    n = ref.shape[1]
    for rt in a.rtol:
        t0 = time.process_time()
        r = gm.simulate(asm, T, dt=knot, loads=loads, method="scipy", scipy_method="RK45",
                        rtol=rt, atol=rt * np.r_[np.full(n, scale), np.full(n, vs)])
        c = time.process_time() - t0
        err = np.abs(r.q.to_numpy() - ref).max() / scale
        print(f"RK45 rtol={rt:g}: cpu {c:.3f} s, error {err:.2e}, events {len(r.events)}, "
              f"ratio to exact {c / cpu_exact:.1f}")


if __name__ == "__main__":
    main()
