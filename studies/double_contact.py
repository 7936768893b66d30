"""The paper's coupled study (section 5, Figures 6-8): the 600 kW turbine in 10 m/s turbulent
wind, started at low rotor speed, cut in near 12 s, then in operation, with three gearboxes
that differ only in the carrier (rear main) bearing and the rotor mounting:

- ``reference``: the carrier bearing of 600kw.toml, no clearance;
- ``clearance``: a large carrier-bearing clearance (1 mm per axis) and a low bearing stiffness
  (1e8 N/m): the shaft-end force goes through the planets into the ring;
- ``clearance_rot60``: the same gearbox with the rotor mounted 60 deg further.

Run: ``gearmodal study double-contact --out runs/double_contact`` (or ``python
studies/double_contact.py OUT``). Writes summary.csv, events_<case>.csv, tooth_forces_<case>.png
and report.html.
"""

from __future__ import annotations

import functools
import math
import sys
import tomllib
from pathlib import Path

import pandas as pd

import gearmodal as gm
from gearmodal.massscale import STUDY_TOP_FREQUENCY_HZ, study_rung
from gearmodal.report import tooth_force_figure, write_study_report
from gearmodal.studies import load_table
from gearmodal.summary import SUMMARY_COLUMNS, summarize

HERE = Path(__file__).resolve().parent
SCENE = HERE / "scenes" / "600kw_turbine_10ms.toml"
#: the 'clearance' gearbox's carrier bearing (N/m, m): the studied fault, as defined once in
#: planetary_clearance.toml (1e8 N/m, 1 mm per axis)
CLEARANCE = tomllib.loads((HERE / "models" / "planetary_clearance.toml").read_text(
    encoding="utf-8"))["planetary_stage"]["carrier_bearing"]
COLUMNS = [*SUMMARY_COLUMNS, "cut_in_time_s", "mean_power_W", "cpu_s"]
#: the studies' output step (s): their row statistics (the p99 forces; this study's DELs, which
#: count the rows) were counted on 1 ms rows, finer than the scene's 2 ms
ROWS_DT = 1e-3
#: dynamic load rating of a planet's bearing set (N): two cylindrical roller bearings of
#: ~1.2 MN each as a pair, 2^(7/9) x 1.2 MN (ISO 281; estimate for the GRC planet bearings)
BEARING_C = 2.06e6
#: the fatigue quantities of every run (gearmodal.fatigue.drivetrain_fatigue, from t = 0)
FATIGUE_COLUMNS = ["del_tooth_N", "del_planet_bearing_N", "p99_tooth_force_N",
                   "p99_planet_bearing_force_N"]
#: the effects with confidence intervals over paired seeds: (variant, against, quantities)
EFFECTS = (("clearance", "reference", [*FATIGUE_COLUMNS, "max_front_force_N",
                                       "max_planet_bearing_force_N",
                                       "peak_load_sharing_factor"]),
           ("clearance_rot60", "clearance", [*FATIGUE_COLUMNS, "max_front_force_N",
                                             "max_planet_bearing_force_N"]))


def planet_spin() -> float:
    """Planet revolutions on its pin per rotor (carrier) revolution: z_ring / z_planet of the
    scene's first stage."""
    from gearmodal.scene import load_scene

    model = load_scene(SCENE).model
    ring = next(b for b in model.bodies.values() if b.role == "ring")
    planet = next(b for b in model.bodies.values() if b.role == "planet")
    return ring.teeth / planet.teeth


def metrics():
    """What every run reports: the double-contact summary with its tables and the fatigue
    quantities over the whole run (a gearmodal callable, so that it pickles to workers)."""
    return functools.partial(summarize, tables=True, fatigue={
        "bearing_C": BEARING_C, "planet_spin": planet_spin(), "t_skip": 0.0})


def effects(runs: pd.DataFrame, level: float = 0.95) -> pd.DataFrame:
    """Each effect of :data:`EFFECTS` as a paired ratio over the seeds (gearmodal.paired,
    (C1), (C2)): one row per variant, reference and quantity."""
    from gearmodal.paired import paired_effects

    return paired_effects(runs, EFFECTS, level)


def _nrel5mw():
    """The 5 MW study module beside this one (registered by name, so that its functions
    pickle into forked workers, as the CLI registers a study)."""
    import importlib.util

    name = "gearmodal_study_double_contact_nrel5mw"
    if name not in sys.modules:
        spec = importlib.util.spec_from_file_location(name, HERE / "double_contact_nrel5mw.py")
        mod = importlib.util.module_from_spec(spec)
        sys.modules[name] = mod
        spec.loader.exec_module(mod)
    return sys.modules[name]


