"""Command line: ``gearmodal campbell|modal|info MODEL.toml``, ``gearmodal fmu MODEL.toml --out
FILE.fmu`` (:mod:`gearmodal.fmu`), ``gearmodal simulate SCENE.toml``
(a gearbox scene with loads, loads from an aeroelastic output file, or the turbine in wind
with the gearbox: see :mod:`gearmodal.scene`), ``gearmodal study NAME --out DIR`` (the
paper's studies in ``studies/``), ``gearmodal rate MODEL.toml --out DIR`` (ISO 6336 and ISO 281
ratings, :mod:`gearmodal.rating`).

Input errors (:class:`gearmodal.ModelError`, missing files) are printed as one line without a
traceback and the exit status is 2; a failed solve (:class:`gearmodal.SolveError`) exits with
4, a refused store (:class:`gearmodal.StoreError`) with 5.
"""

from __future__ import annotations

import argparse
import errno
import math
import os
import sys
from pathlib import Path

import numpy as np

from . import shipped
from .errors import ModelError, SolveError, StoreError, unknown
from .model.validate import plausible

#: the largest input speed (rpm) and number of speeds a Campbell sweep takes from the command
#: line (DESIGN 3.3 names 0-3000 rpm; a million speeds would run for days)
MAX_SPEED_RPM = 1e5
MAX_SPEEDS = 10_000


def _speeds(text: str) -> np.ndarray:
    try:
        a, b, n = text.split(":")
        a, b, n = float(a), float(b), int(n)
    except ValueError:
        raise ModelError("--speeds", f"= {text!r}: expected A:B:N, e.g. 0:30:61") from None
    if not (0 <= a < b <= MAX_SPEED_RPM) or not 2 <= n <= MAX_SPEEDS:
        raise ModelError("--speeds", f"= {text!r}: need 0 <= A < B <= {MAX_SPEED_RPM:g} rpm "
                         f"and 2 <= N <= {MAX_SPEEDS}")
    return np.linspace(a, b, n)


def _default_speeds(model) -> np.ndarray:
    top = None
    if model.speed_range_rpm:
        top = 1.2 * model.speed_range_rpm[1]
    elif model.rated_speed_rpm:
        top = 1.5 * model.rated_speed_rpm
    return np.linspace(0.0, top or 100.0, 61)


def _loads(args, model) -> dict | None:
    """``--load NAME=VALUE`` (repeatable) and ``--balance NAME`` into a loads dict."""
    loads = {}
    for item in args.load or []:
        name, sep, value = item.partition("=")
        try:
            loads[name.strip()] = float(value)
        except ValueError:
            raise ModelError("--load", f"= {item!r}: expected NAME=VALUE, e.g. "
                             "rotor.torque=2.6e5") from None
        if not sep:
            raise ModelError("--load", f"= {item!r}: expected NAME=VALUE")
        if not np.isfinite(loads[name.strip()]):
            raise ModelError("--load", f"= {item!r}: the value must be a finite number "
                             "(N or N m)")
        plausible(f"--load {name.strip()}", loads[name.strip()], "load")
        if name.strip() not in model.load_names:
            raise ModelError(f"--load {name.strip()}",
                             unknown("load", name.strip(), model.load_names))
    if args.balance:
        from .static import balance

        loads = balance(model, loads, on=args.balance)
    return loads or None


def _named(path: str, kind: str) -> str:
    """A file given by its path, or a shipped example by its name (``600kw``: the model
    ``models/600kw.toml`` of :func:`gearmodal.shipped.folder`)."""
    p = Path(path)
    if p.exists() or p.suffix or not path:
        return path
    found = shipped.find(path, kind)
    return str(found) if found is not None else path


def _load(path: str):
    from .model.toml_io import load

    path = _named(path, "models")
    if Path(path).suffix == ".toml":
        from .turbine.structure import is_elastic_turbine_file, load_elastic_turbine

        if is_elastic_turbine_file(path):  # the elastic turbine (issue 56)
            return load_elastic_turbine(path)
    return load(path)


