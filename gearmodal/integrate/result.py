"""``SimulationResult``: time series, contact forces, the contact-state event log and the
double-contact and load-sharing analyses built on it."""

from __future__ import annotations

import json
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from ..errors import ModelError
from ..fatigue import N_REF, WOEHLER, damage_equivalent_load, turning_dels
from ..result_io import (
    VIEW_ROWS,
    copy_table,
    decimated,
    digests,
    parquet_parts,
    read_header,
    read_table,
    refuses_damage,
    remove_table,
    replacing,
    table_chunks,
    table_path,
    thin_frame,
    verify_digests,
    write_header,
    write_table,
)
from ..sharing import MESH_ROLES, k_gamma_table

EVENT_COLUMNS = ["time", "element", "contact", "state_before", "state_after", "gap_rate",
                 "force_after", "peak_force_N", "peak_time"]


#: columns of :attr:`SimulationResult.elements`
ELEMENT_COLUMNS = ["kind", "stage", "role", "planet"]
#: layout version of :meth:`SimulationResult.save` (``result.json``): 2 writes Parquet tables
#: (or CSV when asked for); 1 (CSV only) is still read
SAVE_VERSION = 2
#: the tables indexed by time that a stored result reads from its directory
STORED_TABLES = ("q", "v", "forces", "contact_state")
#: the exact method's streamed statistics tables (read when first asked for)
EXACT_TABLES = ("turning_points", "level_changes")


class StoredTables:
    """The tables of a result kept in ``directory`` (a streamed run, :meth:`SimulationResult.load`),
    read when first asked for (:class:`SimulationResult`'s ``tables``)."""

    def __init__(self, directory):
        self.directory = Path(directory)

    def __call__(self, name: str) -> pd.DataFrame:
        d = self.directory
        if name == "events":
            ev = read_table(d, "events", index_col=None,
                            dtype={c: str for c in ("element", "contact", "state_before",
                                                    "state_after")})
            for c in ("peak_force_N", "peak_time"):  # saved before the exact peaks
                if c not in ev:
                    ev[c] = np.nan
            return ev.astype({"time": float, "gap_rate": float, "force_after": float,
                              "peak_force_N": float, "peak_time": float})
        df = read_table(d, name)
        return df.astype(bool) if name == "contact_state" else df


def _table(name: str, doc: str) -> property:
    """A table of the result, built from the run's arrays on first read (then kept)."""
    attr = "_" + name

    def get(self):
        d = self.__dict__
        val = d.get(attr)
        if val is None and d.get("tables") is not None:
            val = d[attr] = d["tables"](name)
            if all(d.get("_" + t) is not None for t in SimulationResult.TABLES):
                d["tables"] = None  # all built: the run's arrays are not kept twice
        return val

    def set_(self, val):
        if val is None and attr in self.__dict__:
            # the builder knows only the raw run: the corrections simulate applies after it
            # (coupled coordinates, exact-geometry springs, the drivetrain's rigid rotation)
            # would be lost by a rebuild
            raise ValueError(f"SimulationResult.{name} cannot be reset to None")
        self.__dict__[attr] = val

    return property(get, set_, doc=doc)