def cases(duration: float = 30.0, seed: int = 1, gravity: bool = True,
          top_frequency_hz: float | None = None, dt: float | None = None) -> pd.DataFrame:
    """The three cases as scene overrides (one row each, indexed by ``case``); ``gravity``:
    the gearbox bodies' weight (on, as the scene's default); ``top_frequency_hz``: the
    mass-scaling rung (:mod:`gearmodal.massscale`; default: the full model); ``dt``: the
    output step, s (default :data:`ROWS_DT`, 1 ms)."""
    # the runs skip the exact turning points (+65-71 % gearbox CPU: the study would fall
    # below 20x real time), so its DELs count the 1 ms rows (dels_exact False; on the 30 s
    # clearance case 0.25 % below the exact count, benchmarks/exact_fatigue.py): the
    # fatigue study counts them exactly
    common = {"scene.t_end": duration, "wind.seed": seed, "turbine.gravity": gravity,
              "turbine.turning_points": False, "scene.dt": ROWS_DT if dt is None else dt}
    if top_frequency_hz is not None:
        common["turbine.top_frequency_hz"] = top_frequency_hz
    rows = {"reference": {**common, "turbine.mounting_azimuth_deg": 0.0},
            "clearance": {**common, "turbine.mounting_azimuth_deg": 0.0,
                          "model.stages.0.carrier_bearing": CLEARANCE},
            "clearance_rot60": {**common, "turbine.mounting_azimuth_deg": 60.0,
                                "model.stages.0.carrier_bearing": CLEARANCE}}
    df = pd.DataFrame.from_dict(rows, orient="index")
    df.index.name = "case"
    return df


def _verdicts(s: pd.DataFrame) -> list[str]:
    """The paper's claims against the numbers, in plain words."""
    ref, clr, r60 = s.loc["reference"], s.loc["clearance"], s.loc["clearance_rot60"]
    out = []

    def say(ok: bool, claim: str, numbers: str) -> None:
        out.append(f"<li><b>{'Agrees' if ok else 'Does not agree'}</b>: {claim} ({numbers})</li>")

    say(ref.max_back_force_N == 0 and ref.double_contact_time_s == 0,
        "the reference gearbox shows no back-flank forces, no double contact (Figure 6)",
        f"planet 1 back-flank force max {ref.max_back_force_N / 1e3:.1f} kN, double contact "
        f"{ref.double_contact_time_s:.3f} s")
    say(clr.double_contact_time_s > 0 and clr.max_back_force_N > 0,
        "a large carrier-bearing clearance with low stiffness causes double contact (Figure 7)",
        f"double contact {clr.double_contact_time_s:.2f} s, on two planets at once "
        f"{clr.double_contact_two_planets_time_s:.2f} s; back-flank max "
        f"{clr.max_back_force_N / 1e3:.0f} kN")
    say(clr.double_contact_two_planets_time_s > 0,
        "double contact on two planets at once is the mechanism of the load-sharing collapse "
        "(section 2)", f"{clr.double_contact_two_planets_time_s:.3f} s with the clearance, "
        f"{r60.double_contact_two_planets_time_s:.3f} s rotated 60 deg")
    ratio = clr.max_front_force_N / ref.max_front_force_N
    say(ratio > 1.1, "tooth forces increase significantly with the clearance (Figure 7)",
        f"planet 1 front-flank max {clr.max_front_force_N / 1e3:.0f} kN against "
        f"{ref.max_front_force_N / 1e3:.0f} kN, x{ratio:.2f}")
    rb = clr.max_planet_bearing_force_N / ref.max_planet_bearing_force_N
    say(rb > 1.1, "planet-bearing forces increase (section 5.1)",
        f"max {clr.max_planet_bearing_force_N / 1e3:.0f} kN against "
        f"{ref.max_planet_bearing_force_N / 1e3:.0f} kN, x{rb:.2f}")
    r6 = r60.max_front_force_N / clr.max_front_force_N
    say(r6 > 1.0, "mounting the rotor 60 deg further gives even larger tooth forces (Figure 8)",
        f"front-flank max {r60.max_front_force_N / 1e3:.0f} kN against "
        f"{clr.max_front_force_N / 1e3:.0f} kN, x{r6:.2f}; planet bearing x"
        f"{r60.max_planet_bearing_force_N / clr.max_planet_bearing_force_N:.2f}; one seed: "
        "single-run peaks of the rattling carrier scatter by several times between seeds and "
        "between equivalent mountings, see the mounting-azimuth study")
    say(clr.peak_load_sharing_factor > ref.peak_load_sharing_factor + 0.05,
        "load sharing between the planets collapses in double contact (section 2)",
        f"peak load-sharing factor {clr.peak_load_sharing_factor:.2f} against "
        f"{ref.peak_load_sharing_factor:.2f} (1 = equal; 1.5 = two planets carry all)")
    return out


