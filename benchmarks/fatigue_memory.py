"""The fatigue metrics of one stored 600 s turbine case: the memory and CPU time of
``drivetrain_fatigue`` and of ``level_spectrum`` alone, with this code and with an earlier
checkout (``--base``), on the same stored run.

Usage::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/fatigue_memory.py --out DIR \\
        [--base CHECKOUT] [--run RUNDIR] [--quick]

The case is the fatigue study's (``studies/fatigue.py``): the clearance gearbox in the 600 kW
turbine at 18 m/s, seed 1, the study's rung (500 Hz) and 1 ms rows, run once with
``scene.simulate(out=RUNDIR)`` (streamed; ``--run``: reuse it; ``--quick``: 60 s). Each
measurement is a fresh process that loads the stored run, then makes one call: ``fatigue``
(``drivetrain_fatigue`` as the study calls it) or ``spectrum`` (``level_spectrum`` over the
first stage's twelve flanks from ``T_SKIP``). ``call_mb`` is the call's own peak memory: the
process's resident high-water mark during the call (reset before it through
``/proc/self/clear_refs``, Linux) less its resident memory before it (``rss_before_mb``);
``peak_rss_mb`` the process's peak over its life; ``call_cpu_s`` the call's process time.
``--base``: the same calls with the package of another checkout (first on ``sys.path``), the
previous approach. Writes ``DIR/fatigue_memory.csv``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

import pandas as pd

ROOT = Path(__file__).resolve().parent.parent

CHILD = r"""
import json, resource, sys, time
sys.path[:0] = [sys.argv[4], sys.argv[3]]  # the package measured first (not the cwd's)
from double_contact import BEARING_C, planet_spin
from fatigue import T_SKIP
from gearmodal.fatigue import drivetrain_fatigue, level_spectrum
from gearmodal.saved import load_run
spin = planet_spin()
res = load_run(sys.argv[1])
g = res.gearbox
flanks = [c for c in g.force_columns() if c.endswith((".front", ".back"))
          and g.stage_of(c.rsplit(".", 1)[0]) == "stage1"]
def status(key):
    for line in open("/proc/self/status"):
        if line.startswith(key):
            return int(line.split()[1]) / 1024  # MB
open("/proc/self/clear_refs", "w").write("5")  # the peak resident memory reset to now's
before = status("VmRSS:")
t0 = time.process_time()
if sys.argv[2] == "fatigue":
    drivetrain_fatigue(res, bearing_C=BEARING_C, planet_spin=spin, t_skip=T_SKIP)
else:
    level_spectrum(g, flanks, t_from=T_SKIP)
cpu = time.process_time() - t0
import gearmodal
assert gearmodal.__file__.startswith(sys.argv[4]), gearmodal.__file__
print(json.dumps({"rss_before_mb": before, "call_mb": status("VmHWM:") - before,
                  "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
                  "call_cpu_s": cpu}))
"""


def make_run(rundir: Path, t_end: float) -> None:
    sys.path.insert(0, str(ROOT / "studies"))
    from double_contact import CLEARANCE, ROWS_DT, SCENE
    from fatigue import SPEED0_RPM, turbulence_intensity

    from gearmodal.scene import load_scene

    over = {"scene.t_end": t_end, "wind.mean_speed": 18.0,
            "wind.turbulence_intensity": turbulence_intensity(18.0), "wind.seed": 1,
            "turbine.connected": True, "turbine.rotor_speed0_rpm": SPEED0_RPM,
            "scene.dt": ROWS_DT, "turbine.top_frequency_hz": 500.0,
            "model.stages.0.carrier_bearing": CLEARANCE}
    load_scene(SCENE, overrides=over).simulate(out=rundir)


def measure(rundir: Path, what: str, code: Path) -> dict:
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}
    r = subprocess.run([sys.executable, "-c", CHILD, str(rundir), what, str(ROOT / "studies"),
                        str(code)],
                       capture_output=True, text=True, cwd=ROOT, env=env)
    if r.returncode:
        raise RuntimeError(r.stderr[-800:])
    return json.loads(r.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", required=True)
    ap.add_argument("--base", help="a checkout of an earlier commit (the previous approach)")
    ap.add_argument("--run", help="the stored run (made there if missing)")
    ap.add_argument("--quick", action="store_true")
    a = ap.parse_args()
    t_end = 60.0 if a.quick else 600.0
    rundir = Path(a.run or Path(a.out) / "fatigue_memory_run")
    if not (rundir / "stats.json").exists():
        make_run(rundir, t_end)
    from gearmodal.saved import load_run

    n_levels = sum(len(c) for c in load_run(rundir).gearbox.level_chunks())
    codes = [("this", ROOT)] + ([("base", Path(a.base).resolve())] if a.base else [])
    rows = []
    for what in ("spectrum", "fatigue"):
        for name, code in codes:
            rows.append({"t_end_s": t_end, "call": what, "code": name,
                         "level_changes": n_levels, **measure(rundir, what, code)})
            print(rows[-1], flush=True)
    Path(a.out).mkdir(parents=True, exist_ok=True)
    pd.DataFrame(rows).to_csv(Path(a.out) / "fatigue_memory.csv", index=False)


if __name__ == "__main__":
    main()