def cmd_campbell(args) -> int:
    from tqdm import tqdm

    from .campbell import campbell
    from .modal import modal
    from .report import write_campbell_report

    model = _load(args.model)
    speeds = _speeds(args.speeds) if args.speeds is not None else _default_speeds(model)
    loads = _loads(args, model)
    with tqdm(total=len(speeds), desc="Campbell sweep", unit="speed",
              disable=args.quiet) as bar:
        camp = campbell(model, speeds, loads=loads, progress=lambda i, n: bar.update(1),
                        n_modes=args.n_modes, fmax_hz=args.fmax_hz)
    rated = model.rated_speed_rpm if model.rated_speed_rpm is not None else float(speeds[-1])
    res = modal(model, speed_rpm=rated, loads=loads, n_modes=args.n_modes, fmax_hz=args.fmax_hz)
    out = write_campbell_report(camp, res, args.out, summary=model.summary())
    print(f"wrote {out}/report.html")
    return 0


def cmd_modal(args) -> int:
    from .modal import modal
    from .report import write_modal_report

    model = _load(args.model)
    speed = args.speed if args.speed is not None else (model.rated_speed_rpm or 0.0)
    res = modal(model, speed_rpm=speed, loads=_loads(args, model), n_modes=args.n_modes,
                fmax_hz=args.fmax_hz)
    out = write_modal_report(res, args.out, summary=model.summary())
    print(f"wrote {out}/report.html")
    return 0


def cmd_rate(args) -> int:
    from .model import Model
    from .rating import rate
    from .rating.study import is_study

    if is_study(args.model):  # a fatigue study's output: its lifetime spectra
        from .rating.report import write_study_rating
        from .rating.study import rate_study

        table, settings = rate_study(args.model)
        out = write_study_rating(table, settings, args.out)
        low = table.groupby("variant", sort=False)[["S_H_spectrum", "S_F_spectrum"]].min()
        for v, row in low.iterrows():
            print(f"{v}: lowest S_H {row.S_H_spectrum:.3f}, lowest S_F {row.S_F_spectrum:.3f} "
                  "under its lifetime spectrum (first stage, ISO 6336-6)")
        print(f"wrote {out}/index.html")
        return 0
    model = _load(args.model)
    if not isinstance(model, Model):  # an elastic turbine: its gearbox
        if getattr(model, "gearbox", None) is None:
            raise ModelError(args.model, "has no gearbox model to rate (the deck's two-mass "
                             "drivetrain has no gears)")
        model = model.gearbox
    k_gamma = args.k_gamma
    if k_gamma is not None and k_gamma not in ("standard", "model"):
        try:
            k_gamma = float(k_gamma)
        except ValueError:
            raise ModelError("--k-gamma", f"= {args.k_gamma!r}: standard, model or a "
                             "number") from None
        if not 1.0 <= k_gamma <= 3.0:
            raise ModelError("--k-gamma", f"= {k_gamma!r}: must lie in [1, 3]")
    for name in ("torque", "life_h", "application_factor", "speed"):
        x = getattr(args, name)
        if x is not None and not (math.isfinite(x) and x > 0):
            raise ModelError(f"--{name.replace('_', '-')}", f"= {x!r}: must be a number > 0")
    run = None
    if args.run is not None:
        from .saved import load_run
        run = load_run(args.run)
    r = rate(model, args.torque, speed_rpm=args.speed, life_h=args.life_h,
             application_factor=args.application_factor, k_gamma=k_gamma, result=run,
             t_from=args.t_from)
    out = r.save(args.out)
    g = r.gears
    low = g.loc[g[["S_H", "S_F"]].min(axis=1).idxmin()]
    print(f"rated {len(g)} gears and {len(r.bearings)} bearings at "
          f"{r.settings['input_torque_Nm']:.4g} N m: lowest S_H {g.S_H.min():.3f}, "
          f"lowest S_F {g.S_F.min():.3f} (the lowest of both: {low.gear} in {low.mesh}); "
          f"wrote {out}/index.html")
    sp = r.spectrum
    if sp is not None and len(sp) and "S_H_spectrum" in sp:
        print(f"under the run's load spectrum: lowest S_H {sp.S_H_spectrum.min():.3f}, lowest "
              f"S_F {sp.S_F_spectrum.min():.3f} (ISO 6336-6; the run stands for the life)")
    return 0


