"""A design-load-case set for the fatigue of the 600 kW gearbox (issue 22): IEC 61400-1 DLC 1.2
(power production in normal turbulence), the paper's two gearboxes.

Each case is the turbine of studies/scenes/600kw_turbine_10ms.toml on the grid from the start
(``connected``, 22.1 rpm), in Kaimal turbulence of the IEC normal turbulence model
(NTM, IEC 61400-1 ed. 3, 6.3.1.3)::

    sigma_1 = I_ref (0.75 V_hub + 5.6 m/s),    TI = sigma_1 / V_hub                       (D1)

at hub wind speeds from cut-in (4 m/s) to cut-out (24 m/s, the last bin reaching 25 m/s) in 2 m/s
bins, ``seeds`` turbulence seeds per bin (``SEEDS`` = 6 by default: IEC 61400-1 asks for at
least six 10-minute seeds per bin for DLC 1.2), for the ``reference`` gearbox and the ``clearance``
gearbox of studies/double_contact.py, both with the same seeds (paired). The first ``T_SKIP``
s of each run (the start's transient) are not counted. Per run (summary.csv):
:func:`gearmodal.fatigue.drivetrain_fatigue` (tooth and planet-bearing DELs at 1e7 cycles,
99th-percentile loads, the planet bearing's ISO 281 life).

The lifetime (lifetime.csv, spectra.csv): each bin's share of ``YEARS`` years from the
Rayleigh distribution of the wind class (IEC 61400-1 6.3.1.1, ``V_ave = 0.2 V_ref``)::

    P_bin = exp(-pi/4 (V_lo / V_ave)^2) - exp(-pi/4 (V_hi / V_ave)^2)                    (D2)

and every run's damage scaled from its duration to its bin's hours, averaged over the seeds::

    DEL_life = (sum_bins T_bin / n_seeds sum_seeds N_ref DEL_run^m / T_run / N_ref)^(1/m)  (D3)

(the lifetime DEL at N_ref = 1e7 cycles); the planet bearing's equivalent load over its
lifetime revolutions ``P_eq = (sum w N_run P_eq,run^p / sum w N_run)^(1/p)`` and
``L10h = (C / P_eq)^p 10^6 / (revolutions per hour)`` (ISO 281); the LDD (hours) and LRD
(rotor revolutions) of the rotor torque, tooth and planet-bearing force summed likewise; and
the first stage's gears rated under that lifetime LRD of the largest tooth force (ISO 6336-6,
:func:`ratings`): the lowest pitting and tooth-root safety factors ``S_H_stage1``,
``S_F_stage1``, with their clearance/reference ratios and intervals as the others'.

The gearboxes' lifetime ratios (lifetime_ratios.csv) come with a 95 % interval over the seeds:
the lifetime (D3) of each seed alone (its runs in every bin), both gearboxes on that seed, and
the paired ratio (C1) of :mod:`gearmodal.paired` over those per-seed lifetimes; the pooled
ratio (all seeds together, lifetime.csv) beside it.

The runs use the mass-scaling rung at 500 Hz by default (``top_frequency_hz``;
gearmodal.massscale): 2.2-2.7x faster than the full model on the 30 s double-contact runs.
On the reference gearbox its loads are within 0.05 % of the full model's. On the clearance
gearbox the paired-seed means agree within the seeds' scatter, and the planet-bearing DEL is
0.5-1 % low (benchmarks/RESULTS.md, rung ensemble). ``None`` or 0 (``--top-frequency 0``)
runs the full model.

Run: ``gearmodal study fatigue --out runs/fatigue [--quick] [--seeds N]``. ``--quick``: three
bins (6, 12, 18 m/s), one seed, 60 s runs. On gm.sweep: any executor (a Dask cluster's:
``run(out, executor=client.get_executor())``), resumable from ``out/store``.
"""

from __future__ import annotations

import functools
import json
import math
import os
import sys
from pathlib import Path

import numpy as np
import pandas as pd

import gearmodal as gm

