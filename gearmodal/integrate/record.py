"""A run's output rows as tables: the contact and spring forces of states (:class:`ForceMap`),
the event log's labels (:func:`event_table`) and :class:`Recorder`, which writes the rows of a
run to a result directory while it goes (DESIGN 3.2: a run's memory does not grow with its
duration).

The in-memory tables (:class:`gearmodal.integrate._Tables`) and the recorder compute the same
values with the same functions, so a streamed run reads back as the run held in memory.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from ..result_io import TableWriter
from .result import EVENT_COLUMNS
from .turns import LEVEL_COLUMNS, TURN_COLUMNS, level_table, turn_table

#: rows of one stretch the recorder gathers before forming their forces (1 000 x 70 states:
#: 0.6 MB)
BATCH = 1000
#: pandas 3 has a string dtype of its own ("str"); pandas 2 keeps labels as objects
_PANDAS_3 = int(pd.__version__.split(".")[0]) >= 3


class ForceMap:
    """The force table's columns of an assembly and the forces of states.

    Columns: one per mesh flank and per bearing direction (a dead band's two sides combined, a
    polygon's facet forces resolved on the bearing's x and y axes: ``Contacts.columns``), then
    the springs, then the round clearances (scipy). ``system``: the run's first system, whose
    contact damping every force row uses."""

    def __init__(self, system):
        asm = system.asm
        c = asm.contacts
        self.k, self.c = system.k, system.c
        names: dict[str, int] = {}
        cols, rows_, weights = [], [], []
        for e, parts in enumerate(c.columns):
            for key, wgt in parts:
                rows_.append(e)
                cols.append(names.setdefault(key, len(names)))
                weights.append(wgt)
        proj = np.zeros((len(c.element), len(names)))
        np.add.at(proj, (np.array(rows_, dtype=np.int64), np.array(cols, dtype=np.int64)),
                  np.array(weights))
        self.proj = proj
        labels = list(names)
        sp, rd = asm.springs, asm.round
        self.n_sp = len(sp) if sp is not None else 0
        self.n_rd = len(rd) if rd is not None else 0
        if self.n_sp:
            labels += [f"{el}.{ct}" for el, ct in zip(sp.element, sp.contact, strict=True)]
        if self.n_rd:
            labels += [f"{el}.{ct}" for el, ct in zip(rd.element, rd.contact, strict=True)]
        # a bearing direction is a spring or a dead band, never both: the labels are distinct
        self.labels = labels
        self.nf = len(names)

    def rows(self, sy, X: np.ndarray, S: np.ndarray, ts: np.ndarray, K=None,
             out: np.ndarray | None = None) -> np.ndarray:
        """Forces (rows, columns) of states ``X`` with contact states ``S`` at times ``ts``
        (s from the start of ``sy``'s stretch), with system ``sy`` (its geometry: turning
        rows exact); ``K``: every contact's stiffness per row (alternating meshes) or None."""
        if out is None:
            out = np.empty((len(X), len(self.labels)))
        nf, n_sp = self.nf, self.n_sp
        P, R = sy.gaps(X, ts)
        Ks = self.k if K is None else K
        out[:, :nf] = np.where(S, Ks * P + self.c * R, 0.0) @ self.proj
        if n_sp:
            out[:, nf:nf + n_sp] = sy.spring_forces(X, ts)
        if self.n_rd:  # round clearances (scipy): k (r - c) + c_d r' if r > c
            from .scipy_ref import _Round

            rr = _Round(sy)
            out[:, nf + n_sp:] = rr.forces(X, rr.radius(X) > rr.c).reshape(len(X), -1)
        return out


def event_table(system, ev: np.ndarray) -> pd.DataFrame:
    """The event log (:data:`~.result.EVENT_COLUMNS`) of event rows ``ev`` ((n, 8):
    :func:`~.driver.event_rows`) of a run of ``system``."""
    c = system.asm.contacts
    rd = system.asm.round
    # contacts, then a round clearance per bearing (scipy; its x row names the bearing)
    element = list(c.element) + (list(rd.element[::2]) if rd is not None else [])
    contact = list(c.contact) + ["radial"] * (len(element) - len(c.element))
    e = ev[:, 1].astype(np.int64)
    state = np.array(["open", "closed"], dtype=object)

    def labels(values):
        # pandas 3: its string dtype given rather than inferred (-17 % on the table)
        return pd.array(values, dtype="str") if _PANDAS_3 else values

    return pd.DataFrame(dict(zip(EVENT_COLUMNS, (
        ev[:, 0],
        labels(np.array(element, dtype=object)[e]),
        labels(np.array(contact, dtype=object)[e]),
        labels(state[(ev[:, 2] > 0.5).astype(np.int64)]),
        labels(state[(ev[:, 3] > 0.5).astype(np.int64)]),
        ev[:, 4],
        ev[:, 5],
        ev[:, 6],
        ev[:, 7]), strict=True)))


