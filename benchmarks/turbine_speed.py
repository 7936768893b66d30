"""The coupled 600 kW turbine + gearbox: speed and the error of its multirate and refreeze knobs.

Usage::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/turbine_speed.py [--quick] --out DIR

Writes ``DIR/turbine_speed.csv`` with one row per run: ``study``, ``setting``, ``cpu_s``,
``realtime_ratio`` (simulated s per CPU s, the turbulence box excluded), ``aero_s``,
``wind_s``, ``wind_setup_s``, ``gearbox_s``, ``n_events``, ``n_freezes`` and, for the error
studies, ``error_N``: the largest difference after the first 0.5 s of the planet-1 ring and sun
front-flank forces and the carrier-bearing force against the study's reference run.

Studies:

- ``speed``: start-up in 10 m/s turbulent wind (TI 0.12, seed 1) from 6 rpm through cut-in,
  the scene ``studies/scenes/600kw_turbine_10ms.toml`` at its settings (``--quick``: 16 s).
- ``multirate``: on the grid at 22.3 rpm in the same wind, 2 s: aerodynamic step 0.02 s with
  the loads interpolated / held / extrapolated, and 0.05 s, against aerodynamics at every
  gearbox step (``aero_dt = dt``).
- ``refreeze``: the same run with the geometry refrozen every 5, 2, 1, 0.5 deg against 0.25
  deg at dt = 1 ms.

``realtime_ratio`` leaves out the one-off turbulence box (``wind_setup_s``, PyConTurb), built
in the ``speed`` run.

Process time on one core; the numba kernels are compiled (and cached) by a warm-up run first.
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

import pandas as pd  # noqa: E402

import gearmodal as gm  # noqa: E402
from gearmodal.scene import load_scene  # noqa: E402
from gearmodal.turbine import simulate_drivetrain  # noqa: E402

COLUMNS = ["stage1.ring_planet1.front", "stage1.sun_planet1.front", "stage1.carrier_bearing.x",
           "stage1.carrier_bearing.y"]


def _row(study, setting, res, cpu, error=float("nan")):
    st = res.stats
    return {"study": study, "setting": setting, "cpu_s": cpu,
            "realtime_ratio": st["realtime_ratio"], "aero_s": st["aero_s"],
            "wind_s": st["wind_s"], "wind_setup_s": st["wind_setup_s"],
            "gearbox_s": st["gearbox_s"], "n_events": st["n_events"],
            "n_freezes": st["n_freezes"], "error_N": error}


def _error(res, ref) -> float:
    a = res.gearbox.forces[COLUMNS]
    b = ref.gearbox.forces[COLUMNS].reindex(a.index, method="nearest")
    d = (a - b)[a.index > 0.5]
    return float(d.abs().to_numpy().max())


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--out", required=True)
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    scene = load_scene(ROOT / "studies/scenes/600kw_turbine_10ms.toml")
    tb, gb = scene.turbine, scene.model
    t_start = 16.0 if args.quick else scene.t_end
    fields = {k: v for k, v in vars(scene.wind).items() if not k.startswith("_")}
    wind = gm.turbine.Wind(**{**fields, "duration": max(t_start, 3.0) + 1.0})
    rows = []

    def run(t_end, **kw):
        t = time.process_time()
        res = simulate_drivetrain(tb, wind, gb, t_end, **kw)
        return res, time.process_time() - t

    simulate_drivetrain(tb, gm.turbine.Wind(mean_speed=10.0), gb, 0.1, rotor_speed0_rpm=22.3,
                        connected=True)  # numba compile (cached)
    res, cpu = run(t_start, dt=scene.dt, **scene.drivetrain)  # builds box
    rows.append(_row("speed", f"start-up {t_start:g} s, dt {scene.dt:g} s", res, cpu))
    print(rows[-1], flush=True)
    on = {"rotor_speed0_rpm": 22.3, "connected": True}
    t2 = 1.5 if args.quick else 2.0
    ref, cpu = run(t2, dt=2e-3, aero_dt=2e-3, **on)
    rows.append(_row("multirate", "aero every gearbox step (2 ms)", ref, cpu, 0.0))
    for hold, adt in (("interpolate", 0.02), ("hold", 0.02), ("linear", 0.02),
                      ("interpolate", 0.05)):
        res, cpu = run(t2, dt=2e-3, aero_dt=adt, aero_hold=hold, **on)
        rows.append(_row("multirate", f"aero {adt:g} s {hold}", res, cpu, _error(res, ref)))
        print(rows[-1], flush=True)
    ref, cpu = run(t2, dt=1e-3, aero_dt=0.02, refreeze_deg=0.25, **on)
    rows.append(_row("refreeze", "0.25 deg, dt 1 ms", ref, cpu, 0.0))
    for deg in (0.5, 1.0, 2.0, 5.0):
        res, cpu = run(t2, dt=1e-3, aero_dt=0.02, refreeze_deg=deg, **on)
        rows.append(_row("refreeze", f"{deg:g} deg, dt 1 ms", res, cpu, _error(res, ref)))
        print(rows[-1], flush=True)
    df = pd.DataFrame(rows)
    df.to_csv(out / "turbine_speed.csv", index=False)
    print(df.to_string(index=False))
    return 0


if __name__ == "__main__":
    sys.exit(main())