def cmd_simulate(args) -> int:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from .scene import load_scene, settings

    scene = load_scene(_named(args.scene, "scenes"), overrides=settings(args.set))
    if args.t_end is not None:
        if not args.t_end > 0:
            raise ModelError("--t-end", f"= {args.t_end!r}: must be > 0 s")
        scene.t_end = args.t_end
        if scene.wind is not None and scene.wind.duration < args.t_end:
            scene.wind.duration = args.t_end + 1.0
    if args.output_dt is not None:
        if not (math.isfinite(args.output_dt) and args.output_dt > 0):
            raise ModelError("--output-dt", f"= {args.output_dt!r}: must be > 0 s")
        scene.dt = args.output_dt
    from tqdm import tqdm

    from .auto import fingerprint
    from .run import run

    # the tables stream to OUT while the run goes (constant memory), unless CSV is asked for
    # or the step ladder runs: its rungs are stored as they finish, by the scene's
    # fingerprint (the same command again resumes the ladder, another scene or --t-end into
    # the same OUT starts its own)
    auto = scene.method == "auto"
    store = Path(args.out) / "auto_rungs" / fingerprint(scene)[:16] if auto else None
    into = args.out if args.format == "parquet" and not auto else None
    bars = []  # made at the first report: a run that reports none shows no bar

    def progress(i, n):
        if not bars:
            bars.append(tqdm(total=n, desc="run", unit="step", disable=args.quiet))
        bars[0].update(i - bars[0].n)

    try:
        res = run(scene, progress=progress, out=into, store=store)
    finally:
        for bar in bars:
            bar.close()
    fmt = args.format
    if scene.wind is not None:
        scene.wind.release()  # the run is over: its turbulence box is not kept for the figures
    sim = res.gearbox
    out = res.save(args.out, fmt)
    if res.turbine is not None:
        for name, fig in (("drivetrain", res.plot()), ("turbine", res.turbine.plot())):
            fig.savefig(out / f"{name}.png", dpi=130)
            plt.close(fig)
    if res.choice is not None:
        choice = res.choice
        fig = choice.plot()
        fig.savefig(out / "auto.png", dpi=130)
        plt.close(fig)
        st = choice.settings
        loaded = int(choice.table["cached"].sum()) if "cached" in choice.table else 0
        print(f"auto: rung {choice.rung} of {len(choice.table)}"
              + (f" ({loaded} loaded from the store)" if loaded else "")
              + f", dt {st['dt']:.6g} s"
              + f" (within {choice.tol:g} of the next two finer rungs); wrote {out}/auto.csv")
    fig = sim.plot()
    fig.savefig(out / "forces.png", dpi=130)
    plt.close(fig)
    dc = sim.double_contact()
    dc.to_csv(out / "double_contact.csv", index=False)
    _write_load_sharing(sim, out, fmt)
    if res.turbine is not None:
        st = sim.stats  # the turbine run's clock, in its gearbox result's stats
        cut = res.turbine.cut_in_time
        power = res.turbine.view(["power_W"], max_rows=None)["power_W"]
        tail = power[power.index >= power.index[-1] / 2].mean() / 1e3
        print(f"cut-in at {cut:.2f} s" if cut is not None else "no cut-in", end="; ")
        print(f"mean power over the second half {tail:.0f} kW; "
              f"{st['realtime_ratio']:.2f} simulated s per CPU s (aero {st['aero_s']:.2g} s, "
              f"wind {st['wind_s'] + st['wind_setup_s']:.2g} s, gearbox "
              f"{st['gearbox_s']:.2g} s); wrote {out}/turbine_loads.{fmt}, drivetrain.png")
    print(f"{sim.stats['n_events']} contact events, {len(dc)} double-contact episodes, "
          f"{sim.stats['cpu_s']:.3g} s CPU; wrote {out}/events.{fmt}, forces.{fmt}, "
          "forces.png")
    return 0


def _write_load_sharing(sim, out: Path, fmt: str) -> None:
    """``load_sharing.<fmt>`` of a run with planets, written a chunk of rows at a time."""
    if not sim.meshes("sun_planet"):
        return
    if fmt == "csv":
        sim.load_sharing().to_csv(out / "load_sharing.csv", index_label="time")
        return
    from .result_io import TableWriter

    writer = None
    for chunk, _ in sim.load_sharing_chunks():
        if writer is None:
            writer = TableWriter(out, "load_sharing", list(chunk.columns))
        writer.append(chunk.index.to_numpy(dtype=float), chunk.to_numpy(dtype=float))
    if writer is not None:
        writer.close()


