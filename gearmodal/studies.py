"""Parameter studies: run many cases of a scene on any ``concurrent.futures.Executor``, store each
case as it finishes and resume after an interruption (DESIGN 5, ``studies.py``).

A case is a set of overrides of a scene file (:func:`gearmodal.scene.load_scene`): keys of the
scene (``"turbine.mounting_azimuth_deg"``, ``"wind.seed"``, ``"scene.t_end"``) or, with the
prefix ``model.``, of its model file (``"model.stages.0.carrier_bearing"``). The scene may also
be any picklable callable ``scene(**case)`` returning a result.

Store layout (``store=DIR``)::

    DIR/sweep.json                 the layout, the scene's identity (canonical text), the cases
    DIR/cases/<case_id>/row.parquet     one row: the case's scalar results
    DIR/cases/<case_id>/<table>.parquet tables the metrics returned (events, forces, ...)

A case directory is written under a temporary name and renamed when complete, so a sweep
killed at any moment leaves only whole cases; started again with the same arguments it loads
them and runs only the others.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import hashlib
import json
import math
import os
import shutil
import tempfile
import time
import uuid
import warnings
from collections.abc import Callable, Iterable
from pathlib import Path

import numpy as np
import pandas as pd

from .errors import ModelError, SolveError, StoreError
from .result_io import sha256_of
from .store import Store
from .summary import summarize

__all__ = ["load_result", "load_table", "on_cluster", "summarize", "sweep"]

#: how long :func:`on_cluster` waits for a scheduler to answer, s
SCHEDULER_TIMEOUT = 30.0

#: the executors of the clusters entered (:func:`on_cluster`): a sweep given no executor uses
#: the innermost
_CLUSTERS: list = []


@contextlib.contextmanager
def on_cluster(address: str, timeout: float | None = None):
    """Run every sweep inside the ``with`` block (a study's cases) on the Dask scheduler at
    ``address`` (``"tcp://host:8786"``; ``gearmodal study ... --scheduler ADDRESS``), unless
    the sweep is given its own executor. Yields the ``distributed.Client``.

    The scene path is sent resolved, so workers may run in any folder of a file system they
    share with the caller. The rows come back to the caller, which stores them. Needs the
    ``dask`` extra. An address with no scheduler behind it is a :class:`ModelError` after
    ``timeout`` s (default :data:`SCHEDULER_TIMEOUT`).
    """
    try:
        from distributed import Client
    except ImportError:
        raise ModelError("--scheduler", "needs dask.distributed: pip install "
                         "'gearmodal[dask]'") from None
    if not isinstance(address, str) or not address.strip():
        raise ModelError("--scheduler", f"= {address!r}: give the scheduler's address, "
                         "e.g. tcp://host:8786")
    try:
        client = Client(address, timeout=SCHEDULER_TIMEOUT if timeout is None else timeout)
    except (OSError, TimeoutError, ValueError) as e:
        raise ModelError("--scheduler", f"= {address!r}: no Dask scheduler answered there "
                         f"({type(e).__name__}: {str(e).splitlines()[0][:120]})") from None
    _CLUSTERS.append(client.get_executor())
    try:
        yield client
    finally:
        _CLUSTERS.pop()
        client.close()

# -- cases --------------------------------------------------------------------------------------
def _cases(parameters) -> tuple[list, list[dict]]:
    """(labels, cases) from a dict of value lists (full grid), a DataFrame (one case per
    row, index = labels) or a list of dicts."""
    if isinstance(parameters, pd.DataFrame):
        # a missing value (NaN, None) leaves that key of the scene as it is
        rows = [{k: _plain(v) for k, v in r.items() if not _missing(v)}
                for r in parameters.to_dict("records")]
        return list(parameters.index), rows
    if isinstance(parameters, dict):
        if not parameters:
            return [0], [{}]
        keys = list(parameters)
        for k in keys:
            vals = parameters[k]
            if isinstance(vals, (str, bytes)) or not isinstance(vals, Iterable):
                raise ModelError(f"parameters.{k}", f"= {vals!r}: expected a list of values")
        grids = np.meshgrid(*[np.arange(len(list(parameters[k]))) for k in keys], indexing="ij")
        lists = [list(parameters[k]) for k in keys]
        cases = [{k: _plain(lists[j][int(g.flat[i])]) for j, (k, g) in
                  enumerate(zip(keys, grids, strict=True))} for i in range(grids[0].size)]
        return list(range(len(cases))), cases
    if isinstance(parameters, Iterable):
        cases = [dict(c) for c in parameters]
        return list(range(len(cases))), [{k: _plain(v) for k, v in c.items()} for c in cases]
    raise ModelError("parameters", f"expected a dict of value lists, a DataFrame or a list of "
                     f"dicts, got {type(parameters).__name__}")


#: output rows from which a sweep's turbine case streams its rows to disk (100 s at 1 ms): a
#: shorter one is held in memory (17 MB at 30 s), where streaming would cost 15 % of its CPU
STREAM_ROWS = 100_000

def _missing(v) -> bool:
    return v is None or v is pd.NA or (isinstance(v, float) and math.isnan(v))


def _plain(v):
    """numpy scalars as Python numbers (for JSON, TOML-like overrides and hashing)."""
    if isinstance(v, np.generic):
        return v.item()
    if isinstance(v, dict):
        return {k: _plain(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_plain(x) for x in v]
    return v


def _case_json(case: dict) -> str:
    """The case as canonical JSON: sorted keys, integral floats as integers (``1.0`` and ``1``
    are the same case, e.g. a DataFrame column of seeds turned float by a NaN)."""
    def norm(v):
        if isinstance(v, float) and v.is_integer():
            return int(v)
        if isinstance(v, dict):
            return {k: norm(x) for k, x in v.items()}
        if isinstance(v, list):
            return [norm(x) for x in v]
        return v

    return json.dumps(norm(case), sort_keys=True, default=repr)


def _case_id(case: dict) -> str:
    return hashlib.sha256(_case_json(case).encode()).hexdigest()[:16]


def _callable_name(f) -> str:
    """``module.qualname`` of a function, with a partial's arguments."""
    import functools

    if isinstance(f, functools.partial):
        return f"{_callable_name(f.func)}(*{f.args!r}, **{sorted(f.keywords.items())!r})"
    return f"{getattr(f, '__module__', '?')}.{getattr(f, '__qualname__', repr(f))}"


#: the layout of a store; a store of another layout (an older gearmodal) is refused
STORE_FORMAT = "gearmodal.sweep/2"


def _scene_identity(scene) -> dict:
    """What identifies the scene in ``sweep.json``: the file and the SHA-256 of its canonical
    text (:meth:`gearmodal.scene.Scene.identity`: the dumped model, scene and turbine, so a
    comment or a moved file does not change it and an edited value does), or the
    callable's qualified name."""
    if callable(scene):
        return {"callable": _callable_name(scene)}
    from .scene import load_scene

    p = Path(scene)
    if not p.is_file():
        raise ModelError("scene", f"= {str(scene)!r}: no such scene file")
    return {"scene": str(p.resolve()), "scene_sha256": load_scene(p).identity()}


def _worker_start(parent: int) -> None:
    """A sweep's pool worker: Ctrl-C is its parent's to handle (every worker printed its own
    traceback), and it ends with its parent, a kill -9 included (Linux's parent-death
    signal: two workers of a killed study went on computing for good)."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)
    # SIGTERM ends a worker at once (the parent-death signal below is one), whatever handler
    # a forked worker inherited from the command line's (which ends a run cleanly)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    try:
        import ctypes

        libc = ctypes.CDLL("libc.so.6", use_errno=True)
        libc.prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):  # not Linux: the pool's own shutdown only
        return
    if os.getppid() != parent:  # the parent (``parent``'s pid) died before the signal was set
        os._exit(1)


def _terminate_workers(executor) -> None:
    """End a pool's workers now (Ctrl-C: the interpreter's exit would otherwise wait for the
    running cases, 36 s on the fatigue set). Python 3.14's ``terminate_workers``; before it,
    the pool's process table (the same, by hand)."""
    stop = getattr(executor, "terminate_workers", None)
    if stop is not None:
        stop()
        return
    for proc in list(getattr(executor, "_processes", {}).values()):
        proc.terminate()
    executor.shutdown(wait=True, cancel_futures=True)


