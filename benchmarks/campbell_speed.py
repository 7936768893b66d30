"""Speed of a Campbell sweep against the bare LAPACK eigen-solves it needs.

Usage::

    .venv/bin/python benchmarks/campbell_speed.py [--quick] [--out DIR] [--blas-threads N]

Cases (200 speeds, 0..27 rpm of the rotor):

``600kw``
    ``gm.load("studies/models/600kw.toml")`` as shipped (planar gearbox, 35 DOF).
``3stage_full``
    The same three-stage gearbox (planetary 21/39/99, parallel 82/23 and 88/22, the GRC 750 kW
    tooth data of the 600 kW model file) built here with ``gm.planetary_stage`` /
    ``gm.parallel_stage`` / ``gm.drivetrain`` with every gear, the carrier and the housing at the
    ``full`` DOF level (rotor and generator torsional, 68 DOF). At ``full`` level every support
    needs z, rx and ry stiffness as well, or the axial and tilt coordinates are free and the
    eigen-solver returns spurious zero modes; the values used are listed in
    :func:`three_stage_full` (estimates of the right order for roller bearings of this size; the
    benchmark only needs a well-posed model).

For each case the script times

* ``campbell_s``: ``gm.campbell(model, speeds)`` (assembly, eigen-solves, MAC tracking, mode
  types, veerings), best of ``--repeats``;
* ``floor_s``: the same eigenproblems solved back to back with ``scipy.linalg.eig`` (state
  matrix, with the flags ``campbell`` uses) or ``scipy.linalg.eigh`` (undamped at rest) and
  nothing else, matrices built beforehand, best of the same repeats, interleaved with the
  Campbell runs so that both see the same machine state;
* ``floor_lapack_s``: the same solves as LAPACK ``dgeev`` calls through
  ``scipy.linalg.lapack`` (workspace size queried once), as ``campbell`` makes them, without
  ``scipy.linalg.eig``'s Python wrapper; ``ratio_lapack = campbell_s / floor_lapack_s``;
* ``ratio = campbell_s / floor_s`` (the number to compare between machines; aim < 1.5), and
  ``ratio_cpu`` from process CPU time (``time.process_time``, all threads), which other load on
  the machine disturbs less than wall time when BLAS runs on one thread;
* ``reference_s``: the sweep as it was before the speed work (per speed
  ``gearmodal.modal.eigensolve`` + ``gearmodal.campbell.mac`` + ``gearmodal.modetypes.classify``),
  run once, and the check that ``campbell`` still gives its result: frequencies within 1e-9
  relative (rigid modes: 1e-9 of the highest frequency), identical mode types and veering flags;
* ``fallback_speeds``: speeds at which the vectorised mode-type labelling found a value within
  rounding of a threshold and called ``classify`` itself;
* numba: ``import gearmodal; model.assemble()`` in a subprocess with ``NUMBA_CACHE_DIR`` set to a
  fresh directory (cold: every kernel compiled) and again with the same directory (cached), and
  the warm assembly time in this process (best of 5).

Compare ratios, not seconds. ``--blas-threads N`` sets ``OPENBLAS_NUM_THREADS`` (and OMP/MKL)
before numpy is imported; the default leaves the environment alone. ``--quick`` is a smoke run
(40 speeds, 1 repeat, cold/cached compile of the 600 kW case only).
"""

from __future__ import annotations

import argparse
import csv
import importlib
import json
import math
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
MODEL_600KW = ROOT / "studies" / "models" / "600kw.toml"
CASES = ("600kw", "3stage_full")


