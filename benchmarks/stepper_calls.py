"""What a communication step costs: the stepping API (``gm.Stepper``) advanced in calls of 1, 5,
10 and 20 ms against one ``gm.simulate`` call of the same run.

Usage::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/stepper_calls.py --out DIR [--quick]

The run: the clearance planetary stage (``studies/models/planetary_clearance.toml``) at 600 rpm
for 1 s (``--quick``: 0.2 s), its carrier torque, the sun's reaction and a shaft-end force
varying smoothly, given every X ms (X = 1, 5, 10, 20): ``calls`` advances a stepper one call per
X ms with the values at the calls' ends (ramped), ``simulate`` is one ``gm.simulate`` call with
the same values as load Series on the same times (``k dt``), so that both are the same run to
the bit (checked: ``same_events``). ``calls_norecord``: the stepper with ``record=False`` (the
outputs only, as an FMU without a result directory). Each case runs ``--repeat`` times (default
3), the cases interleaved, after one warm-up (compilation); CPU time per case is the fastest
repeat. Writes ``DIR/stepper_calls.csv``: ``call_ms``, ``calls``, ``simulate_s``, ``calls_s``,
``norecord_s``, ``ratio`` (calls over simulate), ``us_per_call`` (the time above ``simulate``
per call), ``same_events`` (the event tables equal to the bit).
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import numpy as np
import pandas as pd

import gearmodal as gm

ROOT = Path(__file__).resolve().parent.parent
RATIO = 1 + 99 / 21
DT = 1e-4


def loads_at(t: np.ndarray) -> dict:
    tc = 2e5 * (1 + 0.5 * np.sin(2 * math.pi * 7 * t))
    return {"carrier.torque": tc, "sun.torque": -tc / RATIO,
            "carrier.force_x": 2e5 * np.cos(30 * t)}


def knots(t_end: float, call_ms: int) -> np.ndarray:
    """The calls' ends, ``k dt`` (as the stepper's knots are)."""
    m = round(call_ms * 1e-3 / DT)
    return np.arange(0, round(t_end / DT) + 1, m) * DT


def one_call(model, t_end: float, call_ms: int):
    tk = knots(t_end, call_ms)
    series = {k: pd.Series(v, index=tk) for k, v in loads_at(tk).items()}
    return gm.simulate(model, t_end, dt=DT, loads=series, speed_rpm=600.0)


def calls(model, t_end: float, call_ms: int, record: bool = True):
    tk = knots(t_end, call_ms)
    vals = loads_at(tk)
    st = gm.Stepper(model, dt=DT, speed_rpm=600.0, record=record,
                    loads={k: float(v[0]) for k, v in vals.items()},
                    outputs=["ring_planet1.front", "carrier_bearing.x"])
    for j in range(1, len(tk)):
        st.advance(tk[j], {k: float(v[j]) for k, v in vals.items()})
    return st.result() if record else None


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", required=True)
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args()
    model = gm.load(ROOT / "studies/models/planetary_clearance.toml")
    t_end = 0.2 if a.quick else 1.0
    one_call(model, 0.02, 1)  # compile
    calls(model, 0.02, 1)
    rows = []
    for c in (1, 5, 10, 20):
        best = {"simulate": math.inf, "calls": math.inf, "norecord": math.inf}
        same = None
        for _ in range(a.repeat):
            for case in best:
                t0 = time.process_time()
                if case == "simulate":
                    res = one_call(model, t_end, c)
                    ref = res.events
                else:
                    res = calls(model, t_end, c, record=case == "calls")
                best[case] = min(best[case], time.process_time() - t0)
                if case == "calls" and same is None:
                    same = bool(res.events.equals(ref))
        n = len(knots(t_end, c)) - 1
        rows.append({"call_ms": c, "calls": n, "simulate_s": round(best["simulate"], 4),
                     "calls_s": round(best["calls"], 4),
                     "norecord_s": round(best["norecord"], 4),
                     "ratio": round(best["calls"] / best["simulate"], 3),
                     "us_per_call": round((best["calls"] - best["simulate"]) / n * 1e6, 1),
                     "same_events": same})
    df = pd.DataFrame(rows)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    df.to_csv(out / "stepper_calls.csv", index=False)
    print(df.to_string(index=False))


if __name__ == "__main__":
    main()
