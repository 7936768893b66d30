"""Coupling accuracy on the 600 kW turbine: the gearbox advanced through the public stepping API
by a host that owns the rotor, exchanging values once per communication step ``H``, against the
monolithic coupled run (the rotor inside the gearbox model on its main shaft, integrated exactly
with it: :func:`gearmodal.turbine.simulate_drivetrain`).

Usage::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/turbine_coupling.py --out DIR [--quick]

The turbine: the shipped scene ``studies/scenes/600kw_turbine_10ms.toml`` (10 m/s, 12 %
turbulence, start at 6 rpm, cut-in near 11 s) with the clearance gearbox of the double-contact
study (the paper's fault), ``T_END`` s.

- ``monolithic``: the coupled run as ``gearmodal simulate`` makes it.
- ``monolithic_1e-3``: the same with the rotor's aerodynamic torque 1e-3 larger: the floor
  below which a coupling error cannot be told from the rattle's own sensitivity (the carrier
  rattles in its clearance: any change moves each impact's peak).
- ``cosim_Hms``: the host owns the rotor (its inertia ``J``, semi-implicit Euler on
  ``min(H, aero_dt)``, the aerodynamic torque from the same plant,
  :class:`gearmodal.turbine.plant.TurbinePlant`, at each aerodynamic step); the gearbox without
  rotor and main shaft is a :class:`gearmodal.Stepper` driven through ``gm.Drive`` with the main
  shaft's stiffness. Once per ``H`` the host sends the rotor's angle and speed and the shaft-end
  force at the step's end (ramped over ``H``) and reads back the shaft torque and the generator
  speed: the usual explicit (Gauss-Seidel) co-simulation.

Writes ``DIR/turbine_coupling.csv``: per case the four engineering quantities of the paper's
study over the run, as the study reports them (:func:`gearmodal.summary.summarize`: planet 1's
tooth peak, the planet-bearing peak, the double-contact time, the load-sharing peak while the
stage is loaded), their relative errors against ``monolithic``,
the rotor speed at the end, ``omega_h`` (the rotor-on-shaft frequency times ``H``: the explicit
exchange's stability number) and ``stable``.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd

import gearmodal as gm
from gearmodal.scene import load_scene
from gearmodal.turbine.drivetrain import couple

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "studies"))
sys.path.insert(0, str(ROOT / "benchmarks"))
from double_contact import CLEARANCE  # noqa: E402

from gearmodal.summary import summarize  # noqa: E402

QUANTITIES = ["max_front_force_N", "max_planet_bearing_force_N", "double_contact_time_s",
              "peak_load_sharing_factor"]
STEPS_MS = (1, 5, 10, 20, 40, 100, 200)


def scene():
    return load_scene(ROOT / "studies/scenes/600kw_turbine_10ms.toml",
                      overrides={"model.stages.0.carrier_bearing": CLEARANCE})


def monolithic(sc, t_end: float, scale: float = 1.0):
    """The coupled run (:func:`simulate_drivetrain`'s loop), the rotor torque times ``scale``
    from the first step on."""
    t0 = time.process_time()
    c = couple(sc.turbine, sc.wind, sc.model, t_end, dt=sc.dt, **sc.drivetrain)
    plant, st, step = c.plant, c.stepper, c.first
    loads = plant.loads
    plant.loads = lambda u: {**loads(u), "rotor.torque": scale * float(u[0])}
    for k in range(1, c.n_aero + 1):
        y = st.advance(k * c.aero_dt, step.loads, hold=step.hold, start=step.start)
        if k < c.n_aero:
            step = plant.step(k, *y.values())
            if plant.switched:
                st.set_speed_torque(plant.generator())
    return c.result(t0)


def without_rotor(model, tilt_deg: float):
    """The drivetrain model without its rotor and main shaft: the gearbox a host drives."""
    gb = model.copy()
    del gb.bodies["rotor"]
    del gb.bearings["main_shaft"]
    gb.input = "stage1.carrier"
    gb.tilt_deg = tilt_deg
    return gb


def cosim(sc, t_end: float, h: float):
    """The explicit co-simulation at communication step ``h`` (module docstring); ``(result,
    plant)``, the result None where it diverged."""
    c = couple(sc.turbine, sc.wind, sc.model, t_end, dt=sc.dt, **sc.drivetrain)
    plant, step, aero_dt = c.plant, c.first, c.aero_dt
    J = float(sc.model.bodies["rotor"].inertia)
    K = float(sc.model.bearings["main_shaft"].stiffness["theta"])
    y0 = c.stepper.values()  # the monolithic start: the drivetrain accelerating rigidly
    q0 = {k: float(v) for k, v in c.stepper.state[0].items() if k != "rotor.theta"}
    theta, w = y0["rotor.theta"], y0["rotor.theta.velocity"]
    s = c.settings
    gb = without_rotor(sc.model, sc.turbine.tilt_deg)
    carrier = [name for name in step.now if name != "rotor.torque"]
    st = gm.Stepper(gb, dt=sc.dt, method=s["method"], speed_rpm=s["rotor_speed0_rpm"],
                    azimuth0=c.stepper.settings["azimuth0"],
                    loads={**{n: step.now[n] for n in carrier}, **plant.constant_loads()},
                    drive=gm.Drive("stage1.carrier.theta", K, 0.0, angle0=theta, speed0=w),
                    speed_torque=plant.generator(), q0=q0, reference="follow",
                    rebase_speed=s["rebase_speed"], rebase_angle=s["rebase_angle"],
                    rebase_dt=aero_dt if h <= aero_dt else h,
                    top_frequency_hz=s["top_frequency_hz"],
                    outputs=["drive.torque", "generator.theta.velocity"], **s["options"])
    out = st.values()
    torque, w_gen = out["drive.torque"], out["generator.theta.velocity"]
    hs = min(h, aero_dt)  # the host's own step
    m_aero = round(aero_dt / hs)  # host steps per aerodynamic step
    n_host = round(h / hs)  # host steps per exchange
    n = round(t_end / h)
    j = 0  # host steps done
    w0 = w

    def at(f: float, name: str) -> float:  # the aerodynamic loads linear over its step
        a, b = step.now[name], step.loads[name]
        return a + f * (b - a)

    for i in range(1, n + 1):
        for _ in range(n_host):
            if j and j % m_aero == 0:  # an aerodynamic step starts: the plant's loads
                step = plant.step(j // m_aero, theta, w, w_gen)
                if plant.switched:
                    st.set_speed_torque(plant.generator())
            f = (j % m_aero) / m_aero
            w += hs * (at(f, "rotor.torque") - torque) / J  # semi-implicit Euler
            theta += hs * w
            j += 1
        f = 1.0 if j % m_aero == 0 else (j % m_aero) / m_aero
        out = st.advance(i * h, {name: at(f, name) for name in carrier},
                         drive_angle=theta, drive_speed=w)
        torque, w_gen = out["drive.torque"], out["generator.theta.velocity"]
        if not (math.isfinite(torque) and abs(w - w0) < 10 * max(w0, 1.0)):
            return None, plant
    return st.result(), plant


def settled(res) -> dict:
    """The four quantities of a run (module docstring)."""
    s = summarize(res)
    return {q: float(s[q]) for q in QUANTITIES}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", required=True)
    ap.add_argument("--quick", action="store_true")
    a = ap.parse_args()
    t_end = 4.0 if a.quick else 20.0
    sc = scene()
    rows = []
    t0 = time.process_time()
    ref = monolithic(sc, t_end)
    rq = settled(ref.gearbox)
    J = float(sc.model.bodies["rotor"].inertia)
    K = float(sc.model.bearings["main_shaft"].stiffness["theta"])
    w_s = math.sqrt(K / J)
    speed = lambda res: float(res.turbine.loads["rotor_speed_rpm"].iloc[-1])  # noqa: E731
    rows.append({"case": "monolithic", "step_ms": 0.0, "cpu_s": time.process_time() - t0,
                 "stable": True, "rotor_speed_rpm": speed(ref), **rq})
    t0 = time.process_time()
    alt = monolithic(sc, t_end, 1 + 1e-3)
    s = settled(alt.gearbox)
    rows.append({"case": "monolithic_1e-3", "step_ms": 0.0, "cpu_s": time.process_time() - t0,
                 "stable": True, "rotor_speed_rpm": speed(alt), **s,
                 **{f"err_{q}": (s[q] - rq[q]) / rq[q] if rq[q] else math.nan
                    for q in QUANTITIES}})
    print(rows[-1], flush=True)
    for h_ms in STEPS_MS:
        t0 = time.process_time()
        res, plant = cosim(sc, t_end, h_ms * 1e-3)
        # the rotor speed at the last aerodynamic step's start, as the monolithic run's table
        row = {"case": f"cosim_{h_ms}ms", "step_ms": h_ms, "cpu_s": time.process_time() - t0,
               "stable": res is not None,
               "rotor_speed_rpm": float(plant.table()["rotor_speed_rpm"].iloc[-1]),
               "omega_h": w_s * h_ms * 1e-3}
        if res is not None:
            s = settled(res)
            row.update(s)
            row.update({f"err_{q}": (s[q] - rq[q]) / rq[q] if rq[q] else math.nan
                        for q in QUANTITIES})
        rows.append(row)
        print(row, flush=True)
    df = pd.DataFrame(rows)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    df.to_csv(out / "turbine_coupling.csv", index=False)
    with pd.option_context("display.width", 200, "display.max_columns", 30):
        print(df.round(4).to_string(index=False))
    print("rotor-on-shaft frequency", w_s, "rad/s;", "np", np.__version__)


if __name__ == "__main__":
    main()