def run(out, *, duration: float = 30.0, seed: int = 1, seeds: int | None = None,
        gravity: bool = True, executor=None, progress: bool = True,
        max_workers: int | None = None,
        top_frequency_hz: float | None = STUDY_TOP_FREQUENCY_HZ,
        dt: float | None = None, turbine: str = "600kw") -> pd.DataFrame:
    """Run the three cases (stored in ``out/store``, resumable) and write the outputs;
    ``gravity=False`` leaves out the gearbox bodies' weight; ``top_frequency_hz``: the
    mass-scaling rung the cases run on (default 500 Hz, :mod:`gearmodal.massscale`; its error
    in benchmarks/RESULTS.md), ``None`` or 0 the full model. ``seeds`` > 1: every case on each
    of the seeds ``seed, seed + 1, ...`` (paired: the same turbulence for the three cases),
    runs.csv (one row per run), summary.csv (means over the seeds), effects.csv (each effect
    as a ratio with its 95 % interval over the seeds, gearmodal.paired) and the paper's
    claims judged on the intervals. ``dt``: the output step, s (default
    :data:`ROWS_DT`, 1 ms).
    ``turbine="nrel5mw"``: the study on the NREL 5 MW turbine and its reference gearbox
    (``double_contact_nrel5mw.py``; 3 seeds by default)."""
    if turbine == "nrel5mw":
        return _nrel5mw().run(out, duration=duration, seed=seed, seeds=seeds or 3,
                              top_frequency_hz=study_rung(top_frequency_hz),
                              max_workers=max_workers, progress=progress)
    if turbine != "600kw":
        raise gm.ModelError("turbine", f"= {turbine!r}: one of 600kw, nrel5mw")
    seeds = 1 if seeds is None else seeds
    out = Path(out)
    top_frequency_hz = study_rung(top_frequency_hz)
    if seeds > 1:
        return _run_seeds(out, duration, seed, seeds, gravity, executor, progress,
                          max_workers, top_frequency_hz, dt)
    res = gm.sweep(SCENE, cases(duration, seed, gravity, top_frequency_hz, dt), executor,
                   store=out / "store", metrics=metrics(), progress=progress,
                   max_workers=max_workers)
    summary = res[[c for c in [*COLUMNS, *FATIGUE_COLUMNS] if c in res]]
    summary.to_csv(out / "summary.csv")
    forces = {c: load_table(out / "store", res.case_id[c], "forces") for c in res.index}
    ymax = max(float(f.filter(regex=r"planet1\.(front|back)$").max().max())
               for f in forces.values())
    blocks = [f"The 600 kW turbine in 10 m/s turbulent wind (seed {seed}, "
              f"{duration:g} s: start-up, cut-in, operation), coupled to the gearbox of "
              "studies/models/600kw.toml, gravity on every gearbox body "
              f"{'on' if gravity else 'off'}; only the carrier bearing and the rotor mounting "
              "differ between the cases. Forces are sampled at the 1 ms output times. "
              + ("The full gearbox model." if top_frequency_hz is None else
                 f"Mass-scaling rung: gearbox modes above {top_frequency_hz:g} Hz slowed to it "
                 "(its error: benchmarks/RESULTS.md)."),
              ("h2", "Summary"), summary, ("h2", "The paper's claims"),
              "<ul>" + "".join(_verdicts(summary)) + "</ul>"]
    for case in res.index:
        load_table(out / "store", res.case_id[case], "events").to_csv(
            out / f"events_{case}.csv", index=False)
        fig = tooth_force_figure(forces[case], f"{case}: planet 1 tooth forces", ymax_N=ymax,
                                 cut_in_s=summary.cut_in_time_s.get(case))
        blocks += [("h2", f"Case {case}"), (f"tooth_forces_{case}.png", fig)]
    write_study_report(out, "Double contact in the 600 kW gearbox (paper, section 5)", blocks)
    return summary


