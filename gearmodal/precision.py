"""A scene's own work-precision table: every method and setting that applies, its CPU time
and its error against the exact method on the quantities engineers read (``gm.fidelity``,
``gearmodal fidelity SCENE --out DIR``; issue "the speed-accuracy trade on every scene",
item 4).

The settings (:func:`settings_of`), each the scene with one change:

- ``exact`` at the scene's ``dt``: the **reference**;
- the same with the first DOF's initial velocity changed by 1e-13 (m/s or rad/s): the
  **floor**, the scene's own sensitivity to rounding. A rattling gearbox is chaotic: two runs
  that differ by rounding part within a fraction of a second, and single-run peaks then
  differ by several percent; no setting's error can be read below the floor's;
- ``exact`` at 4x the scene's ``dt``: the output step places the rows only (the same events
  at the same times, the same exact peaks), so its error is the sampling's (0 on exact peaks);
- ``scipy`` (RK45) at ``rtol`` 1e-4, 1e-6, 1e-8 (``atol`` 1e-12), at the scene's ``dt``;
- ``newmark`` at the scene's ``dt``, ``dt / 4`` and ``dt / 16``.

A turbine scene keeps its ``dt`` a whole fraction of the aerodynamic step (``dt / 4`` and
``dt / 16`` are). The errors of a row against the reference (:func:`errors`):

    peak_error = max over channels c of |P_c - P_c,ref| / max(|P_c,ref|, 0.1 max_c |P_c,ref|)
                                                                                        (F1)

over the channels whose reference peak is the exact maximum of the solution (each flank's and
dead band's: :meth:`~gearmodal.SimulationResult.peaks`); ``sampled_peak_error`` the same over
the others (springs, a bearing's radial force: taken at the output rows by every method, the
reference included, so it moves with ``dt``). The floor (10 % of the largest peak compared)
keeps a channel the reference barely loads from dominating; a contact the reference never makes
and a setting makes at that force counts as an error of 1. ``events_error = |N - N_ref| /
N_ref`` on the contact-event count; on a planetary scene ``double_contact_error`` on the
double-contact time (:func:`gearmodal.summary.summarize`; relative, its floor 1 % of the run's
length). A turbine scene has no floor row (its initial state is the turbine's). A setting that
stops with a :class:`~gearmodal.SolveError` (a diverged Newmark, a scipy run that made energy)
is a row with status ``stopped`` and its message: a stop is the answer, not a failure of the
table; one the model refuses (a method that does not integrate it) is ``refused``.
:meth:`FidelityTable.recommend` gives the cheapest setting whose errors are all within a
target.

Rows are written as they finish to ``out`` (``fidelity.jsonl``, under the scene's identity):
the same command on the same scene resumes, another scene into the same folder is refused.
"""

from __future__ import annotations

import copy
import json
import math
import os
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from .errors import ModelError, SolveError, StoreError
from .single import one_run
from .summary import summarize

__all__ = ["FidelityTable", "fidelity", "settings_of"]

#: the error columns of the table (:func:`errors`)
ERRORS = ("peak_error", "sampled_peak_error", "events_error", "double_contact_error")
#: the default target of :meth:`FidelityTable.recommend` (relative, on every error)
DEFAULT_TARGET = 0.01
#: the floor row's change of the first DOF's initial velocity (m/s or rad/s): rounding level
FLOOR_PERTURBATION = 1e-13
#: the double-contact error's floor, a fraction of the run's length
DC_FLOOR = 0.01
#: F1's floor, a fraction of the largest reference peak of the channels compared
PEAK_FLOOR = 0.1


def settings_of(scene) -> list[tuple[str, dict]]:
    """The settings the table runs on ``scene`` (module docstring): ``(label, changes)``,
    ``changes`` the scene's ``method``, ``dt`` and ``options``; the first is the reference."""
    dt = float(scene.dt)
    out = [("exact (reference)", {"method": "exact", "dt": dt, "options": {}})]
    if scene.turbine is None:  # a turbine scene starts from its own initial state
        out.append(("exact, start perturbed (floor)", {"method": "exact", "dt": dt,
                                                        "options": {},
                                                        "perturb": FLOOR_PERTURBATION}))
    out.append(("exact, output dt x4", {"method": "exact", "dt": 4 * dt, "options": {}}))
    if scene.turbine is not None:
        aero = float(scene.drivetrain.get("aero_dt", 0.02))
        if not abs(aero / (4 * dt) - round(aero / (4 * dt))) < 1e-9 * aero / dt:
            out.pop()
    for rtol in (1e-4, 1e-6, 1e-8):
        out.append((f"scipy RK45 rtol {rtol:g}",
                    {"method": "scipy", "dt": dt, "options": {"rtol": rtol, "atol": 1e-12}}))
    for div in (1, 4, 16):
        out.append((f"newmark dt {dt / div:.3g} s", {"method": "newmark", "dt": dt / div,
                                                      "options": {}}))
    return out


