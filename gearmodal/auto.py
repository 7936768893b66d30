"""``method="auto"``: the cheapest rung of the step ladder whose engineering quantities are
converged to a requested tolerance, chosen by running the ladder (issue "fidelity ladder",
item 3).

The rule
--------
Rung ``l = 0, 1, ...`` runs the scene with the exact method and its step ``dt`` multiplied by
``coarsest / 2^l``: rung 0 is ``coarsest`` times coarser than the scene, each next rung halves
it (a turbine scene's ``dt`` snapped to the nearest whole fraction of its aerodynamic step).
The exact method finds every event whatever ``dt``; the step sets the output sampling of the
peaks and, in a turbine scene, the load hold between aerodynamic steps. Of every rung
the quantities engineers use are taken (:data:`QUANTITIES`, from
:func:`gearmodal.summary.summarize`), and

    d(l, m) = max over the quantities of |Q_l - Q_m| / |Q_m|                          (A1)

is rung ``l``'s difference from a finer rung ``m`` (a quantity that is zero, or undefined, in
both counts as agreeing; in one only, as infinitely far). The choice is the **cheapest rung
that agrees within ``tol`` with each of the next two finer rungs**:

    l* = min { l : d(l, l + 1) <= tol  and  d(l, l + 2) <= tol }                      (A2)

Rungs are run from the coarsest until (A2) holds or ``levels`` rungs have run. Two finer
rungs, not one, because a single agreement can be chance where coarse rungs drive spurious
dynamics (an earlier, refrozen geometry kicked the paper's carrier floating in its clearance
into a rattle above a threshold angle that moved from run to run): a coarse pair can agree
while both are wrong. With the
converged quantities changing geometrically from rung to rung, (A2) bounds rung ``l*``'s
distance from the finest rung run by ``tol``, and from the limit by about ``tol`` for any
convergence faster than linear in the step.

What it cannot do: a scene whose quantities are not reproducible to ``tol`` (a chaotic
rattle: two runs differing by rounding move single-run peaks by ~1-2 % on the paper's
turbine case) never satisfies (A2); the choice then reports ``met = False`` with the table of
what was run, and a scene run with ``method = "auto"`` raises naming ``scene.tolerance``.
The ladder refines the numerical settings only; the model's own fidelity (clearance shape,
DOF level) is the scene's choice.

Resume: with ``store=DIR`` every rung's settings, CPU time and summary are written to
``DIR/rung<l>.json`` as it finishes (atomically), its result to ``DIR/rung<l>/``
(``result.save``; only the last three rungs', which can still be chosen), under the scene's
fingerprint (SHA-256 of the scene's canonical text, ``DIR/auto_store.json``). Started again on
the same scene and store, the ladder loads the finished rungs and runs only the others; a
different scene (or a different ``coarsest``) is refused, as is a store of an older layout.
The chosen rung's result is loaded from the store (``load``); a stored summary that its result
no longer reproduces raises naming ``store``.
"""

from __future__ import annotations

import copy
import json
import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from .errors import ModelError, StoreError
from .saved import load_run
from .single import one_run
from .store import Store
from .summary import summarize

#: the quantities of the paper's double-contact study compared between rungs
QUANTITIES = ("max_front_force_N", "max_planet_bearing_force_N", "double_contact_time_s",
              "peak_load_sharing_factor")
#: default tolerance of ``method = "auto"`` (relative, on every quantity)
DEFAULT_TOL = 0.05
#: default largest number of rungs run
LEVELS = 6


def difference(a: dict, b: dict, quantities=QUANTITIES) -> float:
    """(A1): the largest relative difference of the quantities of ``a`` from those of ``b``
    (the finer rung)."""
    worst = 0.0
    for q in quantities:
        x, y = float(a.get(q, math.nan)), float(b.get(q, math.nan))
        if not (math.isfinite(x) and math.isfinite(y)):
            d = 0.0 if (math.isnan(x) and math.isnan(y)) else math.inf
        elif x == 0.0 or y == 0.0:
            d = 0.0 if x == y else math.inf
        else:
            d = abs(x - y) / abs(y)
        worst = max(worst, d)
    return worst