# -- models ---------------------------------------------------------------------------------
def three_stage_full():
    """The 600 kW model's gearbox with gears, carrier and housing at ``full`` DOF level.

    Gear data as ``studies/models/600kw.toml`` (GRC 750 kW: modules 10 / 8.25 / 5 mm, 20 deg
    normal pressure angle, helix 7.5 / 14 / 14 deg with opposite hands in mesh). Supports,
    ``(x = y, z, rx = ry[, theta])``, N/m and N m/rad (estimates):

    ============== ======== ======== ======== =======
    support        radial   axial z  tilt     theta
    ============== ======== ======== ======== =======
    planet bearing 2.0e9    5.0e8    2.0e8
    carrier        1.0e9    1.0e9    5.0e8
    sun (spline)   1.0e7    1.0e7    1.0e6
    ring (bolted)  5.0e9    5.0e9    5.0e9    3.0e9
    stage 2 wheel  1.5e9    1.5e9    2.0e8
    stage 2 pinion 1.5e9    1.5e9    5.0e7
    stage 3 wheel  1.0e9    1.0e9    5.0e7
    stage 3 pinion 1.0e9    1.0e9    1.0e7
    shaft bending  1.0e7    1.0e7    1.0e7
    suspension     2.0e7    2.0e7    2.0e7    2.0e7
    ============== ======== ======== ======== =======
    """
    import gearmodal as gm

    d = math.radians
    full = "full"

    def sup(radial, axial, tilt, theta=None):
        k = {"x": radial, "y": radial, "z": axial, "rx": tilt, "ry": tilt}
        if theta is not None:
            k["theta"] = theta
        return {"stiffness": k}

    sun = gm.Gear(21, 0.010, d(20), d(7.5), 0.23, mass=80.0, inertia=0.45)
    planet = gm.Gear(39, 0.010, d(20), d(-7.5), 0.23, mass=140.0, inertia=3.6)
    ring = gm.Gear(99, 0.010, d(20), d(-7.5), 0.23, internal=True, mass=620.0, inertia=190.0)
    s1 = gm.planetary_stage(
        sun, planet, ring, n_planets=3, carrier_mass=1000.0, carrier_inertia=110.0,
        mesh_stiffness={"sun_planet": 4.6e9, "ring_planet": 5.0e9}, backlash=3e-4,
        planet_bearing=sup(2e9, 5e8, 2e8), carrier_bearing=sup(1e9, 1e9, 5e8),
        sun_support=sup(1e7, 1e7, 1e6), ring_support=sup(5e9, 5e9, 5e9, 3e9), dofs=full)
    g2 = gm.Gear(82, 0.00825, d(20), d(14), 0.17, mass=350.0, inertia=25.0)
    p2 = gm.Gear(23, 0.00825, d(20), d(-14), 0.18, mass=90.0, inertia=0.4)
    s2 = gm.parallel_stage(g2, p2, mesh_stiffness=3.4e9, backlash=2.5e-4, angle=d(90),
                           gear_bearing=sup(1.5e9, 1.5e9, 2e8),
                           pinion_bearing=sup(1.5e9, 1.5e9, 5e7), dofs=full)
    g3 = gm.Gear(88, 0.005, d(20), d(-14), 0.12, mass=120.0, inertia=3.2)
    p3 = gm.Gear(22, 0.005, d(20), d(14), 0.13, mass=40.0, inertia=0.1)
    s3 = gm.parallel_stage(g3, p3, mesh_stiffness=2.4e9, backlash=1.5e-4, angle=d(90),
                           gear_bearing=sup(1e9, 1e9, 5e7), pinion_bearing=sup(1e9, 1e9, 1e7),
                           dofs=full)
    return gm.drivetrain(
        gm.RigidBody(name="rotor", mass=11000.0, inertia=4e5), [s1, s2, s3],
        main_shaft_stiffness=4.8e7, couplings=[6e6, 4e7],
        generator=gm.RigidBody(name="generator", mass=1000.0, inertia=15.0), hss_stiffness=2e5,
        housing=gm.RigidBody(name="housing", mass=5000.0, inertia=1500.0, dofs=full),
        suspension=sup(2e7, 2e7, 2e7, 2e7), shaft_bending=sup(1e7, 1e7, 1e7),
        name="3stage_full")


def build(case: str):
    import gearmodal as gm

    if case == "600kw":
        return gm.load(MODEL_600KW)
    if case == "3stage_full":
        return three_stage_full()
    raise SystemExit(f"unknown case {case!r}; known: {', '.join(CASES)}")


