"""Wind at the rotating blade elements: mean speed with power-law shear, tower shadow and 3D
turbulence (DESIGN 2.5).

Turbulence (``pip install gearmodal[wind]``), seeded so that runs repeat, on a square grid over
the rotor: ``model = "kaimal"`` (default) from PyConTurb (J. Rinker, DTU Wind Energy), a Kaimal
spectrum with IEC 61400-1 Ed. 4 coherence; ``model = "mann"`` from DTU's hipersim, Mann's
(1994) uniformly sheared spectral tensor, the model HAWC2 uses, generated as a box along the
wind and swept past the rotor at the mean speed (Taylor's frozen turbulence), with length scale
``mann_length_scale`` (default IEC 61400-1: 0.8 Lambda_1, Lambda_1 = 0.7 min(hub height, 60 m)),
anisotropy ``mann_gamma`` (3.9) and either ``mann_alphaeps`` (``alpha eps^(2/3)``, m^(4/3)/s^2)
or, by default, scaled so that the longitudinal standard deviation over the box is
``turbulence_intensity`` times the mean speed (the box's lateral and vertical deviations follow
from the tensor: about 0.7 and 0.5 of it, IEC 61400-1 Annex C). Between grid points the field
is interpolated bilinearly, between time samples linearly. Axes (nonrotating, at the hub):
``x`` downwind along the shaft, ``z`` up, ``y`` completing a right-handed set; ``z`` below is
measured from the ground.

Tower shadow: potential flow around the tower cylinder (radius ``tower_radius``) with the rotor
``tower_distance`` upstream of the tower axis: ``u / U = 1 - a^2 (x^2 - y^2) / (x^2 + y^2)^2``
below the tower top (the classical model of Bak et al., Risø-R-1281, 2001, in its potential-flow
form).
"""

from __future__ import annotations

import contextlib
import functools
from dataclasses import dataclass

import numba
import numpy as np

from ..errors import ModelError
from ..model.schema import Field, Table

#: bytes the coherence matrices of one chunk of frequencies may take (PyConTurb ``nf_chunk``)
COHERENCE_BYTES = 128 * 2**20


