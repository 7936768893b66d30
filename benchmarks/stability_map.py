"""Stability map: where each method fails at the extremes of DESIGN 3.3, and where ``exact`` holds.

Usage::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/stability_map.py [--quick] --out DIR

Writes ``DIR/stability_map.csv`` (one row per case and method: the case's parameters,
``method``, ``setting``, ``status``, ``energy_drift``, ``trajectory_difference`` (max |q -
q_exact| / max |q_exact| at the case's output times), ``n_events``, ``n_events_exact``,
``first_event_error`` (in contact durations), ``cpu_s``, ``note``) and
``DIR/stability_map.md`` (the status table per case and method, pasted into
``benchmarks/RESULTS.md``).

Cases (DESIGN 3.3), each run by every method:

``rattle``
    A free, undamped, unloaded 20/40 gear pair rattling in its backlash (both flanks) for 12
    flight-contact cycles at 40 output steps per cycle (so ``dt`` exceeds the contact when the
    backlash is large): mesh stiffness 1e6 .. 1e11 N/m, pinion mass 0.1 .. 1e5 kg (wheel 4x,
    inertias of solid discs), backlash 0 .. 1e-3 m. The energy must stay constant.
``chatter``
    The same pair pressed by a mean torque with a 2 kHz torque ripple large enough to throw the
    teeth apart every cycle, 1e8 N/m, 1 kg, backlash 1e-6 m: tens of switches per output step.
``clearance``
    A 2 kg planar body in a bearing dead band of 1e-9 .. 1e-3 m (1e9 N/m), bouncing in y with an
    oscillating x force: many switches, no energy conservation (loaded), checked against exact.
``speed``
    An undamped, unloaded Lin & Parker stage (3 planets, backlash 2 um) at 0 .. 3000 rpm
    carrier speed (gyroscopic and centripetal terms), started with a sun velocity: the energy
    (centripetal terms act as springs) must stay constant.

Methods and settings: ``exact`` with both propagators (``taylor``, ``expm``) at the case's
``dt``; ``newmark`` at the same ``dt`` and at ``dt / 16``; ``scipy`` RK45 and Radau at rtol
1e-6 (``atol`` 1e-12 of the state scale).

Status, first match wins: ``stopped`` (the method stopped with a ``SolveError``, its message in
``note``: a method that fails should), ``error`` (it raised anything else), ``timeout`` (CPU
over ``--budget-s``, run in a subprocess and killed), ``nan`` (non-finite state), ``blowup`` (a
displacement beyond 1e3 x the exact run's largest, or in conservative cases an energy change of
more than 10x the initial energy), ``energy`` (conservative cases: ``(max E - min E) / E(0)``
above 1e-6; every conservative case starts with velocities only, ``E(0) > 0``),
``missed_events`` (event count differs from exact's by more than 2 % or the first event time by
more than 1 % of the case's contact duration), else ``ok``. ``exact`` (Taylor) is the reference
for the event counts, so its own status reports only error/timeout/nan/blowup/energy. """

from __future__ import annotations

import argparse
import math
import multiprocessing as mp
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

import gearmodal as gm  # noqa: E402
from gearmodal.integrate.system import PiecewiseLinearSystem  # noqa: E402

ENERGY_TOL = 1e-6
BLOWUP = 10.0


# -- cases ----------------------------------------------------------------------------------
def _pair(mass, k, backlash, damping=0.0):
    return gm.examples.disk_pair(mass, k, backlash, damping)  # tests/test_integrate.py's


def rattle_case(k, mass, backlash):
    m = _pair(mass, k, backlash)
    rp, rw = m.bodies["pinion"].base_radius, m.bodies["wheel"].base_radius
    ip, iw = m.bodies["pinion"].inertia, m.bodies["wheel"].inertia
    me = 1.0 / (rp**2 / ip + rw**2 / iw)
    contact = math.pi / math.sqrt(k / me)
    v = 1e-2
    flight = max(backlash / v, contact)
    # ~40 output steps per flight-contact cycle: the exact method needs no finer dt, Newmark
    # and scipy are what the map is about; the horizon ends between events (12.37 cycles)
    dt = (flight + contact) / 40
    return dict(model=m, t_end=12.37 * (flight + contact), dt=dt, contact_s=contact,
                conservative=True, loads=None,
                q0={"pinion.theta": -backlash / 2 / rp},
                v0={"pinion.theta": v / rp, "wheel.theta": v / rp * ip * rw / (iw * rp)})


def chatter_case():
    m = _pair(1.0, 1e8, 1e-6)
    ip = m.bodies["pinion"].inertia
    rp = m.bodies["pinion"].base_radius
    me_contact = math.pi / math.sqrt(1e8 / (ip / rp**2))
    amp = 40.0  # N m at 2 kHz: an acceleration swing far beyond the backlash per cycle
    return dict(model=m, t_end=5e-3, dt=1e-4, contact_s=me_contact, conservative=False,
                loads={"pinion.torque": lambda t: 2.0 + amp * math.sin(2 * math.pi * 2000 * t)},
                q0=None, v0=None)