def _run_case(scene, case: dict, metrics: Callable, blas_threads: int | None,
              save_to: str | None = None) -> tuple:
    """Run one case in a worker: (row, tables, cpu_s); with ``save_to`` the result is also
    saved there (``result.save``)."""
    from contextlib import nullcontext

    try:
        from threadpoolctl import threadpool_limits
        limit = threadpool_limits(blas_threads) if blas_threads else nullcontext()
    except ImportError:  # pragma: no cover - threadpoolctl is a dependency
        limit = nullcontext()
    t0 = time.process_time()
    scratch = None
    try:
        with limit:
            if callable(scene):
                result = scene(**case)
            else:
                from .scene import load_scene

                sc = load_scene(scene, overrides=case)
                out = None
                if sc.turbine is not None and sc.method != "auto" \
                        and sc.t_end / sc.dt >= STREAM_ROWS:
                    # a long turbine case streams its rows to disk as it runs (a 600 s case
                    # held in memory took 3 GB of a worker) and its metrics read them back a
                    # chunk at a time: into the kept result's folder, or a scratch one
                    out = save_to or tempfile.mkdtemp(prefix="gearmodal-case-")
                    scratch = None if save_to else out
                result = sc.simulate(out=out)
            row = dict(metrics(result))
        tables = row.pop("tables", {}) or {}
        cpu = time.process_time() - t0
        if save_to is not None:
            result.save(save_to)
    finally:
        if scratch is not None:
            shutil.rmtree(scratch, ignore_errors=True)
    return row, tables, cpu


