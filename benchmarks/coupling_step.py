"""Coupling accuracy: the gearbox advanced through the public stepping API by a host that owns
the rotor, exchanging values once per communication step, against the monolithic run of the
same drivetrain (the rotor inside the gearbox model, integrated exactly with it).

Usage::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/coupling_step.py --out DIR [--quick]

The drivetrain: the clearance planetary stage (``studies/models/planetary_clearance.toml``, the
paper's fault) at 22.5 rpm behind a rotor of ``J_ROTOR`` on a main shaft of ``K_SHAFT``,
``C_SHAFT``; the rotor's aerodynamic torque ``T0 (1 + 0.15 sin(2 pi 0.3 t) + 0.05 sin(2 pi
3.1 t)) - C_AERO (w - w0)`` (a gust, the 3P-like ripple and the aerodynamic damping), the sun
held by ``T0 / 5.71`` (the generator's mean), the shaft-end force of the shipped double-contact
scene on the carrier (1.1 Hz).

- ``monolithic``: ``gm.drivetrain(rotor, [stage])``, one ``gm.simulate`` call; the rotor's
  torque a Harmonic load and a damper to ground (``C_AERO``), every load exact.
- ``cosim_Hms``: the stage alone in a ``gm.Stepper`` driven through ``gm.Drive("carrier.theta",
  K_SHAFT, C_SHAFT)``; the host integrates its rotor (``J dw/dt = T_aero(t, w) - T_shaft``,
  semi-implicit Euler on its own step ``H``), sends the rotor's angle and speed and the
  shaft-end force at each step's end (ramped), and reads back ``drive.torque``: the usual
  explicit (Gauss-Seidel) co-simulation.

Three more monolithic runs, their rotor torque larger by 1e-9, 1e-6 and 1e-3, give the floor:
the stage rattles in its clearance, so that any change moves each impact's peak. Writes
``DIR/coupling_step.csv``: per case the four engineering quantities of the paper's
study after the start's transient (from ``T_SKIP``: :func:`settled`; planet-1 tooth peak
``max_front_force_N``, ``max_planet_bearing_force_N``, ``double_contact_time_s``,
``peak_load_sharing_factor``), their
relative errors against ``monolithic``, the final rotor speed, ``omega_h`` (the rotor-on-shaft
frequency ``sqrt(K_SHAFT / J_ROTOR)`` times the step: the explicit exchange's stability number)
and ``stable``.
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
RPM = 22.5
W0 = RPM * math.pi / 30
T0 = 2.6e5  # N m, rated at 22.5 rpm (600 kW)
J_ROTOR = 3.0e5  # kg m^2
K_SHAFT = 5.0e7  # N m/rad
C_SHAFT = 2.0e4  # N m s/rad
C_AERO = 2 * T0 / W0  # N m s/rad: dT/dw of a rotor at constant tip-speed ratio, roughly
DT = 1e-4
QUANTITIES = ["max_front_force_N", "max_planet_bearing_force_N", "double_contact_time_s",
              "peak_load_sharing_factor"]
HARM = [(0.15, 0.3), (0.05, 3.1)]  # aerodynamic torque: (amplitude / T0, Hz)
T_SKIP = 1.0  # s: the quantities after the start's transient


def shaft_end(t):
    """The shipped double-contact scene's shaft-end force on the carrier (N)."""
    w = 2 * math.pi * 1.1
    return -5.0e4 + 4.0e4 * np.sin(w * t), 3.0e4 * np.sin(w * t + math.pi / 2)


def aero(t, w):
    return T0 * (1 + sum(a * math.sin(2 * math.pi * f * t) for a, f in HARM)) \
        - C_AERO * (w - W0)


def monolithic(stage, t_end, scale: float = 1.0):
    rotor = gm.RigidBody(name="rotor", mass=1.0, inertia=J_ROTOR, dofs="torsional")
    model = gm.drivetrain(rotor, [stage], main_shaft_stiffness=K_SHAFT,
                          main_shaft_damping=C_SHAFT, name="monolithic")
    model.add(gm.Bearing("aero_damping", "rotor", None, stiffness={"theta": 0.0},
                         damping={"theta": C_AERO}))
    loads = {"rotor.torque": _sum_harmonics(scale),  # the damper acts on the deflection rate
             "stage1.sun.torque": -T0 / RATIO,
             "stage1.carrier.force_y": gm.Harmonic(-5.0e4, 4.0e4, 1.1),
             "stage1.carrier.force_x": gm.Harmonic(0.0, 3.0e4, 1.1, math.pi / 2)}
    return gm.simulate(model, t_end, dt=DT, loads=loads, speed_rpm=RPM)


def _sum_harmonics(scale: float = 1.0):
    """The aerodynamic torque without its damping, a callable load (sampled every load_dt,
    1e-4 s: within 5e-8 of the 3.1 Hz sine); ``scale`` multiplies it."""
    return lambda t: scale * T0 * (1 + sum(a * np.sin(2 * math.pi * f * t) for a, f in HARM))


