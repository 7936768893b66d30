"""The fidelity ladder on the paper's ``clearance`` case: what each rung costs and how far its
engineering quantities move.

Usage::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/fidelity.py [--quick] --out DIR

The case is the double-contact study's ``clearance`` gearbox (``studies/double_contact.py``:
the 600 kW turbine scene ``studies/scenes/600kw_turbine_10ms.toml``, 10 m/s TI 0.12 wind,
seed 1, carrier bearing 1e8 N/m with 1 mm clearance per axis), 30 s from 6 rpm through cut-in
(``--quick``: 15 s). Each rung changes one setting of the most detailed rung, ``reference``
(output step 1 ms, ``method="exact"``, the turning geometry integrated exactly: the scene's
own settings), through
the scene overrides of :func:`gearmodal.sweep` (cases stored in ``DIR/store``: an interrupted
run resumes, a rerun with more rungs reuses the finished ones).

Writes ``DIR/fidelity.csv``: one row per rung with ``rung``, ``knob``, ``setting``, ``cpu_s``,
``n_dofs``, ``n_events``, the quantities engineers use (``max_front_force_N`` of planet 1,
``max_planet_bearing_force_N``, ``double_contact_time_s``, ``peak_load_sharing_factor``), their
relative errors against ``reference`` (``err_<quantity>``; the double-contact time's error is
relative to the reference's too), and ``error`` for rungs that failed; and
``DIR/fidelity.png`` (error against CPU time per quantity).

The rung ``floor`` is the reference with the initial rotor speed changed by 1e-13 relative, a
perturbation at rounding level. The clearance case rattles chaotically after cut-in, so any
change of setting moves single-run peaks by about as much as this perturbation does: a rung's
error is meaningful only where it exceeds the floor's.

The carrier-bearing clearance is a per-axis dead band in the reference; the rungs
``clearance_polygon<N>x<M>`` make it round by N facets of M ramps each
(:mod:`gearmodal.model.clearance`). The exactly round clearance is nonlinear (``method="scipy"``
only) and cannot run the turbine case (its start is a static equilibrium, and an explicit
solver would need microsecond steps over 30 s); its comparison with the polygon is made on the
planetary stage alone (``benchmarks/clearance_shape.py``).
``--auto TOL`` runs ``method = "auto"`` (:func:`gearmodal.choose_fidelity`) on the same case
instead of the rungs: the step ladder from 4x the reference's ``dt`` down,
until a rung agrees within ``TOL`` with the next two finer ones (``DIR/auto.csv``).

The rung ``mesh_alternating`` makes every mesh's stiffness alternate between single and
double tooth-pair contact at its mesh frequency around the reference's constant stiffness as
its mean (``mesh_alternation = true`` on every stage, :mod:`gearmodal.model.mesh_stiffness`;
contact ratios from the gears). The DOF level of the gearbox stages is a rung
(``stages_dofs``): ``torsional`` (planets on their carrier pins, 15 DOF) and ``full`` (axial
and tilt DOFs too, 65 DOF; the clearance table then keeps the model file's axial and tilt
stiffness of the carrier bearing, ``CARRIER_TILT``). The model-reduction rungs
``top_frequency_<f>Hz`` run the mass-scaling rung (:mod:`gearmodal.massscale`, the scene key
``[turbine] top_frequency_hz``): mass added only along the loaded state's modes above ``f``,
so the kHz mesh modes no longer set the piece length while every gap stays exact (the
turbine studies' default is 500 Hz).
"""

from __future__ import annotations

import argparse
import os
import sys
import time
import tomllib
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "studies"))

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

import gearmodal as gm  # noqa: E402
from gearmodal.studies import summarize  # noqa: E402

SCENE = ROOT / "studies" / "scenes" / "600kw_turbine_10ms.toml"
QUANTITIES = ("max_front_force_N", "max_planet_bearing_force_N", "double_contact_time_s",
              "peak_load_sharing_factor")
REFERENCE = {"scene.dt": 1e-3}
#: the 600 kW model file's carrier bearing in the directions only the full level has
#: (z in N/m, rx and ry in N m/rad; studies/models/600kw.toml)
CARRIER_TILT = {k: v for k, v in tomllib.loads(
    (ROOT / "studies" / "models" / "600kw.toml").read_text(encoding="utf-8"))["stages"][0][
    "carrier_bearing"]["stiffness"].items() if k in ("z", "rx", "ry")}