sys.path.insert(0, str(Path(__file__).resolve().parent))
from double_contact import BEARING_C, CLEARANCE, ROWS_DT, SCENE, planet_spin  # noqa: E402

from gearmodal.fatigue import WOEHLER, drivetrain_fatigue  # noqa: E402
from gearmodal.massscale import STUDY_TOP_FREQUENCY_HZ, study_rung  # noqa: E402
from gearmodal.report import write_study_report  # noqa: E402
from gearmodal.studies import load_table  # noqa: E402

#: cut-in and cut-out hub wind speed of the 600 kW stall turbine (m/s; typical of the class)
V_IN, V_OUT = 4.0, 24.0
#: bin width (m/s)
BIN = 2.0
#: IEC 61400-1 wind classes: reference speed V_ref (m/s) and turbulence categories I_ref
V_REF = {"I": 50.0, "II": 42.5, "III": 37.5}
I_REF = {"A": 0.16, "B": 0.14, "C": 0.12}
#: design life, years, and hours per year
YEARS, HOURS = 20.0, 8766.0
#: start's transient not counted, s
T_SKIP = 5.0
#: turbulence seeds per bin by default (IEC 61400-1 ed. 3, 7.5: at least six 10-min seeds per
#: wind speed bin for DLC 1.2)
SEEDS = 6
#: the lifetime quantities whose ratio between the gearboxes gets an interval over the seeds
RATIOS = ("del_tooth_N", "del_planet_bearing_N", "del_rotor_torque_Nm", "planet_bearing_peq_N",
          "l10_planet_bearing_h", "S_H_stage1", "S_F_stage1")
#: the mesh groups rated under the lifetime spectrum of the largest tooth force (ISO 6336-6,
#: gearmodal.rating.rate_spectrum): the first stage's, whose flanks that spectrum counts
RATED = ("stage1.sun_planet", "stage1.ring_planet")
#: rotor speed of the connected start (rpm): synchronous 1800 rpm / 81.49
SPEED0_RPM = 22.1
VARIANTS = {"reference": {}, "clearance": {"model.stages.0.carrier_bearing": CLEARANCE}}
COLUMNS = ["variant", "wind_speed_mps", "seed", "turbulence_intensity", "del_tooth_N",
           "del_tooth_flank_N", "del_planet_bearing_N", "l10_planet_bearing_h",
           "del_rotor_torque_Nm", "p99_tooth_force_N", "p99_planet_bearing_force_N",
           "max_front_force_N", "mean_power_W", "duration_s", "planet_bearing_peq_N",
           "planet_bearing_revolutions", "cpu_s"]


def turbulence_intensity(v: float, category: str = "B") -> float:
    """(D1): the NTM's longitudinal turbulence intensity at hub speed ``v`` (m/s)."""
    return I_REF[category] * (0.75 * v + 5.6) / v


def bin_hours(speeds, wind_class: str = "II") -> np.ndarray:
    """(D2) times the design life: hours in each 2 m/s bin centred on ``speeds``."""
    v_ave = 0.2 * V_REF[wind_class]
    v = np.asarray(speeds, dtype=float)
    lo, hi = v - BIN / 2, v + BIN / 2
    p = np.exp(-math.pi / 4 * (lo / v_ave) ** 2) - np.exp(-math.pi / 4 * (hi / v_ave) ** 2)
    return p * YEARS * HOURS


def cases(speeds, seeds: list[int], duration: float, top_frequency_hz: float | None,
          category: str = "B") -> pd.DataFrame:
    """The sweep's cases (scene overrides), one row per variant, speed and seed."""
    rows = []
    for name, over in VARIANTS.items():
        for v in speeds:
            for sd in seeds:
                row = {"variant": name, "scene.t_end": duration, "wind.mean_speed": float(v),
                       "wind.turbulence_intensity": turbulence_intensity(v, category),
                       "wind.seed": int(sd), "turbine.connected": True,
                       "turbine.rotor_speed0_rpm": SPEED0_RPM, "scene.dt": ROWS_DT, **over}
                if top_frequency_hz is not None:
                    row["turbine.top_frequency_hz"] = float(top_frequency_hz)
                rows.append(row)
    return pd.DataFrame(rows)