STUDIES = ("double-contact", "gravity-torque", "mounting-azimuth", "clearance-map",
           "load-sharing", "fatigue", "power-curve")


def _study_module(name: str, folder: str | None):
    """The study script ``<name>.py`` shipped with gearmodal (:func:`gearmodal.shipped.folder`; or
    ``--studies DIR``, or the environment variable GEARMODAL_STUDIES), imported as a module."""
    import importlib.util
    import os
    from pathlib import Path

    base = Path(folder or os.environ.get("GEARMODAL_STUDIES") or shipped.folder())
    path = base / f"{name.replace('-', '_')}.py"
    if not path.is_file():
        raise ModelError("--studies", f"= {str(base)!r}: no study script {path.name} there "
                         "(the studies ship with gearmodal as gearmodal.library)")
    mod_name = f"gearmodal_study_{name.replace('-', '_')}"
    spec = importlib.util.spec_from_file_location(mod_name, path)
    mod = importlib.util.module_from_spec(spec)
    # registered so that its functions pickle by reference into forked workers only (not
    # spawn or Dask): the studies therefore hand the sweep gearmodal callables
    sys.modules[mod_name] = mod
    spec.loader.exec_module(mod)
    return mod


def cmd_study(args) -> int:
    import inspect

    mod = _study_module(args.study, args.studies)
    params = inspect.signature(mod.run).parameters
    given = {"duration": args.duration, "seed": args.seed, "seeds": args.seeds,
             "step_deg": args.step, "max_workers": args.workers,
             "gravity": False if args.no_gravity else None,
             "top_frequency_hz": args.top_frequency, "quick": True if args.quick else None}
    flags = {"duration": "--duration", "seed": "--seed", "seeds": "--seeds", "step_deg": "--step",
             "max_workers": "--workers", "gravity": "--no-gravity",
             "top_frequency_hz": "--top-frequency", "quick": "--quick"}
    kwargs = {"progress": not args.quiet}
    if args.turbine is not None:
        if "turbine" not in params:
            raise ModelError("turbine", f"= {args.turbine!r}: the {args.study} study takes no "
                             "turbine name")
        kwargs["turbine"] = args.turbine
    for key, value in given.items():
        if value is None:
            continue
        if key not in params:
            raise ModelError(flags[key], f"the {args.study} study does not take it")
        if key in ("duration", "step_deg") and not value > 0:
            raise ModelError(flags[key], f"= {value!r}: must be > 0")
        if key == "top_frequency_hz" and not value >= 0:
            raise ModelError(flags[key], f"= {value!r}: a frequency > 0 Hz, or 0 for the "
                             "full model")
        if key == "seeds" and value < 1:
            raise ModelError(flags[key], f"= {value!r}: must be an integer >= 1")
        kwargs[key] = value
    if args.scheduler is not None:
        if "max_workers" not in params:
            raise ModelError("--scheduler", f"the {args.study} study runs no sweep of cases "
                             "to send to a cluster")
        if args.workers is not None:
            raise ModelError("--workers", "the cluster's workers run the cases: give "
                             "--scheduler or --workers, not both")
        from .studies import on_cluster

        with on_cluster(args.scheduler):
            summary = mod.run(args.out, **kwargs)
    else:
        summary = mod.run(args.out, **kwargs)
    with __import__("pandas").option_context("display.width", 160, "display.max_columns", 8):
        print(summary)
    print(f"wrote {args.out}/summary.csv and report.html")
    return 0


def _fraction(text: str) -> float:
    """A relative target from ``1%`` or ``0.01``."""
    t = str(text).strip()
    try:
        val = float(t[:-1]) / 100.0 if t.endswith("%") else float(t)
    except ValueError:
        raise ModelError("--target", f"= {text!r}: a relative error, as 1% or 0.01") from None
    if not (math.isfinite(val) and val > 0):
        raise ModelError("--target", f"= {text!r}: must be > 0 (1% or 0.01)")
    return val