#: a stored case's checksums of its files (``{file name: SHA-256}``)
CHECKSUMS = "sha256.json"


def _sha256(path: Path) -> str:
    return sha256_of(path)


def _read_case_file(path: Path) -> pd.DataFrame:
    """A stored case's table, verified: its SHA-256 against the case's checksums (cases
    stored before them: the pages' CRCs only) and every page's CRC; ``ValueError`` naming the
    damage otherwise."""
    sums = path.parent / CHECKSUMS
    if sums.exists():
        try:
            want = json.loads(sums.read_text()).get(path.name)
        except (OSError, ValueError) as e:
            raise ValueError(f"its checksums are unreadable ({e})") from None
        if want is not None and _sha256(path) != want:
            raise ValueError(f"{path.name} does not match its checksum")
    return pd.read_parquet(path, page_checksum_verification=True)


def _write_case(store: Store, cid: str, case: dict, row: dict, tables: dict,
                result_dir: Path | None = None) -> None:
    """Write a case whole (:meth:`gearmodal.store.Store.put`: with the saved result moved in
    as ``result/``); a case another run finished first is kept."""

    def fill(tmp: Path) -> None:
        tmp.mkdir(parents=True)
        frame = pd.DataFrame([{**row, "case_id": cid, "parameters_json": _case_json(case)}])
        frame.to_parquet(tmp / "row.parquet", write_page_checksum=True)
        for name, df in tables.items():
            df.to_parquet(tmp / f"{name}.parquet", write_page_checksum=True)
        # each file's SHA-256: damage anywhere in it (a footer's metadata too, which the
        # pages' CRCs do not cover) is found when the case is read
        (tmp / CHECKSUMS).write_text(json.dumps(
            {f.name: _sha256(f) for f in sorted(tmp.glob("*.parquet"))}, indent=1))
        if result_dir is not None:
            os.rename(result_dir, tmp / "result")

    store.put(f"cases/{cid}", fill, replace=False)


def load_result(store, case_id: str):
    """The result a case of a sweep run with ``keep_results=True`` saved: a
    :class:`~gearmodal.SimulationResult` or, for a turbine scene, a
    :class:`~gearmodal.turbine.DrivetrainResult` (their ``load``), by ``case_id``."""
    path = Path(store) / "cases" / str(case_id) / "result"
    if not path.is_dir():
        raise ModelError("case_id", f"= {case_id!r}: no saved result in {str(store)!r} (run "
                         "the sweep with keep_results=True)")
    from .saved import load_run

    return load_run(path)


def load_table(store, case_id: str, name: str) -> pd.DataFrame:
    """A table a case stored (e.g. ``"events"``, ``"forces"``) by its ``case_id`` (a column of
    the DataFrame :func:`sweep` returns)."""
    path = Path(store) / "cases" / str(case_id) / f"{name}.parquet"
    if not path.exists():
        have = sorted(p.stem for p in path.parent.glob("*.parquet")) if path.parent.exists() \
            else []
        raise ModelError("name", f"= {name!r}: case {case_id} has no such table"
                         + (f"; it has: {', '.join(have)}" if have else ""))
    try:
        return _read_case_file(path)
    except (OSError, ValueError) as e:
        raise StoreError("store", f"= {str(Path(store))!r}: {path.relative_to(Path(store))} "
                         f"is damaged ({str(e).splitlines()[0][:160]})") from None


