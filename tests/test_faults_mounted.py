"""Where the output cannot be written, on real file systems (issue 40 items 3-5): a tmpfs too
small for the run (a full disk) and one mounted read-only. Mounting needs root with the right
to mount (CI's container has it); elsewhere the tests skip, saying why. The command line gives
one line naming the cause (exit status 2, no internal error), and a save that fills the disk
half-way leaves the earlier result there loading as it was."""

import math
import os
import subprocess
import sys
import uuid
from pathlib import Path

import pandas as pd
import pytest

import gearmodal as gm


def _mount(path: Path, options: str) -> bool:
    path.mkdir(parents=True, exist_ok=True)
    r = subprocess.run(["mount", "-t", "tmpfs", "-o", options, "tmpfs", str(path)],
                       capture_output=True, text=True)
    return r.returncode == 0


@pytest.fixture
def mounted(tmp_path):
    """``mount(options) -> folder``: a tmpfs mounted for the test, unmounted after it."""
    if not sys.platform.startswith("linux") or os.geteuid() != 0:
        pytest.skip("mounting a tmpfs needs root on Linux (CI runs these)")
    done = []

    def mount(options: str) -> Path:
        p = tmp_path / f"mnt-{uuid.uuid4().hex[:6]}"
        if not _mount(p, options):
            pytest.skip("this container may not mount a tmpfs (CI's can)")
        done.append(p)
        return p

    yield mount
    for p in reversed(done):
        subprocess.run(["umount", "-l", str(p)], capture_output=True)


def _cli(*args: str) -> subprocess.CompletedProcess:
    exe = os.path.join(os.path.dirname(sys.executable), "gearmodal")
    return subprocess.run([exe, *args], capture_output=True, text=True, timeout=600)


def test_a_full_disk_is_one_line(mounted):
    small = mounted("size=64k")
    r = _cli("simulate", "studies/scenes/planetary_double_contact.toml", "--out",
             str(small / "run"), "--t-end", "0.05", "--quiet")
    assert r.returncode == 2, r.stderr[-500:]
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "No space left on device" in lines[0], r.stderr[-500:]
    assert "internal error" not in r.stderr


def test_a_read_only_folder_is_one_line_before_any_computing(mounted):
    ro = mounted("size=1m,ro")
    r = _cli("simulate", "studies/scenes/planetary_double_contact.toml", "--out",
             str(ro / "run"), "--quiet")
    assert r.returncode == 2, r.stderr[-500:]
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "--out" in lines[0] and "Read-only file system" in lines[0], \
        r.stderr[-500:]


def test_a_save_that_fills_the_disk_keeps_the_earlier_result(mounted):
    p = gm.Gear(20, 0.004, math.radians(20), mass=1.0, inertia=1e-3)
    w = gm.Gear(40, 0.004, math.radians(20), mass=4.0, inertia=1.6e-2)
    pair = gm.gear_pair(p, w, mesh_stiffness=2e8, backlash=1e-4)
    small = mounted("size=256k")
    first = gm.simulate(pair, 0.002, dt=1e-4, v0={"pinion.theta": 1.0})
    first.save(small / "run", format="csv")
    big = gm.simulate(pair, 0.2, dt=1e-5, v0={"pinion.theta": 1.0})  # MBs of CSV
    with pytest.raises(OSError) as e:
        big.save(small / "run", format="csv")
    assert "No space left" in str(e.value)
    back = gm.SimulationResult.load(small / "run")
    pd.testing.assert_frame_equal(back.q, first.q, check_exact=True)
    assert sorted(x.name for x in small.iterdir()) == ["run"]  # nothing left beside it