def _settings(scene) -> dict:
    """The scene's refinable settings: its step ``dt`` (the turning geometry is exact, so
    there is no refreeze angle to refine)."""
    return {"dt": float(scene.dt)}


def _rung_settings(scene, base: dict, f: float) -> dict:
    """Rung settings at factor ``f`` of the scene's. A turbine scene's ``dt`` must divide its
    aerodynamic step: it is snapped to the nearest whole fraction of it (``aero_dt / m``)."""
    st = {k: v * f for k, v in base.items()}
    if scene.turbine is not None:
        aero = float(scene.drivetrain.get("aero_dt", 0.02))
        m = max(1, round(aero / st["dt"]))
        st["dt"] = aero / m
    return st


def fingerprint(scene) -> str:
    """SHA-256 of the scene's inputs as canonical text (:meth:`gearmodal.scene.Scene.identity`:
    the dumped model and scene, the turbine's data) without what does not change a rung's run
    (the file it was loaded from, ``method``, ``tolerance``): what a :func:`choose` store is
    keyed by. Independent of the library version and of the files' comments and layout.
    Raises :class:`ModelError` naming ``store`` when the scene cannot be written as text
    (e.g. a load given as a function)."""
    sc = copy.copy(scene)
    for attr, neutral in (("source", ""), ("method", "exact"), ("tolerance", 0.05)):
        if hasattr(sc, attr):
            setattr(sc, attr, neutral)
    try:
        return sc.identity()
    except (ModelError, AttributeError, TypeError) as err:
        raise StoreError("store", "the scene cannot be fingerprinted for a resumable store "
                         f"({type(err).__name__}: {err}); give its loads as constants, "
                         "waves or a [load_file], or run without a store") from None


#: the layout of a store; a store of another layout (an older gearmodal) is refused
STORE_FORMAT = "gearmodal.auto/3"  # /2: the identity at the meta file's top level (read)


class _Store:
    """The rungs of one ladder on disk (layout in the module docstring), in a
    :class:`gearmodal.store.Store`."""

    def __init__(self, directory, ident: dict):
        self.store = Store(directory, meta="auto_store.json", format=STORE_FORMAT,
                           identity=ident, older=("gearmodal.auto/2",))
        self.dir = self.store.dir
        self.store.clean()
        self.store.write_meta()

    def load(self, level: int, settings: dict) -> dict | None:
        d = self.store.read_json(f"rung{level}.json")
        if d is None:
            return None
        if any(not math.isclose(d["settings"].get(k, math.nan), v, rel_tol=1e-12)
               for k, v in settings.items()):
            return None  # a guard (scene and coarsest, in the identity, pin them): rerun
        return d

    def save(self, level: int, settings: dict, cpu: float, summary: dict,
             result=None) -> None:
        """Store a finished rung: its result first (``rung<l>/``, whole), then its summary
        (``rung<l>.json``, which marks the rung done)."""
        if result is not None:
            self.store.put(f"rung{level}", result.save)
        clean = {k: (float(v) if isinstance(v, (int, float, np.floating, np.integer))
                     else None) for k, v in summary.items()}
        self.store.write_json(f"rung{level}.json",
                              {"settings": settings, "cpu_s": cpu, "summary": clean})

    def result(self, level: int):
        """The stored result of a rung, or None."""
        path = self.dir / f"rung{level}"
        return load_run(path) if path.is_dir() else None

    def drop(self, level: int) -> None:
        """Forget a rung's result (it can no longer be chosen); its summary stays."""
        self.store.drop(f"rung{level}")


def _rung_scene(scene, settings: dict):
    sc = copy.copy(scene)
    sc.method = "exact"
    sc.dt = settings["dt"]
    sc.drivetrain = dict(scene.drivetrain)
    sc.options = dict(scene.options)
    return sc


