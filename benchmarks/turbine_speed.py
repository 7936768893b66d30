"""The coupled 600 kW turbine + gearbox: speed, its floor, and the error of the multirate knob.

Usage::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/turbine_speed.py [--quick] --out DIR \
        [--baseline PATH]

Writes ``DIR/turbine_speed.csv`` with one row per run: ``study``, ``gearbox``, ``setting``,
``cpu_s``, ``realtime_ratio`` (simulated s per CPU s, the turbulence box excluded),
``aero_s``, ``wind_s``, ``gearbox_s``, ``n_events``, ``pieces`` (Taylor pieces summed),
``pieces_per_s`` (per simulated second), ``us_per_piece`` (gearbox CPU per piece),
``root_searches``, the planet-1 tooth-force and planet-bearing peaks (``max_front_force_N``,
``max_planet_bearing_force_N``) and, for the accuracy and multirate studies, ``error``: the
largest relative difference of those peaks (accuracy) or of the planet-1 flank and
carrier-bearing forces (multirate, N) against the study's reference run.

Studies:

- ``speed``: the scene ``studies/scenes/600kw_turbine_10ms.toml`` (start-up in 10 m/s
  turbulent wind from 6 rpm through cut-in; ``--quick``: 10 s) with the ``reference`` gearbox
  and the ``clearance`` gearbox of the double-contact study, at the scene's settings.
- ``accuracy``: the same runs at half the output step: the peaks' relative change.
- ``baseline`` (with ``--baseline PATH``, a checkout of the commit before the exact turning
  geometry): the same two runs by that code at its converged refreeze setting (the scene file
  of that checkout: 0.125 deg at 1 ms), back to back in the same session; ``speedup`` is the
  ratio of its CPU time to this code's.
- ``rung``: the same two runs on the mass-scaling rung (``top_frequency_hz`` = 500 and
  400 Hz, :mod:`gearmodal.massscale`); ``error``: the largest relative difference of the four
  engineering quantities of the fidelity ladder (tooth and planet-bearing peaks, double
  contact time, peak load-sharing factor) from the full model's run (``speed``), ``speedup``
  its CPU ratio; at 500 Hz also the half step (``error`` against the rung's own run).
- ``multirate``: on the grid at 22.3 rpm, 2 s: the aerodynamic step 0.02 s with the loads
  interpolated / held / extrapolated, and 0.05 s, against aerodynamics at every gearbox step.

Process time on one core; the numba kernels are compiled (and cached) by a warm-up run first.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "studies"))

import pandas as pd  # noqa: E402

import gearmodal as gm  # noqa: E402
from gearmodal.auto import QUANTITIES, difference  # noqa: E402
from gearmodal.scene import load_scene  # noqa: E402
from gearmodal.studies import summarize  # noqa: E402
from gearmodal.turbine import simulate_drivetrain  # noqa: E402

SCENE = "studies/scenes/600kw_turbine_10ms.toml"
COLUMNS = ["stage1.ring_planet1.front", "stage1.sun_planet1.front", "stage1.carrier_bearing.x",
           "stage1.carrier_bearing.y"]
PEAKS = ("max_front_force_N", "max_planet_bearing_force_N")

#: one run of a checkout's code on the scene, in a subprocess (the baseline)
_CHILD = r"""
import json, sys, time
sys.path.insert(0, sys.argv[1])
from gearmodal.scene import load_scene
from gearmodal.studies import summarize
from gearmodal.turbine import simulate_drivetrain
over = json.loads(sys.argv[2])
sc = load_scene(sys.argv[1] + "/" + sys.argv[3], over)
simulate_drivetrain(sc.turbine, sc.wind, sc.model, 0.1, **sc.drivetrain)  # compile
t = time.process_time()
res = simulate_drivetrain(sc.turbine, sc.wind, sc.model, sc.t_end, dt=sc.dt, **sc.drivetrain)
cpu = time.process_time() - t
sm = summarize(res)
print(json.dumps({"cpu_s": cpu, "realtime_ratio": res.stats["realtime_ratio"],
                  "gearbox_s": res.stats["gearbox_s"], "n_events": res.stats["n_events"],
                  "max_front_force_N": sm["max_front_force_N"],
                  "max_planet_bearing_force_N": sm["max_planet_bearing_force_N"],
                  "settings": {k: v for k, v in sc.drivetrain.items()}}))