@dataclass(repr=False)
class SimulationResult:
    """Result of :func:`gearmodal.simulate`.

    Attributes
    ----------
    t : (n_times,) output times, s.
    q, v : DataFrames of displacements (m, rad) and velocities by DOF name, indexed by time.
    forces : DataFrame indexed by time: ``<mesh>.front`` / ``<mesh>.back`` flank forces (N)
        and ``<bearing>.<direction>`` bearing forces (N or N m; per-axis dead bands combined,
        polygonal and round clearances resolved on the bearing's x and y axes, positive when
        the bearing pushes body a towards the negative direction).
    events : the contact-state event log, one row per change: ``time`` (s), ``element``,
        ``contact`` (``front``/``back`` flank, bearing side ``x+``..., polygon facet ramp
        ``facet<i>_<m>``, round clearance ``radial``), ``state_before``,
        ``state_after`` (``open``/``closed``), ``gap_rate`` (m/s, penetration rate at the
        switch), ``force_after`` (N, the contact force just after the switch), and on a row
        that opens a contact ``peak_force_N`` and ``peak_time`` (s): the exact peak force of
        the contact episode it ends and when (the exact method's Taylor propagator; NaN on
        other rows and from other methods).
    contact_state : DataFrame of booleans (closed) per contact at the output times.
    settings : the settings that made the run (method, dt, options).
    initial_state : ``{contact name: closed}`` at ``t[0]``.
    stats : counters and CPU time of the run (``cpu_s`` is the integration; the tables are
        not in it, see below). The exact method's (Taylor propagator): ``pieces`` summed,
        ``halved`` (a piece whose series tail was not negligible), ``root_searches`` (gaps
        whose bound did not exclude a crossing), ``taylor_rows`` (gap series formed) and
        ``state_bounds`` (contact states whose own spectral bound was computed and kept, an
        eigenproblem each; once the table's 1 024 states are full, further states are solved
        each time they last and not counted).
    constraint_forces : coupled systems (:class:`gearmodal.Coupled`) only: the Lagrange
        multipliers, one column per constraint row (N or N m), i.e. the forces the constraints
        transmit (for a joint: the force on body ``b`` in joint axes).
    peak_bins : the exact peaks (exact method, Taylor propagator): the largest force of each
        force column, spring channel and radial bearing force (``<element>.radial``) in each
        bin of ``settings["peak_bin"]`` s, located on the pieces' series, never a sampled
        value (long format: ``bin_start_s``, ``channel``, ``peak_force_N``, ``time_s``);
        ``None`` for other methods. Read it with :meth:`peaks`.
    turning_points : the exact turning points (exact method, Taylor propagator) of the same
        channels (:mod:`gearmodal.integrate.turns`): every local extremum of the solution's
        force, located on the pieces' series, and the values on both sides of a jump (a
        contact switching); index ``time`` (s), columns ``channel`` and ``force_N``, each
        channel's rows in time order, its first the run's start and its last the run's end.
        What a rainflow count reads (:func:`gearmodal.fatigue.turning_cycles`): it does not
        depend on the output step. ``None`` for other methods. A stored run reads it when
        first asked for; :meth:`turning_chunks` goes through it a row group at a time.
    level_changes : the exact level changes (exact method, Taylor propagator) of the mesh
        flanks' and the planet bearings' radial forces (:mod:`gearmodal.integrate.turns`):
        when each one's force enters another level bin (the edges of
        :data:`gearmodal.fatigue.RUN_LEVELS`), located on the pieces' series as crossings are;
        index ``time`` (s), columns ``channel``, ``bin`` (the bin from that time on),
        ``level_low_N``, ``level_high_N``, ``input_revolutions`` (the model input's
        revolutions from the start), each channel's first row the run's start; rows of channel
        ``input`` (bin -1) mark the input's revolutions at each peak bin's start and at the
        run's end. What the
        exact load duration and revolution distributions read
        (:func:`gearmodal.fatigue.level_spectrum`): they do not depend on the output step.
        ``None`` for other methods.
    constraint_residual : coupled systems only: the exact residual ``g`` of every constraint
        row along the trajectory (m or rad; rounding for linear constraints, second order for
        linearised joints).
    elements : the model's structure, one row per element with contact or spring rows
        (index ``element``): ``kind`` (``mesh``, ``bearing``, ``spring``, ``round``...),
        ``stage``, ``role`` (``sun_planet``, ``planet_bearing``...) and ``planet`` (the
        planet's body name, ``""`` if none), as the builders set them; the double-contact and
        load-sharing analyses read it.

    The five tables (``q``, ``v``, ``forces``, ``events``, ``contact_state``) are built from
    the run's arrays when first read and then kept, so a study that reads only the event log
    does not pay for the force table (all five: ~1 ms of pandas on the 4 ms stage transient,
    ``benchmarks/work_precision.py``'s paired re-timing). Assigning a
    table replaces it. Once all five are built the run's arrays are released. Pickling and
    ``dataclasses.replace`` build them all.
    """

    t: np.ndarray
    q: pd.DataFrame | None = None
    v: pd.DataFrame | None = None
    forces: pd.DataFrame | None = None
    events: pd.DataFrame | None = None
    contact_state: pd.DataFrame | None = None
    settings: dict = field(default_factory=dict)
    initial_state: dict = field(default_factory=dict)
    stats: dict = field(default_factory=dict)
    constraint_forces: pd.DataFrame | None = None
    constraint_residual: pd.DataFrame | None = None
    elements: pd.DataFrame | None = None
    peak_bins: pd.DataFrame | None = None
    turning_points: pd.DataFrame | None = None
    level_changes: pd.DataFrame | None = None
    #: ``tables(name) -> DataFrame`` builds the tables not given (see the class docstring)
    tables: object = field(default=None, repr=False, compare=False)
    #: the directory a streamed or loaded run's tables are read from (None: in memory)
    stored: Path | None = field(default=None, repr=False, compare=False)
    #: ``(first, last)`` output time, s (a stored run's, without reading its rows)
    span: tuple | None = field(default=None, repr=False, compare=False)

    TABLES = ("q", "v", "forces", "events", "contact_state")

    def __post_init__(self):
        for name in self.TABLES:
            if self.__dict__.get("_" + name) is None and self.tables is None:
                raise TypeError(f"SimulationResult needs {name!r} (or tables=...)")

    def __getstate__(self):
        for name in (*self.TABLES, "elements", "t"):  # build what is still lazy: the
            getattr(self, name)  # builders hold the systems and the assembly
        return {**self.__dict__, "tables": None}

    def __setstate__(self, state):
        for name in (*self.TABLES, "elements"):  # results pickled before these were lazy
            if name in state:
                state["_" + name] = state.pop(name)
        self.__dict__.update(state)

    def __repr__(self) -> str:
        t0, t1 = self._span()
        where = f", stored in {str(self.stored)!r}" if self.stored is not None else ""
        return (f"SimulationResult({self.stats.get('n_steps', '?')} steps to {t1:.6g} s, "
                f"{self.stats.get('n_events', '?')} events, "
                f"method={self.settings.get('method', '?')!r}{where})")

    # the protocol every run result follows (gearmodal.run.RunResult): a gearbox run is its
    # own gearbox, with no turbine side and no fidelity choice
    @property
    def gearbox(self) -> SimulationResult:
        """This result (:class:`gearmodal.run.RunResult`: a turbine run's is its gearbox's)."""
        return self

    @property
    def turbine(self) -> None:
        """No turbine side (:class:`gearmodal.run.RunResult`)."""
        return None

    @property
    def choice(self) -> None:
        """No fidelity choice (:class:`gearmodal.run.RunResult`)."""
        return None

    def time_span(self) -> tuple[float, float]:
        """The first and last output time (s), without reading a stored run's rows."""
        return self._span()

    def _span(self) -> tuple[float, float]:
        """The first and last output time (s), without reading a stored run's rows."""
        if self.span is not None:
            return float(self.span[0]), float(self.span[1])
        t = self.t
        return float(t[0]), float(t[-1])

    # -- peaks -----------------------------------------------------------------------------
    def peaks(self, t_from: float = 0.0) -> pd.DataFrame:
        """The largest force of every force column from ``t_from`` (s) to the end, and of
        every bearing's radial force ``sqrt(F_x^2 + F_y^2)`` (``<element>.radial``), indexed
        by ``channel``: ``peak_force_N`` (N or N m: the largest contact force of a flank or a
        dead band's sides, the largest magnitude of a spring), ``time_s`` and ``exact``.

        ``exact`` is True where the peak is the true maximum of the exact solution
        (:attr:`peak_bins`: every piece's series, never below a sampled value), which needs
        ``t_from`` on the bins' grid (a whole number of ``settings["peak_bin"]``); elsewhere
        the peak is the largest value at the output rows (it depends on the output step).

        Examples
        --------
        >>> import math, gearmodal as gm
        >>> p = gm.Gear(20, 0.004, math.radians(20), mass=1.0, inertia=1e-3)
        >>> w = gm.Gear(40, 0.004, math.radians(20), mass=4.0, inertia=1.6e-2)
        >>> pair = gm.gear_pair(p, w, mesh_stiffness=2e8, backlash=1e-4)
        >>> sim = gm.simulate(pair, 0.01, dt=1e-3, v0={"pinion.theta": 1.0})
        >>> pk = sim.peaks()
        >>> bool(pk.loc["mesh.front", "exact"])
        True
        >>> bool(pk.loc["mesh.front", "peak_force_N"] >= sim.forces["mesh.front"].max())
        True
        """
        if t_from > self._span()[1] + 1e-12:
            raise ModelError("t_from", f"= {t_from!r}: after the run's end "
                             f"({self._span()[1]:.6g} s)")
        rows: dict = {}
        for f in self.force_chunks():  # the sampled maxima, a chunk at a time
            sel = f[f.index >= t_from - 1e-12]
            if sel.empty:
                continue
            cols = {c: sel[c].abs() if not c.endswith((".front", ".back")) else sel[c]
                    for c in sel.columns}
            for c in list(sel.columns):
                el, _, d = c.rpartition(".")
                if d == "x" and f"{el}.y" in sel.columns:
                    cols[f"{el}.radial"] = np.hypot(sel[c], sel[f"{el}.y"])
            for c, x in cols.items():
                top = float(x.max())
                if c not in rows or top > rows[c][0]:
                    rows[c] = (top, float(x.idxmax()), False)
        bins = self.peak_bins
        pbin = self.settings.get("peak_bin")
        if bins is not None and len(bins) and pbin:
            k = t_from / pbin
            if abs(k - round(k)) <= 1e-9 * max(1.0, abs(k)):
                b = bins[bins.bin_start_s >= round(k) * pbin - 1e-9 * pbin]
                if len(b):
                    top = b.loc[b.groupby("channel", sort=False)["peak_force_N"].idxmax()]
                    for ch, v, tt in zip(top.channel, top.peak_force_N, top.time_s,
                                         strict=True):
                        rows[ch] = (float(v), float(tt), True)
        out = pd.DataFrame.from_dict(rows, orient="index",
                                     columns=["peak_force_N", "time_s", "exact"])
        out.index.name = "channel"
        return out

    def force_chunks(self, columns: list[str] | None = None):
        """The force table (``columns`` of it) in chunks of rows: a stored run's row groups
        (a pass over a long run in constant memory), else the whole table."""
        if self.stored is not None and self.__dict__.get("_forces") is None:
            yield from table_chunks(self.stored, "forces", columns)
        else:
            yield self.forces if columns is None else self.forces[columns]

    def turning_chunks(self):
        """The turning points (:attr:`turning_points`) in chunks of rows: a stored run's row
        groups (constant memory), else the whole table; nothing without them."""
        yield from self._exact_chunks("turning_points")

    def level_chunks(self):
        """The level changes (:attr:`level_changes`) in chunks of rows, as
        :meth:`turning_chunks`."""
        yield from self._exact_chunks("level_changes")

    def _exact_chunks(self, name: str):
        if self.stored is not None and self.__dict__.get("_" + name) is None:
            try:
                table_path(self.stored, name)
            except ModelError:
                return
            yield from table_chunks(self.stored, name)
        elif getattr(self, name) is not None:
            yield getattr(self, name)

    # -- structure -----------------------------------------------------------------------
    def meshes(self, role: str | None = None) -> list[str]:
        """Names of the meshes (of ``role``, e.g. ``"sun_planet"``), in model order."""
        el = self.elements
        if el is None:  # a result saved before the structure was kept: the builders' names
            names = [c[:-len(".front")] for c in self.forces.columns if c.endswith(".front")]
            return [n for n in names if role is None
                    or re.search(rf"(^|\.){role}\d*$", n)]
        sel = el[el.kind == "mesh"]
        if role is not None:
            sel = sel[sel.role == role]
        return list(sel.index)

    def elements_of(self, role: str) -> list[str]:
        """Names of the elements of ``role`` (``"planet_bearing"``...), in model order."""
        el = self.elements
        if el is None:  # built before the structure was kept: the builders' names
            pattern = r"planet\d+_bearing" if role == "planet_bearing" else rf"{role}\d*"
            names = dict.fromkeys(c.rsplit(".", 1)[0] for c in self.forces.columns)
            return [n for n in names if re.search(rf"(^|\.){pattern}$", n)]
        return list(el.index[el.role == role])

    def stage_of(self, element: str) -> str:
        """The stage of ``element`` (``"stage1"``; ``""`` outside stages)."""
        el = self.elements
        if el is None or element not in el.index:
            return element.rsplit(".", 1)[0] if "." in element else ""
        return str(el.at[element, "stage"])

    def planet_of(self, element: str) -> str:
        """The planet of ``element`` named within its stage (``"planet1"``), ``""`` if none."""
        el = self.elements
        if el is None or element not in el.index:
            m = re.search(r"(planet\d+)", element)
            return m.group(1) if m else ""
        planet, stage = str(el.at[element, "planet"]), str(el.at[element, "stage"])
        return planet[len(stage) + 1:] if stage and planet.startswith(stage + ".") else planet

    # -- contact intervals ---------------------------------------------------------------
    def _intervals(self) -> dict[str, list[tuple[float, float]]]:
        """Closed intervals of every contact from the exact event times."""
        t0, t1 = self._span()
        out: dict[str, list] = {}
        state = dict(self.initial_state)
        start = {k: t0 for k, v in state.items() if v}
        ev = self.events
        for time_, el, contact, after in zip(ev["time"].to_numpy(float), ev["element"].tolist(),
                                             ev["contact"].tolist(), ev["state_after"].tolist(),
                                             strict=True):
            key = f"{el}:{contact}"
            if after == "closed":
                start[key] = time_
            elif key in start:
                out.setdefault(key, []).append((start.pop(key), time_))
        for key, s in start.items():
            out.setdefault(key, []).append((s, t1))
        return out

    def double_contact(self) -> pd.DataFrame:
        """Episodes with both flanks of a mesh in contact.

        Columns ``start``, ``end``, ``duration`` (s), ``mesh``, ``planet`` (``""`` for a
        parallel stage), ``n_planets`` (1). Episodes with double contact on two or more planets
        at once (any of their meshes) follow with ``mesh = "<stage> (several planets)"``,
        ``planet`` listing them and ``n_planets`` >= 2.
        """
        iv = self._intervals()
        meshes = sorted({k.rsplit(":", 1)[0] for k in iv if k.endswith((":front", ":back"))})
        rows = []
        for m in meshes:
            # the overlaps of two time-ordered lists of disjoint intervals: one merge pass
            fr, bk = iv.get(f"{m}:front", []), iv.get(f"{m}:back", [])
            planet = self.planet_of(m)
            i = j = 0
            while i < len(fr) and j < len(bk):
                s, e = max(fr[i][0], bk[j][0]), min(fr[i][1], bk[j][1])
                if e > s:
                    rows.append((s, e, e - s, m, planet, 1))
                if fr[i][1] < bk[j][1]:
                    i += 1
                else:
                    j += 1
        single = pd.DataFrame(rows, columns=["start", "end", "duration", "mesh", "planet",
                                             "n_planets"]).sort_values("start",
                                                                       ignore_index=True)
        # simultaneous double contact on several planets of one stage: sweep the boundaries
        multi = []
        by_stage: dict[str, list] = {}
        stage = {m: self.stage_of(m) for m in meshes}  # once per mesh, not per episode
        for r in single.itertuples(index=False):
            if r.planet:
                by_stage.setdefault(stage[r.mesh], []).append((r.start, r.end, r.planet))
        for stage, eps in by_stage.items():
            label = f"{stage} (several planets)" if stage else "several planets"
            # one pass over the episodes' ends in time order, counting each planet's open
            # episodes: between two consecutive marks the planets with one open
            edges = sorted([(s, 1, p) for s, e, p in eps] + [(e, -1, p) for s, e, p in eps])
            count: dict[str, int] = {}
            spans = []
            i = 0
            while i < len(edges):
                a = edges[i][0]
                while i < len(edges) and edges[i][0] == a:
                    count[edges[i][2]] = count.get(edges[i][2], 0) + edges[i][1]
                    i += 1
                if i < len(edges):
                    spans.append((a, edges[i][0],
                                  tuple(sorted(p for p, c in count.items() if c > 0))))
            current = None
            for a, b, planets in spans:
                if len(planets) >= 2 and current and current[2] == planets and current[1] == a:
                    current[1] = b
                    continue
                if current:
                    multi.append(current)
                current = [a, b, planets, label] if len(planets) >= 2 else None
            if current:
                multi.append(current)
        multi = [(a, b, b - a, label, ",".join(pl), len(pl)) for a, b, pl, label in multi]
        several = pd.DataFrame(multi, columns=single.columns)
        return pd.concat([single, several], ignore_index=True)

    def load_sharing(self) -> pd.DataFrame:
        """Per-planet share of the load carried by the sun-planet meshes over time.

        Columns ``<stage>.planetN`` (share of the stage's total sun-planet flank force,
        front minus back; NaN where that total is below 1e-3 of its maximum) and
        ``<stage>.factor`` = N * the largest share (1 = equal sharing).
        ``result.attrs["peak_factor"]`` holds the peak factor of each stage.
        """
        parts, peaks = [], {}
        for chunk, top in self.load_sharing_chunks():
            parts.append(chunk)
            for k, val in top.items():
                peaks[k] = np.fmax(peaks.get(k, np.nan), val)
        out = pd.concat(parts) if len(parts) > 1 else parts[0]
        out.attrs["peak_factor"] = {k: float(v) for k, v in peaks.items()}
        return out

    def load_sharing_chunks(self):
        """:meth:`load_sharing` in chunks of rows (a stored run's row groups: constant memory):
        yields ``(table, {stage: largest factor in the chunk, NaN if none})``."""
        by_stage: dict[str, list] = {}
        for m in self.meshes("sun_planet"):
            by_stage.setdefault(self.stage_of(m), []).append(m)
        cols = [f"{m}.{side}" for ms in by_stage.values() for m in ms
                for side in ("front", "back")]

        def totals(f):
            for stage, meshes in by_stage.items():
                net = np.column_stack([f[f"{m}.front"].to_numpy() - f[f"{m}.back"].to_numpy()
                                       for m in meshes])
                yield stage, meshes, net, net.sum(axis=1, keepdims=True)

        if not by_stage:
            for f in self.force_chunks([]):
                yield pd.DataFrame(index=f.index), {}
            return
        # the largest total of each stage over the run: the threshold of an undefined share
        big = dict.fromkeys(by_stage, 0.0)
        for f in self.force_chunks(cols):
            for stage, _, _, tot in totals(f):
                big[stage] = max(big[stage], float(np.abs(tot).max(initial=0.0)))
        for f in self.force_chunks(cols):
            out = pd.DataFrame(index=f.index)
            peaks = {}
            for stage, meshes, net, tot in totals(f):
                # where the stage carries (almost) no load, shares are undefined (rattle,
                # start)
                loaded = np.abs(tot) > 1e-3 * max(big[stage], 1e-300)
                with np.errstate(invalid="ignore", divide="ignore"):
                    share = np.where(loaded, net / np.where(loaded, tot, 1.0), np.nan)
                prefix = f"{stage}." if stage else ""
                for i, m in enumerate(meshes):
                    out[f"{prefix}{self.planet_of(m)}"] = share[:, i]
                with np.errstate(invalid="ignore"):
                    valid = np.isfinite(share).any(axis=1)
                    factor = np.full(len(share), np.nan)
                    factor[valid] = len(meshes) * np.nanmax(share[valid], axis=1)
                out[f"{prefix}factor"] = factor
                peaks[stage or "stage"] = float(np.nanmax(factor)) \
                    if np.isfinite(factor).any() else float("nan")
            yield out, peaks

    def k_gamma(self, window_s: float | str | None = None) -> pd.DataFrame:
        """The mesh load factor K_gamma per stage and mesh kind (:mod:`gearmodal.sharing`):
        the largest planet's net flank force (front minus back), averaged over a window, over
        the mean of the planets'. ``window_s``: None, the whole run (one row per stage and mesh
        kind); a length in s, one row per window from ``t[0]`` (a last, shorter window is
        dropped); ``"revolution"``, one input revolution (``settings["speed_rpm"]``: the
        carrier of a planetary stage with carrier input, the rotor of a drivetrain). Columns
        ``window``, ``t_start``, ``t_end``, ``stage``, ``mesh``, ``n_planets``, ``k_gamma``,
        ``max_planet``, ``mean_load_N``."""
        t = self.forces.index.to_numpy(dtype=float)
        if isinstance(window_s, str):
            if window_s != "revolution":
                raise ModelError("window_s", f"= {window_s!r}: a length in s, "
                                 "'revolution' or None")
            rpm = self.settings.get("speed_rpm")
            if not rpm:
                raise ModelError("window_s", "= 'revolution': this run has no constant input "
                                 "speed (settings['speed_rpm']); give a length in s")
            window_s = 60.0 / abs(float(rpm))
        if window_s is None:
            edges = np.array([t[0], t[-1]])
        else:
            window_s = float(window_s)
            if not (np.isfinite(window_s) and window_s > 0):
                raise ModelError("window_s", f"= {window_s!r}: must be > 0 s")
            n = int(np.floor((t[-1] - t[0]) / window_s * (1 + 1e-12)))
            if n < 1:
                raise ModelError("window_s", f"= {window_s!r} s: longer than the run "
                                 f"({t[-1] - t[0]:.6g} s)")
            edges = t[0] + window_s * np.arange(n + 1)
        meshes = {m: (self.stage_of(m), role, self.planet_of(m))
                  for role in MESH_ROLES for m in self.meshes(role)}
        if not meshes:
            raise ModelError("k_gamma", "this run has no planetary stage (no sun-planet or "
                             "ring-planet meshes)")
        net = pd.DataFrame({m: self.forces[f"{m}.front"].to_numpy()
                            - self.forces[f"{m}.back"].to_numpy() for m in meshes})
        rows = []
        for k in range(len(edges) - 1):
            last = k == len(edges) - 2
            sel = (t >= edges[k]) & ((t <= edges[k + 1]) if last else (t < edges[k + 1]))
            rows.append(net[sel].mean().rename(k))
        table = pd.DataFrame(rows)
        table.index.name = "window"
        out = k_gamma_table(table, meshes)
        out.insert(1, "t_start", edges[out["window"].to_numpy()])
        out.insert(2, "t_end", edges[out["window"].to_numpy() + 1])
        return out

    def damage_equivalent_loads(self, n_ref: float = N_REF, woehler: dict | None = None,
                                t_from: float = 0.0) -> pd.DataFrame:
        """Damage-equivalent loads (:mod:`gearmodal.fatigue`, (F1)) of every flank force
        (``<mesh>.front``/``.back``, with the tooth-root and the tooth-flank exponents) and
        every planet bearing's radial force (``<bearing>.radial``, the bearing exponent) from
        ``t_from`` (s) on, one row each: ``load``, ``kind``, ``m``, ``del_N`` at ``n_ref``
        cycles and ``exact``: True where the count is of the exact solution's turning points
        (:attr:`turning_points`, :func:`gearmodal.fatigue.turning_dels`: independent of the
        output step), False where the run has none and the output rows are counted.
        ``woehler`` overrides :data:`gearmodal.fatigue.WOEHLER`."""
        ex = {**WOEHLER, **(woehler or {})}
        flanks = [f"{m}.{side}" for m in self.meshes() for side in ("front", "back")]
        columns = set(self.force_columns())
        bearings = [b for b in self.elements_of("planet_bearing")
                    if f"{b}.x" in columns and f"{b}.y" in columns]
        kinds = ("tooth_root", "tooth_flank", "bearing")
        radials = [f"{b}.radial" for b in bearings]
        # one pass over the turning points for every channel and exponent
        exact = turning_dels(self, [ex[k] for k in kinds], flanks + radials, t_from, n_ref) \
            if flanks or radials else None
        rows = []
        f = None
        if exact is None:
            f = self.forces[self.forces.index >= t_from - 1e-12]
        for col in flanks:
            for j, kind in enumerate(kinds[:2]):
                if exact is not None:
                    rows.append((col, kind, ex[kind], float(exact.loc[col].iloc[j]), True))
                else:
                    rows.append((col, kind, ex[kind],
                                 damage_equivalent_load(f[col], ex[kind], n_ref), False))
        for b in bearings:
            if exact is not None:
                rows.append((f"{b}.radial", "bearing", ex["bearing"],
                             float(exact.loc[f"{b}.radial"].iloc[2]), True))
            else:
                radial = np.hypot(f[f"{b}.x"], f[f"{b}.y"])
                rows.append((f"{b}.radial", "bearing", ex["bearing"],
                             damage_equivalent_load(radial, ex["bearing"], n_ref), False))
        return pd.DataFrame(rows, columns=["load", "kind", "m", "del_N", "exact"])

    def to_frame(self) -> pd.DataFrame:
        """Displacements and contact forces side by side, indexed by time."""
        return pd.concat([self.q, self.forces], axis=1)

    def plot(self, columns=None, ax=None):
        """Contact forces against time with the events marked; returns the matplotlib Figure.

        Default columns: the flank forces of planet 1 (front and back, sun-planet and
        ring-planet, as in the paper's Figures 6-8) when the model has planets, else all flank
        forces. Forces are sampled at the output times: an impact shorter than ``dt`` shows
        in the event log but may fall between samples here.
        """
        import matplotlib.pyplot as plt

        if ax is None:
            fig, ax = plt.subplots(figsize=(9, 4.5))
        else:
            fig = ax.figure
        flanks = [c for c in self.force_columns() if c.endswith((".front", ".back"))]
        planet1 = [c for c in flanks if re.search(r"planet1\.(front|back)$", c)]
        cols = columns or planet1 or flanks or self.force_columns()
        view = self.view("forces", cols)
        for c in cols:
            ax.plot(view.index, view[c] / 1e3, lw=1.0, label=c,
                    ls="-" if c.endswith(".front") else "--")
        if len(self.events) and len(self.events) < 400:
            for tt in self.events.time:
                ax.axvline(tt, color="0.85", lw=0.5, zorder=0)
        ax.set_xlabel("time [s]")
        ax.set_ylabel("contact force [kN]")
        ax.legend(fontsize=7, ncol=2)
        fig.tight_layout()
        return fig

    def force_columns(self) -> list[str]:
        """The force table's column names (a stored run's without reading its rows)."""
        if self.stored is not None and self.__dict__.get("_forces") is None:
            p = table_path(self.stored, "forces")
            if p.suffix == ".parquet":
                import pyarrow.parquet as pq

                return [c for c in pq.read_schema(parquet_parts(p)[0]).names if c != "time"]
        return list(self.forces.columns)

    def view(self, name: str, columns: list[str], max_rows: int = VIEW_ROWS) -> pd.DataFrame:
        """``columns`` of the table ``name`` (``q``, ``v``, ``forces``) for a figure: at most
        about ``max_rows`` rows, each bucket of rows keeping those where a column is largest
        or smallest (:func:`gearmodal.result_io.decimated`; a stored run is read a row group
        at a time), so no peak of a plotted column is lost. A short run: every row."""
        if self.stored is not None and self.__dict__.get("_" + name) is None:
            return decimated(self.stored, name, list(columns), max_rows)
        table = getattr(self, name)[list(columns)]
        return table if len(table) <= max_rows else thin_frame(table, max_rows)

    def save(self, directory, format: str = "parquet") -> Path:
        """Write the tables ``q``, ``v``, ``forces``, ``events``, ``contact_state``,
        ``elements``, ``peak_bins`` (and, for coupled systems, ``constraint_forces`` and
        ``constraint_residual``) as Parquet (``format="parquet"``, the default: compressed,
        floats exact) or CSV (``format="csv"``), ``settings.json`` (settings and ``stats``)
        and ``result.json`` (layout version, initial state): what :meth:`load` reads back. A
        stored run (``stored``) saved to its own directory writes only what is not there
        yet; to another directory its tables are copied, not read. Saving over an earlier
        result replaces it whole (it stays readable until the new one is complete), and
        ``result.json`` holds every file's SHA-256: :meth:`load` names a damaged or edited
        file instead of loading it."""
        from ..result_io import _check_format

        _check_format(format)
        d = Path(directory)
        same = self.stored is not None and d.is_dir() \
            and d.resolve() == Path(self.stored).resolve()
        if same:  # streamed here: the rest beside it
            self._write(d, format, True)
            return d
        with replacing(d) as target:  # an earlier result there stays until this one is whole
            self._write(target, format, False)
        return d

    def _write(self, d: Path, format: str, same: bool) -> None:
        """:meth:`save`'s files into ``d`` (``same``: the run's own stored directory)."""
        for name in (*STORED_TABLES, "events"):
            src = None
            if self.stored is not None and self.__dict__.get("_" + name) is None:
                src = table_path(self.stored, name)
            if same and src is not None and src.suffix == f".{format}":
                continue  # streamed here
            if src is not None and src.suffix == f".{format}":
                copy_table(src, d)
                continue
            if name == "events":
                write_table(self.events, d, name, format, index_label=None)
            else:
                write_table(getattr(self, name), d, name, format)
        for name in (*STORED_TABLES, "events"):  # one format per directory
            remove_table(d / f"{name}.{'csv' if format == 'parquet' else 'parquet'}")
        if self.peak_bins is not None:
            write_table(self.peak_bins, d, "peak_bins", format, index_label=None)
        for name in EXACT_TABLES:
            src = None
            if self.stored is not None and self.__dict__.get("_" + name) is None:
                try:
                    src = table_path(self.stored, name)
                except ModelError:
                    src = None
            if src is not None and src.suffix == f".{format}":
                if not same:
                    copy_table(src, d)
            elif getattr(self, name) is not None:
                write_table(getattr(self, name), d, name, format)
            remove_table(d / f"{name}.{'csv' if format == 'parquet' else 'parquet'}")
        if self.elements is not None:
            write_table(self.elements, d, "elements", format, index_label="element")
        if self.constraint_forces is not None:
            write_table(self.constraint_forces, d, "constraint_forces", format)
        if self.constraint_residual is not None:
            write_table(self.constraint_residual, d, "constraint_residual", format)
        (d / "settings.json").write_text(json.dumps(
            {**self.settings, "stats": self.stats}, indent=2, default=str))
        # every file's SHA-256 (a CSV has no checksum of its own; a Parquet table's pages do,
        # not its footer or a folder's list of parts): a damaged or edited file is named when
        # the result is loaded
        names = [f"{n}.{format}" for n in (*STORED_TABLES, "events", "peak_bins",
                                           *EXACT_TABLES, "elements",
                                           "constraint_forces", "constraint_residual")]
        write_header(d, "SimulationResult", SAVE_VERSION, initial_state=self.initial_state,
                     constraints=self.constraint_forces is not None, tables=format,
                     span=list(self._span()),
                     sha256=digests(d, [*names, "settings.json"]))

    @classmethod
    @refuses_damage
    def load(cls, directory) -> SimulationResult:
        """The result :meth:`save` wrote to ``directory`` (Parquet or CSV): every table and
        number as it was (floats exact), the tables read when first asked for; ``settings``
        as JSON holds them (values JSON cannot hold come back as their text). A directory of
        an older layout is refused naming it."""
        d = Path(directory)
        head = read_header(d, "SimulationResult", (1, SAVE_VERSION))
        if head["version"] >= 2 and "sha256" not in head:
            raise ModelError("directory", f"= {str(d)!r}: result.json has no sha256 (every "
                             "save of this layout writes it): edited or damaged; save the "
                             "result again")
        verify_digests(d, head.get("sha256") or {})  # (layout 1, before the checksums: none)
        for name in (*STORED_TABLES, "events"):
            table_path(d, name)  # every table there (a missing one named now, not later)
        bins = elements = None
        try:
            bins = read_table(d, "peak_bins", index_col=None, dtype={"channel": str})
        except ModelError:
            pass
        try:
            elements = read_table(d, "elements", index_col="element", dtype=str,
                                  keep_default_na=False)
            elements = elements.astype(str)
        except ModelError:
            pass
        extra = {}
        if head.get("constraints"):
            extra = {"constraint_forces": read_table(d, "constraint_forces"),
                     "constraint_residual": read_table(d, "constraint_residual")}
        try:
            meta = json.loads((d / "settings.json").read_text())
        except (OSError, ValueError) as e:
            raise ModelError("directory", f"= {str(d)!r}: settings.json is unreadable "
                             f"({e})") from None
        stats = meta.pop("stats", {})
        span = head.get("span")
        return cls(t=None, tables=StoredTables(d), stored=d,
                   span=tuple(span) if span else None, settings=meta,
                   initial_state={k: bool(x) for k, x in head["initial_state"].items()},
                   stats=stats, elements=elements, peak_bins=bins, **extra)


