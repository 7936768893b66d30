"""Every figure of the documentation, written by one command: ``gearmodal docs-figures --out
docs`` (issue 23).

Each figure is what a user's own command writes (``gearmodal campbell 600kw``, ``gearmodal
simulate gear_rattle``, ``gearmodal study double-contact``, ...), run in a fresh process into
a work folder and copied under the name the documentation uses; the mode-shape drawings come
from :meth:`gearmodal.ModalResult.plot_shape` and :meth:`~gearmodal.ModalResult.animate_shape`.
``quick=True`` runs the same commands on short runs and coarse grids (seconds instead of
minutes; CI checks that every figure is still written), into a folder that is not ``docs/``.
"""

from __future__ import annotations

import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

from . import shipped
from .errors import ModelError


@dataclass(frozen=True)
class Figure:
    """One documentation figure: ``name`` in the docs folder, the ``gearmodal`` command that
    writes it (``args``, with ``quick`` added for a quick run) and the file it writes there."""

    name: str
    args: tuple[str, ...]
    writes: str
    quick: tuple[str, ...] = ()


#: the figures of docs/ (the README's are among them), in the order they are made
FIGURES: tuple[Figure, ...] = (
    Figure("600kw_campbell.png", ("campbell", "600kw"), "campbell.png",
           ("--speeds", "0:30:5")),
    Figure("600kw_campbell_low.png", ("campbell", "600kw"), "campbell_low.png",
           ("--speeds", "0:30:5")),
    Figure("nrel5mw_campbell_low.png", ("campbell", "nrel5mw", "--speeds", "0:13:27"),
           "campbell_low.png", ("--speeds", "0:13:3")),
    Figure("nrel5mw_elastic_campbell.png", ("campbell", "nrel5mw_elastic", "--speeds",
                                            "0:13:27"),
           "campbell_turbine.png", ("--speeds", "0:13:3")),
    Figure("gear_rattle_forces.png", ("simulate", "gear_rattle"), "forces.png",
           ("--t-end", "0.02")),
    Figure("planetary_double_contact_forces.png", ("simulate", "planetary_double_contact"),
           "forces.png", ("--t-end", "0.03")),
    Figure("600kw_turbine_drivetrain.png", ("simulate", "600kw_turbine_10ms"),
           "drivetrain.png", ("--t-end", "1")),
    Figure("double_contact_clearance.png", ("study", "double-contact"),
           "tooth_forces_clearance.png", ("--duration", "1")),
    Figure("gravity_torque.png", ("study", "gravity-torque"), "planet_forces.png",
           ("--step", "30")),
    Figure("mounting_azimuth.png", ("study", "mounting-azimuth", "--seeds", "5"),
           "mounting_azimuth.png", ("--duration", "1", "--step", "60", "--seeds", "1")),
    Figure("clearance_map.png", ("study", "clearance-map"), "clearance_map.png",
           ("--duration", "0.02")),
    Figure("load_sharing.png", ("study", "load-sharing"), "k_gamma.png", ("--step", "120")),
    Figure("fatigue_quick.png", ("study", "fatigue", "--quick"), "fatigue.png",
           ("--duration", "16")),
)

#: the mode-shape drawings: (file name, model, mode index at rated speed, animated too); the
#: housing translation near 10 Hz and a translational mode of the planetary stage
MODE_SHAPES: tuple[tuple[str, str, int, bool], ...] = (
    ("600kw_mode_housing", "600kw", 2, True),
    ("600kw_mode_planetary", "600kw", 7, False),
)


def _run(argv: list[str], log: Path) -> None:
    with open(log, "w") as f:
        rc = subprocess.run([sys.executable, "-m", "gearmodal", *argv], stdout=f,
                            stderr=subprocess.STDOUT).returncode
    if rc:
        tail = log.read_text().strip().splitlines()[-1:] or [""]
        raise RuntimeError(f"gearmodal {' '.join(argv)} failed (exit {rc}): {tail[0]}")


#: the interactive Campbell diagram of the 600 kW drivetrain (plotly, its script from the CDN)
INTERACTIVE = "600kw_campbell_interactive.html"


def interactive_campbell(folder: Path, path: Path) -> Path:
    """The interactive Campbell diagram of the saved Campbell result in ``folder`` as a page
    at ``path`` (plotly's script loaded from its CDN: a page of the documentation site)."""
    from .campbell import CampbellResult

    fig = CampbellResult.load(folder).plot_interactive(fmax_hz=60.0)
    # a fixed div id: the page is the same on every run (plotly draws a random one)
    fig.write_html(path, include_plotlyjs="cdn", full_html=True, div_id="campbell-interactive")
    return path