@dataclass
class FidelityChoice:
    """What :func:`choose` ran and chose.

    Attributes
    ----------
    met : whether a rung satisfied the rule (A2).
    rung : index of the chosen rung in ``table`` (``None`` if not ``met``).
    settings : the chosen rung's settings (``dt`` in s), to put in the scene for further
        runs.
    result : the chosen rung's result (``None`` if not ``met``).
    table : one row per rung run: ``rung``, ``dt``, ``cpu_s``,
        ``n_events``, the quantities, ``diff_next`` = d(l, l + 1) and ``diff_next2`` =
        d(l, l + 2) of (A1) (NaN where that rung was not run), ``chosen``, ``cached``
        (loaded from the store, not run).
    tol : the tolerance asked for.
    results : every rung's result, in rung order (only with ``keep_all=True``).
    """

    met: bool
    rung: int | None
    settings: dict
    result: object
    table: pd.DataFrame
    tol: float
    quantities: tuple = QUANTITIES
    results: list = field(default_factory=list, repr=False)

    def to_frame(self) -> pd.DataFrame:
        return self.table.copy()

    def save(self, directory) -> Path:
        """Write ``auto.csv`` (the table) and ``auto.json`` (tolerance, rule, choice)."""
        d = Path(directory)
        d.mkdir(parents=True, exist_ok=True)
        self.table.to_csv(d / "auto.csv", index=False)
        (d / "auto.json").write_text(json.dumps(
            {"tol": self.tol, "met": self.met, "rung": self.rung, "settings": self.settings,
             "quantities": list(self.quantities),
             "rule": "cheapest rung within tol of each of the next two finer rungs "
                     "(gearmodal/auto.py, A1-A2)"}, indent=2))
        return d

    def plot(self, ax=None):
        """Each quantity against the rung's step, relative to the finest rung run; the
        tolerance band and the chosen rung marked. Returns the matplotlib Figure."""
        import matplotlib.pyplot as plt

        if ax is None:
            fig, ax = plt.subplots(figsize=(6.5, 4.0))
        else:
            fig = ax.figure
        t = self.table
        for q in self.quantities:
            ref = t[q].iloc[-1]
            if ref and np.isfinite(ref):
                ax.plot(t["dt"], t[q] / ref, "o-", label=q, lw=1)
        ax.axhspan(1 - self.tol, 1 + self.tol, color="0.9", zorder=0, label=f"tol {self.tol:g}")
        if self.rung is not None:
            ax.axvline(t["dt"].iloc[self.rung], color="k", lw=0.8, ls="--", label="chosen")
        ax.set_xscale("log")
        ax.set_xlabel("dt [s]")
        ax.set_ylabel("quantity / finest rung")
        ax.legend(fontsize=7)
        fig.tight_layout()
        return fig