def _with(scene, changes: dict):
    sc = copy.copy(scene)
    sc.method, sc.dt, sc.options = changes["method"], changes["dt"], dict(changes["options"])
    sc.drivetrain = dict(scene.drivetrain)
    if changes.get("perturb"):
        first = sc.model.assemble().dof_names[0]
        sc.v0 = {**scene.v0, first: scene.v0.get(first, 0.0) + changes["perturb"]}
    return sc


def _quantities(res) -> dict:
    """Peaks by channel, event count and double-contact time of one run."""
    gb = res.gearbox if hasattr(res, "gearbox") else res
    pk = gb.peaks()
    out = {"peaks": {str(c): float(v) for c, v in pk["peak_force_N"].items()},
           "exact": [str(c) for c in pk.index[pk["exact"].to_numpy(dtype=bool)]],
           "n_events": int(gb.stats.get("n_events", len(gb.events))),
           "double_contact_s": math.nan}
    try:
        out["double_contact_s"] = float(summarize(gb)["double_contact_time_s"])
    except ModelError:  # not a planetary stage
        pass
    return out


def _peak_error(pp: dict, rp: dict, channels) -> tuple[float, str]:
    """(F1) over ``channels`` of the reference peaks ``rp``: the largest error, its channel."""
    floor = PEAK_FLOOR * max((abs(rp[c]) for c in channels), default=0.0)
    worst, where = (0.0 if channels else math.nan), ""
    for c in channels:
        v = rp[c]
        d = (abs(pp[c] - v) / max(abs(v), floor, 1e-300)) if c in pp else math.inf
        if d > worst:
            worst, where = d, c
    return worst, where


def errors(row: dict, ref: dict, t_end: float) -> dict:
    """The errors (F1) of a run's quantities ``row`` against the reference's ``ref``, and the
    channel of the largest peak error."""
    rp, pp = ref["peaks"], row["peaks"]
    exact = [c for c in rp if c in set(ref["exact"])]
    sampled = [c for c in rp if c not in set(ref["exact"])]
    pe, where = _peak_error(pp, rp, exact)
    se, swhere = _peak_error(pp, rp, sampled)
    ne = abs(row["n_events"] - ref["n_events"]) / max(ref["n_events"], 1)
    a, b = row["double_contact_s"], ref["double_contact_s"]
    dc = (abs(a - b) / max(abs(b), DC_FLOOR * t_end) if math.isfinite(b) else math.nan)
    return {"peak_error": pe, "worst_channel": where, "sampled_peak_error": se,
            "worst_sampled_channel": swhere, "events_error": ne, "double_contact_error": dc}