def cmd_fidelity(args) -> int:
    import matplotlib

    matplotlib.use("Agg")
    from tqdm import tqdm

    from .precision import fidelity
    from .scene import load_scene, settings

    target = _fraction(args.target)
    scene = load_scene(_named(args.scene, "scenes"), overrides=settings(args.set))
    if scene.method == "auto":
        scene.method = "exact"  # the table runs its own settings
    bar = tqdm(total=None, desc="fidelity", unit="setting", disable=args.quiet)

    def progress(i, n):
        bar.total = n
        bar.update(i - bar.n)

    try:
        table = fidelity(scene, target=target, out=args.out, progress=progress)
    finally:
        bar.close()
    table.save(args.out)
    cols = ["setting", "status", "cpu_s", "n_events", "peak_error", "sampled_peak_error",
            "events_error", "double_contact_error"]
    with __import__("pandas").option_context("display.width", 160, "display.max_columns", 10,
                                             "display.float_format", "{:.3g}".format):
        print(table.to_frame()[cols].to_string(index=False))
    rec = table.recommend()
    print(f"recommended for {target:g}: "
          + (rec.setting if rec is not None else "none within the target")
          + f"; wrote {args.out}/fidelity.csv, fidelity.png, fidelity.json")
    return 0


def cmd_docs_figures(args) -> int:
    from .figures import check_out, docs_figures

    out = check_out(args.out)
    written = docs_figures(out, quick=args.quick, work=args.work, jobs=args.jobs,
                           progress=None if args.quiet else
                           lambda name, s: print(f"  {name}: {s:.1f} s", flush=True))
    print(f"wrote {len(written)} figures into {out}")
    return 0


def cmd_fmu(args) -> int:
    from .fmu import export_fmu

    drive = None
    if not args.drive and (args.drive_stiffness is not None or args.drive_damping):
        raise ModelError("--drive-stiffness", "and --drive-damping set the drive's spring: "
                         "they need --drive DOF (the rotation the host's shaft drives)")
    if args.rebase_dt is not None and args.reference != "follow":
        raise ModelError("--rebase-dt", f"= {args.rebase_dt!r}: re-basing is for "
                         "--reference follow (the reference is fixed here)")
    if args.drive:
        if args.drive_stiffness is None:
            raise ModelError("--drive-stiffness", "is needed with --drive (N m/rad)")
        drive = {"dof": args.drive, "stiffness": args.drive_stiffness,
                 "damping": args.drive_damping}
    out = export_fmu(_named(args.model, "models"), args.fmu_out, inputs=args.input,
                     outputs=args.output, drive=drive, dt=args.dt,
                     speed_rpm=args.speed_rpm, method=args.method, reference=args.reference,
                     rebase_dt=args.rebase_dt)
    print(f"wrote {out}")
    return 0


