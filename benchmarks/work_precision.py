"""Work-precision diagram of ``gm.simulate``: exact vs Newmark vs ``solve_ivp``.

Usage::

    .venv/bin/python benchmarks/work_precision.py [--quick] --out DIR

Writes ``DIR/work_precision.csv`` (one row per run: ``problem, method, setting, error, cpu_s``
and diagnostics), ``DIR/work_precision.png`` (error against CPU seconds, log-log, one panel per
problem), ``DIR/summary.json`` (reference cross-check, numba compile times, the cheapest setting
per method reaching ``TARGET``, the exact/scipy cost ratio) and ``DIR/profile_<problem>.txt``
(cProfile of the cheapest exact setting that reaches ``TARGET``).

Problems
--------
``gear_rattle``
    The 20/40 tooth pair of ``tests/validation/test_exactness.py`` (2e8 N/m, backlash 0.1 mm)
    with mesh damping 2000 N s/m (9 % of critical for the mesh mode) and each wheel held by a
    torsional shaft to the ground (2e3 and 2e4 N m/rad; modes 188 Hz and 3.0 kHz), the pinion
    driven by ``2 + 10 sin(2 pi 100 t)`` N m: the mean torque closes the front flank, the
    oscillating one throws the teeth across the backlash onto the back flank and back, 475
    contact events in 0.3 s. The torque is given as a pandas Series sampled every 0.2 ms
    (linear in between), a multiple of every ``dt`` used, so that all methods and steps see the
    *same* forcing (``gm.simulate`` holds loads linearly between its own output times: a smooth
    sine sampled at each method's ``dt`` would be a different problem per ``dt``, with an
    O(dt^2) difference). With lighter mesh damping (200-500 N s/m) this pair rattles
    chaotically: two exact runs that differ only in ``dt`` (rounding) separate from 1e-14 to
    1e-3 within 0.12 s, so no method has a pointwise reference there; 2000 N s/m keeps the
    rattle regular (exact runs agree to ~1e-12 at 0.3 s).
``planetary_clearance``
    The Lin & Parker stage of ``test_exactness.py`` (3 planets, backlash 2 um, carrier bearing
    clearance 20 um in x and y, mesh damping 50 N s/m), driven by carrier/sun torque forces
    +-2 kN and a radial carrier force -3 kN from rest into double contact, 0 to 4 ms: 310
    contact events, 141 double-contact episodes, 219 distinct contact states (18 DOF, 16
    unilateral contacts).

Error and reference
-------------------
``error = max over output times and DOFs |q - q_ref| / max over times and DOFs |q_ref|`` on a
common output grid, the coarsest exact/Newmark ``dt`` of the problem (every other ``dt`` divides
it; the exact and Newmark methods output exactly on their grids, which contain it; the scipy
runs are asked for output on it, ``dt`` = the grid step). ``q_ref`` is the exact method at
``dt = grid / 64``; it is cross-checked against DOP853 at ``rtol = 1e-13`` twice: as is, and
with ``max_step`` a quarter of the shortest interval between two events of one contact in the
reference (solve_ivp sees only sign changes between its own steps, and DOP853's long steps can
step over a brief contact or separation even at this tolerance); the differences (same error
measure, also over the first quarter of the horizon), the event counts and the largest
event-time difference are reported. The reference being exact, the remaining difference is
the DOP853 error, amplified by the problem's sensitivity (rounding-level differences between
exact runs at different ``dt`` grow to ~1e-12 over the rattle's 0.3 s).

Scipy runs use ``atol = rtol * scale`` per state component, ``scale`` = max |q_ref| for the
displacements and max |v_ref| for the velocities (taken from the reference: favourable to
scipy). For each scipy method ``rtol`` is tightened a decade at a time until a run takes longer
than ``--max-run-s`` (the remaining tighter settings are skipped and listed in the summary).

Timing
------
``cpu_s`` is ``time.process_time()`` around ``gm.simulate`` (best of 3 for runs under 1 s, of 2
under 10 s, else one run), given the pre-assembled model so that assembly is not counted
(``gm.simulate`` accepts an ``Assembly``), after a warm-up call of every method on the problem so
that numba compile / cache loading is excluded. BLAS is limited to one thread (``*_NUM_THREADS
= 1`` unless set) so that process time is not inflated by spinning BLAS threads. The numba
compile time is measured separately: a subprocess with a fresh ``NUMBA_CACHE_DIR`` times
``import gearmodal``, the first ``assemble()`` (generated kernels) and the first exact
``simulate`` (integrator kernels) against a second, warm one; a second subprocess with the same
cache directory shows the cached (load-only) cost.

The claim checked (issue "Event-driven piecewise-linear integrator", item 7): the exact method
reaches ``error <= 1e-6`` at least 100 times cheaper than the cheapest scipy setting that reaches
it. ``ratio = cpu_s(cheapest scipy with error <= 1e-6) / cpu_s(cheapest exact with error <=
1e-6)`` per problem is printed and stored. The ``exact`` rows time the integration alone
(``peak_bin=None``), as the other methods' rows; ``exact_peaks`` rows time ``gm.simulate``'s
default, which also finds the exact peaks (the other methods only sample theirs): on the
event-dense ``planetary_clearance`` transient that is about 2.3 times the CPU.

``--quick`` runs fewer steps and tolerances (under 5 minutes on 2 cores). The summary records
the git commit measured: the integrators are still changing.
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import cProfile  # noqa: E402
import io  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import platform  # noqa: E402
import pstats  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import gearmodal as gm  # noqa: E402
from gearmodal.integrate import PEAK_BIN  # noqa: E402

TARGET = 1e-6
CLAIM_RATIO = 100.0
REF_DIVISOR = 64
SCIPY_METHODS = ("RK45", "DOP853", "Radau", "LSODA")
ERROR_DEF = ("error = max over output times and DOFs |q - q_ref| / max over times and DOFs "
             "|q_ref|; q_ref = exact method at dt = grid/64 (cross-checked against DOP853 at "
             "rtol 1e-13); output grid = coarsest exact/newmark dt; cpu_s = process_time "
             "around gm.simulate, numba compile excluded")


# -- problems -------------------------------------------------------------------------------
def gear_rattle_model(gm=gm):
    """The test's 20/40 pair, damped mesh, each wheel on a torsional shaft to the ground
    (built with the package ``gm``: another revision's, in ``kernel_ab.py``)."""
    m = gm.examples.gear_pair(mesh_damping=2000.0)
    m.add(gm.Bearing("input_shaft", "pinion", None, stiffness={"theta": 2e3}))
    m.add(gm.Bearing("output_shaft", "wheel", None, stiffness={"theta": 2e4}))
    return m.check()


def gear_rattle_loads(t_end, knot=2e-4, mean=2.0, amplitude=10.0, freq=100.0):
    """Pinion torque 2 + 10 sin(2 pi 100 t) N m sampled every 0.2 ms, linear in between."""
    tk = np.arange(int(round(t_end / knot)) + 1) * knot
    return {"pinion.torque": pd.Series(mean + amplitude * np.sin(2 * np.pi * freq * tk),
                                       index=tk)}


def planetary_clearance_model(gm=gm):
    """``clearance_stage()`` of tests/validation/test_exactness.py (built with ``gm``)."""
    lp = dict(mass={"carrier": 5.43, "ring": 2.35, "sun": 0.4, "planet": 0.66},
              inertia_over_r2={"carrier": 6.29, "ring": 3.0, "sun": 0.39, "planet": 0.61},
              bearing={"carrier": 1e8, "ring": 1e8, "sun": 1e8, "planet": 1e8},
              torsional={"carrier": 1e6, "ring": 1e9, "sun": 1e6},
              mesh={"sun_planet": 5e8, "ring_planet": 5e8})
    m = gm.lin_parker_stage(3, **lp, pressure_angle=math.radians(24.6), backlash=2e-6,
                            mesh_damping=50.0)
    m.bearings["carrier_support"].clearance = {"x": 2e-5, "y": 2e-5}
    return m


def planetary_clearance_loads(t_end):
    return {"carrier.force_u": 2e3, "sun.force_u": -2e3, "carrier.force_y": -3e3}


def problems(quick: bool) -> dict:
    """Per problem: model, loads, horizon, output grid, the exact / Newmark dt divisors of the
    grid and the scipy rtols."""
    rt_full = [10.0**-k for k in range(3, 13)]
    rt_quick = [1e-4, 1e-6, 1e-8, 1e-9, 1e-10]
    return {
        "gear_rattle": dict(
            model=gear_rattle_model, loads=gear_rattle_loads, t_end=0.3, grid=2e-4,
            exact=[1, 2, 4, 8, 16] if not quick else [1, 4, 16],
            newmark=[2**k for k in range(0, 11)] if not quick else [1, 8, 64],
            rtol=rt_quick if quick else rt_full),
        "planetary_clearance": dict(
            model=planetary_clearance_model, loads=planetary_clearance_loads, t_end=0.004,
            grid=4e-5,
            exact=[1, 2, 4, 8, 16, 32] if not quick else [1, 4, 16],
            newmark=[2**k for k in range(0, 12)] if not quick else [1, 8, 64],
            rtol=rt_quick if quick else rt_full),
    }


# -- running --------------------------------------------------------------------------------
def run(asm, spec, method, dt, **opts):
    return gm.simulate(asm, spec["t_end"], dt=dt, loads=spec["loads"](spec["t_end"]),
                       method=method, **opts)


def timed(asm, spec, method, dt, quick=False, **opts):
    """(best process time over repeats, last result, repeats): best of 3 under 1 s, of 2 under
    10 s (1 with ``quick``), else a single run."""
    best, sim, k = math.inf, None, 0
    while True:
        t0 = time.process_time()
        sim = run(asm, spec, method, dt, **opts)
        best = min(best, time.process_time() - t0)
        k += 1
        # short runs are timed more often: a 5 ms run is at the mercy of one interruption
        wanted = 10 if best < 0.1 else 3 if best < 1.0 else 2 if (best < 10.0 and not quick) \
            else 1
        if k >= wanted:
            return best, sim, k


def rel_error(sim, q_ref, step):
    q = sim.q.to_numpy()[::step]
    if q.shape != q_ref.shape or not np.all(np.isfinite(q)):
        return math.inf
    return float(np.abs(q - q_ref).max() / np.abs(q_ref).max())


def profile_exact(asm, spec, dt, path: Path, top=25):
    pr = cProfile.Profile()
    pr.enable()
    run(asm, spec, "exact", dt)
    pr.disable()
    s = io.StringIO()
    st = pstats.Stats(pr, stream=s).sort_stats("tottime")
    st.print_stats(top)
    path.write_text(s.getvalue())
    rows = []
    for (file, line, fn), (_cc, nc, tt, ct, _callers) in st.stats.items():
        rows.append((tt, ct, nc, f"{Path(file).name}:{line}({fn})"))
    rows.sort(reverse=True)
    return [dict(function=r[3], tottime_s=round(r[0], 4), cumtime_s=round(r[1], 4), calls=r[2])
            for r in rows[:8]]


COMPILE_SNIPPET = r"""
import json, math, sys, time
t0 = time.process_time()
sys.path.insert(0, {root!r})
import gearmodal as gm
sys.path.insert(0, {bench!r})
import work_precision as wp
t1 = time.process_time()
spec = wp.problems(True)[{problem!r}]
asm = spec["model"]().assemble()
t2 = time.process_time()
wp.run(asm, spec, "exact", spec["grid"])
t3 = time.process_time()
wp.run(asm, spec, "exact", spec["grid"])
t4 = time.process_time()
print(json.dumps(dict(import_s=t1 - t0, first_assemble_s=t2 - t1, first_simulate_s=t3 - t2,
                      second_simulate_s=t4 - t3)))
"""


def compile_times(problem: str) -> dict:
    """Cold (fresh NUMBA_CACHE_DIR) and cached numba costs in subprocesses."""
    code = COMPILE_SNIPPET.format(root=str(ROOT), bench=str(Path(__file__).parent),
                                  problem=problem)
    out = {}
    with tempfile.TemporaryDirectory() as cache:
        env = {**os.environ, "NUMBA_CACHE_DIR": cache}
        for label in ("cold", "cached"):
            r = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                               text=True, check=True)
            d = json.loads(r.stdout.strip().splitlines()[-1])
            d["simulate_compile_s"] = d["first_simulate_s"] - d["second_simulate_s"]
            out[label] = {k: round(v, 3) for k, v in d.items()}
    return out