def clearance_case(clearance):
    m = gm.Model("block", input="body")
    m.add(gm.RigidBody(name="body", mass=2.0, inertia=1.0, dofs="planar"))
    m.add(gm.Bearing("b", "body", None, stiffness={"x": 1e9, "y": 1e9, "theta": 1e4},
                     clearance={"x": clearance, "y": clearance}))
    contact = math.pi / math.sqrt(1e9 / 2.0)
    return dict(model=m, t_end=0.05, dt=1e-4, contact_s=contact, conservative=False,
                loads={"body.force_x": lambda t: 1e3 * math.sin(60 * t)}, q0=None,
                v0={"body.y": 0.05})


def speed_case(rpm):
    lp = dict(mass={"carrier": 5.43, "ring": 2.35, "sun": 0.4, "planet": 0.66},
              inertia_over_r2={"carrier": 6.29, "ring": 3.0, "sun": 0.39, "planet": 0.61},
              bearing={"carrier": 1e8, "ring": 1e8, "sun": 1e8, "planet": 1e8},
              torsional={"carrier": 1e6, "ring": 1e9, "sun": 1e6},
              mesh={"sun_planet": 5e8, "ring_planet": 5e8})
    m = gm.lin_parker_stage(3, **lp, pressure_angle=math.radians(24.6), backlash=2e-6)
    contact = math.pi / math.sqrt(5e8 / 0.66)
    return dict(model=m, t_end=2e-3, dt=2e-5, contact_s=contact, conservative=True, loads=None,
                q0=None, v0={"sun.u": 0.01, "sun.x": 0.005}, speed_rpm=float(rpm))


def cases(quick: bool) -> dict:
    out = {}
    ks = [1e6, 1e8, 1e11] if not quick else [1e6, 1e11]
    masses = [0.1, 1.0, 1e5] if not quick else [0.1, 1e5]
    backlashes = [0.0, 1e-6, 1e-3] if not quick else [0.0, 1e-3]
    for k in ks:
        for mass in masses:
            for b in backlashes:
                out[f"rattle k={k:g} m={mass:g} b={b:g}"] = (rattle_case, (k, mass, b),
                                                            dict(k=k, mass=mass, backlash=b))
    out["chatter k=1e8 m=1 b=1e-06"] = (chatter_case, (), dict(k=1e8, mass=1.0, backlash=1e-6))
    for c in ([1e-9, 1e-6, 1e-3] if not quick else [1e-9, 1e-3]):
        out[f"clearance c={c:g}"] = (clearance_case, (c,), dict(clearance=c))
    for rpm in ([0, 1000, 3000] if not quick else [0, 3000]):
        out[f"speed {rpm} rpm"] = (speed_case, (rpm,), dict(speed_rpm=rpm))
    return out


def methods(dt):
    return [("exact", "taylor", dict(method="exact", propagator="taylor")),
            ("exact", "expm", dict(method="exact", propagator="expm")),
            ("newmark", "dt", dict(method="newmark")),
            ("newmark", "dt/16", dict(method="newmark", dt=dt / 16)),
            ("scipy", "RK45 rtol=1e-6", dict(method="scipy", scipy_method="RK45", rtol=1e-6)),
            ("scipy", "Radau rtol=1e-6", dict(method="scipy", scipy_method="Radau",
                                              rtol=1e-6))]


# -- one run in a subprocess (killed on timeout) ---------------------------------------------
def _run(conn, case_name, opts):
    try:
        fn, args, _ = cases(False)[case_name]  # the quick cases are a subset
        c = fn(*args)
        kw = dict(opts)
        dt = kw.pop("dt", c["dt"])
        t0 = time.process_time()
        sim = gm.simulate(c["model"], c["t_end"], dt=dt, loads=c["loads"], q0=c["q0"],
                          v0=c["v0"], speed_rpm=c.get("speed_rpm", 0.0), **kw)
        cpu = time.process_time() - t0
        S = PiecewiseLinearSystem(c["model"].assemble(), c.get("speed_rpm", 0.0))
        x = np.concatenate([sim.q.to_numpy(), sim.v.to_numpy()], axis=1)
        E = Tk = None
        if c["conservative"] and np.all(np.isfinite(x)):
            E = np.array([S.energy(xx) for xx in x])
            v = sim.v.to_numpy()
            Tk = 0.5 * np.einsum("ti,ij,tj->t", v, S.asm.M, v)  # kinetic energy, J
        t_out = np.arange(int(round(c["t_end"] / c["dt"]))) * c["dt"]  # the case's grid
        q = np.column_stack([np.interp(t_out, sim.t, col) for col in sim.q.to_numpy().T])
        conn.send(dict(ok=True, cpu_s=cpu, q=q, E=E, T=Tk, events=sim.events.time.to_numpy(),
                       contact_s=c["contact_s"], conservative=c["conservative"]))
    except Exception as exc:  # a failing method is a result
        conn.send(dict(ok=False, stopped=isinstance(exc, gm.SolveError),
                       note=f"{type(exc).__name__}: {exc}"[:500]))