def cmd_info(args) -> int:
    model = _load(args.model)
    print(model.summary())
    print(f"DOFs ({len(model.dof_names)}; the names [q0] and [v0] take):")
    for n in model.dof_names:
        print(" ", n)
    names = model.assemble().load_names
    print(f"loads ({len(names)}; the names [loads] takes, N or N m):")
    for n in names:
        print(" ", n)
    return 0


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="gearmodal", description="Wind-turbine gearbox dynamics.",
                                epilog="--debug (anywhere): show the traceback of an internal "
                                       "error")
    from . import __version__

    p.add_argument("--version", action="version", version=f"gearmodal {__version__}")
    sub = p.add_subparsers(dest="command", required=True)
    c = sub.add_parser("campbell", help="Campbell diagram and modal report of a model file")
    c.add_argument("model", help="model file (TOML)")
    c.add_argument("--out", required=True, type=_out_folder, help="output folder")
    c.add_argument("--speeds", help="input speeds A:B:N in rpm (default 0 to 1.2 x range)")
    c.add_argument("--quiet", action="store_true", help="no progress bar")
    for sp in (c,):
        sp.add_argument("--load", action="append", metavar="NAME=VALUE",
                        help="a load in N or N m (repeatable): the modes are those of the "
                             "loaded contact state")
        sp.add_argument("--balance", metavar="NAME",
                        help="set this load so that the loads are in equilibrium")
    c.set_defaults(func=cmd_campbell)
    m = sub.add_parser("modal", help="modes at one speed, with report")
    m.add_argument("model")
    m.add_argument("--out", required=True, type=_out_folder)
    m.add_argument("--speed", type=float, help="input speed in rpm (default: rated)")
    m.add_argument("--load", action="append", metavar="NAME=VALUE",
                   help="a load in N or N m (repeatable)")
    m.add_argument("--balance", metavar="NAME", help="set this load to balance the others")
    for sp in (c, m):
        sp.add_argument("--n-modes", type=int, dest="n_modes", metavar="N",
                        help="a band: only the N lowest modes (default: every mode)")
        sp.add_argument("--fmax-hz", type=float, dest="fmax_hz", metavar="HZ",
                        help="a band: only the modes below HZ (default: every mode)")
    m.set_defaults(func=cmd_modal)
    sm = sub.add_parser("simulate", help="simulate a scene (model + loads + solver settings)")
    sm.add_argument("scene", help="scene file (TOML), see gearmodal/scene.py")
    sm.add_argument("--out", required=True, type=_out_folder, help="output folder")
    sm.add_argument("--t-end", type=float, dest="t_end", help="override the end time, s")
    sm.add_argument("--output-dt", type=float, dest="output_dt",
                    help="override the output step (the scene's dt), s: with the exact method "
                         "it only places the rows (the events, the exact peaks and the "
                         "solution do not depend on it), so a coarser one writes less; "
                         "newmark integrates at it; a turbine scene's must divide aero_dt")
    sm.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                    help="change a setting of the scene (repeatable), by the names of "
                         "gm.simulate: method=newmark, dt=1e-4, t_end=0.1, options.rtol=1e-3; "
                         "or any key of its tables: loads.NAME=VALUE, model.KEY=VALUE")
    sm.add_argument("--quiet", action="store_true", help="no progress bar")
    sm.add_argument("--format", choices=("parquet", "csv"), default="parquet",
                    help="the result tables' format (default parquet: written while the run "
                         "goes, in constant memory; csv: the run held in memory, then "
                         "written)")
    sm.set_defaults(func=cmd_simulate)
    fd = sub.add_parser("fidelity", help="the scene's work-precision table: every method "
                        "and setting, CPU time and error against the exact method")
    fd.add_argument("scene", help="scene file (TOML)")
    fd.add_argument("--out", required=True, type=_out_folder,
                    help="output folder (fidelity.csv, .png, .json; a rerun resumes)")
    fd.add_argument("--target", default="1%",
                    help="the error the recommended setting must stay within (default 1%%)")
    fd.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                    help="change a setting of the scene first (as for simulate)")
    fd.add_argument("--quiet", action="store_true", help="no progress bar")
    fd.set_defaults(func=cmd_fidelity)
    st = sub.add_parser("study", help="run one of the paper's studies (studies/*.py): "
                        + ", ".join(STUDIES))
    st.add_argument("study", choices=STUDIES)
    st.add_argument("turbine", nargs="?", help="the turbine a study runs on (power-curve: "
                    "nrel5mw; double-contact: 600kw, the default, or nrel5mw)")
    st.add_argument("--out", required=True, type=_out_folder,
                    help="output folder (its store/ makes a rerun resume)")
    st.add_argument("--duration", type=float, help="simulated time per case, s (turbine "
                    "studies: default 30 s, the paper's start-up, cut-in and operation; "
                    "fatigue: 600 s, --quick 60 s)")
    st.add_argument("--seed", type=int, help="turbulence seed (default 1)")
    st.add_argument("--seeds", type=int, help="number of turbulence seeds from --seed on, "
                    "the same for every case (double-contact, mounting-azimuth: default 1, "
                    "several give effects with 95 %% intervals; fatigue: default 6 per bin, as IEC "
                    "61400-1 asks for DLC 1.2)")
    st.add_argument("--step", type=float, help="azimuth step, deg (gravity-torque, "
                    "mounting-azimuth, load-sharing)")
    st.add_argument("--no-gravity", action="store_true", dest="no_gravity",
                    help="leave out the gearbox bodies' weight (double-contact, "
                         "mounting-azimuth; default: on)")
    st.add_argument("--quick", action="store_true", help="a short version: fewer bins, "
                    "seeds and seconds (fatigue)")
    st.add_argument("--top-frequency", type=float, dest="top_frequency", metavar="HZ",
                    help="mass-scaling rung: the gearbox's modes above HZ slowed to it "
                         "(turbine studies; default 500, its error in docs/guide/fidelity.md; "
                         "0: the full model, about 2x slower)")
    st.add_argument("--workers", type=int, help="parallel processes (default: CPU count)")
    st.add_argument("--scheduler", metavar="ADDRESS",
                    help="run the cases on the Dask scheduler at ADDRESS (tcp://host:8786; "
                         "the dask extra) instead of local processes")
    st.add_argument("--studies", help="folder of the study scripts (default: the source "
                    "tree's studies/)")
    st.add_argument("--quiet", action="store_true", help="no progress bar")
    st.set_defaults(func=cmd_study)
    d = sub.add_parser("docs-figures", help="write every figure of the documentation "
                       "(docs/ in the source tree), each by the command a user would run")
    d.add_argument("--out", required=True, type=_out_folder, help="output folder (docs)")
    d.add_argument("--quick", action="store_true", help="short runs and coarse grids "
                   "(checks that every figure is still written, not for docs/)")
    d.add_argument("--work", type=_out_folder, help="folder for the commands' own outputs "
                   "(default: a temporary one; given, a rerun resumes the studies)")
    d.add_argument("--jobs", type=int, default=1, metavar="N",
                   help="run N of the figures' commands at once (default 1)")
    d.add_argument("--quiet", action="store_true", help="no progress lines")
    d.set_defaults(func=cmd_docs_figures)
    f = sub.add_parser("fmu", help="the model as an FMI 2.0 co-simulation FMU (the fmu "
                       "extra; the host needs Python with gearmodal)")
    f.add_argument("model", help="model file (TOML)")
    f.add_argument("--out", required=True, dest="fmu_out", metavar="FILE.fmu",
                   help="the FMU to write")
    f.add_argument("--input", action="append", metavar="LOAD",
                   help="a load the host sets (repeatable; default: the torque on every "
                        "input and output wheel)")
    f.add_argument("--output", action="append", metavar="NAME",
                   help="an output (repeatable): a DOF, DOF.velocity, a force column, "
                        "drive.torque (default: the wheels' angles and speeds and every "
                        "force)")
    f.add_argument("--drive", metavar="DOF", help="the host's shaft drives this rotation "
                   "through a spring (inputs drive.angle, drive.speed; output drive.torque)")
    f.add_argument("--drive-stiffness", type=float, dest="drive_stiffness", metavar="K",
                   help="the drive's torsional stiffness, N m/rad")
    f.add_argument("--drive-damping", type=float, default=0.0, dest="drive_damping",
                   metavar="C", help="the drive's damping, N m s/rad (default 0)")
    f.add_argument("--dt", type=float, default=1e-4, help="output step, s (the parameter's "
                   "start value; a communication step must be a whole number of them; "
                   "default 1e-4)")
    f.add_argument("--speed-rpm", type=float, default=0.0, dest="speed_rpm",
                   help="input speed, rpm (the parameter's start value; default 0)")
    f.add_argument("--method", default="exact", choices=("exact", "newmark", "scipy"),
                   help="integration method (default exact)")
    f.add_argument("--reference", default="fixed", choices=("fixed", "follow"),
                   help="the reference rotation: fixed at --speed-rpm (default), or follow "
                        "the drivetrain (a host driving a planetary stage at a varying "
                        "speed; gm.Stepper)")
    f.add_argument("--rebase-dt", type=float, dest="rebase_dt", metavar="S",
                   help="with --reference follow: re-base every S seconds (default: at "
                        "every communication step)")
    f.set_defaults(func=cmd_fmu)
    ra = sub.add_parser("rate", help="ISO 6336 gear and ISO 281 bearing ratings of a model "
                                     "at its rated torque (the model's [rating] table)")
    ra.add_argument("model", help="model file (TOML) with a [rating] table, or a fatigue "
                    "study's output folder (gearmodal study fatigue --out DIR)")
    ra.add_argument("--out", required=True, type=_out_folder, help="output folder")
    ra.add_argument("--torque", type=float, help="input torque, N m (default: the table's "
                                                 "input_torque)")
    ra.add_argument("--speed", type=float, help="input speed, rpm (default: rated)")
    ra.add_argument("--life-h", type=float, dest="life_h", help="required life, h (default: "
                                                                "the table's, 20 years)")
    ra.add_argument("--application-factor", type=float, dest="application_factor",
                    help="K_A (default: the table's)")
    ra.add_argument("--k-gamma", dest="k_gamma", help="planets' K_gamma: standard (IEC "
                    "61400-4), model (the static equilibrium's) or a number")
    ra.add_argument("--run", metavar="DIR", help="a saved run of this model (gearmodal "
                    "simulate --out DIR): rate under its exact load spectrum too (ISO 6336-6)")
    ra.add_argument("--t-from", type=float, dest="t_from", default=0.0, metavar="S",
                    help="with --run: count the spectrum from this time on (default 0)")
    ra.set_defaults(func=cmd_rate)
    i = sub.add_parser("info", help="model summary and DOF names")
    i.add_argument("model")
    i.set_defaults(func=cmd_info)
    return p