# -- the floor: the eigenproblems alone -------------------------------------------------------
def eigenproblems(model, speeds_rpm):
    """The eigenproblems of ``gm.campbell(model, speeds_rpm)``: ``("eigh", Ks, M)`` where the
    damping term vanishes, else ``("eig", A)`` with the state matrix of ``eigensolve``."""
    import numpy as np
    import scipy.linalg as sla

    from gearmodal.modal import RPM

    asm = model.assemble()
    st = asm.state()
    K, C, M, n = asm.stiffness(st), asm.damping(st), asm.M, asm.n
    out = []
    for rpm in speeds_rpm:
        om = rpm * RPM
        D = C + (om * asm.G if om else 0.0)
        Ks = K + (om**2 * asm.K_cent if om else 0.0)
        if not np.any(D):
            out.append(("eigh", Ks, M))
            continue
        A = np.block([[np.zeros((n, n)), np.eye(n)],
                      [-sla.solve(M, Ks, assume_a="pos"), -sla.solve(M, D, assume_a="pos")]])
        out.append(("eig", A))
    return out


def time_floor(problems, lapack: bool = False) -> tuple[float, float]:
    """Wall and process CPU seconds for the eigen-solves alone, back to back (copies made
    beforehand because the solver may overwrite its input, as ``campbell`` lets it).

    ``lapack=False``: ``scipy.linalg.eig(A, overwrite_a=True, check_finite=False)``, the floor
    as defined. ``lapack=True``: LAPACK ``dgeev`` through ``scipy.linalg.lapack`` with the
    workspace size queried once, i.e. without ``scipy.linalg.eig``'s Python around it (the
    workspace query on every call and the conversion of all eigenvectors to complex), which is
    how ``campbell`` calls it."""
    import numpy as np
    import scipy.linalg as sla

    work = [(p[0], np.asfortranarray(p[1]).copy(order="F"), *p[2:]) for p in problems]
    geev = lwork = None
    if lapack:
        eigs = [p[1] for p in work if p[0] == "eig"]
        if eigs:
            geev, geev_lwork = sla.get_lapack_funcs(("geev", "geev_lwork"), (eigs[0],))
            lwork = int(np.real(geev_lwork(eigs[0].shape[0], compute_vl=0, compute_vr=1)[0]))
    t0, c0 = time.perf_counter(), time.process_time()
    for p in work:
        if p[0] == "eigh":
            sla.eigh(p[1], p[2])
        elif lapack:
            geev(p[1], compute_vl=0, compute_vr=1, lwork=lwork, overwrite_a=1)
        else:
            sla.eig(p[1], overwrite_a=True, check_finite=False)
    return time.perf_counter() - t0, time.process_time() - c0


# -- the reference: the sweep before the speed work -----------------------------------------
def reference_campbell(model, speeds_rpm):
    """Frequencies, mode types and veering flags as ``gm.campbell`` computed them before it was
    optimised: one ``eigensolve``, ``mac`` and ``classify`` per speed."""
    import numpy as np
    from scipy.optimize import linear_sum_assignment

    from gearmodal.campbell import _find_veerings, mac
    from gearmodal.modal import RPM, eigensolve
    from gearmodal.modetypes import classify

    asm = model.assemble()
    st = asm.state()
    K, C = asm.stiffness(st), asm.damping(st)
    s = np.asarray(speeds_rpm, dtype=float)
    n = asm.n
    freqs, zetas = np.zeros((s.size, n)), np.zeros((s.size, n))
    types = np.empty((s.size, n), dtype=object)
    shapes, prev = [], None
    for i, rpm in enumerate(s):
        lam, phi = eigensolve(asm.M, C, K, asm.G, rpm * RPM, asm.K_cent)
        absl = np.abs(lam)
        f = absl / (2 * math.pi)
        with np.errstate(invalid="ignore", divide="ignore"):
            z = np.where(absl > 0, -lam.real / np.where(absl > 0, absl, 1.0), 0.0)
        if prev is not None:
            mm = mac(prev, phi, asm.M)
            cost = -mm + 1e-6 * np.abs(freqs[i - 1][:, None] - f[None, :]) / (1.0 + f.max())
            _, col = linear_sum_assignment(cost)
            f, z, phi = f[col], z[col], phi[:, col]
        freqs[i], zetas[i] = f, z
        types[i] = classify(asm, phi, f)
        shapes.append(phi)
        prev = phi
    veer = np.zeros((s.size, n), dtype=bool)
    for i, a, b, *_ in _find_veerings(s, freqs, shapes, asm.M):
        veer[i, a] = veer[i, b] = True
    return freqs, zetas, types, veer