def coherence_chunk(nt: int, n_points: int) -> int:
    """PyConTurb's ``nf_chunk`` for a box of ``nt`` time steps and ``n_points`` columns: as
    many frequencies per chunk (their coherence in one vectorised call) as fit in
    :data:`COHERENCE_BYTES`; every frequency in one chunk when they all fit (6x faster than
    one at a time on the 30 s scene). Chunk sizes between 1 and the frequency count rely on
    :func:`aligned_chunks` (PyConTurb 2.7 mislabels the frequencies at multiples of the
    chunk); without it (another PyConTurb version) only 1 or all are used."""
    n_f = nt // 2 + 1
    fit = max(COHERENCE_BYTES // (n_points**2 * 8), 1)
    if fit >= n_f:
        return n_f
    return fit if _aligned_fix_applies() else 1


@functools.cache
def _aligned_fix_applies() -> bool:
    """Whether the installed PyConTurb has the 2.7 chunk loop :func:`aligned_chunks` fixes."""
    try:
        from importlib.metadata import version

        return version("pyconturb").startswith("2.7.")
    except Exception:  # pragma: no cover - not installed
        return False


@contextlib.contextmanager
def aligned_chunks():
    """Within the block, PyConTurb 2.7's ``gen_turb`` gets every frequency's own coherence
    with any ``nf_chunk``. Its loop (``pyconturb/simulation.py``) makes a chunk at frequency
    index ``i = (k - 1) c + 1`` from the indices ``get_chunk_idcs`` gives for chunk
    ``i // c = k - 1`` (``[(k - 1) c, k c)``) and reads entry ``i % c`` for ``i`` up to
    ``k c``: entry 0, read at ``i = k c``, holds frequency ``(k - 1) c``. The indices given
    here put ``k c`` in entry 0 (the others unchanged), so every read is right; checked against
    the frequency-by-frequency box in tests/test_turbine.py. Does nothing for another
    PyConTurb version."""
    if not _aligned_fix_applies():
        yield
        return
    import pyconturb.simulation as sim

    saved = sim.get_chunk_idcs

    def get_chunk_idcs(freq, i_chunk, nf_chunk):
        if nf_chunk <= 1:
            return saved(freq, i_chunk, nf_chunk)
        idx = np.arange(i_chunk * nf_chunk, (i_chunk + 1) * nf_chunk)
        idx[0] = (i_chunk + 1) * nf_chunk
        return np.minimum(idx, len(freq) - 1)  # beyond the last: never read

    sim.get_chunk_idcs = get_chunk_idcs
    try:
        yield
    finally:
        sim.get_chunk_idcs = saved


#: turbulence boxes kept per process (by the wind's parameters; a 600 s box of 7 x 7 points
#: is 7 MB)
BOX_CACHE = 4
_BOXES: dict = {}


@dataclass
class Wind:
    """A wind field.

    Parameters
    ----------
    mean_speed : m/s at hub height. hub_height : m.
    shear_exponent : power-law exponent (0.2 is IEC's normal wind profile).
    turbulence_intensity : longitudinal standard deviation / mean speed (0 = no turbulence);
        lateral and vertical are 0.8 and 0.5 of it (IEC 61400-1 Kaimal).
    seed : random seed of the turbulence.
    duration : s of turbulence to generate. dt : s between turbulence samples.
    half_width : m, the grid covers ``hub +- half_width`` (set it to ~1.1 rotor radii).
    grid_points : points per side of the turbulence grid.
    tower_radius : m (0: no tower shadow). tower_distance : m from rotor plane to tower axis.
    model : ``"kaimal"`` or ``"mann"`` (module docstring). mann_length_scale : m (None: IEC).
    mann_gamma : Mann's anisotropy. mann_alphaeps : ``alpha eps^(2/3)`` (None: scale to the
    turbulence intensity).
    """

    mean_speed: float = 10.0
    hub_height: float = 40.0
    shear_exponent: float = 0.2
    turbulence_intensity: float = 0.0
    seed: int = 1
    duration: float = 60.0
    dt: float = 0.1
    half_width: float = 24.0
    grid_points: int = 7
    tower_radius: float = 1.0
    tower_distance: float = 2.5
    model: str = "kaimal"
    mann_length_scale: float | None = None
    mann_gamma: float = 3.9
    mann_alphaeps: float | None = None

    def __post_init__(self):
        if self.model not in ("kaimal", "mann"):
            raise ModelError("wind.model", f"= {self.model!r}: must be 'kaimal' or 'mann'")
        for label, val, lo, hi in (("mann_length_scale", self.mann_length_scale, 1.0, 1e3),
                                   ("mann_gamma", self.mann_gamma, 0.0, 10.0),
                                   ("mann_alphaeps", self.mann_alphaeps, 1e-6, 100.0)):
            if val is not None and not (isinstance(val, (int, float)) and lo <= val <= hi):
                raise ModelError(f"wind.{label}", f"= {val!r}: must be in [{lo}, {hi}]")
        for label, val, lo, hi in (("mean_speed", self.mean_speed, 0.0, 60.0),
                                   ("hub_height", self.hub_height, 1.0, 500.0),
                                   ("shear_exponent", self.shear_exponent, 0.0, 1.0),
                                   ("turbulence_intensity", self.turbulence_intensity, 0.0, 1.0),
                                   ("duration", self.duration, 1e-3, 1e5),
                                   ("dt", self.dt, 1e-3, 10.0),
                                   ("half_width", self.half_width, 0.1, 500.0),
                                   ("tower_radius", self.tower_radius, 0.0, 20.0)):
            if not (lo <= float(val) <= hi):
                raise ModelError(f"wind.{label}", f"= {val!r}: must be in [{lo}, {hi}]")
        if self.tower_radius > 0 and self.tower_distance <= self.tower_radius:
            raise ModelError("wind.tower_distance", f"= {self.tower_distance!r}: must exceed "
                             f"the tower radius {self.tower_radius} m")
        if self.grid_points < 2:
            raise ModelError("wind.grid_points", f"= {self.grid_points!r}: at least 2")
        self._box = None

    @property
    def turbulent(self) -> bool:
        """True when the wind has turbulence (an intensity, or Mann's alpha eps^(2/3))."""
        return self.turbulence_intensity > 0 or self.mann_alphaeps is not None

    def __getstate__(self):
        """Pickle without the turbulence box: a cache rebuilt from the seed on first use, so
        that a pickled (or fingerprinted) wind is the same before and after a run."""
        return {**self.__dict__, "_box": None}

    # -- turbulence box ------------------------------------------------------------------
    def _turbulence(self):
        """(times, y, z, box[time, comp, iy, iz]) of the turbulent fluctuations (read-only;
        the process keeps the last :data:`BOX_CACHE` boxes by their parameters, so that the
        cases of a study on one seed generate it once per worker)."""
        if self._box is None:
            key = tuple((k, v) for k, v in sorted(vars(self).items())
                        if k not in ("_box", "shear_exponent", "tower_radius", "tower_distance"))
            box = _BOXES.get(key)
            if box is None:
                box = self._generate()
                for a in box:
                    a.flags.writeable = False
                _BOXES[key] = box
                while len(_BOXES) > BOX_CACHE:
                    _BOXES.pop(next(iter(_BOXES)))
            self._box = box
        return self._box

    def _generate(self):
        """A new box: (times, y, z, box) as :meth:`_turbulence` returns it. Made with one BLAS
        thread: with two, PyConTurb's products round differently (3.6e-15 m/s on the 30 s
        scene's box), which a rattling gearbox amplifies into its peaks, so a seed would not
        give the same run on every machine."""
        from threadpoolctl import threadpool_limits

        with threadpool_limits(1, user_api="blas"):
            return self._generate_box()

    def _generate_box(self):
        ny = self.grid_points
        y = np.linspace(-self.half_width, self.half_width, ny)
        z = self.hub_height + np.linspace(-self.half_width, self.half_width, ny)
        nt = int(np.ceil(self.duration / self.dt)) + 1
        t = np.arange(nt) * self.dt
        if not self.turbulent:
            box = np.zeros((nt, 3, ny, ny))
        elif self.model == "mann":
            box = self._mann_box(nt, ny, float(y[1] - y[0]))
        else:
            try:
                from pyconturb import gen_spat_grid, gen_turb
                from pyconturb.sig_models import constant_sig
                from pyconturb.wind_profiles import constant_profile
            except ImportError as err:  # pragma: no cover - environment
                raise ModelError("wind.turbulence_intensity", "turbulence needs PyConTurb: "
                                 "pip install 'gearmodal[wind]'") from err
            spat = gen_spat_grid(y, z)
            sig = self.turbulence_intensity * self.mean_speed
            with aligned_chunks():
                df = gen_turb(spat, T=nt * self.dt, nt=nt, seed=int(self.seed),
                              u_ref=self.mean_speed, z_ref=self.hub_height,
                              wsp_func=constant_profile, sig_func=constant_sig,
                              sig_vals=[sig, 0.8 * sig, 0.5 * sig], comps=[0, 1, 2],
                              nf_chunk=coherence_chunk(nt, spat.shape[1]))
            vals = df.to_numpy()[:nt]  # columns u_p0, v_p0, w_p0, u_p1, ...: y outer, z inner
            box = vals.reshape(nt, ny, ny, 3).transpose(0, 3, 1, 2).copy()
            box -= box.mean(axis=0, keepdims=True)  # the mean comes from the profile
        return t, y, z, box

    def _mann_box(self, nt: int, ny: int, dy: float) -> np.ndarray:
        """The Mann box swept past the rotor, (nt, 3, ny, ny): x = U t along the wind."""
        try:
            from hipersim import MannTurbulenceField
        except ImportError as err:  # pragma: no cover - environment
            raise ModelError("wind.model", "= 'mann' needs hipersim: pip install "
                             "'gearmodal[wind]'") from err
        length = self.mann_length_scale
        if length is None:  # IEC 61400-1: L = 0.8 Lambda_1, Lambda_1 = 0.7 min(z_hub, 60 m)
            length = 0.8 * 0.7 * min(self.hub_height, 60.0)
        nx = 1 << max(int(np.ceil(np.log2(nt))), 4)  # the FFT's length, a power of two
        field = MannTurbulenceField.generate(
            alphaepsilon=self.mann_alphaeps if self.mann_alphaeps is not None else 1.0,
            L=length, Gamma=self.mann_gamma, Nxyz=(nx, ny, ny),
            dxyz=(self.mean_speed * self.dt, dy, dy), seed=int(self.seed))
        uvw = np.asarray(field.uvw, dtype=float)  # (3, nx, ny, nz): u, v lateral, w up
        if self.mann_alphaeps is None:  # scaled to the target intensity
            uvw = uvw * (self.turbulence_intensity * self.mean_speed / uvw[0].std())
        box = uvw[:, :nt].transpose(1, 0, 2, 3).copy()
        box -= box.mean(axis=0, keepdims=True)
        return box

    # -- sampling --------------------------------------------------------------------------
    def velocity(self, t: float, y: np.ndarray, z: np.ndarray) -> np.ndarray:
        """Wind velocity (3, ...) = (u downwind, v lateral, w up) in m/s at time ``t`` and
        points ``(y, z)`` (m; ``z`` above ground), including shear and tower shadow."""
        y = np.asarray(y, dtype=float)
        z = np.asarray(z, dtype=float)
        shape = np.broadcast_shapes(y.shape, z.shape)
        yf = np.ascontiguousarray(np.broadcast_to(y, shape)).ravel()
        zf = np.ascontiguousarray(np.broadcast_to(z, shape)).ravel()
        if self.turbulent:
            tt, gy, gz, box = self._turbulence()
            if t > tt[-1] + 1e-9:
                raise ModelError("wind.duration", f"= {self.duration}: the run reached t = "
                                 f"{t:.3f} s beyond the turbulence generated")
            k = min(int(t / self.dt), len(tt) - 2)
            w = (t - tt[k]) / self.dt
        else:
            gy = gz = np.zeros(2)
            box, k, w = np.zeros((2, 3, 2, 2)), 0, 0.0
        out = _sample(yf, zf, float(self.mean_speed), float(self.hub_height),
                      float(self.shear_exponent), self.turbulent, box, k, w, gy[0],
                      gy[1] - gy[0], gz[0], gz[1] - gz[0], float(self.tower_radius),
                      float(self.tower_distance))
        return out.reshape((3, *shape))


@numba.njit(cache=True)
def _sample(y, z, U, z_hub, alpha, turbulent, box, k, w, y0, dy, z0, dz, r_tower, x_tower):
    """:meth:`Wind.velocity` at the points ``(y[i], z[i])``: power-law shear, the box
    frames ``k`` and ``k + 1`` blended by ``w`` and interpolated bilinearly (clipped to the
    grid), the potential-flow tower shadow below the hub (3, n)."""
    n = y.shape[0]
    ny, nz = box.shape[2], box.shape[3]
    out = np.zeros((3, n))
    for i in range(n):
        zc = max(z[i], 0.1)
        out[0, i] = U * (zc / z_hub) ** alpha
        if turbulent:
            fy = min(max((y[i] - y0) / dy, 0.0), ny - 1 - 1e-12)
            fz = min(max((z[i] - z0) / dz, 0.0), nz - 1 - 1e-12)
            iy, iz = int(fy), int(fz)
            ay, az = fy - iy, fz - iz
            for c in range(3):
                v = 0.0
                for f, wf in ((k, 1.0 - w), (k + 1, w)):
                    v += wf * ((1 - ay) * (1 - az) * box[f, c, iy, iz]
                               + ay * (1 - az) * box[f, c, iy + 1, iz]
                               + (1 - ay) * az * box[f, c, iy, iz + 1]
                               + ay * az * box[f, c, iy + 1, iz + 1])
                out[c, i] += v
        if r_tower > 0 and z[i] < z_hub:
            r2 = x_tower * x_tower + y[i] * y[i]
            out[0, i] *= 1.0 - r_tower * r_tower * (x_tower * x_tower - y[i] * y[i]) / (r2 * r2)
    return out


#: the ``[wind]`` table of a scene file (:mod:`gearmodal.model.schema`)
Wind.SCHEMA = Table("wind", (
    Field("mean_speed", "number", "m/s", low=0.0, high=60.0, default=10.0,
          doc="mean wind speed at hub height"),
    Field("hub_height", "number", "m", low=1.0, high=500.0,
          doc="hub height (default: the turbine's)"),
    Field("shear_exponent", "number", low=0.0, high=1.0, default=0.2,
          doc="power-law shear exponent (IEC normal wind profile: 0.2)"),
    Field("turbulence_intensity", "number", low=0.0, high=1.0, default=0.0,
          doc="longitudinal standard deviation over the mean (0: no turbulence)"),
    Field("seed", "integer", low=0, high=2**32 - 1, default=1, doc="seed of the turbulence"),
    Field("duration", "number", "s", low=1e-3, high=1e5,
          doc="turbulence to generate (default: the scene's t_end + 1 s)"),
    Field("dt", "number", "s", low=1e-3, high=10.0, default=0.1,
          doc="step of the turbulence samples"),
    Field("half_width", "number", "m", low=0.1, high=500.0,
          doc="the grid covers hub +- half_width (default: 1.1 rotor radii)"),
    Field("grid_points", "integer", low=2, high=64, default=7,
          doc="grid points per side (the box grows as their square)"),
    Field("tower_radius", "number", "m", low=0.0, high=20.0, default=1.0,
          doc="tower radius (0: no tower shadow)"),
    Field("tower_distance", "number", "m", low=0.0, low_open=True, default=2.5,
          doc="rotor plane to tower axis"),
    Field("model", "choice", choices=("kaimal", "mann"), default="kaimal",
          doc="turbulence model: Kaimal (PyConTurb) or Mann (hipersim, as HAWC2)"),
    Field("mann_length_scale", "number", "m", low=1.0, high=1e3,
          doc="Mann length scale L (default IEC: 0.8 x 0.7 min(hub height, 60 m))"),
    Field("mann_gamma", "number", low=0.0, high=10.0, default=3.9,
          doc="Mann anisotropy Gamma"),
    Field("mann_alphaeps", "number", "m^(4/3)/s^2", low=1e-6, high=100.0,
          doc="Mann alpha eps^(2/3) (default: scaled to turbulence_intensity)")),
    "Wind of a turbine scene (`gearmodal.turbine.Wind`).")