def _verdicts_ci(eff: pd.DataFrame, summary: pd.DataFrame, n: int) -> list[str]:
    """The paper's claims judged on the paired intervals over ``n`` seeds."""
    out = []

    def row(effect, q):
        return eff[(eff.effect == effect) & (eff.quantity == q)].iloc[0]

    def ci(r) -> str:
        return (f"x{r.ratio:.2f} [{r.low:.2f}, {r.high:.2f}]" if math.isfinite(r.low)
                else f"x{r.ratio:.2f}")

    def need(r) -> str:
        return (f"; {int(r.seeds_needed)} seeds decide it" if math.isfinite(r.seeds_needed)
                else "")

    def say(verdict: str, claim: str, numbers: str) -> None:
        out.append(f"<li><b>{verdict}</b>: {claim} ({numbers})</li>")

    ref = summary.loc["reference"]
    say("Holds" if ref.max_back_force_N == 0 and ref.double_contact_time_s == 0 else
        "Does not hold", "no back-flank forces and no double contact without clearance "
        "(Figure 6)", f"mean over {n} seeds: back-flank max {ref.max_back_force_N / 1e3:.1f} "
        f"kN, double contact {ref.double_contact_time_s:.3f} s")
    for q, claim in (("del_tooth_N", "tooth loads increase with the clearance (Figure 7): "
                      "tooth-root DEL"),
                     ("p99_tooth_force_N", "tooth loads increase with the clearance (Figure "
                      "7): 99th-percentile tooth force"),
                     ("del_planet_bearing_N", "planet-bearing loads increase (section 5.1): "
                      "DEL"),
                     ("p99_planet_bearing_force_N", "planet-bearing loads increase (section "
                      "5.1): 99th percentile")):
        r = row("clearance / reference", q)
        verdict = ("Holds" if r.differs and r.ratio > 1 else
                   "Opposite" if r.differs else "Not decided")
        say(verdict, claim, ci(r) + need(r))
    for q, claim in (("del_tooth_N", "the rotor mounted 60 deg further gives larger tooth "
                      "loads (Figure 8): DEL"),
                     ("p99_tooth_force_N", "the rotor mounted 60 deg further gives larger "
                      "tooth loads (Figure 8): 99th percentile"),
                     ("max_front_force_N", "the rotor mounted 60 deg further gives larger "
                      "tooth loads (Figure 8): the single-run peak the paper shows")):
        r = row("clearance_rot60 / clearance", q)
        verdict = ("Holds" if r.differs and r.ratio > 1 else
                   "Opposite" if r.differs else "Not decided")
        say(verdict, claim, ci(r) + need(r))
    return out


def _run_seeds(out: Path, duration, seed, seeds, gravity, executor, progress, max_workers,
               top_frequency_hz, dt=None) -> pd.DataFrame:
    """:func:`run` over ``seeds`` paired seeds."""
    one = cases(duration, seed, gravity, top_frequency_hz, dt)
    table = pd.concat([one.assign(**{"wind.seed": seed + k}) for k in range(seeds)])
    labels = table.index.to_numpy()
    res = gm.sweep(SCENE, table.reset_index(drop=True), executor, store=out / "store",
                   metrics=metrics(), progress=progress, max_workers=max_workers)
    res["case"] = labels
    res["seed"] = res["wind.seed"]
    cols = ["case", "seed", *[c for c in [*COLUMNS, *FATIGUE_COLUMNS] if c in res]]
    runs = res[cols].reset_index(drop=True)
    runs.to_csv(out / "runs.csv", index=False)
    summary = runs.drop(columns="seed").groupby("case", sort=False).mean()
    summary["n_seeds"] = seeds
    summary.to_csv(out / "summary.csv")
    eff = effects(runs)
    eff.to_csv(out / "effects.csv", index=False)
    first = res[res.seed == seed]
    forces = {c: load_table(out / "store", cid, "forces")
              for c, cid in zip(first.case, first.case_id, strict=True)}
    ymax = max(float(f.filter(regex=r"planet1\.(front|back)$").max().max())
               for f in forces.values())
    blocks = [f"The 600 kW turbine in 10 m/s turbulent wind, {duration:g} s (start-up, cut-in, "
              f"operation), on {seeds} paired seeds ({seed}-{seed + seeds - 1}: the same "
              "turbulence for the three cases), gravity "
              f"{'on' if gravity else 'off'}; "
              + ("the full gearbox model." if top_frequency_hz is None else
                 f"mass-scaling rung at {top_frequency_hz:g} Hz.")
              + " Each effect is the geometric-mean ratio over the seeds with its 95 % "
              "interval (gearmodal.paired, (C1)); 'seeds decide it': how many seeds the "
              "interval needs to exclude 1 with the spread seen (C2). DELs at 1e7 cycles over "
              "the whole run (tooth root m = 8.7, bearing 10/3).",
              ("h2", "The paper's claims on the intervals"),
              "<ul>" + "".join(_verdicts_ci(eff, summary, seeds)) + "</ul>",
              ("h2", "Effects"), eff, ("h2", f"Means over {seeds} seeds"), summary,
              ("h2", "Runs"), runs]
    for case, f in forces.items():
        fig = tooth_force_figure(f, f"{case}: planet 1 tooth forces (seed {seed})",
                                 ymax_N=ymax)
        blocks += [("h2", f"Case {case}, seed {seed}"), (f"tooth_forces_{case}.png", fig)]
    write_study_report(out, "Double contact in the 600 kW gearbox over paired seeds", blocks)
    return summary


if __name__ == "__main__":
    print(run(sys.argv[1] if len(sys.argv) > 1 else "runs/double_contact"))