@dataclass
class FidelityTable:
    """What :func:`fidelity` ran: one row per setting.

    ``table`` columns: ``setting``, ``method``, ``dt``, ``options`` (JSON), ``status``
    (``reference``, ``floor``, ``ok``, ``stopped``, ``refused``), ``cpu_s``, ``n_events``,
    ``exact_channels`` (how many of its peaks are exact maxima), the errors (:data:`ERRORS`,
    relative, NaN where not run or not applicable), ``worst_channel`` and
    ``worst_sampled_channel`` (where the peak errors are), ``note`` (a stop's message).
    ``scene``: the scene file."""

    table: pd.DataFrame
    scene: str = ""
    target: float = DEFAULT_TARGET
    meta: dict = field(default_factory=dict)

    def to_frame(self) -> pd.DataFrame:
        """The table (a copy)."""
        return self.table.copy()

    def recommend(self, target: float | None = None) -> pd.Series | None:
        """The cheapest (CPU) setting that finished with every error within ``target``
        (default: the table's, 1 %), the reference included; ``None`` if none."""
        target = self.target if target is None else float(target)
        if not (math.isfinite(target) and target > 0):
            raise ModelError("target", f"= {target!r}: must be a relative error > 0")
        t = self.table
        ok = t[t.status.isin(["reference", "ok"])]  # not the floor: the same setting
        err = ok[list(ERRORS)].fillna(0.0).max(axis=1)
        good = ok[err <= target]
        return None if good.empty else good.sort_values("cpu_s").iloc[0]

    def plot(self, ax=None):
        """Error (the largest of the errors) against CPU time, one point per setting that
        finished, the reference at the floor; the target as a line. Returns the Figure."""
        import matplotlib.pyplot as plt

        if ax is None:
            fig, ax = plt.subplots(figsize=(6.5, 4.2))
        else:
            fig = ax.figure
        t = self.table[self.table.status.isin(["reference", "ok"])]
        err = t[list(ERRORS)].fillna(0.0).max(axis=1).clip(lower=1e-6)
        for method, mk in (("exact", "o"), ("scipy", "s"), ("newmark", "^")):
            sel = t.method == method
            ax.loglog(t.cpu_s[sel], err[sel], mk, label=method)
            for _, r in t[sel].iterrows():
                ax.annotate(r.setting, (r.cpu_s, err[r.name]), fontsize=6,
                            xytext=(3, 3), textcoords="offset points")
        ax.axhline(self.target, color="0.5", lw=0.8, ls="--", label=f"target {self.target:g}")
        floor = self.table[self.table.status == "floor"]
        if len(floor):
            fe = float(floor[list(ERRORS)].fillna(0.0).max(axis=1).max())
            ax.axhline(max(fe, 1e-6), color="r", lw=0.8, ls=":",
                       label="floor (start perturbed by rounding)")
        stopped = self.table[self.table.status == "stopped"]
        if len(stopped):
            ax.text(0.01, 0.01, "stopped (SolveError): " + ", ".join(stopped.setting),
                    transform=ax.transAxes, fontsize=6, va="bottom")
        ax.set_xlabel("CPU time [s]")
        ax.set_ylabel("largest relative error vs exact (floor 1e-6)")
        ax.set_title(Path(self.scene).name or "scene", fontsize=9)
        ax.legend(fontsize=7)
        fig.tight_layout()
        return fig

    def save(self, directory) -> Path:
        """Write ``fidelity.csv`` (the table), ``fidelity.png`` (:meth:`plot`) and
        ``fidelity.json`` (scene, target, recommendation, the rule) into ``directory``."""
        import matplotlib.pyplot as plt

        d = Path(directory)
        d.mkdir(parents=True, exist_ok=True)
        self.table.to_csv(d / "fidelity.csv", index=False)
        fig = self.plot()
        fig.savefig(d / "fidelity.png", dpi=120)
        plt.close(fig)
        rec = self.recommend()
        (d / "fidelity.json").write_text(json.dumps(
            {"scene": self.scene, "target": self.target,
             "recommended": None if rec is None else rec.setting,
             "rule": "cheapest setting with peak, event-count and double-contact errors "
                     "within the target (gearmodal/precision.py, F1)", **self.meta},
            indent=2))
        return d


