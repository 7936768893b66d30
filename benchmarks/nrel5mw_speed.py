"""The coupled NREL 5 MW turbine on the 5 MW reference gearbox: speed and peak accuracy of the
fidelity rungs (issue 36, item 5).

Usage::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/nrel5mw_speed.py --out DIR [--quick]

The run: :func:`gearmodal.turbine.nrel5mw.simulate` (the BEM rotor, ROSCO every 12.5 ms, the
47-DOF gearbox ``studies/models/nrel5mw.toml`` by the exact method, its two planetary stages'
turning geometry included) in Kaimal turbulence at 12 m/s, IEC class B (turbulence intensity
0.17), seed 1, for ``T_END`` s from the controller's steady state.

- ``full``: the whole model (the reference).
- ``top_<f>Hz``: the mass-scaling rung (``top_frequency_hz``, :mod:`gearmodal.massscale`): the
  gearbox's modes above ``f`` slowed to it by added mass along them.

Per case: CPU seconds of the run (``stats["cpu_s"]``, everything from the coupling's set-up to
the result, the turbulence box excepted) and the real-time ratio (simulated over CPU seconds);
the exact peak of every mesh flank and bearing force channel (``SimulationResult.peaks``) and
its relative error against ``full``: the largest over the tooth flanks (``err_tooth``), over
the bearings (planet, carrier and parallel-stage bearings: ``err_bearing``) and over the
supports (the rings' and suns' supports, the shaft end's and the torque arms':
``err_support``); the mean rotor speed and electrical power. ``T_END`` 600 s (the IEC
10-minute run; ``--quick`` 30 s).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
import pandas as pd

from gearmodal.turbine import nrel5mw

TOPS_HZ = (500.0, 300.0, 200.0, 100.0, 50.0)


def run(t_end: float, top: float | None):
    w = nrel5mw.wind(12.0, turbulence_intensity=0.17, seed=1, duration=t_end + 5.0)
    return nrel5mw.simulate(w, t_end, dt=0.0125, top_frequency_hz=top)


def peaks(res) -> pd.Series:
    """The exact peak of every force channel, N, by channel."""
    p = res.gearbox.peaks()["peak_force_N"]
    return p[[c for c in p.index if c.endswith(".front") or c.endswith(".back")
              or c.endswith(".radial")]]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", required=True)
    ap.add_argument("--quick", action="store_true")
    a = ap.parse_args()
    t_end = 30.0 if a.quick else 600.0
    rows, ref = [], None
    for top in (None, *TOPS_HZ):
        t0 = time.process_time()
        res = run(t_end, top)
        wall = time.process_time() - t0
        pk = peaks(res)
        if ref is None:
            ref = pk
        rel = (pk - ref) / ref.where(ref > 0)
        tooth = [c for c in pk.index if c.endswith(".front") or c.endswith(".back")]
        bearing = [c for c in pk.index if c.endswith("bearing.radial")]
        support = [c for c in pk.index if c.endswith(".radial") and c not in bearing]
        ld = res.turbine.loads
        s = res.stats
        row = {"case": "full" if top is None else f"top_{top:g}Hz",
               "top_frequency_hz": top, "t_end_s": t_end, "cpu_s": s["cpu_s"],
               "realtime_ratio": s["realtime_ratio"], "process_cpu_s": wall,
               "pieces": s["pieces"], "max_tooth_N": float(pk[tooth].max()),
               "max_bearing_N": float(pk[bearing].max()),
               "err_tooth": float(np.nanmax(np.abs(rel[tooth]))),
               "err_bearing": float(np.nanmax(np.abs(rel[bearing]))),
               "err_support": float(np.nanmax(np.abs(rel[support]))),
               "rotor_speed_rpm": float(ld["rotor_speed_rpm"].mean()),
               "power_kW": float(ld["power_W"].mean() / 1e3)}
        rows.append(row)
        print(row, flush=True)
    df = pd.DataFrame(rows)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    df.to_csv(out / "nrel5mw_speed.csv", index=False)
    with pd.option_context("display.width", 200, "display.max_columns", 30):
        print(df.round(4).to_string(index=False))


if __name__ == "__main__":
    main()