def fidelity_metrics(result) -> dict:
    """The study's summary plus the gearbox's DOF count."""
    out = summarize(result)
    out["n_dofs"] = int(result.gearbox.q.shape[1])
    return out


def rungs(quick: bool) -> list[tuple[str, str, str, dict]]:
    """(rung, knob, setting, overrides on top of the reference)."""
    from double_contact import CLEARANCE

    out = [("reference", "-", "dt 1 ms, exact (Taylor, turning geometry exact)", {}),
           ("floor", "chaos floor", "rotor speed at start x (1 + 1e-13)",
            {"turbine.rotor_speed0_rpm": 6.0 * (1 + 1e-13)})]
    # the output step samples the peaks and holds the aerodynamic loads' interpolation; the
    # exact method finds every event whatever it is
    for dt in ((5e-4, 2e-3) if quick else (5e-4, 2e-3, 4e-3)):
        out.append((f"dt_{dt * 1e3:g}ms", "dt", f"{dt * 1e3:g} ms", {"scene.dt": dt}))
    # the model-reduction rung (gearmodal.massscale, (S1)): mass added along the loaded
    # state's modes above f_top, every gap exact; the turbine studies run on 500 Hz
    for f_top in ((500.0,) if quick else (500.0, 400.0)):
        out.append((f"top_frequency_{f_top:g}Hz", "mass scaling",
                    f"modes above {f_top:g} Hz slowed to it (every gap exact)",
                    {"turbine.top_frequency_hz": f_top}))
    out.append(("newmark", "method", "newmark, dt 1 ms", {"scene.method": "newmark"}))
    if not quick:
        out.append(("newmark_0.25ms", "method", "newmark, dt 0.25 ms",
                    {"scene.method": "newmark", "scene.dt": 2.5e-4}))
    for facets, ramps in (((16, 4),) if quick else ((16, 1), (16, 4), (32, 4))):
        out.append((f"clearance_polygon{facets}x{ramps}", "carrier clearance shape",
                    f"round by {facets} facets x {ramps} ramps (per-axis dead band in the "
                    "reference)",
                    {"model.stages.0.carrier_bearing": {
                        **CLEARANCE, "clearance_shape": "polygon", "facets": facets,
                        "ramps": ramps}}))
    out.append(("mesh_alternating", "mesh stiffness",
                "single/double tooth-pair alternation at the mesh frequency, every stage "
                "(constant mean stiffness in the reference)",
                {f"model.stages.{i}.mesh_alternation": True for i in range(3)}))
    if not quick:  # the gears are helical (overlap ratio ~1): a milder wave
        out.append(("mesh_alternating_1.2", "mesh stiffness",
                    "as mesh_alternating with double/single-pair stiffness 1.2 (not 1.75)",
                    {f"model.stages.{i}.mesh_alternation": {"stiffness_ratio": 1.2}
                     for i in range(3)}))
    for level in ("torsional", "full"):
        over = {f"model.stages.{i}.dofs": level for i in range(3)}
        if level == "full":  # the clearance table replaces the model file's carrier bearing:
            # keep that bearing's axial and tilt stiffness, which only the full level uses
            over["model.stages.0.carrier_bearing"] = {
                **CLEARANCE, "stiffness": {**CLEARANCE["stiffness"], **CARRIER_TILT}}
        out.append((f"dofs_{level}", "stages_dofs", f"all stages {level}", over))
    return out