def bench_problem(name, spec, out: Path, max_run_s: float, quick: bool,
                  log) -> tuple[list, dict, dict]:
    asm = spec["model"]().assemble()
    grid = spec["grid"]
    # warm-up: compile / load numba kernels and import scipy's solvers
    for method, kw in (("exact", {}), ("newmark", {}), ("scipy", {"rtol": 1e-3})):
        gm.simulate(asm, 20 * grid, dt=grid, loads=spec["loads"](spec["t_end"]), method=method,
                    **kw)
    # reference
    dt_ref = grid / REF_DIVISOR
    t0 = time.process_time()
    ref = run(asm, spec, "exact", dt_ref)
    ref_cpu = time.process_time() - t0
    q_ref = ref.q.to_numpy()[::REF_DIVISOR]
    v_ref = ref.v.to_numpy()[::REF_DIVISOR]
    n = q_ref.shape[1]
    scale = np.concatenate([np.full(n, np.abs(q_ref).max()), np.full(n, np.abs(v_ref).max())])
    log(f"[{name}] reference: exact dt={dt_ref:.4g} s, {len(ref.events)} events, "
        f"{len(ref.double_contact())} double-contact episodes, {ref_cpu:.2f} s cpu")
    ev_r = ref.events.time.to_numpy()
    # DOP853 twice: as is, and with its step capped at a quarter of the shortest interval
    # between two events of one contact in the reference, so that no brief contact or
    # separation fits inside one step (solve_ivp sees only sign changes between its steps)
    shortest = min(float(np.diff(g.time.to_numpy()).min()) for _, g in
                   ref.events.groupby(["element", "contact"]) if len(g) > 1)
    check = dict(reference=f"exact dt={dt_ref:.6g}", reference_events=len(ev_r),
                 reference_cpu_s=round(ref_cpu, 3),
                 double_contact_episodes=len(ref.double_contact()),
                 shortest_contact_interval_s=shortest, dop853_rtol=1e-13)
    for label, extra in (("dop853", {}), ("dop853_max_step", {"max_step": shortest / 4})):
        t0 = time.process_time()
        dop = run(asm, spec, "scipy", grid, scipy_method="DOP853", rtol=1e-13,
                  atol=1e-13 * scale, **extra)
        dop_cpu = time.process_time() - t0
        ev_d = dop.events.time.to_numpy()
        m = min(len(ev_r), len(ev_d))
        quarter = len(q_ref) // 4
        d = dict(events=len(ev_d), cpu_s=round(dop_cpu, 3), difference=rel_error(dop, q_ref, 1),
                 difference_first_quarter=float(
                     np.abs(dop.q.to_numpy()[:quarter] - q_ref[:quarter]).max()
                     / np.abs(q_ref).max()),
                 max_event_time_difference_s=float(np.abs(ev_r[:m] - ev_d[:m]).max()) if m
                 else None, **extra)
        check[label] = d
        cap = f" max_step {extra['max_step']:.3g}" if extra else ""
        log(f"[{name}] cross-check {label} rtol 1e-13{cap}: "
            f"difference {d['difference']:.3g} (first quarter of the horizon "
            f"{d['difference_first_quarter']:.3g}), {len(ev_d)} vs {len(ev_r)} events, max "
            f"event-time difference {d['max_event_time_difference_s']:.3g} s "
            f"({dop_cpu:.1f} s cpu)")

    rows = []

    def record(method, setting, dt, sim, cpu, reps, step, **extra):
        err = rel_error(sim, q_ref, step)
        row = dict(problem=name, method=method, setting=setting, error=err, cpu_s=cpu,
                   dt=dt, n_events=len(sim.events), n_events_ref=len(ev_r), repeats=reps,
                   runner_cpu_s=sim.stats.get("cpu_s"), **extra)
        rows.append(row)
        log(f"[{name}] {method:8s} {setting:22s} error {err:9.3g}  cpu {cpu:8.4f} s  "
            f"events {len(sim.events)}")

    for div in spec["exact"]:
        dt = grid / div
        # "exact": the integration alone, as the other methods (peak_bin=None);
        # "exact_peaks": gm.simulate's default, with the exact peaks (the other methods have
        # none: their peaks are samples)
        for label, prop, pb in (("exact", "taylor", None), ("exact_peaks", "taylor", PEAK_BIN),
                                ("exact_expm", "expm", None)):
            cpu, sim, reps = timed(asm, spec, "exact", dt, quick, propagator=prop, peak_bin=pb)
            record(label, f"dt={dt:.4g}", dt, sim, cpu, reps, div, propagator=prop,
                   exponentials=sim.stats.get("exponentials"), states=sim.stats.get("states"),
                   pieces=sim.stats.get("pieces"), root_searches=sim.stats.get("root_searches"))
    for div in spec["newmark"]:
        dt = grid / div
        cpu, sim, reps = timed(asm, spec, "newmark", dt, quick)
        record("newmark", f"dt={dt:.4g}", dt, sim, cpu, reps, div)
    skipped, failures = [], []
    # run_scipy's own cap is 1e7 events; a solver stuck re-firing an event at its restart time
    # (LSODA on planetary_clearance) would run for many minutes and fill the memory first
    event_cap = max(1000, 20 * len(ev_r))
    for sm in SCIPY_METHODS:
        too_slow = False
        for rtol in spec["rtol"]:
            setting = f"{sm} rtol={rtol:.0e}"
            if too_slow:
                skipped.append(setting)
                continue
            try:
                cpu, sim, reps = timed(asm, spec, "scipy", grid, quick, scipy_method=sm, rtol=rtol,
                                       atol=rtol * scale, max_events=event_cap)
            except Exception as exc:  # a failing solver is a result, not a crash
                log(f"[{name}] scipy    {setting:22s} FAILED: {exc}")
                rows.append(dict(problem=name, method="scipy", setting=setting,
                                 error=math.inf, cpu_s=math.nan, dt=grid, scipy_method=sm,
                                 rtol=rtol, note=f"failed: {exc}"))
                failures.append(f"{setting}: {exc}")
                continue
            record("scipy", setting, grid, sim, cpu, reps, 1, scipy_method=sm, rtol=rtol,
                   nfev=sim.stats.get("nfev"))
            too_slow = cpu > max_run_s
    summary = dict(cross_check=check, skipped_as_too_slow=skipped, failed=failures)
    return rows, summary, dict(asm=asm, scale=scale, event_cap=event_cap)


