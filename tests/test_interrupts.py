"""Interruptions leave nothing behind (issue 40 item 2): a sweep's workers end with their
parent (kill -9 included), Ctrl-C is one line and ends the workers at once, and the next run
removes the temporary case folders a killed writer left. Real processes and signals: the
waits poll up to generous limits, so that a busy machine only makes them slower."""

import os
import signal
import subprocess
import sys
import time

import pytest

import gearmodal as gm

SCENE = "studies/scenes/600kw_turbine_10ms.toml"


def _children(pid: int) -> list[int]:
    out = []
    try:
        for tid in os.listdir(f"/proc/{pid}/task"):
            with open(f"/proc/{pid}/task/{tid}/children") as f:
                out += [int(c) for c in f.read().split()]
    except FileNotFoundError:
        pass
    return out


def _running(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().split()[2] != "Z"
    except FileNotFoundError:
        return False


def _wait(cond, limit: float) -> bool:
    end = time.monotonic() + limit
    while time.monotonic() < end:
        if cond():
            return True
        time.sleep(0.1)
    return cond()


pytestmark = pytest.mark.skipif(not os.path.isdir("/proc/self/task"),
                                reason="reads the process table from Linux's /proc")


@pytest.mark.slow
def test_workers_end_with_a_killed_parent(tmp_path):
    code = (f"import gearmodal as gm; gm.sweep({SCENE!r}, {{'scene.t_end': [300.0, 301.0]}}, "
            "max_workers=2, progress=False)")
    p = subprocess.Popen([sys.executable, "-c", code], start_new_session=True)
    try:
        assert _wait(lambda: len(_children(p.pid)) >= 2, 120.0)
        workers = _children(p.pid)
        os.kill(p.pid, signal.SIGKILL)
        p.wait()
        assert _wait(lambda: not any(_running(w) for w in workers), 60.0), workers
    finally:
        if p.poll() is None:
            os.killpg(p.pid, signal.SIGKILL)


@pytest.mark.slow
@pytest.mark.parametrize("how, status, line", [
    ("group", 130, "gearmodal: interrupted"),  # Ctrl-C reaches the whole foreground group
    ("term", 143, "gearmodal: terminated"),  # kill, a batch system's limit: the parent only
])
def test_ctrl_c_and_sigterm_are_one_line_and_end_the_workers(tmp_path, how, status, line):
    exe = os.path.join(os.path.dirname(sys.executable), "gearmodal")
    p = subprocess.Popen([exe, "study", "fatigue", "--quick", "--seeds", "1", "--duration",
                          "300", "--workers", "2", "--quiet", "--out", str(tmp_path)],
                         stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        assert _wait(lambda: len(_children(p.pid)) >= 2, 120.0)
        workers = _children(p.pid)
        time.sleep(1.0)
        if how == "group":
            os.killpg(p.pid, signal.SIGINT)
        else:
            os.kill(p.pid, signal.SIGTERM)
        err = p.communicate(timeout=120)[1]
        assert p.returncode == status
        assert err.strip().splitlines() == [line], err[-2000:]
        assert _wait(lambda: not any(_running(w) for w in workers), 60.0), workers
    finally:
        if p.poll() is None:
            os.killpg(p.pid, signal.SIGKILL)


def test_a_killed_writers_temporary_case_is_cleaned(tmp_path):
    store = tmp_path / "store"
    old = store / "cases" / ".tmp-abc-12345678"
    old.mkdir(parents=True)
    (old / "row.parquet").write_bytes(b"half")
    then = time.time() - 3600
    os.utime(old, (then, then))
    fresh = store / "cases" / ".tmp-def-12345678"
    fresh.mkdir()  # a writer that may still be running: kept
    gm.sweep("studies/scenes/planetary_double_contact.toml", {"scene.t_end": [0.002]}, store=store,
             progress=False, max_workers=1)
    assert not old.exists() and fresh.exists()