def lifetime(runs: pd.DataFrame, spectra: dict, wind_class: str = "II") -> tuple:
    """(D3): the lifetime table per variant and the lifetime spectra, from the runs'
    rows and their ``spectra`` tables (keyed by the runs' index)."""
    mt, mb = WOEHLER["tooth_root"], WOEHLER["bearing"]
    speeds = np.sort(runs.wind_speed_mps.unique())
    hours = dict(zip(speeds, bin_hours(speeds, wind_class), strict=True))
    rows, parts = [], []
    for variant, g in runs.groupby("variant", sort=False):
        # per run: seconds of the lifetime it stands for (its bin's, shared by its seeds)
        n_seeds = g.groupby("wind_speed_mps").seed.transform("size")
        w = g.wind_speed_mps.map(hours) * 3600.0 / n_seeds / g.duration_s
        dmg = {m: float(np.sum(w * g[col] ** m)) for col, m in
               (("del_tooth_N", mt), ("del_planet_bearing_N", mb), ("del_rotor_torque_Nm", mt))}
        revs = float(np.sum(w * g.planet_bearing_revolutions))
        p_eq = float((np.sum(w * g.planet_bearing_revolutions * g.planet_bearing_peq_N ** mb)
                      / revs) ** (1 / mb))
        total_h = float(sum(hours.values()))
        l10_rev = (BEARING_C / p_eq) ** mb * 1e6
        rows.append({"variant": variant, "hours": total_h,
                     "del_tooth_N": (np.sum(w * g.del_tooth_N ** mt)) ** (1 / mt),
                     "del_planet_bearing_N": (np.sum(w * g.del_planet_bearing_N ** mb))
                     ** (1 / mb),
                     "del_rotor_torque_Nm": (np.sum(w * g.del_rotor_torque_Nm ** mt))
                     ** (1 / mt),
                     "planet_bearing_peq_N": p_eq,
                     "l10_planet_bearing_h": l10_rev / (revs / total_h),
                     "damage_tooth": dmg[mt]})
        for i, wi in w.items():
            parts.append(spectra[i].assign(variant=variant,
                                           hours=spectra[i].time_s * wi / 3600.0,
                                           revolutions=spectra[i].revolutions * wi))
    life = pd.DataFrame(rows).set_index("variant")
    life = life.drop(columns="damage_tooth")
    spec = (pd.concat(parts).groupby(["variant", "quantity", "level_low", "level_high"],
                                     sort=False)[["hours", "revolutions"]].sum().reset_index())
    for variant in life.index:
        for k, v in ratings(spec[spec.variant == variant], life.loc[variant, "hours"]).items():
            life.loc[variant, k] = v
    return life, spec


@functools.lru_cache(maxsize=1)
def _rated_model():
    from gearmodal.scene import load_scene

    return load_scene(SCENE).model


def ratings(spec: pd.DataFrame, hours: float) -> dict:
    """The lowest ISO 6336-6 safety factors of the first stage's gears (pitting ``S_H_stage1``,
    tooth root ``S_F_stage1``) under a variant's lifetime spectrum of the largest tooth force
    (every flank of the stage: conservative for each), over ``hours``; NaN without one. The
    clearance only changes a bearing, so both gearboxes are rated on the reference model's
    gears (gearmodal.rating.rate_spectrum: K_A = K_gamma = K_v = 1, the loads' own
    dynamics)."""
    from gearmodal.rating import rate_spectrum

    s = spec[spec.quantity == "tooth_force_N"]
    if s.empty or not (s.revolutions > 0).any():
        return {"S_H_stage1": math.nan, "S_F_stage1": math.nan}
    r = rate_spectrum(_rated_model(), s, meshes=list(RATED), hours=hours)
    return {"S_H_stage1": float(r.S_H_spectrum.min()), "S_F_stage1": float(r.S_F_spectrum.min())}