# -- the sweep ----------------------------------------------------------------------------------
def sweep(scene, parameters, executor: cf.Executor | None = None, store=None, *,
          metrics: Callable | None = None, progress: bool = True, max_workers: int | None = None,
          blas_threads: int | None = 1, errors: str = "raise",
          keep_results: bool = False) -> pd.DataFrame:
    """Run every case of a parameter study and return one row per case.

    Parameters
    ----------
    scene : path of a scene file (each case is ``load_scene(scene, overrides=case)
        .simulate()``), or a picklable callable ``scene(**case)`` returning a result.
    parameters : ``{key: [values]}`` (the full grid, first key slowest), a DataFrame (one
        case per row; its index labels the rows returned; NaN/None leaves a key as the scene
        has it) or a list of dicts. Keys are scene
        keys (``"turbine.mounting_azimuth_deg"``) or model keys with the prefix ``model.``
        (``"model.stages.0.backlash"``); values may be tables (dicts).
    executor : any ``concurrent.futures.Executor`` (e.g. a Dask ``client.get_executor()`` for
        a cluster). Default: a local process pool with ``max_workers`` (default: the CPU
        count) processes, shut down at the end.
    store : directory. Each case is written there when it finishes (atomically, Parquet); a
        sweep started again with the same scene and store loads the finished cases and runs
        only the others. The store refuses a different scene (its files' SHA-256 differ) or
        different metrics.
    metrics : ``metrics(result) -> dict`` of scalars, optionally with ``"tables"``: a dict of
        DataFrames stored per case (:func:`load_table`). Default :func:`summarize`.
        Must be picklable (a module-level function or a ``functools.partial`` of one).
    progress : a tqdm progress bar on stderr.
    blas_threads : BLAS threads per case (1: parallel cases do not oversubscribe the cores;
        None leaves the setting alone).
    errors : ``"raise"`` (default: the first failure is raised after the cases already
        running have finished and been stored; pending ones are dropped) or ``"record"`` (the
        message goes into the ``error`` column and the case is not stored, so a resume
        retries it).
    keep_results : also keep each case's whole result in the store (``result.save``; read it
        back with :func:`load_result`). Off by default: a 30 s turbine run is ~100 MB of CSV.
        Needs a ``store`` on a file system the workers share.

    Returns
    -------
    DataFrame indexed like the cases, with the parameter columns, the metrics, ``case_id``,
    ``cpu_s`` (the case's CPU time in its worker) and ``cached`` (loaded from the store).
    ``.attrs["store"]`` holds the store path.
    """
    if max_workers is not None and (not isinstance(max_workers, int) or max_workers < 1):
        raise ModelError("max_workers", f"= {max_workers!r}: must be an integer >= 1")
    if errors not in ("raise", "record"):
        raise ModelError("errors", f"= {errors!r}: must be 'raise' or 'record'")
    if keep_results and store is None:
        raise ModelError("keep_results", "= True needs a store to keep the results in")
    metrics = summarize if metrics is None else metrics
    labels, cases = _cases(parameters)
    ids = [_case_id(c) for c in cases]
    if len(set(ids)) != len(ids):
        raise ModelError("parameters", "two cases are identical")
    root = disk = None
    ident = {**_scene_identity(scene), "metrics": _callable_name(metrics)}
    if store is not None:
        disk = Store(store, meta="sweep.json", format=STORE_FORMAT, identity=ident,
                     compare=("scene_sha256", "callable", "metrics"),
                     labels={"scene_sha256": "scene", "callable": "scene"})
        root = disk.dir / "cases"
        root.mkdir(parents=True, exist_ok=True)
        disk.clean("cases")
        # every case this store has seen, earlier runs' first (a run on a subset keeps them)
        known = {c["case_id"]: c for c in disk.previous.get("cases", [])}
        known.update({i: {"case_id": i, **c} for i, c in zip(ids, cases, strict=True)})
        disk.write_meta(cases=list(known.values()))
    rows: dict[str, dict] = {}
    for cid in ids:
        if root is not None and (root / cid).is_dir() \
                and not (root / cid / "row.parquet").exists():
            # a case folder without its row (damaged: cases are written whole): again
            warnings.warn(f"sweep: stored case {cid} has no row.parquet; computing it again",
                          stacklevel=2)
            shutil.rmtree(root / cid, ignore_errors=True)
        if root is not None and (root / cid / "row.parquet").exists():
            try:
                r = _read_case_file(root / cid / "row.parquet").iloc[0].to_dict()
            except (OSError, ValueError, IndexError) as e:
                # a damaged case (its checksum fails, truncated, empty): computed again
                warnings.warn(f"sweep: stored case {cid} is damaged "
                              f"({str(e).splitlines()[0][:120]}); computing it again",
                              stacklevel=2)
                shutil.rmtree(root / cid, ignore_errors=True)
                continue
            r.pop("parameters_json", None)
            rows[cid] = {**r, "cached": True}
    todo = [(cid, c) for cid, c in zip(ids, cases, strict=True) if cid not in rows]
    from tqdm.auto import tqdm

    bar = tqdm(total=len(cases), initial=len(cases) - len(todo), disable=not progress,
               desc="sweep", unit="case")
    if executor is None and _CLUSTERS and todo:
        if max_workers is not None:
            raise ModelError("max_workers", f"= {max_workers!r}: the sweep runs on a "
                             "cluster (on_cluster, --scheduler): its workers are the "
                             "cluster's")
        executor = _CLUSTERS[-1]
    own = executor is None and todo
    if own:
        executor = cf.ProcessPoolExecutor(max_workers=min(max_workers or os.cpu_count() or 1,
                                                          len(todo)),
                                          initializer=_worker_start,
                                          initargs=(os.getpid(),))
    interrupted = False
    try:
        saves = {cid: (str(root / f".res-{cid}-{uuid.uuid4().hex[:8]}") if keep_results
                       else None) for cid, _ in todo}
        # a scene file by its absolute path: workers may run in another folder (a cluster's)
        job = scene if callable(scene) else str(Path(scene).resolve())
        futures = {executor.submit(_run_case, job, c, metrics, blas_threads, saves[cid]):
                   (cid, c) for cid, c in todo}
        for fut in cf.as_completed(futures):
            cid, c = futures[fut]
            try:
                row, tables, cpu = fut.result()
            except Exception as err:
                if errors == "raise":
                    # keep the work already under way: store the cases still running when
                    # they finish, drop the pending ones, then raise
                    for f in futures:
                        f.cancel()
                    for f in cf.as_completed([f for f in futures if not f.cancelled()
                                              and f is not fut]):
                        if f.exception() is None and root is not None:
                            fid, fc = futures[f]
                            if not (root / fid).exists():
                                r, t, cpu_f = f.result()
                                _write_case(disk, fid, fc, {**r, "cpu_s": cpu_f}, t,
                                            _saved(saves[fid]))
                    if isinstance(err, cf.process.BrokenProcessPool):
                        raise SolveError("sweep", f"a worker process died (killed, or out of "
                                         f"memory) while running case {cid}; the finished "
                                         "cases are stored: run the sweep again to resume "
                                         "(or give errors='record')") from err
                    raise
                rows[cid] = {"error": f"{type(err).__name__}: {err}", "cached": False}
                if saves[cid] is not None:
                    shutil.rmtree(saves[cid], ignore_errors=True)
            else:
                row["cpu_s"] = cpu
                if root is not None:
                    _write_case(disk, cid, c, row, tables, _saved(saves[cid]))
                rows[cid] = {**row, "case_id": cid, "cached": False}
            bar.update(1)
    except KeyboardInterrupt:
        interrupted = True
        raise
    finally:
        bar.close()
        if own and interrupted:  # the running cases are not waited for: their workers end
            _terminate_workers(executor)
        elif own:
            executor.shutdown(wait=True, cancel_futures=True)
    params = pd.DataFrame(cases, index=labels)
    res = pd.DataFrame([{**rows[cid], "case_id": cid} for cid in ids], index=labels)
    out = pd.concat([params, res.drop(columns=[c for c in params.columns if c in res])], axis=1)
    if isinstance(parameters, pd.DataFrame):
        out.index.name = parameters.index.name
    out.attrs["store"] = str(store) if store is not None else None
    return out


def _saved(path: str | None) -> Path | None:
    return Path(path) if path is not None and Path(path).is_dir() else None
