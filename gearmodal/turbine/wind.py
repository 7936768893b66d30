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

from dataclasses import dataclass

import numba
import numpy as np

from ..errors import ModelError
from ..model.schema import Field, Table

#: bytes the coherence matrices of one chunk of frequencies may take (:func:`kaimal_box`):
#: 8 MiB is 48 frequencies of a 7 x 7 grid's 147 columns, vectorised enough (the 30 s
#: scene's box: 0.07 s) and small beside a long run's box
COHERENCE_BYTES = 8 * 2**20


def coherence_chunk(nt: int, n_points: int) -> int:
    """Frequencies per chunk of :func:`kaimal_box` for a box of ``nt`` time steps and
    ``n_points`` columns: as many as fit in :data:`COHERENCE_BYTES` (at least one). The box
    does not depend on it (each frequency's coherence and Cholesky factor are its own)."""
    n_f = nt // 2 + 1
    return int(min(max(COHERENCE_BYTES // (n_points**2 * 8), 1), n_f))


def kaimal_box(y: np.ndarray, z: np.ndarray, nt: int, dt: float, seed: int, u_ref: float,
               sig_vals: list) -> np.ndarray:
    """A Kaimal turbulence box with IEC 61400-1 coherence by the Veers method, as PyConTurb's
    ``gen_turb`` makes it (constant mean ``u_ref`` and standard deviations ``sig_vals`` of u,
    v, w; points ``y`` outer, ``z`` inner): ``(nt, 3, ny, ny)`` m/s, the mean included.

    The same operations on the same numbers in the same order as PyConTurb 2.7 (its random
    stream drawn row by row; tests/test_turbine.py compares the boxes to the bit), in memory
    that does not hold the box five times over and without PyConTurb's import (28 MB of
    SciPy and h5py): ``gen_turb`` keeps the magnitudes, the random phases, the spectrum, the
    time series and a DataFrame of them (a 3 600 s box on 7 x 7 points peaked 420 MB above
    the box's 42 MB). Here the phases are drawn and the coherence is formed a chunk of
    frequencies at a time (:func:`coherence_chunk`), and each column's inverse FFT goes
    straight into the box.

    Kaimal spectrum (IEC 61400-1 ed. 3, C.2): ``S_k(f) = 4 tau_k / (1 + 6 tau_k f)^(5/3)``,
    ``tau_k = L_k / U``, ``L_k = (8.1, 2.7, 0.66) Lambda_1``, ``Lambda_1 = 0.7 z`` below 60 m
    else 42 m; magnitudes ``sqrt(S df / 2)`` scaled to ``sig_vals`` exactly; u coherence
    ``exp(-12 sqrt((f / U)^2 + (0.12 / L_c)^2) r)``, ``L_c = 340.2`` m (IEC ed. 4 as
    PyConTurb); v and w uncorrelated between points."""
    import itertools

    from scipy.linalg import cholesky

    ny = len(y)
    ys, zs = np.meshgrid(y, z)
    n_p = ys.size
    k = np.tile(np.array([0, 1, 2]), n_p).astype(float)  # columns u_p0, v_p0, w_p0, u_p1...
    yy = np.repeat(ys.T.ravel(), 3).astype(float)
    zz = np.repeat(zs.T.ravel(), 3).astype(float)
    n_s = k.size
    T = nt * dt
    n_f = nt // 2 + 1
    freq = np.arange(n_f) / T
    # magnitudes (PyConTurb: kaimal_spectrum, spc_to_mag, constant_sig)
    f = np.reshape(freq, (-1, 1))
    lambda_1 = 0.7 * zz * (zz < 60) + 42 * (zz >= 60)
    l_k = lambda_1 * (8.1 * np.isclose(k, 0) + 2.7 * np.isclose(k, 1) + 0.66 * np.isclose(k, 2))
    tau = np.reshape((l_k / u_ref), (1, -1))
    mags = np.sqrt(((4 * tau) / np.power(1. + 6 * tau * f, 5. / 3.)) * freq[1] / 2)
    mags[0, :] = 0.
    sig_k = np.empty(n_s)
    for ki in (0, 1, 2):
        sig_k[k.astype(int) == ki] = sig_vals[ki]
    if nt == 2:
        std_now = np.sqrt(nt / (nt - 1) * np.sum(np.abs(mags)**2, axis=0))
    else:
        std_now = np.sqrt(nt / (nt - 1) * (2 * np.sum(np.abs(mags)**2, axis=0)
                                           - ((nt + 1) % 2) * np.abs(mags[-1, :])**2))
    mags = ((sig_k / std_now) * mags).astype(float)
    # the u components' point pairs and distances (PyConTurb: get_iec_cor_mat)
    i_u = np.arange(n_s)[k == 0]
    pairs = list(itertools.combinations(i_u, 2))
    ii = np.array([p[0] for p in pairs], dtype=np.int64)
    jj = np.array([p[1] for p in pairs], dtype=np.int64)
    r = np.sqrt((yy[ii] - yy[jj])**2 + (zz[ii] - zz[jj])**2)
    spectrum = np.zeros((n_f, n_s), dtype=np.complex128)
    rng = np.random.RandomState(seed)  # gen_turb: np.random.seed(seed); rand(n_f, n_s)
    chunk = coherence_chunk(nt, n_s)
    empty = np.array([])
    for a in range(0, n_f, chunk):
        b = min(a + chunk, n_f)
        phases = np.exp(1j * 2 * np.pi * rng.rand(b - a, n_s))
        if b == n_f and not (nt % 2):  # even nt: the last phase 0 or pi (a real signal)
            phases[-1, :] = np.exp(1j * np.round(np.real(phases[-1, :])) * np.pi)
        lo = max(a, 1)  # the mean (frequency 0) stays zero
        if lo >= b:
            continue
        fc = np.array(freq[lo:b]).reshape(-1, 1)
        coh = np.repeat(np.eye(n_s, dtype=np.float64)[None, :, :], b - lo, axis=0)
        exp_constant = np.sqrt((1 / u_ref * fc)**2 + (0.12 / 340.2)**2).astype(np.float64)
        for c0 in range(0, len(ii), 10_000):  # PyConTurb's pairs per chunk
            sl = slice(c0, c0 + 10_000)
            vals = np.exp(-12 * np.abs(r[sl]) * exp_constant)
            coh[:, ii[sl], jj[sl]] = vals
            coh[:, jj[sl], ii[sl]] = np.conj(vals)
        for i in range(lo, b):
            L = cholesky(coh[i - lo], check_finite=False, lower=True) * mags[i]
            spectrum[i, :] = L @ np.concatenate((empty, phases[i - a, :]))
        del coh
    del mags  # the spectrum is formed: the box takes its place
    wsp = np.ones_like(yy) * u_ref * (k == 0)
    box = np.empty((nt, 3, ny, ny))
    for j in range(n_s):  # columns u_p0, v_p0, w_p0, u_p1, ...: y outer, z inner
        p, c = divmod(j, 3)
        box[:, c, p // ny, p % ny] = np.fft.irfft(spectrum[:, j], n=nt) * nt + wsp[j]
    return box


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
    def release(self) -> None:
        """Drop this wind's turbulence box from memory (it and the process's cache of boxes
        hold it; a 3 600 s box of 7 x 7 points is 42 MB): after a long run, before its
        figures. A later sample generates it again, the same to the bit."""
        key = self._key()
        self._box = None
        _BOXES.pop(key, None)

    def _key(self) -> tuple:
        return tuple((k, v) for k, v in sorted(vars(self).items())
                     if k not in ("_box", "shear_exponent", "tower_radius", "tower_distance"))

    def _turbulence(self):
        """(times, y, z, box[time, comp, iy, iz]) of the turbulent fluctuations (read-only;
        the process keeps the last :data:`BOX_CACHE` boxes by their parameters, so that the
        cases of a study on one seed generate it once per worker)."""
        if self._box is None:
            key = self._key()
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
            sig = self.turbulence_intensity * self.mean_speed
            box = kaimal_box(y, z, nt, self.dt, int(self.seed), self.mean_speed,
                             [sig, 0.8 * sig, 0.5 * sig])
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
    def velocity(self, t: float, y: np.ndarray, z: np.ndarray,
                 x: np.ndarray | None = None) -> np.ndarray:
        """Wind velocity (3, ...) = (u downwind, v lateral, w up) in m/s at time ``t`` and
        points ``(y, z)`` (m; ``z`` above ground), including shear and tower shadow; ``x``:
        each point's distance upwind of the tower's axis for the shadow (m; default
        ``tower_distance``, the rotor plane's)."""
        y = np.asarray(y, dtype=float)
        z = np.asarray(z, dtype=float)
        if y.shape == z.shape:  # (the rotor's points every aerodynamic step)
            shape, yf, zf = y.shape, y.ravel(), z.ravel()
        else:
            shape = np.broadcast_shapes(y.shape, z.shape)
            yf = np.ascontiguousarray(np.broadcast_to(y, shape)).ravel()
            zf = np.ascontiguousarray(np.broadcast_to(z, shape)).ravel()
        if x is None:
            xf = np.full(yf.shape, float(self.tower_distance))
        else:
            xf = np.ascontiguousarray(np.broadcast_to(np.asarray(x, dtype=float), shape)).ravel()
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
                      gy[1] - gy[0], gz[0], gz[1] - gz[0], float(self.tower_radius), xf)
        return out.reshape((3, *shape))


@numba.njit(cache=True)
def _sample(y, z, U, z_hub, alpha, turbulent, box, k, w, y0, dy, z0, dz, r_tower, xt):
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
            x_tower = xt[i]
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