def paired_ratio(spec, ctx, be, bs, rounds=3):
    """Re-time the cheapest exact and scipy settings alternately (best of ``rounds`` each), so
    that both see the same machine state; returns (ratio, exact s, scipy s, exact s with its
    result tables read). ``gm.simulate`` builds the result's tables (q, v, forces, events,
    contact_state) when they are first read, for every method alike: the last number times the
    exact run followed by reading all five."""
    te = ts = tt = math.inf
    for _ in range(rounds):
        t0 = time.process_time()
        sim = run(ctx["asm"], spec, "exact", float(be["dt"]), peak_bin=None)
        t1 = time.process_time()
        for name in sim.TABLES:
            getattr(sim, name)
        te = min(te, t1 - t0)
        tt = min(tt, time.process_time() - t0)
        t0 = time.process_time()
        run(ctx["asm"], spec, "scipy", spec["grid"], scipy_method=bs["scipy_method"],
            rtol=float(bs["rtol"]), atol=float(bs["rtol"]) * ctx["scale"],
            max_events=ctx["event_cap"])
        ts = min(ts, time.process_time() - t0)
    return ts / te, te, ts, tt


def git_state() -> str:
    """HEAD commit and whether gearmodal/ differs from it (the integrators change often)."""
    try:
        head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT,
                              capture_output=True, text=True, check=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "gearmodal"], cwd=ROOT,
                               capture_output=True, text=True, check=True).stdout.strip()
        return head + (" (gearmodal/ modified)" if dirty else "")
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def cheapest(df, method, target=TARGET):
    ok = df[(df.method == method) & (df.error <= target)]
    return None if ok.empty else ok.loc[ok.cpu_s.idxmin()]


