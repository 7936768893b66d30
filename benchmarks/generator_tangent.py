"""The generator's tangent on the 600 kW turbine: what the re-basing knobs cost and change.

Usage::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/generator_tangent.py --out DIR \\
        [--duration 30] [--rounds 2] [--base REV] [--work WORK]

The induction generator enters the gearbox equations linearised (:class:`gearmodal.SpeedTorque`):
its torque taken at the generator's speed at each aerodynamic step's start, its slope at the
reference speed, which is re-based where the drivetrain's speed drifts by ``rebase_speed`` (1 %
by default) or its rigid rotation by ``rebase_angle`` (5e-4 rad). The runs: the double-contact
study's ``reference`` and ``clearance`` cases (its own scene overrides, ``duration`` s, 1 ms
rows, no turning points) at

- ``default``: ``rebase_speed`` 1e-2, ``rebase_angle`` 5e-4 rad;
- ``rebase 1e-3``: ``rebase_speed`` 1e-3;
- ``every step``: both 1e-6, a re-basing at every aerodynamic step: the reference of the
  errors;

and, with ``--base REV``, ``default`` and ``every step`` by that revision's package
(``kernel_ab.base_package``: the tangent's torque and slope both kept from one re-basing to the
next, before the torque was taken at every step). ``error``: the largest relative difference
of the study's four quantities (:data:`gearmodal.auto.QUANTITIES`) and the mean power from
this code's ``every step`` run (:func:`gearmodal.auto.difference`). This code's runs are timed
in alternation, ``--rounds`` times (process CPU, the minimum); ``cpu_ratio``: over
``default``'s; ``tangents``: the generator's tangents taken anew between re-basings (its
speed had left the last one's by ``rebase_speed``). The clearance gearbox rattles in its
clearance: any change of a run moves its single-run peaks by about 1-2 %
(:mod:`gearmodal.auto`), so its errors above that say nothing of the tangent.

Writes ``DIR/generator_tangent.csv`` and prints it.
"""

from __future__ import annotations

import argparse
import importlib
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "studies"))
sys.path.insert(0, str(ROOT / "benchmarks"))

import pandas as pd  # noqa: E402

from gearmodal.auto import QUANTITIES, difference  # noqa: E402

SETTINGS = {"default": {}, "rebase 1e-3": {"rebase_speed": 1e-3},
            "every step": {"rebase_speed": 1e-6, "rebase_angle": 1e-6}}
COMPARED = (*QUANTITIES, "mean_power_W")


def runner(package: str, case: str, duration: float):
    """A function ``run(setting) -> (cpu s, stats, summary)`` for the study's ``case``
    made with ``package`` (``gearmodal`` or ``gearmodal_base``)."""
    import double_contact as dc

    load_scene = importlib.import_module(package + ".scene").load_scene
    sim = importlib.import_module(package + ".turbine").simulate_drivetrain
    summarize = importlib.import_module(package + ".summary").summarize
    sc = load_scene(dc.SCENE, dc.cases(duration).loc[case].dropna().to_dict())
    sim(sc.turbine, sc.wind, sc.model, 0.1, **sc.drivetrain)  # the kernels compiled

    def run(setting: str):
        t = time.process_time()
        r = sim(sc.turbine, sc.wind, sc.model, sc.t_end, dt=sc.dt,
                **{**sc.drivetrain, **SETTINGS[setting]})
        return time.process_time() - t, r.stats, summarize(r)
    return run


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", required=True)
    ap.add_argument("--duration", type=float, default=30.0)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--base", default=None)
    ap.add_argument("--work", default=tempfile.gettempdir())
    a = ap.parse_args(argv)
    if a.base:
        from kernel_ab import base_package

        sys.path.insert(0, base_package(a.base, Path(a.work)))
    rows = []
    for case in ("reference", "clearance"):
        run = runner("gearmodal", case, a.duration)
        cpu = {s: [] for s in SETTINGS}
        got = {}
        for i in range(a.rounds):
            for s in (SETTINGS if i % 2 == 0 else reversed(list(SETTINGS))):
                c, n, summ = run(s)
                cpu[s].append(c)
                got[s] = (n, summ)
        ref = got["every step"][1]
        for s, (n, summ) in got.items():
            rows.append({"gearbox": case, "code": "this", "setting": s,
                         "n_rebases": n["n_rebases"], "tangents": n["speed_torque_tangents"],
                         "cpu_s": min(cpu[s]),
                         "cpu_ratio": min(cpu[s]) / min(cpu["default"]),
                         "error": difference(summ, ref, COMPARED),
                         **{q: summ[q] for q in COMPARED}})
        if a.base:
            base = runner("gearmodal_base", case, a.duration)
            for s in ("default", "every step"):
                c, n, summ = base(s)
                rows.append({"gearbox": case, "code": a.base, "setting": s,
                             "n_rebases": n["n_rebases"],
                             "tangents": n.get("speed_torque_tangents", float("nan")),
                             "cpu_s": c, "cpu_ratio": float("nan"),
                             "error": difference(summ, ref, COMPARED),
                             **{q: summ[q] for q in COMPARED}})
    df = pd.DataFrame(rows)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    df.to_csv(out / "generator_tangent.csv", index=False)
    with pd.option_context("display.width", 200, "display.max_columns", 20):
        print(df.to_string(index=False))
    return 0


if __name__ == "__main__":
    sys.exit(main())
