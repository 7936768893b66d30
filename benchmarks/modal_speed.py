"""gm.modal at one speed against ROSS's Rotor.run_modal at an equal number of DOFs (issue 23).

gearmodal: the shipped 600 kW drivetrain (`studies/models/600kw.toml`, 35 DOF), `gm.modal`
at 22.1 rpm plus a small step per call (no call repeats a speed; the model object is the same,
as in a user's session). ROSS: a steel shaft of 5 Timoshenko elements (6 nodes x 6 DOF = 36
DOF), a disk, two anisotropic bearings, `rotor.run_modal(speed)` at 200 rad/s plus a step per
call (ROSS caches a repeated speed). ROSS runs in its own virtual environment
(`--ross-python`: it pins plotly < 6, which the project does not). Every code runs in its own
subprocess, which times the first call (imports done; numba's cache, compilation and any
assembly caches in it) and the median and minimum of ``--repeat`` further calls; the
subprocesses alternate for ``--rounds`` rounds and each code's median over its rounds is
reported.

``--baseline PATH`` (a checkout of an earlier commit, e.g. ``git archive <commit> | tar -x -C
PATH``) times that code as well, and checks that this checkout's ``gm.modal`` gives the
baseline's results: frequencies, damping ratios, shapes, mode types, kinetic and strain
energy tables, geometry and contact state, on the 600 kW drivetrain (0, 22.1 and 30 rpm, and
22.1 rpm under a balanced rotor torque of 2.6e5 N m) and the shipped and example models at a
few speeds. Without it only the cache check runs: a model changed in place (a nested bearing
stiffness, a body's inertia, an element removed) gives exactly the modes of a fresh copy.

    python3 -m venv /tmp/rossenv && /tmp/rossenv/bin/pip install ross-rotordynamics "plotly<6"
    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/modal_speed.py \
        --ross-python /tmp/rossenv/bin/python [--baseline PATH]

Writes benchmarks/results/modal_speed.csv (or ``--out``): one row per code with
``ratio_to_ross`` (median per call, gearmodal / ROSS; below 1 is faster) and the commit.
"""

from __future__ import annotations

import argparse
import json
import os
import pickle
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
HERE = Path(__file__).resolve().parent
ROOT = HERE.parent

ROSS_SCRIPT = r"""
import json, sys, time, warnings
warnings.filterwarnings("ignore")
import numpy as np
import ross as rs
repeat = int(sys.argv[1])
steel = rs.Material(name="Steel", rho=7810, E=211e9, G_s=81.2e9)
shaft = [rs.ShaftElement(L=0.25, idl=0.0, odl=0.05, material=steel, shear_effects=True,
                         rotary_inertia=True, gyroscopic=True) for _ in range(5)]
disks = [rs.DiskElement.from_geometry(n=2, material=steel, width=0.07, i_d=0.05, o_d=0.28)]
bearings = [rs.BearingElement(n=0, kxx=1e6, kyy=8e5, cxx=10.0),
            rs.BearingElement(n=5, kxx=1e6, kyy=8e5, cxx=10.0)]
rotor = rs.Rotor(shaft, disks, bearings)
t0 = time.perf_counter(); rotor.run_modal(speed=200.0); first = time.perf_counter() - t0
ts = []
for k in range(repeat):
    t0 = time.perf_counter(); rotor.run_modal(speed=200.0 + 0.37 * (k + 1))
    ts.append(time.perf_counter() - t0)
print(json.dumps({"n_dofs": int(rotor.ndof), "first_s": first,
                  "median_s": float(np.median(ts)), "min_s": float(min(ts)),
                  "version": rs.__version__}))
"""

#: gm.modal timed with the code of the checkout sys.argv[1]
GM_SCRIPT = r"""
import json, sys, time
sys.path.insert(0, sys.argv[1])
import numpy as np
import gearmodal as gm
repeat = int(sys.argv[2])
model = gm.load(sys.argv[1] + "/studies/models/600kw.toml")
t0 = time.perf_counter(); gm.modal(model, 22.1); first = time.perf_counter() - t0
ts = []
for k in range(repeat):
    t0 = time.perf_counter(); gm.modal(model, 22.1 + 0.01 * (k + 1))
    ts.append(time.perf_counter() - t0)
print(json.dumps({"n_dofs": model.n_dofs, "first_s": first, "median_s": float(np.median(ts)),
                  "min_s": float(min(ts)), "version": gm.__version__}))
"""

