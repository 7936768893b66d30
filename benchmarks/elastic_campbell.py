"""What the elastic turbine costs a Campbell sweep (issue 56): the 5 MW on its detailed gearbox,
elastic (tower, blades in multi-blade coordinates, 27 coordinates more) against rigid (the
gearbox model alone, its rotor a rigid inertia).

Usage::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/elastic_campbell.py [--rounds 3]

Each case sweeps 27 speeds over 0-13 rpm with ``gm.campbell``, every mode (the full solve) and
the band of the 30 lowest (``n_modes=30``); the models are built before the clock starts (the
elastic turbine's build, pybmodes' two finite-element solves included, is timed apart). The
minimum process CPU of ``--rounds`` alternating runs, per speed, and the ratio elastic / rigid.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import gearmodal as gm
from gearmodal.turbine import nrel5mw

SPEEDS = np.linspace(0.0, 13.0, 27)


def _cpu(fn) -> float:
    t0 = time.process_time()
    fn()
    return time.process_time() - t0


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rounds", type=int, default=3)
    args = ap.parse_args(argv)
    gearbox = gm.load("studies/models/nrel5mw.toml")
    build = _cpu(lambda: nrel5mw.flexible(gearbox=gearbox))
    elastic = nrel5mw.flexible(gearbox=gearbox)
    models = {"rigid": gearbox, "elastic": elastic}
    print(f"elastic turbine built in {build:.2f} s CPU; "
          f"{gearbox.assemble().n} and {elastic.assemble().reduced().n} coordinates")
    for label, kw in (("every mode", {}), ("30 lowest", {"n_modes": 30})):
        best = {k: float("inf") for k in models}
        for m in models.values():
            gm.campbell(m, SPEEDS[:3], **kw)  # warm
        for _ in range(args.rounds):
            for k, m in models.items():
                best[k] = min(best[k], _cpu(lambda m=m, kw=kw: gm.campbell(m, SPEEDS, **kw)))
        per = {k: 1e3 * v / SPEEDS.size for k, v in best.items()}
        print(f"{label}: rigid {per['rigid']:.1f} ms, elastic {per['elastic']:.1f} ms per "
              f"speed, ratio {best['elastic'] / best['rigid']:.2f}")


if __name__ == "__main__":
    main()