"""


def gearboxes() -> dict:
    from double_contact import CLEARANCE

    return {"reference": {}, "clearance": {"model.stages.0.carrier_bearing": CLEARANCE}}


def _row(study, gearbox, setting, res, cpu, t_sim, error=float("nan")):
    st = res.stats
    sm = summarize(res)
    pieces = st.get("pieces", 0)
    return {"study": study, "gearbox": gearbox, "setting": setting, "cpu_s": cpu,
            "realtime_ratio": st["realtime_ratio"], "aero_s": st["aero_s"],
            "wind_s": st["wind_s"], "gearbox_s": st["gearbox_s"], "n_events": st["n_events"],
            "pieces": pieces, "pieces_per_s": pieces / t_sim,
            "us_per_piece": 1e6 * st["gearbox_s"] / max(pieces, 1),
            "root_searches": st.get("root_searches", 0),
            **{k: sm[k] for k in PEAKS}, "error": error}


def _force_error(res, ref) -> float:
    a = res.gearbox.forces[COLUMNS]
    b = ref.gearbox.forces[COLUMNS].reindex(a.index, method="nearest")
    d = (a - b)[a.index > 0.5]
    return float(d.abs().to_numpy().max())


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--out", required=True)
    ap.add_argument("--baseline", help="checkout of the refreeze code to time back to back")
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    t_sim = 10.0 if args.quick else None
    rows = []

    def save():
        pd.DataFrame(rows).to_csv(out / "turbine_speed.csv", index=False)

    sc0 = load_scene(ROOT / SCENE)
    simulate_drivetrain(sc0.turbine, gm.turbine.Wind(mean_speed=10.0), sc0.model, 0.1,
                        rotor_speed0_rpm=22.3, connected=True)  # numba compile (cached)
    for name, over in gearboxes().items():
        over = {**over, **({"scene.t_end": t_sim} if t_sim else {})}
        sc = load_scene(ROOT / SCENE, over)
        runs = {}
        for label, dt in (("scene", sc.dt), ("half step", sc.dt / 2)):
            t = time.process_time()
            res = simulate_drivetrain(sc.turbine, sc.wind, sc.model, sc.t_end, dt=dt,
                                      **sc.drivetrain)
            runs[label] = (res, time.process_time() - t)
        res, cpu = runs["scene"]
        rows.append(_row("speed", name, f"{sc.t_end:g} s, dt {sc.dt:g} s", res, cpu, sc.t_end))
        a, b = summarize(res), summarize(runs["half step"][0])
        err = max(abs(a[k] - b[k]) / abs(b[k]) for k in PEAKS)
        rows.append(_row("accuracy", name, f"dt {sc.dt / 2:g} s (half step)",
                         runs["half step"][0], runs["half step"][1], sc.t_end, err))
        print(rows[-2], rows[-1], sep="\n", flush=True)
        save()
        full = summarize(res)
        for f_top in (500.0, 400.0):
            steps = (("scene", sc.dt), ("half step", sc.dt / 2)) if f_top == 500.0 else \
                (("scene", sc.dt),)
            got = {}
            for label, dt in steps:
                t = time.process_time()
                rr = simulate_drivetrain(sc.turbine, sc.wind, sc.model, sc.t_end, dt=dt,
                                         top_frequency_hz=f_top, **sc.drivetrain)
                got[label] = (rr, time.process_time() - t)
            rr, cpu_r = got["scene"]
            rows.append({**_row("rung", name, f"top_frequency_hz {f_top:g}", rr, cpu_r,
                                sc.t_end, difference(summarize(rr), full, QUANTITIES)),
                         "speedup": cpu / cpu_r})
            if "half step" in got:
                rh, cpu_h = got["half step"]
                a, b = summarize(rr), summarize(rh)
                rows.append(_row("rung", name, f"top_frequency_hz {f_top:g}, dt "
                                 f"{sc.dt / 2:g} s (half step)", rh, cpu_h, sc.t_end,
                                 max(abs(a[k] - b[k]) / abs(b[k]) for k in PEAKS)))
            print(*rows[-len(got):], sep="\n", flush=True)
            save()
        if args.baseline:
            base = Path(args.baseline).resolve()
            r = subprocess.run([sys.executable, "-c", _CHILD, str(base), json.dumps(over), SCENE],
                               capture_output=True, text=True, check=True,
                               env={**os.environ, "PYTHONPATH": str(base)})
            got = json.loads(r.stdout.strip().splitlines()[-1])
            rows.append({"study": "baseline", "gearbox": name,
                         "setting": "refreeze code at its scene settings "
                                    + json.dumps(got.pop("settings")),
                         **got, "speedup": got["cpu_s"] / cpu})
            print(rows[-1], flush=True)
            save()
    on = {"rotor_speed0_rpm": 22.3, "connected": True}
    t2 = 1.5 if args.quick else 2.0
    tb, gb = sc0.turbine, sc0.model
    wind = gm.turbine.Wind(**{**{k: v for k, v in vars(sc0.wind).items()
                                  if not k.startswith("_")}, "duration": 4.0})

    def run(**kw):
        t = time.process_time()
        res = simulate_drivetrain(tb, wind, gb, t2, **kw)
        return res, time.process_time() - t

    ref, cpu = run(dt=2e-3, aero_dt=2e-3, **on)
    rows.append(_row("multirate", "reference", "aero every gearbox step (2 ms)", ref, cpu, t2,
                     0.0))
    for hold, adt in (("interpolate", 0.02), ("hold", 0.02), ("linear", 0.02),
                      ("interpolate", 0.05)):
        res, cpu = run(dt=2e-3, aero_dt=adt, aero_hold=hold, **on)
        rows.append(_row("multirate", "reference", f"aero {adt:g} s {hold}", res, cpu, t2,
                         _force_error(res, ref)))
    save()
    print(pd.DataFrame(rows).to_string(index=False))
    return 0


if __name__ == "__main__":
    sys.exit(main())