#: the results compared between checkouts: sys.argv[1] the checkout, sys.argv[2] the output
CHECK_SCRIPT = r"""
import pickle, sys
sys.path.insert(0, sys.argv[1])
import numpy as np
import gearmodal as gm
ex = gm.examples
big = gm.load(sys.argv[1] + "/studies/models/600kw.toml")
torque = gm.balance(big, {"rotor.torque": 2.6e5}, on="generator.torque")
cases = [("600kw", big, s, None) for s in (0.0, 22.1, 30.0)]
cases.append(("600kw loaded", big, 22.1, torque))
for name in ("gear_pair", "planetary_clearance"):
    m = gm.load(sys.argv[1] + f"/studies/models/{name}.toml")
    cases += [(name, m, s, None) for s in (0.0, 20.0, 600.0)]
for label, m in (("example gear_pair planar", ex.gear_pair("planar")),
                 ("example gear_pair full helical", ex.gear_pair("full", helix_angle=0.3)),
                 ("example stage planar", ex.planetary_stage("planar")),
                 ("example stage full", ex.planetary_stage("full")),
                 ("example stage torsional", ex.planetary_stage("torsional"))):
    cases += [(label, m, s, None) for s in (0.0, 20.0, 600.0)]
cases.append(("600kw assembly", big.assemble(), 22.1, None))
out = []
for label, m, speed, loads in cases:
    for _ in range(2):  # twice: the second call may reuse what the first one kept
        r = gm.modal(m, speed, loads=loads)
    out.append((f"{label} at {speed} rpm" + (" loaded" if loads else ""), {
        "frequencies_hz": r.frequencies_hz, "damping_ratios": r.damping_ratios,
        "shapes": r.shapes, "mode_types": list(r.mode_types), "dof_names": list(r.dof_names),
        "kinetic_energy": r.kinetic_energy, "strain_energy": r.strain_energy,
        "geometry": r.geometry, "contact_state": r.contact_state}))
with open(sys.argv[2], "wb") as f:
    pickle.dump(out, f)
"""


def _run(cmd: list[str]) -> str:
    return subprocess.run(cmd, capture_output=True, text=True, check=True).stdout


def _last_json(text: str) -> dict:
    return json.loads(text.strip().splitlines()[-1])


def _commit(root: Path) -> str:
    try:
        out = _run(["git", "-C", str(root), "rev-parse", "--short", "HEAD"]).strip()
        dirty = _run(["git", "-C", str(root), "status", "--porcelain", "--untracked-files=no",
                      "--", "gearmodal"]).strip()
        return out + ("+changes" if dirty else "")
    except (subprocess.CalledProcessError, FileNotFoundError):
        return "?"


def _compare(a, b) -> str | None:
    """None when equal, else what differs (exact, then the largest difference)."""
    import pandas as pd

    if a is None or b is None:
        return None if a is None and b is None else "one is None"
    if isinstance(a, pd.DataFrame):
        try:
            pd.testing.assert_frame_equal(a, b, check_exact=True)
            return None
        except AssertionError as e:
            try:
                pd.testing.assert_frame_equal(a, b, check_exact=False, rtol=0, atol=1e-12)
            except AssertionError:
                return str(e).splitlines()[0]
            d = np.abs(a.to_numpy(float) - b.to_numpy(float)).max()
            return f"differs by at most {d:.1e} (abs; shares of 1)"
    if isinstance(a, list):
        return None if a == b else f"{a} != {b}"
    a, b = np.asarray(a), np.asarray(b)
    if a.shape != b.shape:
        return f"shape {a.shape} != {b.shape}"
    if np.array_equal(a, b):
        return None
    d = np.abs(a - b).max()
    return f"differs by at most {d:.1e} (largest {np.abs(a).max():.1e})"