def compare(camp, ref) -> dict:
    """Largest frequency difference (relative; rigid modes relative to the highest frequency)
    and whether mode types and veering flags are identical."""
    import numpy as np

    freqs, _, types, veer = ref
    rigid = types == "rigid"
    scale = np.where(rigid, np.max(freqs), np.abs(freqs))
    rel = np.abs(camp.frequencies_hz - freqs) / np.where(scale > 0, scale, 1.0)
    return {"max_rel_df": float(rel.max()),
            "types_identical": bool(np.array_equal(camp.mode_types, types)),
            "veering_identical": bool(np.array_equal(camp.veering, veer))}


# -- numba compile times ---------------------------------------------------------------------
def compile_child(case: str) -> None:
    """Run in a subprocess: time ``import gearmodal``, the model build and the first
    ``model.assemble()`` (numba kernels loaded from, or compiled into, NUMBA_CACHE_DIR)."""
    t0 = time.perf_counter()
    import gearmodal  # noqa: F401

    t1 = time.perf_counter()
    model = build(case)
    t2 = time.perf_counter()
    model.assemble()
    t3 = time.perf_counter()
    print(json.dumps({"import_s": t1 - t0, "build_s": t2 - t1, "first_assemble_s": t3 - t2}))


def compile_times(case: str) -> dict:
    out = {}
    with tempfile.TemporaryDirectory(prefix="numba_cache_") as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache)
        for label in ("cold", "cached"):
            r = subprocess.run([sys.executable, __file__, "--compile-child", case], env=env,
                               capture_output=True, text=True, check=True, cwd=ROOT)
            res = json.loads(r.stdout.strip().splitlines()[-1])
            out[f"import_{label}_s"] = res["import_s"]
            out[f"numba_{label}_s"] = res["first_assemble_s"]
            if label == "cold":
                out["numba_cache_files"] = sum(len(f) for _, _, f in os.walk(cache))
    return out


# -- main -------------------------------------------------------------------------------------
def run_case(case: str, n_speeds: int, repeats: int, with_compile: bool) -> dict:
    import numpy as np

    import gearmodal as gm
    gc = importlib.import_module("gearmodal.campbell")  # gm.campbell is the function

    model = build(case)
    speeds = np.linspace(0.0, 27.0, n_speeds)
    gm.campbell(model, speeds[:3])  # warm up (numba kernels, imports)
    problems = eigenproblems(model, speeds)
    camp_t, floor_t, camp_c, floor_c, lap_t = [], [], [], [], []
    for _ in range(repeats):
        t0, c0 = time.perf_counter(), time.process_time()
        camp = gm.campbell(model, speeds)
        camp_t.append(time.perf_counter() - t0)
        camp_c.append(time.process_time() - c0)
        wall, cpu = time_floor(problems)
        floor_t.append(wall)
        floor_c.append(cpu)
        lap_t.append(time_floor(problems, lapack=True)[0])
    # fallbacks of the vectorised mode-type labelling to classify()
    calls = []
    exact = gc.classify

    def counting(*args, **kwargs):
        calls.append(1)
        return exact(*args, **kwargs)

    gc.classify = counting
    try:
        gm.campbell(model, speeds)
    finally:
        gc.classify = exact
    t0 = time.perf_counter()
    ref = reference_campbell(model, speeds)
    ref_t = time.perf_counter() - t0
    asm_t = min(_timed(model.assemble) for _ in range(5))
    row = {
        "case": case, "n_dofs": model.n_dofs, "n_speeds": n_speeds,
        "campbell_s": min(camp_t), "floor_s": min(floor_t),
        "ratio": min(camp_t) / min(floor_t),
        "campbell_cpu_s": min(camp_c), "floor_cpu_s": min(floor_c),
        "ratio_cpu": min(camp_c) / min(floor_c),
        "floor_lapack_s": min(lap_t), "ratio_lapack": min(camp_t) / min(lap_t),
        "reference_s": ref_t, "speedup_vs_reference": ref_t / min(camp_t),
        "eig_calls": sum(p[0] == "eig" for p in problems),
        "eigh_calls": sum(p[0] == "eigh" for p in problems),
        "fallback_speeds": len(calls),
        **compare(camp, ref),
        "assemble_s": asm_t,
        "repeats": repeats,
        "blas_threads": os.environ.get("OPENBLAS_NUM_THREADS", "default"),
        "cpus": os.cpu_count(),
    }
    if with_compile:
        row.update(compile_times(case))
    return row