def run_one(case_name, opts, budget_s):
    parent, child = mp.Pipe(duplex=False)
    p = mp.get_context("fork").Process(target=_run, args=(child, case_name, opts))
    t0 = time.perf_counter()
    p.start()
    child.close()
    res = None
    if parent.poll(budget_s):
        try:
            res = parent.recv()
        except EOFError:
            res = dict(ok=False, note="the run died")
    p.join(timeout=1.0)
    if p.is_alive():
        p.kill()
        p.join()
    if res is None:
        res = dict(ok=False, timeout=True, note=f"over {budget_s:g} s (wall "
                   f"{time.perf_counter() - t0:.0f} s)")
    return res


def classify(res, ref):
    """(status, energy drift, trajectory difference to exact) of one run (module docstring)."""
    if not res["ok"]:
        status = ("timeout" if res.get("timeout") else
                  "stopped" if res.get("stopped") else "error")
        return status, None, None
    q = res["q"]
    if not np.all(np.isfinite(q)):
        return "nan", None, None
    drift = traj = None
    if ref is not None and ref["ok"] and np.all(np.isfinite(ref["q"])) and \
            ref["q"].shape == q.shape:
        big = np.abs(ref["q"]).max()
        traj = float(np.abs(q - ref["q"]).max() / big) if big > 0 else None
        if big > 0 and np.abs(q).max() > 1e3 * big:
            return "blowup", drift, traj
    if res["E"] is not None:
        # relative to the initial energy (every conservative case starts with velocities
        # only, so E(0) = T(0) > 0), or the largest kinetic energy if that is zero
        E = res["E"]
        scale = abs(float(E[0])) or max(float(res["T"].max()), 1e-300)
        drift = float((E.max() - E.min()) / scale)
        if np.abs(E - E[0]).max() > BLOWUP * scale:
            return "blowup", drift, traj
    if drift is not None and drift > ENERGY_TOL:
        return "energy", drift, traj
    if ref is not None and ref is not res and ref["ok"]:
        n, nr = len(res["events"]), len(ref["events"])
        if abs(n - nr) > max(0.02 * nr, 0):
            return "missed_events", drift, traj
        if nr and abs(res["events"][0] - ref["events"][0]) > 0.01 * res["contact_s"]:
            return "missed_events", drift, traj
    return "ok", drift, traj


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="the corners only, fewer settings")
    ap.add_argument("--out", required=True, type=Path)
    ap.add_argument("--budget-s", type=float, default=None,
                    help="CPU budget per run before it counts as a timeout (default 20 s, 8 s "
                    "quick)")
    args = ap.parse_args(argv)
    out: Path = args.out
    out.mkdir(parents=True, exist_ok=True)
    budget = args.budget_s or (8.0 if args.quick else 20.0)
    gm.simulate(_pair(1.0, 1e8, 1e-4), 1e-3, dt=1e-4, v0={"pinion.theta": 1.0})  # compile
    rows = []
    wall0 = time.perf_counter()
    for name, (fn, fargs, params) in cases(args.quick).items():
        dt = fn(*fargs)["dt"]
        ref = None
        for method, setting, opts in methods(dt):
            res = run_one(name, opts, budget)
            if method == "exact" and setting == "taylor":
                ref = res
            status, drift, traj = classify(res, ref if (method, setting) != ("exact", "taylor")
                                           else None)
            ev = res.get("events")
            ev_ref = None if ref is None else ref.get("events")
            first_err = (abs(ev[0] - ev_ref[0]) / res["contact_s"] if ev is not None and
                         ev_ref is not None and len(ev) and len(ev_ref) else None)
            rows.append(dict(case=name, **params, method=method, setting=setting,
                             status=status, energy_drift=drift, trajectory_difference=traj,
                             n_events=None if ev is None else len(ev),
                             n_events_exact=None if ev_ref is None else len(ev_ref),
                             first_event_error=first_err,
                             cpu_s=res.get("cpu_s"), note=res.get("note", "")))
            print(f"{time.perf_counter() - wall0:7.1f}s {name:32s} {method:7s} {setting:16s} "
                  f"{status:13s} drift {drift if drift is not None else float('nan'):9.2g} "
                  f"events {rows[-1]['n_events']} / {rows[-1]['n_events_exact']} "
                  f"{res.get('note', '')[:60]}", flush=True)
    df = pd.DataFrame(rows)
    df.to_csv(out / "stability_map.csv", index=False)
    df["label"] = df.method + " " + df.setting
    table = df.pivot(index="case", columns="label", values="status")
    table = table.loc[list(dict.fromkeys(df.case)), list(dict.fromkeys(df.label))]
    lines = ["| case | " + " | ".join(table.columns) + " |",
             "|---" * (len(table.columns) + 1) + "|"]
    lines += [f"| {case} | " + " | ".join(str(v) for v in row) + " |"
              for case, row in table.iterrows()]
    (out / "stability_map.md").write_text("\n".join(lines) + "\n")
    print(table.to_string())


if __name__ == "__main__":
    main()
