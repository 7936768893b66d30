"""The paper's double-contact study on a turbine of today: the NREL 5 MW turbine (its OpenFAST
deck, ROSCO in the loop) on the 5 MW reference gearbox (``studies/models/nrel5mw.toml``), in
turbulent wind at 12 m/s (IEC class B, turbulence intensity 0.17), on paired seeds.

The cases differ only in stage 1's carrier bearing and the main shaft's support of the carrier:

- ``reference``: the file's carrier bearings (Nejad et al.'s PLC-A and PLC-B), no clearance;
- ``clearance``: the paper's fault scaled to this gearbox: a low bearing stiffness (1e8 N/m)
  and a radial clearance per axis of 3.3 times the stage's backlash (the 600 kW study's 1 mm
  against 0.3 mm), 4.5 mm;
- ``clearance_3point``: the same fault with the carrier no longer held by the rear main bearing
  (``shaft_bending`` 1e8 N/m instead of 1.2e10: the gearbox is the rear main bearing, as in the
  paper's three-point mount), so the shaft-end force goes through the carrier bearing.

Run: ``gearmodal study double-contact nrel5mw --out runs/double_contact_5mw [--seeds N]``
(``double_contact.run(out, turbine="nrel5mw")``). Writes runs.csv (one row per run),
summary.csv (means over the seeds), effects.csv (each case against the reference as a paired
ratio with its 95 % interval, gearmodal.paired) and report.html; the runs go to ``store/`` as
they finish (a rerun resumes).
"""

from __future__ import annotations

import functools
from pathlib import Path

import pandas as pd

import gearmodal as gm
from gearmodal.massscale import STUDY_TOP_FREQUENCY_HZ
from gearmodal.paired import paired_effects
from gearmodal.report import write_study_report
from gearmodal.summary import summarize
from gearmodal.turbine import nrel5mw

MODEL = Path(__file__).resolve().parent / "models" / "nrel5mw.toml"
#: the fault (module docstring): stage 1's carrier bearing, N/m and m
CLEARANCE = {"stiffness": {"x": 1.0e8, "y": 1.0e8}, "clearance": {"x": 4.5e-3, "y": 4.5e-3}}
#: the carrier's support by the main shaft without the rear main bearing, N/m
THREE_POINT = {"x": 1.0e8, "y": 1.0e8}
CASES = {"reference": {}, "clearance": {"stages.0.carrier_bearing": CLEARANCE},
         "clearance_3point": {"stages.0.carrier_bearing": CLEARANCE,
                              "shaft_bending.stiffness": THREE_POINT}}
WIND_SPEED, TURBULENCE = 12.0, 0.17
QUANTITIES = ["max_front_force_N", "max_planet_bearing_force_N", "peak_load_sharing_factor"]
COLUMNS = ["max_front_force_N", "max_back_force_N", "double_contact_time_s",
           "double_contact_two_planets_time_s", "max_planet_bearing_force_N",
           "peak_load_sharing_factor", "n_events", "mean_power_W", "cpu_s"]


def case(name: str, seed: int, duration: float, top_frequency_hz: float | None) -> dict:
    """One run: the gearbox of case ``name``, the turbulence of ``seed``; its summary
    (:func:`gearmodal.summary.summarize`) and CPU seconds."""
    gearbox = gm.load(MODEL, overrides=CASES[name])
    wind = nrel5mw.wind(WIND_SPEED, turbulence_intensity=TURBULENCE, seed=int(seed),
                        duration=duration + 5.0)
    res = nrel5mw.simulate(wind, duration, gearbox=gearbox, dt=0.0125,
                           top_frequency_hz=top_frequency_hz, turning_points=False)
    out = summarize(res)
    out["mean_power_W"] = float(res.turbine.loads["power_W"].mean())
    out["cpu_s"] = float(res.stats["cpu_s"])
    return out


def _row(result: dict) -> dict:
    return dict(result)


def effects(runs: pd.DataFrame, level: float = 0.95) -> pd.DataFrame:
    """Each fault case against the reference, per quantity, as a paired ratio over the seeds
    (gearmodal.paired, (C1))."""
    return paired_effects(runs, [(var, "reference", QUANTITIES)
                                 for var in ("clearance", "clearance_3point")], level)


def run(out, *, duration: float = 30.0, seed: int = 1, seeds: int = 3,
        top_frequency_hz: float | None = STUDY_TOP_FREQUENCY_HZ,
        max_workers: int | None = None,
        progress: bool = True) -> pd.DataFrame:
    """The three cases on ``seeds`` paired seeds from ``seed``, ``duration`` s each, on the
    mass-scaling rung ``top_frequency_hz`` (default 500 Hz, as the 600 kW study: tooth and
    bearing peaks within 0.1 % of the full model's on this turbine, benchmarks/RESULTS.md;
    ``None`` or 0: the full model)."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    top = top_frequency_hz or None
    table = pd.DataFrame([{"name": c, "seed": seed + k} for k in range(seeds) for c in CASES])
    res = gm.sweep(functools.partial(case, duration=duration, top_frequency_hz=top), table,
                   store=out / "store", metrics=_row, max_workers=max_workers,
                   progress=progress)
    res = res.rename(columns={"name": "case"})
    runs = res[["case", "seed", *[c for c in COLUMNS if c in res]]].reset_index(drop=True)
    runs.to_csv(out / "runs.csv", index=False)
    summary = runs.drop(columns="seed").groupby("case", sort=False).mean()
    summary["n_seeds"] = seeds
    summary.to_csv(out / "summary.csv")
    eff = effects(runs) if seeds > 1 else pd.DataFrame()
    eff.to_csv(out / "effects.csv", index=False)
    write_study_report(out, "Double contact in the NREL 5 MW drivetrain", [
        f"The NREL 5 MW turbine (ROSCO, the BEM rotor on its deck's blade) on the 5 MW "
        f"reference gearbox, {WIND_SPEED:g} m/s Kaimal turbulence (intensity {TURBULENCE:g}), "
        f"{duration:g} s from the controller's steady state, seeds {seed}-{seed + seeds - 1} "
        "paired (the same turbulence for every case), gravity on; "
        + ("the full gearbox model." if top is None else
           f"mass-scaling rung at {top:g} Hz.")
        + " The forces are the exact peaks of stage 1 (planet 1's flanks, every planet "
        "bearing); each effect the geometric-mean ratio over the seeds with its 95 % "
        "interval.", ("h2", "Effects"), eff, ("h2", f"Means over {seeds} seeds"), summary,
        ("h2", "Runs"), runs])
    return summary