for _name, _doc in (
        ("q", "Displacements (m, rad) by DOF name, indexed by time (s)."),
        ("v", "Velocities (m/s, rad/s) by DOF name, indexed by time (s)."),
        ("forces", "Contact and spring forces (N, N m) by element, indexed by time (s)."),
        ("events", "The contact-state event log, one row per change."),
        ("contact_state", "Closed (True) per contact at the output times.")):
    # after the dataclass is made: its __init__ assigns through these (a None keeps it lazy)
    setattr(SimulationResult, _name, _table(_name, _doc))


def _time_property() -> property:
    """:attr:`SimulationResult.t`: a stored run's output times are read when first asked for
    (a 3 600 s run at 1 ms: 29 MB a streamed run need not hold)."""

    def get(self):
        val = self.__dict__.get("_t")
        if val is None and self.__dict__.get("stored") is not None:
            val = self.__dict__["_t"] = read_table(self.stored, "q", columns=[]).index \
                .to_numpy(dtype=float)
        return val

    def set_(self, val):
        self.__dict__["_t"] = None if val is None else np.asarray(val, dtype=float)

    return property(get, set_, doc="Output times, s.")


SimulationResult.t = _time_property()


def _elements_property() -> property:
    """:attr:`SimulationResult.elements`, which :func:`gearmodal.simulate` gives as its builder
    (a callable): built on first read (~0.5 ms of pandas a run need not pay), then kept."""

    def get(self):
        val = self.__dict__.get("_elements")
        if callable(val):
            val = self.__dict__["_elements"] = val()
        return val

    def set_(self, val):
        self.__dict__["_elements"] = val

    return property(get, set_, doc="The model's structure: one row per element with contact "
                    "or spring rows (kind, stage, role, planet), indexed by element.")


SimulationResult.elements = _elements_property()


def _exact_property(name: str, doc: str) -> property:
    """:attr:`SimulationResult.turning_points`, :attr:`SimulationResult.level_changes`: a
    stored run's table is read when first asked for (a long run's rows need not be held by a
    pass that streams them)."""

    def get(self):
        val = self.__dict__.get("_" + name)
        if val is None and self.__dict__.get("stored") is not None \
                and not self.__dict__.get(f"_{name}_read"):
            self.__dict__[f"_{name}_read"] = True
            if any((Path(self.stored) / f"{name}.{ext}").exists()
                   for ext in ("parquet", "csv")):
                val = read_table(self.stored, name, dtype={"channel": str})
                self.__dict__["_" + name] = val
        return val

    def set_(self, val):
        self.__dict__["_" + name] = val

    return property(get, set_, doc=doc)


SimulationResult.turning_points = _exact_property(
    "turning_points", "The exact turning points of the force channels (time, channel, "
    "force_N), or None (see the class docstring).")
SimulationResult.level_changes = _exact_property(
    "level_changes", "The exact level changes of the flank and radial bearing forces (time, "
    "channel, bin, level_low_N, level_high_N, input_revolutions), or None (see the class "
    "docstring).")
