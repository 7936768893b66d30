"""NREL's ROSCO controller in the loop: the compiled ``libdiscon.so`` the ``rosco`` wheel ships,
called through the Bladed-style ``DISCON`` interface every aeroelastic code uses.

The ``rosco`` wheel (2.10) holds the controller compiled for Linux (``rosco/lib/libdiscon.so``
and its Fortran runtime in ``rosco.libs/``) and, under ``Examples/Test_Cases/NREL-5MW/``, the
NREL 5 MW turbine's OpenFAST deck with the ``DISCON.IN`` tuned for it. Its Python side imports
WISDEM, which a user of gearmodal does not need: install it with ``pip install --no-deps
"rosco>=2.10,<2.11"`` (the README's ``nrel5mw`` extra); gearmodal only loads the library.

**The interface** (the Bladed "swap array", ``avrSWAP``: 32-bit floats, record ``k`` at index
``k - 1``): the simulation writes the status (record 1: 0 first call, 1 running, -1 last),
time (2), communication interval (3), blade pitch angles (4, 33, 34; rad), the measured
generator speed (20; rad/s), rotor speed (21), generator torque (23; N m), hub-height wind
speed (27; m/s) and the number of blades (61); the controller writes the demanded generator
torque (47; N m) and blade pitch angles (42-44; rad) back. The character arguments are the
parameter file's path (``DISCON.IN``) and the name its debug output files take.

**Two instances in one process.** ``libdiscon.so`` keeps its state in Fortran module
variables: two controllers loaded from the same file would share them (the dynamic loader
returns the same handle). Each :class:`Rosco` therefore loads its own copy of the library from
a private temporary folder (beside a link to the wheel's ``rosco.libs``, where the library's
run path looks for its Fortran runtime), so each has its own state; its debug files go to that
folder too, which :meth:`Rosco.close` removes. What the controller prints (its banner, warnings
and status lines) goes to that folder's ``rosco.log``, not to the terminal.
"""

from __future__ import annotations

import ctypes
import importlib.util
import math
import os
import shutil
import sys
import tempfile
import threading
from pathlib import Path

import numpy as np

from ..errors import ModelError, SolveError

#: the swap array's length (ROSCO reads records up to 165 and writes some beyond)
SWAP_SIZE = 500
#: the deck of the NREL 5 MW turbine inside the rosco wheel
NREL5MW_DECK = Path("Examples") / "Test_Cases" / "NREL-5MW"
#: standard output is the process's: one controller call redirects it at a time
_STDOUT = threading.Lock()


def rosco_files() -> tuple[Path, Path]:
    """``(libdiscon.so, the NREL 5 MW deck folder)`` of the installed ``rosco`` wheel; a
    :class:`~gearmodal.ModelError` saying how to install it when it is missing."""
    spec = importlib.util.find_spec("rosco")
    if spec is None or spec.origin is None:
        raise ModelError("rosco", "is not installed: pip install --no-deps "
                         "\"rosco>=2.10,<2.11\" (gearmodal loads its compiled controller only; "
                         "the README's nrel5mw extra)")
    pkg = Path(spec.origin).parent
    lib = pkg / "lib" / "libdiscon.so"
    deck = pkg.parent / NREL5MW_DECK
    if not lib.exists():
        raise ModelError("rosco", f"has no compiled controller at {lib} (a wheel for this "
                         "platform ships it: Linux x86_64)")
    return lib, deck


def read_discon(discon_in=None) -> dict[str, list[str]]:
    """Every parameter of a ``DISCON.IN`` (default: the 5 MW one of the wheel), ``{name:
    value tokens}``: a line ``VALUE [VALUE ...] ! NAME - comment``. Checked before the
    compiled controller reads the file (it ends the process on what it cannot read): every
    value is a quoted string or a finite number (a clear error naming the file, the key and
    the value), and the files it names (``PerfFileName``) exist."""
    path = Path(discon_in) if discon_in is not None else rosco_files()[1] / "DISCON.IN"
    try:
        text = path.read_text(errors="replace")
    except OSError as e:
        raise ModelError("discon_in", f"= {str(path)!r}: cannot read it ({e.strerror or e})") \
            from None
    out: dict[str, list[str]] = {}
    for number, line in enumerate(text.splitlines(), 1):
        value, bang, comment = line.partition("!")
        name = comment.strip().split(" ")[0].split("\t")[0] if bang else ""
        tokens = value.split()
        if not name or not tokens or line.lstrip().startswith("!"):
            continue
        for tok in tokens:
            if tok.startswith('"') or tok.startswith("'"):
                continue
            try:
                x = float(tok.replace("D", "E").replace("d", "e"))
            except ValueError:
                raise ModelError(f"{path.name}:{number} {name}", f"= {tok!r}: not a number "
                                 "(quote a text value)") from None
            if not math.isfinite(x):
                raise ModelError(f"{path.name}:{number} {name}", f"= {tok!r}: must be a "
                                 "finite number")
        out[name] = tokens
    perf = out.get("PerfFileName")
    if perf:
        f = Path(perf[0].strip('"\''))
        f = f if f.is_absolute() else path.parent / f
        if not f.is_file():
            raise ModelError(f"{path.name} PerfFileName", f"= {perf[0]}: no such file "
                             f"({f}); the controller reads its Cp, Ct and Cq tables there")
    return out