def lifetime_ratios(runs: pd.DataFrame, spectra: dict, wind_class: str = "II",
                    level: float = 0.95) -> pd.DataFrame:
    """The clearance gearbox's lifetime quantities over the reference's: the pooled ratio (all
    seeds, :func:`lifetime`) and the paired ratio (C1) over the per-seed lifetimes (each seed's
    runs alone in every bin) with its ``level`` interval, one row per quantity (columns
    ``pooled``, ``ratio``, ``low``, ``high``, ``n``, ``differs``); NaN intervals with one
    seed."""
    from gearmodal.paired import paired_ratio

    pooled, _ = lifetime(runs, spectra, wind_class)
    seeds = sorted(runs.seed.unique())
    per = {v: [] for v in ("reference", "clearance")}
    for sd in seeds:
        g = runs[runs.seed == sd]
        life, _ = lifetime(g, {i: spectra[i] for i in g.index}, wind_class)
        for v in per:
            per[v].append(life.loc[v])
    rows = []
    for q in RATIOS:
        a = [r[q] for r in per["clearance"]]
        b = [r[q] for r in per["reference"]]
        if not np.all(np.isfinite(np.concatenate([a, b]))):  # no spectrum to rate on
            rows.append({"quantity": q, "pooled": math.nan, "ratio": math.nan,
                         "low": math.nan, "high": math.nan, "n": len(a), "differs": False})
            continue
        pr = paired_ratio(a, b, level)
        rows.append({"quantity": q,
                     "pooled": float(pooled.loc["clearance", q] / pooled.loc["reference", q]),
                     "ratio": pr["ratio"], "low": pr["low"], "high": pr["high"],
                     "n": pr["n"], "differs": pr["differs"]})
    return pd.DataFrame(rows).set_index("quantity")


def _figure(runs: pd.DataFrame, spec: pd.DataFrame):
    import matplotlib.pyplot as plt

    fig, axs = plt.subplots(1, 3, figsize=(13, 4))
    for variant, g in runs.groupby("variant", sort=False):
        m = g.groupby("wind_speed_mps")
        axs[0].plot(m.del_tooth_N.mean().index, m.del_tooth_N.mean() / 1e3, "o-", label=variant)
        axs[1].plot(m.del_planet_bearing_N.mean().index, m.del_planet_bearing_N.mean() / 1e3,
                    "o-", label=variant)
        s = spec[(spec.variant == variant) & (spec.quantity == "planet_bearing_force_N")]
        axs[2].step(s.level_high / 1e3, np.cumsum(s.revolutions[::-1])[::-1], where="post",
                    label=variant)
    axs[0].set(xlabel="hub wind speed [m/s]", ylabel="tooth-root DEL at 1e7 cycles [kN]")
    axs[1].set(xlabel="hub wind speed [m/s]", ylabel="planet-bearing DEL at 1e7 cycles [kN]")
    axs[2].set(xlabel="planet-bearing force [kN]", ylabel="lifetime rotor revolutions above",
               yscale="log")
    for ax in axs:
        ax.grid(alpha=0.3)
        ax.legend()
    fig.tight_layout()
    return fig