#: errors of writing the output, reported in one line (not a bug of gearmodal)
_WRITE_ERRORS = {errno.EACCES, errno.EPERM, errno.EROFS, errno.ENOSPC, errno.EDQUOT,
                 errno.ENOTDIR, errno.EISDIR}


def _check_writable(folder: str) -> None:
    """``--out`` can be written: a folder (not a file), made if missing and a file created and
    removed in it; otherwise a :class:`ModelError` naming the folder and the cause."""
    from .result_io import file_in_the_way

    p = Path(folder)
    if (f := file_in_the_way(p)) is not None:
        raise ModelError("--out", f"= {folder!r} is a file, not a folder" if f == p else
                         f"= {folder!r}: cannot write there ({str(f)!r} is a file, not a "
                         "folder)")
    probe = p / f".gearmodal-write-test-{os.getpid()}"
    try:
        p.mkdir(parents=True, exist_ok=True)
        probe.write_bytes(b"")
        probe.unlink()
    except OSError as e:
        raise ModelError("--out", f"= {folder!r}: cannot write there ({e.strerror or e})") \
            from None


def _out_folder(value: str) -> str:
    """``--out``: a folder to write into, not empty (that it is a folder, made if missing,
    :func:`_check_writable` checks with gearmodal's one-line message)."""
    if not value or "\x00" in value:
        raise argparse.ArgumentTypeError(f"{value!r}: give an output folder")
    return value