def cosim(stage, t_end, h):
    fy0, fx0 = shaft_end(0.0)
    box = gm.Stepper(stage, dt=DT, speed_rpm=RPM,
                     loads={"sun.torque": -T0 / RATIO, "carrier.force_x": float(fx0),
                            "carrier.force_y": float(fy0)},
                     drive=gm.Drive("carrier.theta", K_SHAFT, C_SHAFT, angle0=0.0, speed0=W0),
                     outputs=["drive.torque"])
    w, angle, torque = W0, 0.0, 0.0
    n = round(t_end / h)
    for k in range(1, n + 1):
        t = k * h
        w += h * (aero(t - h, w) - torque) / J_ROTOR  # semi-implicit Euler
        angle += h * w
        fy, fx = shaft_end(t)
        out = box.advance(t, {"carrier.force_x": fx, "carrier.force_y": fy},
                          drive_angle=angle, drive_speed=w)
        torque = out["drive.torque"]
        if not math.isfinite(torque) or abs(w - W0) > W0:
            return None, w
    return box.result(), w


def settled(res, t_from: float) -> dict:
    """The four quantities after the start (from ``t_from`` s): planet 1's largest front-flank
    force and the largest planet-bearing radial force (exact peaks), the time with both flanks
    of some mesh in contact, the largest load-sharing factor."""
    pk = res.peaks(t_from)["peak_force_N"]
    tooth = max(float(pk[c]) for c in pk.index if "_planet1." in c and c.endswith(".front"))
    bearing = max(float(pk[c]) for c in pk.index if "_bearing.radial" in c and "planet" in c)
    dc = res.double_contact()
    spans = sorted((max(a, t_from), b) for a, b in zip(dc.start, dc.end, strict=True)
                   if b > t_from)
    total, end = 0.0, -math.inf
    for a, b in spans:
        if b > end:
            total += b - max(a, end)
            end = b
    ls = res.load_sharing()
    fac = ls.filter(like="factor").iloc[:, 0]
    return {"max_front_force_N": tooth, "max_planet_bearing_force_N": bearing,
            "double_contact_time_s": total,
            "peak_load_sharing_factor": float(fac[fac.index >= t_from].max())}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", required=True)
    ap.add_argument("--quick", action="store_true")
    a = ap.parse_args()
    stage = gm.load(ROOT / "studies/models/planetary_clearance.toml")
    t_end = 2.0 if a.quick else 10.0
    rows = []
    t0 = time.process_time()
    ref = monolithic(stage, t_end)
    rq = settled(ref, T_SKIP)
    w_ref = W0 + float(ref.v["rotor.theta"].iloc[-1])
    rows.append({"case": "monolithic", "step_ms": 0.0, "cpu_s": time.process_time() - t0,
                 "stable": True, "rotor_speed_rad_s": w_ref,
                 **{q: rq[q] for q in QUANTITIES}})
    # the floor: the monolithic run with its rotor torque 1e-9 larger (the stage rattles in
    # its clearance: impacts are chaotic, so any change moves each peak by this much)
    for scale, name in ((1 + 1e-9, "monolithic_1e-9"), (1 + 1e-6, "monolithic_1e-6"),
                        (1 + 1e-3, "monolithic_1e-3")):
        t0 = time.process_time()
        alt = monolithic(stage, t_end, scale)
        s = settled(alt, T_SKIP)
        row = {"case": name, "step_ms": 0.0, "cpu_s": time.process_time() - t0,
               "stable": True, "rotor_speed_rad_s": W0 + float(alt.v["rotor.theta"].iloc[-1])}
        for q in QUANTITIES:
            row[q] = s[q]
            row[f"err_{q}"] = (s[q] - rq[q]) / rq[q] if rq[q] else math.nan
        rows.append(row)
        print(row, flush=True)
    for h_ms in (1, 5, 10, 20, 50, 100, 200, 500):
        t0 = time.process_time()
        res, w = cosim(stage, t_end, h_ms * 1e-3)
        row = {"case": f"cosim_{h_ms}ms", "step_ms": h_ms, "cpu_s": time.process_time() - t0,
               "stable": res is not None, "rotor_speed_rad_s": w,
               "omega_h": math.sqrt(K_SHAFT / J_ROTOR) * h_ms * 1e-3}
        if res is not None:
            s = settled(res, T_SKIP)
            for q in QUANTITIES:
                row[q] = s[q]
                row[f"err_{q}"] = (s[q] - rq[q]) / rq[q] if rq[q] else math.nan
        rows.append(row)
        print(row, flush=True)
    df = pd.DataFrame(rows)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    df.to_csv(out / "coupling_step.csv", index=False)
    print(df.to_string(index=False))


if __name__ == "__main__":
    main()