def run(out, *, quick: bool = False, seed: int = 1, seeds: int | None = None,
        duration: float | None = None, top_frequency_hz: float | None = STUDY_TOP_FREQUENCY_HZ,
        wind_class: str = "II", turbulence_category: str = "B", executor=None,
        progress: bool = True, max_workers: int | None = None) -> pd.DataFrame:
    """Run the set (stored in ``out/store``, resumable) and write summary.csv (one row per
    run), lifetime.csv, lifetime_ratios.csv (with two or more seeds), spectra.csv,
    fatigue.png and report.html; returns the lifetime table. Defaults: 11 bins x ``SEEDS``
    (6) seeds x 600 s (``quick``: 3 bins x 1 seed x 60 s); ``executor``: any
    ``concurrent.futures.Executor`` (:func:`gearmodal.sweep`)."""
    if wind_class not in V_REF:
        raise gm.ModelError("wind_class", f"= {wind_class!r}: one of {', '.join(V_REF)}")
    if turbulence_category not in I_REF:
        raise gm.ModelError("turbulence_category",
                            f"= {turbulence_category!r}: one of {', '.join(I_REF)}")
    out = Path(out)
    top_frequency_hz = study_rung(top_frequency_hz)
    speeds = [6.0, 12.0, 18.0] if quick else list(np.arange(V_IN, V_OUT + 1e-9, BIN))
    n_seeds = seeds if seeds is not None else (1 if quick else SEEDS)
    duration = duration if duration is not None else (60.0 if quick else 600.0)
    if not duration > T_SKIP + 10.0:
        raise gm.ModelError("duration", f"= {duration!r}: must exceed {T_SKIP + 10:g} s (the "
                            f"first {T_SKIP:g} s are a transient)")
    spin = planet_spin()
    table = cases(speeds, [seed + k for k in range(n_seeds)], duration, top_frequency_hz,
                  turbulence_category)
    metrics = functools.partial(drivetrain_fatigue, bearing_C=BEARING_C, planet_spin=spin,
                                t_skip=T_SKIP)
    res = gm.sweep(SCENE, table.drop(columns="variant"), executor, store=out / "store",
                   metrics=metrics, progress=progress, max_workers=max_workers)
    res["variant"] = table.variant.to_numpy()
    res["wind_speed_mps"] = res["wind.mean_speed"]
    res["seed"] = res["wind.seed"]
    res["turbulence_intensity"] = res["wind.turbulence_intensity"]
    runs = res[COLUMNS].reset_index(drop=True)
    runs.to_csv(out / "summary.csv", index=False)
    spectra = {i: load_table(out / "store", cid, "spectra")
               for i, cid in enumerate(res.case_id)}
    life, spec = lifetime(runs, spectra, wind_class)
    if "reference" in life.index and "clearance" in life.index:
        life.loc["clearance / reference"] = life.loc["clearance"] / life.loc["reference"]
    life.to_csv(out / "lifetime.csv")
    spec.to_csv(out / "spectra.csv", index=False)
    # what `gearmodal rate DIR` needs to rate the set: the scene, relative to this folder
    (out / "study.json").write_text(json.dumps(
        {"study": "fatigue", "scene": os.path.relpath(SCENE, out.resolve())}, indent=1))
    ratios = None
    if n_seeds >= 2 and {"reference", "clearance"} <= set(runs.variant):
        ratios = lifetime_ratios(runs, spectra, wind_class)
        ratios.to_csv(out / "lifetime_ratios.csv")
    fig = _figure(runs, spec)
    rung = ("the full gearbox model" if top_frequency_hz is None else
            f"the mass-scaling rung at {top_frequency_hz:g} Hz (benchmarks/RESULTS.md)")
    write_study_report(out, "Fatigue of the 600 kW gearbox: IEC 61400-1 DLC 1.2", [
        f"{len(speeds)} hub wind speeds ({speeds[0]:g}-{speeds[-1]:g} m/s, {BIN:g} m/s bins) x "
        f"{n_seeds} seed(s) x {duration:g} s (the first {T_SKIP:g} s not counted), Kaimal "
        f"turbulence of the NTM, category {turbulence_category}; wind class {wind_class} "
        f"(Rayleigh, V_ave {0.2 * V_REF[wind_class]:g} m/s) over {YEARS:g} years; both "
        f"gearboxes with the same seeds; {rung}. DELs at 1e7 cycles, exponents: tooth root "
        f"{WOEHLER['tooth_root']}, bearing {WOEHLER['bearing']:.3g}; planet bearing "
        f"C = {BEARING_C / 1e6:.2f} MN (estimate).",
        ("h2", "Lifetime"), life,
        *((("h2", "Clearance / reference over the seeds (95 % interval of the paired ratio)"),
           ratios) if ratios is not None else ()),
        ("h2", "Runs"), runs.drop(columns="cpu_s"),
        ("fatigue.png", fig)])
    return life


if __name__ == "__main__":
    print(run(sys.argv[1] if len(sys.argv) > 1 else "runs/fatigue", quick=True))