class Terminated(KeyboardInterrupt):
    """SIGTERM (``kill``, a batch system's time limit), raised where the run is, so that it
    ends as Ctrl-C does: the sweep's workers ended, what was stored kept, one line."""


def _on_sigterm(signum, frame):
    raise Terminated()


def main(argv=None) -> int:
    """The command line; returns the exit status (0 done, 2 bad input, 3 internal error, 4 the
    solve failed, 5 a store refused, 130 interrupted, 143 terminated). Bad input gets one line
    naming the field; an internal error one line and a hint (``--debug`` shows its
    traceback)."""
    argv = list(sys.argv[1:] if argv is None else argv)
    debug = "--debug" in argv
    if debug:
        argv.remove("--debug")
    args = build_parser().parse_args(argv)
    import signal
    import threading

    previous = None
    if threading.current_thread() is threading.main_thread():
        previous = signal.signal(signal.SIGTERM, _on_sigterm)
    try:
        if getattr(args, "out", None):
            _check_writable(args.out)  # before any computing
        return args.func(args)
    except ModelError as e:
        print(f"gearmodal: error: {e}", file=sys.stderr)
        return 2
    except SolveError as e:
        print(f"gearmodal: the solve failed: {e}", file=sys.stderr)
        return 4
    except StoreError as e:
        print(f"gearmodal: store refused: {e}", file=sys.stderr)
        return 5
    except FileNotFoundError as e:
        print(f"gearmodal: error: {e.filename or e}: file not found", file=sys.stderr)
        return 2
    except KeyboardInterrupt as e:
        if isinstance(e, Terminated):
            print("gearmodal: terminated", file=sys.stderr)
            return 143
        print("gearmodal: interrupted", file=sys.stderr)
        return 130
    except Exception as e:
        if isinstance(e, OSError) and e.errno in _WRITE_ERRORS:
            # the output cannot be written (a full disk, a read-only folder): one line
            print(f"gearmodal: error: cannot write {e.filename or 'the output'}: "
                  f"{e.strerror}", file=sys.stderr)
            return 2
        if debug:  # a bug, not the input: one line, and how to see and report it
            raise
        print(f"gearmodal: internal error: {type(e).__name__}: {str(e)[:300]} (a bug: please "
              "report it with the command; add --debug for the traceback)", file=sys.stderr)
        return 3
    finally:
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
