"""gm.modal and gm.campbell against ROSS on one rotor built in both tools, by size (issue 39).

The rotor (as ``modal_speed.py``'s ROSS rotor, generalised to N elements): a solid steel shaft
(rho 7810 kg/m^3, E 211 GPa, G 81.2 GPa), 0.05 m across and 1.25 m long; a steel disk
(width 0.07 m, bore 0.05 m, outside 0.28 m) at the node nearest 40 % of the length; two
anisotropic bearings (kxx 1e6, kyy 8e5 N/m, cxx = cyy 10 N s/m) at the end nodes. A size is
given as DOF = 6 (N + 1): 36, 72, 204, 402 are N = 5, 11, 33, 66.

ROSS: N ``rs.ShaftElement`` (Timoshenko: shear, rotary inertia, gyroscopic; Cowper's shear
coefficient), ``rs.DiskElement.from_geometry``, two ``rs.BearingElement``. It runs in its own
virtual environment (``--ross-python``: it pins plotly < 6, which the project does not).

gearmodal: N + 1 ``gm.RigidBody`` at the ``full`` DOF level (x, y, z, rx, ry, theta) on the
shaft axis (global z) at the node positions, all spinning with the input (``speed_ratio`` 1,
so their gyroscopic terms are the shaft's and the disk's at that speed), joined by springs:

* the shaft: one ``gm.Bearing`` between consecutive bodies, acting at the element's midpoint
  (``at = (0, 0, L/2)`` from the first body), with x, y ``12 E I / (L^3 (1 + phi))``, rx, ry
  ``E I / L``, z ``E A / L`` and theta ``G J / L``; ``phi = 12 E I / (kappa G A L^2)`` with
  Cowper's ``kappa = 6 (1 + nu) / (7 + 6 nu)`` = 0.886 (``nu = E / 2G - 1``), as ROSS. A
  Timoshenko element's bending energy in one plane is exactly
  ``12 E I / (L^3 (1 + phi)) (v2 - v1 - L/2 (t1 + t2))^2 / 2 + E I / L (t2 - t1)^2 / 2``: the
  translation of the two bodies' points at the midpoint against each other and their relative
  tilt, which is what a bearing at the midpoint measures. The assembled stiffness (and
  damping) matrix equals ROSS's to the last bit (checked once, N = 5);
* the masses are lumped: each body carries half of each adjacent element's mass ``rho A L``,
  polar inertia ``rho J L`` and the section's rotary inertia ``rho I L``, with no term for
  the half-element's length (of the lumpings tried, adding a rigid half-element's
  ``(m/2) (L/2)^2 / 3`` about the node, its own ``(m/2) (L/2)^2 / 12`` or ``(m/2) L^2 / 78``
  made the largest of the six differences from ROSS's larger, at every size), plus the disk's
  mass, ``Ip = m (D^2 + d^2) / 8`` and ``Id = Ip / 2 + m w^2 / 12`` (ROSS's values) at its
  node. The lumped mass is what separates the models: at 36 DOF the third pair is 2 % and the
  fifth 7.5 % low (the first pair 0.2 %), at 204 DOF all six are within 0.2 %;
* the end bodies sit on ``gm.Bearing`` to the ground with x 1e6, y 8e5 N/m and 10 N s/m.

Nothing else is added: the shaft springs hold every body's tilt, and the rotor keeps an axial
and a torsional rigid-body mode in both tools (ROSS's bearings have no kzz and nothing holds
the torsion), which the frequency comparison leaves out (frequencies below 0.1 Hz). With the
stiffness equal, the models differ in the mass (lumped against consistent) and so in the
shaft's gyroscopic matrix; the first six non-rigid frequencies at rest and at the top speed are
compared per size (``max_rel_df_0``, ``max_rel_df_top``).

Timed, per size, each tool in its own subprocess (CPU seconds of the process,
``time.process_time``, one BLAS thread; imports and model building excluded):

* ``modal``: one speed per call, 200 rad/s plus 0.37 rad/s per call (ROSS caches a repeated
  speed): ``gm.modal(model, rpm)`` (all modes: it has no band) against ROSS
  ``rotor.run_modal(speed)`` (``default``: ``num_modes=12``, ARPACK shift-invert, 6 modes
  reported), ``run_modal(speed, num_modes=32)`` (``band32``: ROSS's count of 32, ARPACK
  ``k = 64`` eigenvalues, 16 modes reported) and ``run_modal(speed, num_modes=2 * DOF)``
  (``all``: the state size, which ARPACK cannot do, so scipy's ``eigs`` solves it densely; every
  mode with its shape);
* ``campbell``: ``--speeds`` speeds from 0 to ``--top-speed`` rad/s (the same in rpm for
  gearmodal), shifted by 0.013 rad/s per call; CPU per call divided by the number of speeds:
  ``gm.campbell(model, rpm)`` (and ``n_modes=32``: ``band32``) against ROSS
  ``rotor.run_campbell(speeds, frequencies=f)`` with
  ``f`` = 6 (``default``; ROSS then calls ``run_modal(num_modes=16)`` per speed), 14
  (``band32``: ``run_modal(num_modes=32)`` per speed) and DOF - 2 (``all``:
  ``run_modal(num_modes=2 * DOF)`` per speed, every mode tracked).

Each analysis first makes one call that is timed on its own (``first_s``; for ``modal`` the
first call of the process, for ROSS with its numba compilation, for gearmodal with the
assembly and numba's cache; for ``campbell`` a sweep over the first 3 speeds, per speed, made
after the modal calls), then calls until at least ``--min-calls`` (campbell: 1) are made and
they took ``--budget`` CPU seconds, at most ``--repeat`` (campbell: ``--repeat-campbell``);
their median and minimum are kept. ROSS's ``run_modal`` cache is cleared after each call,
outside the timing (it keeps up to 128 results, with every mode's shape for ``all``). The
subprocesses alternate over ``--rounds`` rounds (ROSS first in even rounds, gearmodal first in
odd ones), one at a time; each row's median is the median of its rounds' medians.

    python3 -m venv /tmp/rossenv && /tmp/rossenv/bin/pip install ross-rotordynamics "plotly<6"
    .venv/bin/python benchmarks/modal_size.py --ross-python /tmp/rossenv/bin/python [--quick]
    .venv/bin/python benchmarks/modal_size.py --profile 204,402   # where gearmodal's time goes

Writes benchmarks/results/modal_size.csv (or ``--out``): one row per tool, variant, DOF and
analysis with ``median_s`` (per call, or per speed for campbell), ``ratio_to_ross_all``
(gearmodal's matching variant: all modes) and ``ratio_to_ross_default`` (below 1 is faster),
the tool's first six non-rigid frequencies at rest (``f1_hz``..``f6_hz``) and the largest
relative difference of gearmodal's from ROSS's at rest and at the top speed. ``--quick``:
36 and 72 DOF, 2 rounds, few calls.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent

RPM = 2.0 * math.pi / 60.0  # rad/s per rpm
# the rotor, SI units
RHO, E, G = 7810.0, 211e9, 81.2e9  # steel: kg/m^3, Pa, Pa
SHAFT_OD, SHAFT_LENGTH = 0.05, 1.25  # m
DISK_WIDTH, DISK_ID, DISK_OD, DISK_AT = 0.07, 0.05, 0.28, 0.4  # m, m, m, share of the length
KXX, KYY, CXX = 1e6, 8e5, 10.0  # bearings: N/m, N/m, N s/m (cyy = cxx)
MODAL_SPEED, MODAL_STEP = 200.0, 0.37  # rad/s: the first modal call's speed, and the step
CAMPBELL_STEP, WARMUP_SPEEDS = 0.013, 3  # rad/s per Campbell call; speeds of its first call
RIGID_HZ = 0.1  # frequencies below this are the rigid-body modes
VARIANTS = {"ross": ("default", "band32", "all"), "gearmodal": ("all", "band32")}
#: modes of gearmodal's band (ROSS's num_modes of its band32)
BAND = 32


def n_elements(dofs: int) -> int:
    if dofs % 6 or dofs < 12:
        raise SystemExit(f"size {dofs}: DOF must be 6 (N + 1) for N >= 1 shaft elements")
    return dofs // 6 - 1


def disk_node(n: int) -> int:
    """The node nearest DISK_AT of the length."""
    return int(round(DISK_AT * n))


def disk_inertia() -> tuple[float, float, float]:
    """Mass, polar and diametral inertia of the disk (ROSS's DiskElement.from_geometry)."""
    m = RHO * math.pi / 4 * (DISK_OD**2 - DISK_ID**2) * DISK_WIDTH
    ip = m / 8 * (DISK_OD**2 + DISK_ID**2)
    return m, ip, ip / 2 + m * DISK_WIDTH**2 / 12


# -- the two models ---------------------------------------------------------------------------
def ross_rotor(n: int):
    import ross as rs

    steel = rs.Material(name="Steel", rho=RHO, E=E, G_s=G)
    shaft = [rs.ShaftElement(L=SHAFT_LENGTH / n, idl=0.0, odl=SHAFT_OD, material=steel,
                             shear_effects=True, rotary_inertia=True, gyroscopic=True)
             for _ in range(n)]
    disks = [rs.DiskElement.from_geometry(n=disk_node(n), material=steel, width=DISK_WIDTH,
                                          i_d=DISK_ID, o_d=DISK_OD)]
    bearings = [rs.BearingElement(n=0, kxx=KXX, kyy=KYY, cxx=CXX),
                rs.BearingElement(n=n, kxx=KXX, kyy=KYY, cxx=CXX)]
    return rs.Rotor(shaft, disks, bearings)


def gearmodal_rotor(n: int):
    """The same rotor as N + 1 full-DOF rigid bodies joined by the Timoshenko springs (module
    docstring)."""
    import gearmodal as gm

    L = SHAFT_LENGTH / n
    A, I = math.pi * SHAFT_OD**2 / 4, math.pi * SHAFT_OD**4 / 64
    J = 2 * I
    nu = E / (2 * G) - 1
    kappa = 6 * (1 + nu) / (7 + 6 * nu)  # Cowper, solid circle (ROSS's default)
    phi = 12 * E * I / (kappa * G * A * L**2)
    shaft = {"x": 12 * E * I / (L**3 * (1 + phi)), "y": 12 * E * I / (L**3 * (1 + phi)),
             "z": E * A / L, "rx": E * I / L, "ry": E * I / L, "theta": G * J / L}
    half = RHO * L / 2  # per unit of section property: half an element
    dm, dip, did = disk_inertia()
    model = gm.Model(f"shaft_{n}", input="n0")
    for i in range(n + 1):
        k = 1 if i in (0, n) else 2  # half-elements at this node
        mass, ip, idia = k * half * A, k * half * J, k * half * I
        if i == disk_node(n):
            mass, ip, idia = mass + dm, ip + dip, idia + did
        model.add(gm.RigidBody(name=f"n{i}", mass=mass, inertia=ip, inertia_diametral=idia,
                               dofs="full", position=(0.0, 0.0, i * L), speed_ratio=1.0))
    for i in range(n):
        model.add(gm.Bearing(f"e{i}", f"n{i}", f"n{i + 1}", stiffness=dict(shaft),
                             at=(0.0, 0.0, L / 2)))
    for i in (0, n):
        model.add(gm.Bearing(f"bearing{i}", f"n{i}", None, stiffness={"x": KXX, "y": KYY},
                             damping={"x": CXX, "y": CXX}))
    return model


# -- the children: one tool at one size ------------------------------------------------------
def time_calls(call, min_calls: int, max_calls: int, budget_s: float, after=None) -> dict:
    """CPU seconds per unit of ``call(k)`` (it returns its units: 1 call, or its speeds):
    ``k = 0`` timed alone (``first_s``), then ``k = 1, 2, ...`` until ``min_calls`` are made
    and they took ``budget_s``, at most ``max_calls``. ``after()`` runs untimed after each."""
    c0 = time.process_time()
    units = call(0)
    first = (time.process_time() - c0) / units
    if after is not None:
        after()
    ts, spent = [], 0.0
    while len(ts) < max_calls:
        c0 = time.process_time()
        units = call(len(ts) + 1)
        dt = time.process_time() - c0
        ts.append(dt / units)
        spent += dt
        if after is not None:
            after()
        if len(ts) >= min_calls and spent >= budget_s:
            break
    return {"first_s": first, "median_s": float(np.median(ts)), "min_s": float(min(ts)),
            "calls": len(ts)}


def _campbell_speeds(a, k: int) -> np.ndarray:
    """Speeds of the k-th Campbell call, rad/s (k = 0: the first WARMUP_SPEEDS of them)."""
    s = np.linspace(0.0, a.top_speed, a.speeds) + CAMPBELL_STEP * k
    return s[:WARMUP_SPEEDS] if k == 0 else s


def _first_six(f_hz) -> list[float]:
    f = np.sort(np.asarray(f_hz, dtype=float))
    return f[f > RIGID_HZ][:6].tolist()


def child_ross(a) -> dict:
    c0 = time.process_time()
    import warnings

    warnings.filterwarnings("ignore")  # ARPACK's k >= N - 1 fallback, REFPROP's absence
    import ross as rs

    import_s = time.process_time() - c0
    n = n_elements(a.size)
    rotor = ross_rotor(n)
    ndof = int(rotor.ndof)
    modes = {"default": 12, "band32": 32, "all": 2 * ndof}
    freqs = {"default": 6, "band32": 14, "all": ndof - 2}
    clear = rotor.run_modal.cache_clear
    out = []
    for v in VARIANTS["ross"]:
        def modal(k, nm=modes[v]):
            rotor.run_modal(MODAL_SPEED + MODAL_STEP * k, num_modes=nm)
            return 1

        out.append({"variant": v, "analysis": "modal", "n_speeds": 1,
                    **time_calls(modal, a.min_calls, a.repeat, a.budget, clear)})
    for v in VARIANTS["ross"]:
        def camp(k, f=freqs[v]):
            s = _campbell_speeds(a, k)
            rotor.run_campbell(s, frequencies=f)
            return s.size

        out.append({"variant": v, "analysis": "campbell", "n_speeds": a.speeds,
                    **time_calls(camp, 1, a.repeat_campbell, a.budget, clear)})
    f = {}
    for label, speed in (("0", 0.0), ("top", a.top_speed)):
        ev = rotor.run_modal(speed, num_modes=2 * ndof).evalues
        f[label] = _first_six(np.abs(ev[ev.imag > 0]) / (2 * math.pi))
    return {"tool": "ross", "version": rs.__version__, "n_dofs": ndof, "import_s": import_s,
            "results": out, "freqs": f}


def child_gearmodal(a) -> dict:
    c0 = time.process_time()
    sys.path.insert(0, str(ROOT))
    import gearmodal as gm

    import_s = time.process_time() - c0
    model = gearmodal_rotor(n_elements(a.size))

    def modal(k, nm=None):
        gm.modal(model, (MODAL_SPEED + MODAL_STEP * k) / RPM, n_modes=nm)
        return 1

    def camp(k, nm=None):
        s = _campbell_speeds(a, k)
        gm.campbell(model, s / RPM, n_modes=nm)
        return s.size

    out = []
    for variant, nm in (("all", None), ("band32", BAND)):
        out += [{"variant": variant, "analysis": "modal", "n_speeds": 1,
                 **time_calls(lambda k, nm=nm: modal(k, nm), a.min_calls, a.repeat,
                              a.budget)},
                {"variant": variant, "analysis": "campbell", "n_speeds": a.speeds,
                 **time_calls(lambda k, nm=nm: camp(k, nm), 1, a.repeat_campbell,
                              a.budget)}]
    f = {label: _first_six(gm.modal(model, speed / RPM).frequencies_hz)
         for label, speed in (("0", 0.0), ("top", a.top_speed))}
    # the band's error: its modes against the full solve's, at rest and at the top speed
    # (rigid modes, below 0.1 Hz, against the highest frequency)
    band_err = 0.0
    for speed in (0.0, a.top_speed):
        fa = gm.modal(model, speed / RPM).frequencies_hz[:BAND]
        fb = gm.modal(model, speed / RPM, n_modes=BAND).frequencies_hz
        band_err = max(band_err, float(np.max(np.abs(fb - fa) / np.maximum(fa, fa.max()
                                                                             * (fa < 0.1)))))
    for r in out:
        r["band_max_rel_df"] = band_err if r["variant"] == "band32" else 0.0
    return {"tool": "gearmodal", "version": gm.__version__, "n_dofs": model.n_dofs,
            "import_s": import_s, "results": out, "freqs": f}


def child_profile(a) -> None:
    """cProfile of gm.modal (``--repeat`` calls) and one gm.campbell sweep at ``a.size``:
    the top 10 functions by cumulative and by internal time."""
    import cProfile
    import pstats

    sys.path.insert(0, str(ROOT))
    import gearmodal as gm

    model = gearmodal_rotor(n_elements(a.size))
    gm.modal(model, MODAL_SPEED / RPM)  # assembly, numba's cache
    gm.campbell(model, _campbell_speeds(a, 0) / RPM)
    calls = {"gm.modal": lambda: [gm.modal(model, (MODAL_SPEED + MODAL_STEP * k) / RPM)
                                  for k in range(1, a.repeat + 1)],
             "gm.campbell": lambda: gm.campbell(model, _campbell_speeds(a, 1) / RPM)}
    for name, fn in calls.items():
        prof = cProfile.Profile(timer=time.process_time)
        prof.enable()
        fn()
        prof.disable()
        what = f"{a.repeat} calls" if name == "gm.modal" else f"{a.speeds} speeds"
        print(f"\n=== {name}, {a.size} DOF, {what} ===")
        for key in ("cumulative", "tottime"):
            top = 12 if key == "cumulative" else 10  # the first two are the lambda here
            pstats.Stats(prof).strip_dirs().sort_stats(key).print_stats(top)


# -- the parent -------------------------------------------------------------------------------
def _run(cmd: list[str], env=None) -> str:
    r = subprocess.run(cmd, capture_output=True, text=True, env=env, cwd=ROOT)
    if r.returncode:
        raise SystemExit(f"{' '.join(cmd[:4])} ... failed ({r.returncode}):\n{r.stderr[-3000:]}")
    return r.stdout


def _last_json(text: str) -> dict:
    return json.loads(text.strip().splitlines()[-1])


def _commit(root: Path) -> str:
    try:
        out = subprocess.run(["git", "-C", str(root), "rev-parse", "--short", "HEAD"],
                             capture_output=True, text=True, check=True).stdout.strip()
        dirty = subprocess.run(["git", "-C", str(root), "status", "--porcelain",
                                "--untracked-files=no", "--", "gearmodal"],
                               capture_output=True, text=True, check=True).stdout.strip()
        return out + ("+changes" if dirty else "")
    except (subprocess.CalledProcessError, FileNotFoundError):
        return "?"


def _child_args(a) -> list[str]:
    return ["--speeds", str(a.speeds), "--top-speed", repr(a.top_speed),
            "--repeat", str(a.repeat), "--repeat-campbell", str(a.repeat_campbell),
            "--min-calls", str(a.min_calls), "--budget", repr(a.budget)]


def _rel(f, ref) -> float:
    f, ref = np.asarray(f), np.asarray(ref)
    k = min(f.size, ref.size)
    return float(np.max(np.abs(f[:k] / ref[:k] - 1))) if k else math.nan


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--ross-python", help="python of a venv with ROSS (required unless "
                                          "--profile)")
    ap.add_argument("--sizes", default=None, help="DOF, comma-separated, each 6 (N + 1) "
                                                  "(default 36,72,204,402; --quick 36,72)")
    ap.add_argument("--quick", action="store_true", help="smoke run: 36 and 72 DOF, 2 rounds")
    ap.add_argument("--rounds", type=int, default=None, help="default 3 (--quick 2)")
    ap.add_argument("--repeat", type=int, default=None,
                    help="most timed modal calls per process (default 30, --quick 5)")
    ap.add_argument("--repeat-campbell", type=int, default=None,
                    help="most timed Campbell sweeps per process (default 5, --quick 2)")
    ap.add_argument("--min-calls", type=int, default=3, help="fewest timed modal calls")
    ap.add_argument("--budget", type=float, default=None,
                    help="CPU seconds after which the timed calls stop (default 2, --quick 0.3)")
    ap.add_argument("--speeds", type=int, default=20, help="speeds per Campbell sweep")
    ap.add_argument("--top-speed", type=float, default=1000.0, help="rad/s")
    ap.add_argument("--blas-threads", type=int, default=1)
    ap.add_argument("--out", default=str(HERE / "results" / "modal_size.csv"))
    ap.add_argument("--profile", metavar="SIZES",
                    help="instead: cProfile gearmodal at these DOF (comma-separated)")
    ap.add_argument("--child", choices=("ross", "gearmodal", "profile"), help=argparse.SUPPRESS)
    ap.add_argument("--size", type=int, help=argparse.SUPPRESS)
    a = ap.parse_args(argv)
    profile_calls = a.repeat or 10
    a.rounds = a.rounds or (2 if a.quick else 3)
    a.repeat = a.repeat or (5 if a.quick else 30)
    a.repeat_campbell = a.repeat_campbell or (2 if a.quick else 5)
    a.budget = a.budget if a.budget is not None else (0.3 if a.quick else 2.0)
    if a.child == "ross":
        print(json.dumps(child_ross(a)))
        return 0
    if a.child == "gearmodal":
        print(json.dumps(child_gearmodal(a)))
        return 0
    if a.child == "profile":
        child_profile(a)
        return 0

    env = dict(os.environ)
    for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        env[var] = str(a.blas_threads)
    if a.profile:
        for size in (int(s) for s in a.profile.split(",")):
            n_elements(size)
            print(_run([sys.executable, __file__, "--child", "profile", "--size", str(size),
                        "--repeat", str(profile_calls),
                        "--speeds", str(a.speeds), "--top-speed", repr(a.top_speed)], env))
        return 0
    if not a.ross_python:
        ap.error("--ross-python is required")
    sizes = [int(s) for s in (a.sizes or ("36,72" if a.quick else "36,72,204,402")).split(",")]
    for s in sizes:
        n_elements(s)
    pythons = {"ross": a.ross_python, "gearmodal": sys.executable}
    runs = {(tool, s): [] for s in sizes for tool in pythons}
    t_start = time.perf_counter()
    for r in range(a.rounds):
        for s in sizes:
            for tool in (("ross", "gearmodal") if r % 2 == 0 else ("gearmodal", "ross")):
                t0 = time.perf_counter()
                res = _last_json(_run([pythons[tool], __file__, "--child", tool, "--size",
                                       str(s), *_child_args(a)], env))
                runs[tool, s].append(res)
                print(f"round {r + 1}/{a.rounds}: {tool} {s} DOF, "
                      f"{time.perf_counter() - t0:.0f} s wall", flush=True)
    wall = time.perf_counter() - t_start

    import pandas as pd

    commit = _commit(ROOT)
    rows = []
    for (tool, s), rs_ in runs.items():
        f = rs_[0]["freqs"]
        agree = {"max_rel_df_0": _rel(runs["gearmodal", s][0]["freqs"]["0"],
                                      runs["ross", s][0]["freqs"]["0"]),
                 "max_rel_df_top": _rel(runs["gearmodal", s][0]["freqs"]["top"],
                                        runs["ross", s][0]["freqs"]["top"])}
        for j, res in enumerate(rs_[0]["results"]):
            per = [r["results"][j] for r in rs_]
            rows.append({
                "tool": tool, "variant": res["variant"], "n_dofs": rs_[0]["n_dofs"],
                "analysis": res["analysis"], "n_speeds": res["n_speeds"],
                "calls": int(np.median([p["calls"] for p in per])),
                "first_s": float(np.median([p["first_s"] for p in per])),
                "band_max_rel_df": float(res.get("band_max_rel_df", 0.0)),
                "median_s": float(np.median([p["median_s"] for p in per])),
                "min_s": float(min(p["min_s"] for p in per)),
                **{f"f{k + 1}_hz": (f["0"][k] if k < len(f["0"]) else math.nan)
                   for k in range(6)},
                **agree,
                "import_s": float(np.median([r["import_s"] for r in rs_])),
                "version": rs_[0]["version"], "commit": commit if tool == "gearmodal" else "",
                "rounds": a.rounds, "blas_threads": a.blas_threads})
    table = pd.DataFrame(rows)
    ross = table[table.tool == "ross"].set_index(["n_dofs", "analysis", "variant"]).median_s
    key = list(zip(table.n_dofs, table.analysis, strict=True))
    for v in ("all", "default"):
        table[f"ratio_to_ross_{v}"] = table.median_s.to_numpy() / np.array(
            [ross.get((d, an, v), math.nan) for d, an in key])
    table = table.sort_values(["analysis", "n_dofs", "tool", "variant"],
                              key=lambda c: c.map({"modal": 0, "campbell": 1}) if
                              c.name == "analysis" else c, kind="stable")
    cols = ["tool", "variant", "n_dofs", "analysis", "n_speeds", "calls", "first_s",
            "median_s", "min_s", "ratio_to_ross_all", "ratio_to_ross_default"]
    table = table[cols + [c for c in table.columns if c not in cols]]
    Path(a.out).parent.mkdir(parents=True, exist_ok=True)
    table.to_csv(a.out, index=False)

    _print(table)
    print(f"\n{a.rounds} rounds, {wall / 60:.1f} min wall; gearmodal {commit}, ROSS "
          f"{table[table.tool == 'ross'].version.iloc[0]}; BLAS threads {a.blas_threads}; "
          f"wrote {a.out}")
    return 0


def _print(table) -> None:
    show = table.copy()
    show["tool"] = show.tool + " " + show.variant
    show["first [s]"] = show.first_s.map(lambda x: f"{x:.3g}")
    for c in ("median_s", "min_s"):
        show[c.replace("_s", " [ms]")] = (1e3 * show[c]).map(lambda x: f"{x:.3g}")
    for c in ("ratio_to_ross_all", "ratio_to_ross_default"):
        show[c.replace("ratio_to_", "/ ")] = show[c].map(lambda x: f"{x:.3g}")
    cols = ["n_dofs", "tool", "calls", "first [s]", "median [ms]", "min [ms]", "/ ross_all",
            "/ ross_default"]
    for an, unit in (("modal", "per call"), ("campbell", "per speed")):
        part = show[show.analysis == an]
        extra = f", {part.n_speeds.iloc[0]} speeds" if an == "campbell" else ""
        print(f"\n{an}: CPU {unit}{extra}")
        print(part[cols].to_string(index=False))
    print("\nfirst six non-rigid frequencies at rest, Hz (and the largest relative "
          "difference, at rest and at the top speed)")
    for d, part in table.groupby("n_dofs"):
        fr = {t: part[part.tool == t].iloc[0] for t in ("ross", "gearmodal")}
        fs = {t: " ".join(f"{fr[t][f'f{k}_hz']:8.3f}" for k in range(1, 7)) for t in fr}
        rel = " ".join(f"{100 * (fr['gearmodal'][f'f{k}_hz'] / fr['ross'][f'f{k}_hz'] - 1):8.3f}"
                       for k in range(1, 7))
        print(f"{d:4d} DOF  ROSS      {fs['ross']}\n          gearmodal {fs['gearmodal']}\n"
              f"          diff %    {rel}   largest {100 * fr['ross'].max_rel_df_0:.3f} % at "
              f"rest, {100 * fr['ross'].max_rel_df_top:.3f} % at the top speed")


if __name__ == "__main__":
    sys.exit(main())