def fidelity(scene, *, target: float = DEFAULT_TARGET, out=None,
             progress: Callable[[int, int], None] | None = None) -> FidelityTable:
    """The work-precision table of ``scene`` (a :class:`gearmodal.scene.Scene`; its method and
    options are replaced by each setting's, :func:`settings_of`): CPU time and errors (F1)
    against the exact method of every setting, and :meth:`FidelityTable.recommend`'s choice
    for ``target`` (relative, default 1 %).

    ``out``: a folder the rows are written to as they finish (``fidelity.jsonl``), and from
    which a second call on the same scene resumes; ``progress(i, n)`` after each setting.

    Raises :class:`ModelError` for a bad ``target`` or a scene the exact method refuses,
    :class:`StoreError` for an ``out`` holding another scene's rows, and the reference's own
    :class:`SolveError` (without it there is nothing to measure against). The scene's own
    method and options do not matter (each setting sets them)."""
    if not (isinstance(target, (int, float)) and math.isfinite(target) and target > 0):
        raise ModelError("target", f"= {target!r}: must be a relative error > 0 (0.01 = 1 %)")
    ident = None
    if out is not None:  # the scene's identity, whatever method it names (the table sets it)
        canon = copy.copy(scene)
        canon.method, canon.options = "exact", {}
        ident = canon.identity()
    done = _resume(out, ident)
    plan = settings_of(scene)
    rows, ref = [], None
    for i, (label, changes) in enumerate(plan):
        if label in done:
            rec = done[label]
        else:
            rec = _run_one(scene, label, changes)
            if out is not None and rec["status"] != "refused":  # a refusal is not kept
                _append(out, ident, rec)
        if i == 0 and rec["status"] == "refused":
            raise ModelError("scene", f"the exact method refuses it: {rec['note']}")
        if i == 0 and rec["status"] != "ok":
            raise SolveError("reference", f"the exact method on the scene: {rec['note']}")
        if i == 0:
            ref = rec["q"]
        rows.append(rec)
        if progress is not None:
            progress(i + 1, len(plan))
    table = []
    for i, rec in enumerate(rows):
        r = {"setting": rec["label"], "method": rec["method"], "dt": rec["dt"],
             "options": json.dumps(rec["options"]), "status": rec["status"],
             "cpu_s": rec["cpu_s"], "n_events": math.nan, "exact_channels": math.nan,
             **{e: math.nan for e in ERRORS}, "worst_channel": "",
             "worst_sampled_channel": "", "note": rec["note"]}
        if rec["status"] == "ok":
            q = rec["q"]
            r.update(n_events=q["n_events"], exact_channels=len(q["exact"]),
                     **errors(q, ref, float(scene.t_end)))
            if i == 0:
                r["status"] = "reference"
            elif changes_of(plan, rec["label"]).get("perturb"):
                r["status"] = "floor"
        table.append(r)
    return FidelityTable(pd.DataFrame(table), scene=str(scene.source), target=float(target),
                         meta={"t_end_s": float(scene.t_end), "identity": ident})


def changes_of(plan, label: str) -> dict:
    """The changes of the setting ``label`` of ``plan`` (:func:`settings_of`)."""
    return dict(plan)[label]


def _run_one(scene, label: str, changes: dict) -> dict:
    rec = {"label": label, "method": changes["method"], "dt": changes["dt"],
           "options": changes["options"], "status": "ok", "note": "", "cpu_s": math.nan,
           "q": None}
    sc = _with(scene, changes)
    try:  # compile and load the method's kernels untimed, on a short stretch
        warm = copy.copy(sc)
        warm.t_end = min(float(sc.t_end), 20 * float(sc.dt))
        with np.errstate(all="ignore"):
            one_run(warm)
    except (SolveError, ModelError):
        pass  # the timed run says so
    t0 = time.process_time()
    try:
        with np.errstate(all="ignore"):
            res = one_run(sc)
        rec["q"] = _quantities(res)
    except SolveError as e:
        rec["status"], rec["note"] = "stopped", str(e)
    except ModelError as e:
        rec["status"], rec["note"] = "refused", str(e)
    rec["cpu_s"] = time.process_time() - t0
    return rec


def _resume(out, ident: str) -> dict:
    if out is None:
        return {}
    f = Path(out) / "fidelity.jsonl"
    if not f.exists():
        return {}
    done = {}
    text = f.read_text(encoding="utf-8")
    if text and not text.endswith("\n"):  # a last row cut by a stop: it runs again
        text = text[:text.rfind("\n") + 1]
        f.write_text(text, encoding="utf-8")
    lines = text.splitlines()
    for n, line in enumerate(lines, 1):
        try:
            rec = json.loads(line)
        except json.JSONDecodeError:
            raise StoreError("out", f"{f}:{n}: not a row of the fidelity table") from None
        if rec.get("identity") != ident:
            raise StoreError("out", f"= {str(out)!r} holds the fidelity rows of another scene "
                             f"(identity {str(rec.get('identity'))[:12]}...): use another "
                             "folder")
        done[rec["label"]] = rec
    return done


def _append(out, ident: str, rec: dict) -> None:
    d = Path(out)
    d.mkdir(parents=True, exist_ok=True)
    with open(d / "fidelity.jsonl", "a", encoding="utf-8") as fh:
        fh.write(json.dumps({**rec, "identity": ident}) + "\n")
        fh.flush()
        os.fsync(fh.fileno())