def plot(df, path: Path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = list(dict.fromkeys(df.problem))
    fig, axes = plt.subplots(1, len(names), figsize=(6.2 * len(names), 5.0), squeeze=False)
    styles = {"exact": ("k", "o", "exact, Taylor propagator (dt)"),
              "exact_expm": ("tab:purple", "D", "exact, expm propagator (dt)"),
              "newmark": ("tab:gray", "s", "Newmark (dt)")}
    colours = dict(zip(SCIPY_METHODS, ("tab:blue", "tab:orange", "tab:green", "tab:red"),
                       strict=True))
    for ax, name in zip(axes[0], names, strict=True):
        d = df[(df.problem == name) & np.isfinite(df.error) & np.isfinite(df.cpu_s)]
        for method, (c, mk, label) in styles.items():
            s = d[d.method == method].sort_values("cpu_s")
            ax.loglog(s.cpu_s, np.maximum(s.error, 1e-16), color=c, marker=mk, label=label)
        for sm, c in colours.items():
            s = d[(d.method == "scipy") & (d.scipy_method == sm)].sort_values("rtol",
                                                                             ascending=False)
            if len(s):
                ax.loglog(s.cpu_s, np.maximum(s.error, 1e-16), color=c, marker="^", ls="--",
                          label=f"solve_ivp {sm} (rtol)")
                for r in s.itertuples():
                    ax.annotate(f"{r.rtol:.0e}", (r.cpu_s, max(r.error, 1e-16)), fontsize=6,
                                color=c, xytext=(3, 2), textcoords="offset points")
        ex = d[d.method == "exact"]
        if len(ex):
            ax.annotate(f"exact, dt = {ex.dt.min():.3g} ... {ex.dt.max():.3g} s",
                        (ex.cpu_s.max(), max(ex.error.max(), 1e-16)), fontsize=7,
                        xytext=(6, 6), textcoords="offset points")
        ax.set_ylim(1e-16, None)
        failed = df[(df.problem == name) & ~np.isfinite(df.error)]
        if len(failed):
            groups: dict[str, list] = {}
            for r in failed.itertuples():
                sm, _, rt = r.setting.partition(" rtol=")
                groups.setdefault(sm, []).append(rt)
            text = "; ".join(f"{sm} rtol {', '.join(v)}" for sm, v in groups.items())
            ax.text(0.02, 0.02, f"failed, no point: {text}", fontsize=6,
                    transform=ax.transAxes, color="tab:red", wrap=True)
        ax.axhline(TARGET, color="0.6", lw=0.8, ls=":")
        ax.set_title(name)
        ax.set_xlabel("CPU time [s] (process time, numba compile excluded)")
        ax.set_ylabel("error: max |q - q_ref| / max |q_ref|")
        ax.grid(True, which="major", lw=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="fewer settings, < 5 min")
    ap.add_argument("--out", required=True, type=Path)
    ap.add_argument("--problems", nargs="*", default=None)
    ap.add_argument("--replot", action="store_true",
                    help="only redraw DIR/work_precision.png from DIR/work_precision.csv")
    ap.add_argument("--max-run-s", type=float, default=None,
                    help="stop tightening a scipy method after a run this long (default 8 s "
                    "quick, 60 s full)")
    args = ap.parse_args(argv)
    out: Path = args.out
    out.mkdir(parents=True, exist_ok=True)
    if args.replot:
        plot(pd.read_csv(out / "work_precision.csv", comment="#"), out / "work_precision.png")
        return
    max_run_s = args.max_run_s or (8.0 if args.quick else 60.0)
    wall0 = time.perf_counter()

    def log(msg):
        print(f"{time.perf_counter() - wall0:7.1f}s {msg}", flush=True)

    specs = problems(args.quick)
    names = args.problems or list(specs)
    all_rows, summary = [], {"quick": args.quick, "error_definition": ERROR_DEF,
                             "target": TARGET, "machine": platform.platform(),
                             "python": platform.python_version(),
                             "cpus": os.cpu_count(), "load_average_at_start": os.getloadavg(),
                             "blas_threads": os.environ.get("OPENBLAS_NUM_THREADS"),
                             "problems": {}}
    for name in names:
        spec = specs[name]
        rows, s, ctx = bench_problem(name, spec, out, max_run_s, args.quick, log)
        all_rows += rows
        df = pd.DataFrame(rows)
        best = {}
        for method in ("exact", "exact_expm", "newmark"):
            b = cheapest(df, method)
            best[method] = None if b is None else dict(setting=b.setting, error=b.error,
                                                       cpu_s=b.cpu_s)
        for sm in SCIPY_METHODS:
            b = cheapest(df[df.get("scipy_method", pd.Series(dtype=str)) == sm], "scipy")
            best[f"scipy {sm}"] = None if b is None else dict(setting=b.setting, error=b.error,
                                                              cpu_s=b.cpu_s)
        bs = cheapest(df, "scipy")
        be = cheapest(df, "exact")
        ratio = (bs.cpu_s / be.cpu_s) if (bs is not None and be is not None) else None
        s["best_reaching_target"] = best
        s["ratio_cheapest_scipy_over_cheapest_exact"] = ratio
        s["claim_met"] = bool(ratio is not None and ratio >= CLAIM_RATIO)
        if ratio is not None:
            pr, pe, ps, pt = paired_ratio(spec, ctx, be, bs, rounds=10)
            s["paired_ratio"] = dict(ratio=pr, exact_cpu_s=pe, scipy_cpu_s=ps,
                                     exact=be.setting, scipy=bs.setting,
                                     exact_with_tables_cpu_s=pt, ratio_with_tables=ps / pt)
            log(f"[{name}] paired re-timing: exact {pe:.4g} s, scipy {ps:.4g} s, ratio "
                f"{pr:.3g}; exact with all result tables read {pt:.4g} s, ratio {ps / pt:.3g}")
        if be is not None:
            s["exact_profile_top"] = profile_exact(
                spec["model"]().assemble(), spec, float(be["dt"]), out / f"profile_{name}.txt")
        s["numba_compile"] = compile_times(name)
        log(f"[{name}] numba: {s['numba_compile']}")
        summary["problems"][name] = s
        if ratio is None:
            log(f"[{name}] RATIO: cannot be computed (exact reaches {TARGET:g}: "
                f"{be is not None}; some scipy setting reaches it: {bs is not None})")
        else:
            verdict = "MET" if ratio >= CLAIM_RATIO else "NOT MET"
            log(f"[{name}] RATIO cheapest scipy ({bs.setting}, {bs.cpu_s:.4g} s) / cheapest "
                f"exact ({be.setting}, {be.cpu_s:.4g} s) = {ratio:.3g}: claim (>= "
                f"{CLAIM_RATIO:g}) {verdict}")
    df = pd.DataFrame(all_rows)
    cols = ["problem", "method", "setting", "error", "cpu_s"]
    df = df[cols + [c for c in df.columns if c not in cols]]
    with open(out / "work_precision.csv", "w") as fh:
        fh.write(f"# {ERROR_DEF}\n")
        fh.write(f"# generated by benchmarks/work_precision.py{' --quick' if args.quick else ''}"
                 f" on {platform.platform()}, {os.cpu_count()} cpus\n")
        df.to_csv(fh, index=False)
    plot(df, out / "work_precision.png")
    summary["wall_s"] = round(time.perf_counter() - wall0, 1)
    summary["git"] = git_state()
    summary["load_average_at_end"] = os.getloadavg()
    (out / "summary.json").write_text(json.dumps(summary, indent=2, default=str))
    log(f"wrote {out / 'work_precision.csv'}, {out / 'work_precision.png'}, "
        f"{out / 'summary.json'}")


if __name__ == "__main__":
    main()