def choose(scene, tol: float = DEFAULT_TOL, *, coarsest: float = 4.0, levels: int = LEVELS,
           quantities=QUANTITIES, progress=None, keep_all: bool = False,
           store=None) -> FidelityChoice:
    """Run the step ladder of ``scene`` from ``coarsest`` times its settings and choose the
    cheapest rung converged to ``tol`` by rule (A2) of :mod:`gearmodal.auto`.

    Parameters
    ----------
    scene : a :class:`gearmodal.scene.Scene` (its ``dt`` is the scale;
        its method is replaced by ``"exact"``).
    tol : relative tolerance on every quantity, > 0 (0.05 = 5 %).
    coarsest : rung 0's settings are this many times the scene's (>= 1).
    levels : at most this many rungs are run (3 to 12); each halves the previous one's.
    quantities : keys of :func:`gearmodal.summary.summarize` compared.
    progress : ``progress(rung, settings, row)`` after each rung (CLI, studies).
    keep_all : keep every rung's result in ``choice.results`` (memory: a turbine run each);
        by default only the chosen one is kept. Rungs loaded from ``store`` have ``None``.
    store : directory; each rung is written there as it finishes and a ladder started again
        with the same scene and store resumes (module docstring, "Resume"). The table's
        ``cached`` column says which rungs were loaded.
    """

    if not isinstance(tol, (int, float)) or isinstance(tol, bool) or not 0 < tol < 10:
        raise ModelError("tol", f"= {tol!r}: must be a relative tolerance in (0, 10)")
    if not isinstance(coarsest, (int, float)) or not coarsest >= 1:
        raise ModelError("coarsest", f"= {coarsest!r}: must be a factor >= 1")
    if not isinstance(levels, int) or isinstance(levels, bool) or not 3 <= levels <= 12:
        raise ModelError("levels", f"= {levels!r}: must be an integer from 3 to 12")
    # every use of the scene first (its rungs' settings and scenes, its fingerprint), then
    # the store and the runs
    base = _settings(scene)
    rung_settings = [_rung_settings(scene, base, coarsest / 2.0**level)
                     for level in range(levels)]
    rung_scenes = [_rung_scene(scene, st) for st in rung_settings]
    ident = None if store is None else {"scene_sha256": fingerprint(scene),
                                        "coarsest": float(coarsest)}
    disk = None if store is None else _Store(store, ident)
    rows, results, summaries = [], [], []
    chosen = None
    for level in range(levels):
        st = rung_settings[level]
        got = None if disk is None else disk.load(level, st)
        if got is not None:
            res, cpu = None, float(got["cpu_s"])
            summ = {k: (math.nan if v is None else v) for k, v in got["summary"].items()}
            if isinstance(summ.get("n_events"), float) and summ["n_events"].is_integer():
                summ["n_events"] = int(summ["n_events"])
        else:
            t0 = time.process_time()
            res = one_run(rung_scenes[level])
            cpu = time.process_time() - t0
            summ = summarize(res)
            if disk is not None:
                disk.save(level, st, cpu, summ, res)
        results.append(res)
        summaries.append(summ)
        if not keep_all and level >= 3:
            results[level - 3] = None  # only the last three rungs can still be chosen
            if disk is not None:
                disk.drop(level - 3)
        rows.append({"rung": level, **st, "cpu_s": cpu, "n_events": summ.get("n_events"),
                     **{q: summ.get(q, math.nan) for q in quantities},
                     "cached": got is not None})
        if progress is not None:
            progress(level, st, rows[-1])
        if level >= 2:
            cand = level - 2
            if (difference(summaries[cand], summaries[cand + 1], quantities) <= tol
                    and difference(summaries[cand], summaries[cand + 2], quantities) <= tol):
                chosen = cand
                break
    n = len(rows)
    for i, r in enumerate(rows):
        r["diff_next"] = difference(summaries[i], summaries[i + 1], quantities) \
            if i + 1 < n else math.nan
        r["diff_next2"] = difference(summaries[i], summaries[i + 2], quantities) \
            if i + 2 < n else math.nan
        r["chosen"] = i == chosen
    table = pd.DataFrame(rows)
    settings = {k: v for k, v in rows[chosen].items() if k in base} if chosen is not None \
        else {}
    result = results[chosen] if chosen is not None else None
    if chosen is not None and result is None:  # loaded from the store: its saved result
        result = disk.result(chosen) if disk is not None else None
        if result is None:  # a store without it: run it again
            result = one_run(rung_scenes[chosen])
        again = summarize(result)
        if difference(again, summaries[chosen], quantities) > 1e-12:
            raise StoreError("store", f"= {str(store)!r}: rung {chosen} run again differs "
                             "from its stored summary (made by another gearmodal version?): "
                             "delete the store")
        if keep_all:
            results[chosen] = result
    return FidelityChoice(met=chosen is not None, rung=chosen, settings=settings,
                          result=result, table=table, tol=float(tol),
                          quantities=tuple(quantities), results=results if keep_all else [])


def chosen_result(choice: FidelityChoice, field_: str = "tol"):
    """The chosen rung's result (:class:`gearmodal.run.ChosenRun` wraps it with the choice);
    raises :class:`ModelError` naming ``field_`` when no rung met the tolerance."""
    if not choice.met:
        d = choice.table[["rung", "dt", "diff_next", "diff_next2"]].to_string(index=False)
        raise ModelError(field_, f"= {choice.tol:g}: no rung of the step ladder agreed with "
                         f"the next two finer ones within it ({len(choice.table)} rungs run):\n"
                         f"{d}\nthe scene may not be reproducible to this tolerance (a "
                         "chaotic rattle); raise it, or run more levels with gm.auto.choose")
    return choice.result