def discon_value(name: str, discon_in=None) -> float:
    """The number a ``DISCON.IN`` gives for ``name`` (``"VS_RtTq"``; default file: the 5 MW
    one of the wheel): the first value on the line whose comment starts with it."""
    path = Path(discon_in) if discon_in is not None else rosco_files()[1] / "DISCON.IN"
    values = read_discon(path)
    if name not in values:
        raise ModelError("discon_in", f"{path.name} gives no {name}")
    tok = values[name][0]
    try:
        return float(tok.replace("D", "E").replace("d", "e"))
    except ValueError:
        raise ModelError(f"{path.name} {name}", f"= {tok}: not a number") from None


def _private_folder() -> Path:
    """A new private folder for one controller, in a path without dots: ROSCO names its
    debug files from the output name cut at its first ``.``, so under a ``TMPDIR`` such as
    ``mktemp -d`` makes (``/tmp/tmp.AbC``) they would land outside the folder. Tried in
    order: ``TMPDIR`` (the system's temporary folder), ``/tmp``, ``/dev/shm``, the working
    folder."""
    tried = []
    for base in (tempfile.gettempdir(), "/tmp", "/dev/shm", os.getcwd()):
        if "." in base or base in tried:
            tried.append(base)
            continue
        tried.append(base)
        try:
            d = Path(tempfile.mkdtemp(prefix="gearmodal-rosco-", dir=base))
        except OSError:
            continue
        if "." not in str(d):
            return d
        shutil.rmtree(d, ignore_errors=True)
    raise ModelError("TMPDIR", f"= {tempfile.gettempdir()!r}: ROSCO needs a writable "
                     "temporary folder whose path has no '.' (it cuts its debug files' names "
                     "at the first one); tried " + ", ".join(tried))