def _timed(fn) -> float:
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="smoke run: 40 speeds, 1 repeat")
    ap.add_argument("--out", default=str(ROOT / "benchmarks" / "results"),
                    help="directory for campbell_speed.csv (default benchmarks/results)")
    ap.add_argument("--repeats", type=int, default=None, help="timed repeats (default 3)")
    ap.add_argument("--speeds", type=int, default=None, help="number of speeds (default 200)")
    ap.add_argument("--blas-threads", type=int, default=None,
                    help="set OPENBLAS/OMP/MKL_NUM_THREADS before numpy is imported")
    ap.add_argument("--cases", default=",".join(CASES), help="comma-separated cases")
    ap.add_argument("--compile-child", default=None, help=argparse.SUPPRESS)
    a = ap.parse_args(argv)
    if a.compile_child:
        compile_child(a.compile_child)
        return 0
    if a.blas_threads is not None:
        for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
            os.environ[var] = str(a.blas_threads)
    n_speeds = a.speeds or (40 if a.quick else 200)
    repeats = a.repeats or (1 if a.quick else 3)
    rows = []
    for k, case in enumerate(a.cases.split(",")):
        rows.append(run_case(case, n_speeds, repeats, with_compile=not a.quick or k == 0))
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    cols = list(dict.fromkeys(c for r in rows for c in r))
    with open(out / "campbell_speed.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=cols)
        w.writeheader()
        w.writerows(rows)
    _print_table(rows)
    print(f"\nmachine: {platform.machine()} {platform.processor() or ''} {os.cpu_count()} cpus, "
          f"python {platform.python_version()}, OPENBLAS_NUM_THREADS="
          f"{os.environ.get('OPENBLAS_NUM_THREADS', 'unset')}")
    print(f"wrote {out / 'campbell_speed.csv'}")
    bad = [r["case"] for r in rows if not (r["types_identical"] and r["veering_identical"]
                                            and r["max_rel_df"] <= 1e-9)]
    if bad:
        print("MISMATCH against the reference sweep: " + ", ".join(bad))
        return 1
    return 0


def _print_table(rows) -> None:
    head = ("case", "n_dofs", "n_speeds", "campbell_s", "floor_s", "ratio", "ratio_cpu",
            "ratio_lapack", "reference_s",
            "fallback_speeds", "max_rel_df", "types_identical", "assemble_s", "numba_cold_s",
            "numba_cached_s")
    cells = [[_fmt(r.get(h, "")) for h in head] for r in rows]
    width = [max(len(h), *(len(c[i]) for c in cells)) for i, h in enumerate(head)]
    print("  ".join(h.rjust(wd) for h, wd in zip(head, width, strict=True)))
    for c in cells:
        print("  ".join(x.rjust(wd) for x, wd in zip(c, width, strict=True)))


def _fmt(x) -> str:
    if isinstance(x, bool) or not isinstance(x, float):
        return str(x)
    return f"{x:.3g}" if abs(x) >= 1e-3 or x == 0 else f"{x:.1e}"


if __name__ == "__main__":
    sys.exit(main())