def run_auto(tol: float, t_end: float, out: Path, clearance: dict) -> None:
    """``gm.choose_fidelity`` on the clearance case: writes ``DIR/auto.csv``, ``auto.json``,
    ``auto.png`` (rungs are run in this process, one after the other)."""
    import matplotlib

    matplotlib.use("Agg")
    from gearmodal.scene import load_scene

    sc = load_scene(SCENE, {"scene.t_end": t_end, "model.stages.0.carrier_bearing": clearance,
                            **REFERENCE})
    t0 = time.perf_counter()

    def show(level, st, row):
        print(f"rung {level}: " + ", ".join(f"{k} {v:.6g}" for k, v in st.items())
              + f", {row['cpu_s']:.1f} s CPU, " + ", ".join(f"{q} {row[q]:.6g}"
                                                          for q in QUANTITIES), flush=True)

    ch = gm.choose_fidelity(sc, tol, progress=show, store=out / "auto_rungs")
    ch.save(out)
    ch.plot().savefig(out / "auto.png", dpi=130)
    pd.set_option("display.width", 220)
    print(ch.table.to_string())
    print(f"met {ch.met}, rung {ch.rung}, settings {ch.settings}; wrote {out / 'auto.csv'} "
          f"({time.perf_counter() - t0:.0f} s)")


def plot(df: pd.DataFrame, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(QUANTITIES), figsize=(4.2 * len(QUANTITIES), 4.0))
    ok = df[df["error"].isna()] if "error" in df else df
    floor = ok[ok.rung == "floor"]
    for ax, qn in zip(axes, QUANTITIES, strict=True):
        col = f"err_{qn}"
        d = ok[(ok.rung != "reference") & ok[col].notna()]
        for r in d.itertuples():
            e = max(getattr(r, col), 1e-6)
            ax.loglog(r.cpu_s, e, "o", color="k" if r.rung != "floor" else "tab:red")
            ax.annotate(r.rung, (r.cpu_s, e), fontsize=6, xytext=(3, 2),
                        textcoords="offset points")
        if len(floor) and np.isfinite(floor[col].iloc[0]):
            ax.axhline(max(floor[col].iloc[0], 1e-6), color="tab:red", lw=0.8, ls="--",
                       label="chaos floor")
        ax.set_title(qn.replace("_", " "), fontsize=8)
        ax.set_xlabel("CPU time [s]")
        ax.set_ylabel("relative error vs reference")
        ax.grid(True, lw=0.3)
    axes[0].legend(fontsize=7)
    fig.suptitle("Fidelity ladder, paper's clearance case (benchmarks/fidelity.py)", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="15 s runs, fewer rungs")
    ap.add_argument("--out", required=True, type=Path)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--auto", type=float, metavar="TOL",
                    help="instead of the rungs: method = 'auto' (gm.choose_fidelity) with this "
                         "tolerance on the case, from 4x the reference's settings")
    args = ap.parse_args(argv)
    from double_contact import CLEARANCE

    out: Path = args.out
    out.mkdir(parents=True, exist_ok=True)
    t_end = 15.0 if args.quick else 30.0
    if args.auto is not None:
        return run_auto(args.auto, t_end, out, CLEARANCE)
    table = rungs(args.quick)
    cases = [{"scene.t_end": t_end, "model.stages.0.carrier_bearing": CLEARANCE, **REFERENCE,
              **over} for _, _, _, over in table]
    t0 = time.perf_counter()
    res = gm.sweep(str(SCENE), cases, store=out / "store", metrics=fidelity_metrics,
                   max_workers=args.workers, errors="record")
    res = res.reset_index(drop=True)
    rows = []
    for (name, knob, setting, _), (_, r) in zip(table, res.iterrows(), strict=True):
        row = dict(rung=name, knob=knob, setting=setting, cpu_s=r.get("cpu_s"),
                   n_dofs=r.get("n_dofs"), n_events=r.get("n_events"),
                   **{q: r.get(q) for q in QUANTITIES},
                   error=r.get("error") if isinstance(r.get("error"), str) else None)
        rows.append(row)
    df = pd.DataFrame(rows)
    ref = df[df.rung == "reference"].iloc[0]
    for q in QUANTITIES:
        df[f"err_{q}"] = (df[q] - ref[q]).abs() / abs(ref[q]) if ref[q] else np.nan
    df.to_csv(out / "fidelity.csv", index=False)
    plot(df, out / "fidelity.png")
    pd.set_option("display.width", 200)
    print(df[["rung", "cpu_s", "n_dofs", "n_events", *QUANTITIES,
              *[f"err_{q}" for q in QUANTITIES]]].to_string())
    print(f"wrote {out / 'fidelity.csv'} and {out / 'fidelity.png'} "
          f"({time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    main()