class Rosco:
    """One ROSCO controller (module docstring).

    Parameters
    ----------
    discon_in : its parameter file; default: the ``DISCON.IN`` of the NREL 5 MW turbine the
        wheel ships.
    dt : the controller's sample time, s (its calls should come every ``dt``).
    blades : number of blades.
    pitch0 : the blades' pitch at the start, rad.
    efficiency : the generator's, 0..1: the electrical power the controller is told (record
        15) is the shaft power times it.
    """

    def __init__(self, discon_in=None, *, dt: float, blades: int = 3, pitch0: float = 0.0,
                 efficiency: float = 1.0):
        lib, deck = rosco_files()
        self.discon_in = Path(discon_in) if discon_in is not None else deck / "DISCON.IN"
        if not self.discon_in.is_file():
            raise ModelError("discon_in", f"= {str(self.discon_in)!r}: no such file")
        if not (isinstance(dt, (int, float)) and math.isfinite(dt) and dt > 0):
            raise ModelError("dt", f"= {dt!r}: must be a finite number > 0 s")
        if isinstance(blades, bool) or not isinstance(blades, (int, np.integer)) or \
                not 1 <= blades <= 10:
            raise ModelError("blades", f"= {blades!r}: an integer from 1 to 10")
        if not (isinstance(efficiency, (int, float)) and 0 < efficiency <= 1):
            raise ModelError("efficiency", f"= {efficiency!r}: the generator's, a number in "
                             "(0, 1]")
        if not (isinstance(pitch0, (int, float)) and math.isfinite(pitch0)):
            raise ModelError("pitch0", f"= {pitch0!r}: a finite angle in rad")
        read_discon(self.discon_in)  # the controller ends the process on what it cannot read
        self.dt = float(dt)
        self.efficiency = float(efficiency)
        self._lib = None
        self._dir = _private_folder()
        try:
            (self._dir / "rosco.libs").symlink_to(lib.parent.parent.parent / "rosco.libs")
            copy = self._dir / "lib" / "discon" / "libdiscon.so"
            copy.parent.mkdir(parents=True)
            shutil.copy2(lib, copy)
            self._lib = ctypes.CDLL(str(copy))
        except OSError as e:
            shutil.rmtree(self._dir, ignore_errors=True)
            raise ModelError("rosco", f"its library could not be loaded from a private copy "
                             f"in {self._dir.parent} ({e}); a temporary folder that allows "
                             "executables is needed (TMPDIR)") from None
        # the controller writes its banner and status to standard output (Fortran unit 6),
        # buffered by the Fortran runtime: flushed after each call, while standard output is
        # its log (the runtime may be scipy's copy of the same library, loaded and set up
        # before this: its buffering cannot be switched off here)
        runtime = sorted(p.name for p in (self._dir / "rosco.libs").glob("libgfortran*"))
        self._flush = ctypes.CDLL(runtime[0])._gfortran_flush_i4 if runtime else None
        self.log = self._dir / "rosco.log"  # what the controller printed
        self._log = None  # its file, open while the controller lives (opened at the 1st call)
        self._lib.DISCON.argtypes = [ctypes.POINTER(ctypes.c_float),
                                     ctypes.POINTER(ctypes.c_int32), ctypes.c_char_p,
                                     ctypes.c_char_p, ctypes.c_char_p]
        self._lib.DISCON.restype = None
        self._infile = str(self.discon_in.resolve()).encode()
        self._outname = str(self._dir / "rosco").encode()
        self._msg = ctypes.create_string_buffer(1000)
        self._fail = ctypes.c_int32(0)
        self.swap = np.zeros(SWAP_SIZE, dtype=np.float32)
        self._args = (self.swap.ctypes.data_as(ctypes.POINTER(ctypes.c_float)),  # fixed
                      ctypes.byref(self._fail), self._infile, self._outname, self._msg)
        s = self.swap
        s[2] = self.dt
        s[60] = blades
        s[3] = s[32] = s[33] = pitch0
        s[48], s[49] = 1000, len(self._infile)
        s[50], s[51] = len(self._outname), 1000
        self.started = False
        self.torque, self.pitch = 0.0, float(pitch0)

    def step(self, t: float, generator_speed: float, rotor_speed: float, pitch: float,
             generator_torque: float, wind_speed: float) -> tuple[float, float]:
        """One controller call at time ``t`` (s) with the measured ``generator_speed`` and
        ``rotor_speed`` (rad/s), the blades' ``pitch`` (rad), the ``generator_torque`` (N m)
        and the hub-height ``wind_speed`` (m/s): returns the demanded generator torque (N m)
        and collective blade pitch (rad)."""
        if self._lib is None:
            raise ModelError("rosco", "the controller was closed")
        for name, v in (("t", t), ("generator_speed", generator_speed),
                        ("rotor_speed", rotor_speed), ("pitch", pitch),
                        ("generator_torque", generator_torque), ("wind_speed", wind_speed)):
            try:
                ok = math.isfinite(v)
            except TypeError:
                ok = False
            if not ok:
                raise ModelError(f"rosco.step {name}", f"= {v!r}: must be a finite number "
                                 "(a diverged turbine run feeds the controller this)")
        s = self.swap
        s[0] = 1.0 if self.started else 0.0
        s[1] = t
        s[3] = s[32] = s[33] = pitch
        s[19], s[20] = generator_speed, rotor_speed
        s[22] = generator_torque
        s[26] = wind_speed
        s[14] = generator_torque * generator_speed * self.efficiency  # electrical power, W
        self._call()
        self.started = True
        self.torque, self.pitch = float(s[46]), float(s[41])
        return self.torque, self.pitch

    def _call(self) -> None:
        """Call DISCON with the process's standard output sent to :attr:`log` (a solver
        never prints). Standard output is the process's: the redirection holds a lock, so
        controllers in several threads take turns (and nothing else printed during a call
        reaches the terminal); with no standard output to redirect, the call is made as
        is."""
        args = self._args
        with _STDOUT:
            if sys.stdout is not None:
                sys.stdout.flush()
            try:
                saved = os.dup(1)
            except OSError:  # no standard output: nothing to keep from the terminal
                self._lib.DISCON(*args)
                return
            try:
                if self._log is None:
                    self._log = open(self.log, "ab")  # noqa: SIM115 (closed in close())
                os.dup2(self._log.fileno(), 1)
                self._lib.DISCON(*args)
                if self._flush is not None:
                    self._flush(ctypes.byref(ctypes.c_int32(6)))
            finally:
                os.dup2(saved, 1)
                os.close(saved)
        if self._fail.value < 0:
            msg = self._msg.value.decode(errors="replace").strip()
            raise SolveError("rosco", f"DISCON failed at t = {float(self.swap[1]):.4g} s: {msg}")

    def close(self) -> None:
        """End the controller (its last call) and remove its private folder."""
        if self._lib is not None and self.started:
            self.swap[0] = -1.0
            try:
                self._call()
            except SolveError:
                pass
        self._lib = None
        if self._log is not None:
            self._log.close()
            self._log = None
        shutil.rmtree(self._dir, ignore_errors=True)

    def __enter__(self) -> Rosco:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