def mode_shapes(out: Path, frames: int = 16) -> list[Path]:
    """Draw :data:`MODE_SHAPES` (a PNG each, and the animated ones as a GIF) into ``out``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from .modal import modal
    from .model.toml_io import load

    written = []
    for name, model_name, i, animated in MODE_SHAPES:
        model = load(shipped.find(model_name, "models"))
        res = modal(model, speed_rpm=model.rated_speed_rpm or 0.0)
        fig = res.plot_shape(i)
        fig.savefig(out / f"{name}.png", dpi=110)
        plt.close(fig)
        written.append(out / f"{name}.png")
        if animated:
            written.append(res.animate_shape(i, out / f"{name}.gif", frames=frames, dpi=60))
    return written


def docs_figures(out, *, quick: bool = False, work=None, progress=None,
                 jobs: int = 1) -> list[Path]:
    """Write every documentation figure (:data:`FIGURES`, :data:`MODE_SHAPES`) into ``out``
    (the source tree's ``docs/`` for the real ones). ``quick``: short runs and coarse grids,
    for checking that every command still writes its figure. ``work``: the folder the
    commands write into (default: a temporary one; given, a rerun resumes the studies from
    their stores). ``progress(name, seconds)`` is called after each figure (the seconds of
    the command that wrote it). ``jobs``: how many of the commands run at once (each in its
    own process). Returns the paths written, in :data:`FIGURES` order."""
    if not (isinstance(jobs, int) and not isinstance(jobs, bool) and 1 <= jobs <= 64):
        raise ModelError("jobs", f"= {jobs!r}: an integer in [1, 64]")
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    tmp = None
    if work is None:
        tmp = tempfile.TemporaryDirectory(prefix="gearmodal-figures-")
        work = tmp.name
    work = Path(work)
    work.mkdir(parents=True, exist_ok=True)
    written: list[Path] = []
    try:
        # one run writes several figures (the Campbell pair): each command once
        runs: dict[tuple[str, ...], Path] = {}
        for fig in FIGURES:
            argv = [*fig.args, *(fig.quick if quick else ())]
            runs.setdefault(tuple(argv), work / "_".join(a.strip("-").replace(":", "-")
                                                         for a in argv))
        seconds = _run_all(runs, work, jobs)
        reported: set[tuple[str, ...]] = set()
        for fig in FIGURES:
            key = tuple([*fig.args, *(fig.quick if quick else ())])
            src = runs[key] / fig.writes
            if not src.is_file():
                raise RuntimeError(f"gearmodal {' '.join(key)} did not write {fig.writes}")
            shutil.copyfile(src, out / fig.name)
            written.append(out / fig.name)
            if progress:
                progress(fig.name, 0.0 if key in reported else seconds[key])
            reported.add(key)
        t0 = time.perf_counter()
        campbell_dir = runs[tuple([*FIGURES[0].args, *(FIGURES[0].quick if quick else ())])]
        written.append(interactive_campbell(campbell_dir, out / INTERACTIVE))
        if progress:
            progress(INTERACTIVE, time.perf_counter() - t0)
        t0 = time.perf_counter()
        written += mode_shapes(out, frames=8 if quick else 16)
        if progress:
            progress("mode shapes", time.perf_counter() - t0)
    finally:
        if tmp is not None:
            tmp.cleanup()
    return written


def _run_all(runs: dict[tuple[str, ...], Path], work: Path, jobs: int) -> dict:
    """Run each command of ``runs`` (argv -> its output folder), ``jobs`` at a time; the
    seconds each took. The first failure stops the commands not yet started and is raised."""
    def one(argv: tuple[str, ...]) -> float:
        t0 = time.perf_counter()
        folder = runs[argv]
        _run([*argv, "--out", str(folder), "--quiet"], work / f"{folder.name}.log")
        return time.perf_counter() - t0

    if jobs == 1:
        return {argv: one(argv) for argv in runs}
    from concurrent.futures import ThreadPoolExecutor

    ex = ThreadPoolExecutor(max_workers=jobs)
    try:
        futures = {argv: ex.submit(one, argv) for argv in runs}
        return {argv: f.result() for argv, f in futures.items()}
    finally:
        ex.shutdown(wait=True, cancel_futures=True)


def check_out(out) -> Path:
    """``--out`` of docs-figures: a folder, not a file."""
    p = Path(out)
    if p.exists() and not p.is_dir():
        raise ModelError("--out", f"= {str(out)!r} is a file, not a folder")
    return p