class Recorder:
    """Writes a run's rows to ``directory`` as they come (:class:`~.driver.Driver`'s sink):
    ``q``, ``v``, ``forces``, ``contact_state`` and ``events`` as Parquet tables
    (:class:`~gearmodal.result_io.TableWriter`), the forces computed per chunk with the
    chunk's system (:class:`ForceMap`). ``elastic``: ``X -> (q, v)`` rows for the tables (the
    turbine's rigid rotation taken out), by default the state's halves. ``mesh_k``:
    ``(system, azimuths) -> stiffness rows or None`` (alternating meshes)."""

    TABLES = ("q", "v", "forces", "contact_state", "events")

    def __init__(self, directory, system, dt: float, elastic=None, mesh_k=None):
        d = Path(directory)
        d.mkdir(parents=True, exist_ok=True)
        self.directory = d
        self.system0 = system
        self.dt = float(dt)
        self.fmap = ForceMap(system)
        self.elastic = elastic
        self.mesh_k = mesh_k
        dofs = list(system.asm.dof_names)
        self.writers = {
            "q": TableWriter(d, "q", dofs), "v": TableWriter(d, "v", dofs),
            "forces": TableWriter(d, "forces", self.fmap.labels),
            "contact_state": TableWriter(d, "contact_state", list(system.names), dtype=bool)}
        self.n_events = 0
        self._pending: list = []  # rows of the current stretch not yet formed
        self._n_pending = 0
        # the event log (written even empty) and the exact turning points and level changes
        # (each made with its first rows): rows gathered and made a frame a batch at a time
        self._batches: dict[str, _Batched] = {"events": _Batched(
            TableWriter(d, "events", EVENT_COLUMNS[1:], dtype=None),
            lambda ev: event_table(system, ev).set_index("time"))}

    def rows(self, k0: int, X: np.ndarray, S: np.ndarray, system, seg_k0: int,
             azimuths: np.ndarray | None) -> None:
        """Output rows ``k0 ..`` (states ``X``, contact states ``S``) of ``system``'s stretch,
        which began at output step ``seg_k0``; ``azimuths``: the rows' input azimuths. Rows
        of one stretch are gathered up to :data:`BATCH` before their forces are formed (a
        turbine run hands over 21 rows per aerodynamic step: formed one call at a time they
        cost 40 % of the integration)."""
        p = self._pending
        if p and (p[0][3] is not system or self._n_pending >= BATCH):
            self._flush()
        self._pending.append((k0, np.array(X), np.array(S), system, seg_k0,
                              None if azimuths is None else np.array(azimuths)))
        self._n_pending += len(X)

    def _flush(self) -> None:
        p = self._pending
        if not p:
            return
        k0, _, _, system, seg_k0, az = p[0]
        X = np.concatenate([e[1] for e in p]) if len(p) > 1 else p[0][1]
        S = np.concatenate([e[2] for e in p]) if len(p) > 1 else p[0][2]
        if az is not None:
            az = np.concatenate([e[5] for e in p]) if len(p) > 1 else az
        self._pending, self._n_pending = [], 0
        idx = np.arange(k0, k0 + len(X))
        t = idx * self.dt
        ts = t - seg_k0 * self.dt
        K = None
        if self.mesh_k is not None and az is not None:
            K = self.mesh_k(system, az)
        F = self.fmap.rows(system, X, S, ts, K)
        n = system.n
        q, v = (X[:, :n], X[:, n:]) if self.elastic is None else self.elastic(X)
        w = self.writers
        w["q"].append(t, q)
        w["v"].append(t, v)
        w["forces"].append(t, F)
        w["contact_state"].append(t, S)

    def events(self, ev: np.ndarray) -> None:
        """Event rows ((n, 8), times from the run's start), gathered as arrays and made a
        table a batch at a time (a table per aerodynamic step cost the clearance gearbox's
        turbine run 40 % of its integration)."""
        if len(ev):
            self.n_events += len(ev)
            self._batches["events"].add(ev)

    def turns(self, rows: np.ndarray, channels: list[str]) -> None:
        """Exact turning points ((n, 4): time, channel index, value, -;
        :class:`~.turns.TurnPoints`) to the table ``turning_points``, made a table a batch
        at a time (as the events)."""
        self._batched("turning_points", TURN_COLUMNS,
                      lambda r: turn_table(channels, r)).add(rows)

    def levels(self, rows: np.ndarray, channels: list[str], levels: dict) -> None:
        """Exact level changes ((n, 4): time, channel index, bin, revolutions;
        :class:`~.turns.TurnPoints`) to the table ``level_changes``, a batch at a time."""
        self._batched("level_changes", LEVEL_COLUMNS,
                      lambda r: level_table(channels, levels, r)).add(rows)

    def _batched(self, name: str, columns, frame) -> _Batched:
        if name not in self._batches:
            self._batches[name] = _Batched(TableWriter(self.directory, name, list(columns),
                                                       dtype=None), frame)
        return self._batches[name]

    def close(self) -> Path:
        """Close every table; returns the directory."""
        self._flush()
        for w in self.writers.values():
            w.close()
        for b in self._batches.values():
            b.close()
        return self.directory


class _Batched:
    """Rows of one table (events, turning points, level changes) gathered as arrays, made a
    frame (``frame(rows)``) and written a batch of :data:`BATCH` rows at a time (a frame per
    aerodynamic step cost the clearance gearbox's turbine run 40 % of its integration)."""

    def __init__(self, writer: TableWriter, frame):
        self.writer = writer
        self.frame = frame
        self.rows: list = []
        self.n = 0

    def add(self, rows: np.ndarray) -> None:
        self.rows.append(np.array(rows, dtype=float))
        self.n += len(rows)
        if self.n >= BATCH:
            self.flush()

    def flush(self) -> None:
        if self.rows:
            rows = np.concatenate(self.rows)
            self.rows, self.n = [], 0
            self.writer.append_frame(self.frame(rows))

    def close(self) -> None:
        self.flush()
        self.writer.close()