def check_against(baseline: Path) -> list[str]:
    """Differences between the baseline's gm.modal results and this checkout's."""
    with tempfile.TemporaryDirectory() as tmp:
        res = {}
        for tag, root in (("baseline", baseline), ("this", ROOT)):
            path = Path(tmp) / f"{tag}.pkl"
            _run([sys.executable, "-c", CHECK_SCRIPT, str(root), str(path)])
            with open(path, "rb") as f:
                res[tag] = pickle.load(f)
    problems = []
    for (label, old), (label2, new) in zip(res["baseline"], res["this"], strict=True):
        assert label == label2
        for key in old:
            diff = _compare(old[key], new[key])
            if diff is not None:
                problems.append(f"{label}: {key} {diff}")
    return problems


def check_cache() -> list[str]:
    """A model changed in place gives the modes of a fresh copy, not of what was cached."""
    import gearmodal as gm

    problems = []
    m = gm.load(ROOT / "studies" / "models" / "600kw.toml")

    def scale_stiffness(m):
        m.bearings["suspension"].stiffness["x"] *= 2.0  # nested, in place

    def scale_inertia(m):
        m.bodies["generator"].inertia *= 1.5

    def remove(m):
        del m.bearings["shaft_bending"]

    for change in (scale_stiffness, scale_inertia, remove):
        before = gm.modal(m, 22.1)
        change(m)
        after, fresh = gm.modal(m, 22.1), gm.modal(m.copy(), 22.1)
        if np.array_equal(after.frequencies_hz, before.frequencies_hz):
            problems.append(f"{change.__name__}: the modes did not change")
        for key in ("frequencies_hz", "damping_ratios", "shapes"):
            if not np.array_equal(getattr(after, key), getattr(fresh, key)):
                problems.append(f"{change.__name__}: {key} differ from a fresh copy's")
        for key in ("kinetic_energy", "strain_energy"):
            if _compare(getattr(after, key), getattr(fresh, key)) is not None:
                problems.append(f"{change.__name__}: {key} differ from a fresh copy's")
    return problems


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--ross-python", required=True, help="python of a venv with ROSS")
    ap.add_argument("--baseline", help="a checkout of an earlier commit: timed and compared")
    ap.add_argument("--baseline-commit", help="the baseline's commit, if PATH is no git checkout")
    ap.add_argument("--repeat", type=int, default=30)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--out", default=str(HERE / "results" / "modal_speed.csv"))
    a = ap.parse_args(argv)
    import pandas as pd

    problems = check_cache()
    if a.baseline:
        problems += check_against(Path(a.baseline).resolve())
    print("results: " + ("identical to the baseline's" if a.baseline else "cache check")
          + (" (and the cache check)" if a.baseline else "")
          + (" FAILED:\n  " + "\n  ".join(problems) if problems else " passed"))

    codes = {"ROSS run_modal": [a.ross_python, "-c", ROSS_SCRIPT, str(a.repeat)],
             "gearmodal gm.modal": [sys.executable, "-c", GM_SCRIPT, str(ROOT), str(a.repeat)]}
    commits = {"ROSS run_modal": "", "gearmodal gm.modal": _commit(ROOT)}
    if a.baseline:
        name = "gearmodal gm.modal (baseline)"
        codes[name] = [sys.executable, "-c", GM_SCRIPT, str(Path(a.baseline).resolve()),
                       str(a.repeat)]
        commits[name] = a.baseline_commit or _commit(Path(a.baseline))
    runs = {k: [] for k in codes}
    for _ in range(a.rounds):
        for k, cmd in codes.items():
            runs[k].append(_last_json(_run(cmd)))
    rows = []
    for k, rs_ in runs.items():
        rows.append({"code": k, "commit": commits[k], "n_dofs": rs_[0]["n_dofs"],
                     "version": rs_[0]["version"],
                     "first_s": float(np.median([r["first_s"] for r in rs_])),
                     "median_s": float(np.median([r["median_s"] for r in rs_])),
                     "min_s": float(min(r["min_s"] for r in rs_))})
    table = pd.DataFrame(rows)
    table["ratio_to_ross"] = table.median_s / table.median_s[0]
    print(table.to_string(index=False))
    print("ratio gearmodal / ROSS (median per call): "
          + ", ".join(f"{r.code} {r.ratio_to_ross:.2f}" for r in table.iloc[1:].itertuples()))
    Path(a.out).parent.mkdir(parents=True, exist_ok=True)
    table.to_csv(a.out, index=False)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
