"""Azimuth-dependent geometry as exact trigonometric polynomials (DESIGN 3.2, rotating
geometry).

A model whose frames turn against each other (a carrier against a fixed housing) assembles to
matrices that depend on the input azimuth ``psi`` only through the frame rotations
``Rz(r_f psi)``. With frame speed ratios 0 and 1 (the usual planetary carrier input) every
assembled entry is a trigonometric polynomial in ``psi``: the gap and load rows are products of
at most two rotations (a frame rotation and a line of action turning with a planet centre), so
of degree 2, and the stiffness ``sum k w w^T`` is of degree 4. :class:`AzimuthAssembler`
samples the assembly at ``2 D + 1`` equally spaced azimuths, takes their discrete Fourier
coefficients (exact interpolation of a degree-``D`` trigonometric polynomial), checks the
interpolant against a direct assembly at an azimuth off the sample grid, and then evaluates any
azimuth for the cost of a few array sums instead of a full assembly. Its coefficients are the
harmonics the exact method integrates (:mod:`gearmodal.integrate.periodic`); models for which
the check fails (other frame speed ratios) are refused there with a clear error.
"""

from __future__ import annotations

import copy
import dataclasses
import hashlib
import math
from collections import OrderedDict

import numpy as np

from ..assembly import Assembly
from ..errors import ModelError
from ..model.dump import dumps

#: trigonometric degree of the interpolant (module docstring)
DEGREE = 4
#: off-grid azimuth of the check (rad), and the check's tolerance relative to each array's size
CHECK_AZIMUTH = 0.4142135623730951
CHECK_RTOL = 1e-10

_FIELDS = ("M", "C", "K", "G", "K_cent", "K_geom", "f_cent", "B")
#: fits kept per process, by the model's text (:func:`gearmodal.dumps`, whose model assembles
#: to exactly the same matrices) and the degree: a study's seeds and a test's runs of one
#: gearbox would fit it once (2.2 s for the 5 MW gearbox's 86 assemblies). Off (0) for now:
#: with it on, runs compared across processes (the FMU against the Stepper, a Dask sweep
#: against the process pool, whose forked workers inherit the fits) differed at rounding
#: level in some clean-clone CI runs; the suspicion has not been confirmed (CHANGELOG,
#: 2026-12-08), so the cache stays off until it is
FITS_KEPT = 0
_FITS: OrderedDict[str, dict] = OrderedDict()


def _arrays(asm: Assembly, waves: bool = False) -> dict[str, np.ndarray]:
    out = {f: getattr(asm, f) for f in _FIELDS}
    out["contacts.W"] = asm.contacts.W
    # the offsets without their waves (orders that are not whole numbers: run-out, TE), which
    # join the harmonics afterwards with their own orders
    out["contacts.offset"] = asm.contacts.offset if waves else \
        asm.contacts.offset - asm.contacts.wave_offset(asm.azimuth)
    if asm.springs is not None:
        out["springs.W"] = asm.springs.W
    if asm.round is not None:
        out["round.W"] = asm.round.W
    return out


def _fit_key(model, degree: int) -> str | None:
    """The fit's key: the SHA-256 of the model's text and the degree; None for a model that
    cannot be written as text (a user-written system: fitted every time)."""
    try:
        text = dumps(model, rating=False)
    except (ModelError, TypeError, ValueError, AttributeError, KeyError):
        return None
    return hashlib.sha256(f"{degree}\n{text}".encode()).hexdigest()


class AzimuthAssembler:
    """``assemble(azimuth)`` of ``model`` by exact trigonometric interpolation (module
    docstring), falling back to direct assembly when the model's geometry is not such a
    polynomial. ``exact`` tells which path is taken."""

    def __init__(self, model, degree: int = DEGREE):
        key = _fit_key(model, degree)
        kept = _FITS.get(key) if key is not None and FITS_KEPT > 0 else None
        if kept is not None:  # the same model fitted before in this process: a copy of it
            _FITS.move_to_end(key)
            self.__dict__.update(copy.deepcopy(kept))
            self.model = model
            return
        self.model = model
        ratios = sorted({abs(float(f.speed_ratio)) for f in model.frames.values()} - {0.0})
        if all(r == 1.0 for r in ratios):
            self._fit_revolution(degree)
        else:
            self._fit_orders(degree, ratios)
        self._add_waves(self.template.contacts.waves)
        check = model.assemble(azimuth=CHECK_AZIMUTH)
        got = self._values(CHECK_AZIMUTH)
        self.exact = all(
            np.allclose(got[k], v, rtol=0, atol=CHECK_RTOL * max(np.abs(v).max(initial=0), 1e-30))
            for k, v in _arrays(check, waves=True).items())
        if key is not None and FITS_KEPT > 0:
            _FITS[key] = copy.deepcopy({k: v for k, v in self.__dict__.items() if k != "model"})
            while len(_FITS) > FITS_KEPT:
                _FITS.popitem(last=False)

    def _fit_revolution(self, degree: int) -> None:
        """Frames at speed ratios 0 and 1: the discrete Fourier coefficients of ``2 D + 1``
        assemblies over one revolution (module docstring)."""
        model = self.model
        n_s = 2 * degree + 1
        self.harmonics = np.arange(degree + 1)
        psi = 2 * math.pi * np.arange(n_s) / n_s
        samples = [model.assemble(azimuth=float(p)) for p in psi]
        self.template = samples[0]
        # real DFT: a_h = (2 / n_s) sum f(psi_j) cos(h psi_j), b_h likewise with sin; a_0 halved
        cos = np.cos(np.outer(self.harmonics, psi)) * (2.0 / n_s)
        sin = np.sin(np.outer(self.harmonics, psi)) * (2.0 / n_s)
        cos[0] *= 0.5
        self.coef: dict[str, tuple[np.ndarray, np.ndarray]] = {}
        stacked = {key: np.stack([_arrays(s)[key] for s in samples]) for key in _arrays(samples[0])}
        for key, arr in stacked.items():
            flat = arr.reshape(n_s, -1)
            shape = (len(self.harmonics),) + arr.shape[1:]
            self.coef[key] = ((cos @ flat).reshape(shape), (sin @ flat).reshape(shape))
        # keep only the harmonics present (the 600 kW drivetrain is of degree 1) and return
        # the fields that do not turn as they are
        top = 0
        self.constant = {}
        for key, (a, b) in self.coef.items():
            scale = max(float(np.abs(a).max(initial=0.0)), float(np.abs(b).max(initial=0.0)),
                        1e-300)
            live = [h for h in range(1, len(self.harmonics))
                    if max(np.abs(a[h]).max(initial=0.0), np.abs(b[h]).max(initial=0.0))
                    > 1e-14 * scale]
            if live:
                top = max(top, max(live))
            else:
                self.constant[key] = a[0].copy()
        self.harmonics = self.harmonics[:top + 1].astype(float)
        self.coef = {k: (a[:top + 1], b[:top + 1]) for k, (a, b) in self.coef.items()}

    def _fit_orders(self, degree: int, ratios: list[float]) -> None:
        """Frames at other speed ratios (a second planetary stage's carrier at 75/19 of the
        input): every assembled entry is a trigonometric polynomial whose orders are the sums
        ``sum_f n_f r_f`` of at most ``D`` frame ratios (each row a product of at most two
        frame rotations, each matrix of two rows), not whole numbers and not periodic in one
        revolution. Its coefficients at those orders are fitted by least squares to
        assemblies at ``N`` azimuths ``N`` golden-angle steps apart (2.4 rad each,
        so the span resolves the closest two orders), ``N`` twice the unknowns; the
        residual at the samples and the off-grid check (module docstring) confirm the fit."""
        model = self.model
        orders = {0.0}
        for _ in range(degree):
            orders |= {abs(o + s * r) for o in orders for r in ratios for s in (1.0, -1.0)}
        orders = np.array(sorted(orders))
        keep = np.concatenate([[True], np.diff(orders) > 1e-9])
        self.harmonics = orders[keep]
        hs = self.harmonics
        n_s = 2 * (2 * len(hs) - 1)
        psi = math.pi * (3.0 - math.sqrt(5.0)) * np.arange(n_s)  # golden angle steps
        V = np.concatenate([np.cos(np.outer(psi, hs)), np.sin(np.outer(psi, hs[1:]))], axis=1)
        samples = [model.assemble(azimuth=float(p)) for p in psi]
        self.template = samples[0]
        self.coef = {}
        self.constant = {}
        H = len(hs)
        for key in _arrays(samples[0]):
            arr = np.stack([_arrays(s)[key] for s in samples])
            flat = arr.reshape(n_s, -1)
            sol, *_ = np.linalg.lstsq(V, flat, rcond=None)
            a = sol[:H].reshape((H,) + arr.shape[1:])
            b = np.concatenate([np.zeros((1,) + arr.shape[1:]),
                                sol[H:].reshape((H - 1,) + arr.shape[1:])])
            scale = max(float(np.abs(flat).max(initial=0.0)), 1e-300)
            a[np.abs(a) <= 1e-13 * scale] = 0.0  # rounding of the fit
            b[np.abs(b) <= 1e-13 * scale] = 0.0
            if not np.any(a[1:]) and not np.any(b[1:]):
                self.constant[key] = a[0].copy()
            self.coef[key] = (a, b)
        live = np.zeros(H, bool)
        live[0] = True
        for key, (a, b) in self.coef.items():
            if key not in self.constant:
                live |= (np.abs(a) + np.abs(b)).reshape(H, -1).max(axis=1) > 0
        self.harmonics = hs[live]
        self.coef = {k: (a[live], b[live]) for k, (a, b) in self.coef.items()}

    def with_mass(self, M: np.ndarray) -> AzimuthAssembler:
        """A copy whose (constant) mass matrix is ``M`` (the mass-scaling rung,
        :mod:`gearmodal.massscale`); every other field, the loads' masses included, as is."""
        out = copy.copy(self)
        out.template = dataclasses.replace(self.template, M=M)
        out.constant = {**self.constant, "M": M}
        out.coef = dict(self.coef)
        a, b = self.coef["M"]
        a = a.copy()
        a[0] = M
        a[1:] = 0.0
        out.coef["M"] = (a, np.zeros_like(b))
        return out

    def _add_waves(self, waves) -> None:
        """Append the offset waves' orders to the harmonics (every other field zero there):
        ``Re(z e^(i h psi)) = a cos(h psi) + b sin(h psi)`` with ``a = Re z``, ``b = -Im z``."""
        if waves is None or not len(waves):
            return
        orders = np.unique(waves.h)
        n_c = len(self.template.contacts)
        self.harmonics = np.concatenate([self.harmonics, orders])
        key = "contacts.offset"
        self.constant.pop(key, None)  # it turns now (its coefficients are in coef already)
        for k, (a, b) in list(self.coef.items()):
            extra = np.zeros((len(orders),) + a.shape[1:])
            ea, eb = extra.copy(), extra.copy()
            if k == key:
                for j, h in enumerate(orders):
                    sel = waves.h == h
                    np.add.at(ea[j], waves.rows[sel], waves.z[sel].real)
                    np.add.at(eb[j], waves.rows[sel], -waves.z[sel].imag)
                assert ea.shape[1:] == (n_c,)
            self.coef[k] = (np.concatenate([a, ea]), np.concatenate([b, eb]))

    def _values(self, azimuth: float, keys=None) -> dict[str, np.ndarray]:
        """The arrays at ``azimuth`` (rad): every one, or those named in ``keys``."""
        c = np.cos(self.harmonics * azimuth)
        s = np.sin(self.harmonics * azimuth)
        items = self.coef.items() if keys is None else ((k, self.coef[k]) for k in keys)
        return {k: (self.constant[k].copy() if k in self.constant
                    else np.tensordot(c, a, axes=1) + np.tensordot(s, b, axes=1))
                for k, (a, b) in items}

    def assemble(self, azimuth: float) -> Assembly:
        """The :class:`~gearmodal.assembly.Assembly` at input azimuth ``azimuth`` (rad)."""
        if not self.exact:
            return self.model.assemble(azimuth=azimuth)
        v = self._values(float(azimuth))
        t = self.template
        contacts = dataclasses.replace(t.contacts, W=v["contacts.W"],
                                       offset=v["contacts.offset"])
        springs = t.springs
        if springs is not None:
            springs = dataclasses.replace(springs, W=v["springs.W"])
        round_ = t.round
        if round_ is not None:
            round_ = dataclasses.replace(round_, W=v["round.W"])
        return dataclasses.replace(t, **{f: v[f] for f in _FIELDS}, contacts=contacts,
                                   springs=springs, round=round_, azimuth=float(azimuth))

    def spring_forces(self, azimuth: np.ndarray, rate: np.ndarray, Q: np.ndarray,
                      V: np.ndarray) -> np.ndarray | None:
        """Forces of the always-active springs at their exact geometry: ``k g + c g'`` with
        ``g = W(psi) q`` and ``g' = W(psi) v + psi' W'(psi) q`` at each row's ``azimuth``
        (rad) and azimuth rate ``rate`` (rad/s); ``None`` when the interpolant is not exact.
        A frozen segment's rows would put a sawtooth of ``k |q| (psi - psi_mid)`` on springs
        across turning frames (tens of kN on the 600 kW carrier bearing at 2 deg)."""
        if not self.exact or "springs.W" not in self.coef:
            return None
        sp = self.template.springs
        a, b = self.coef["springs.W"]
        hs = self.harmonics
        az = np.asarray(azimuth, dtype=float)
        Q, V = np.asarray(Q, dtype=float), np.asarray(V, dtype=float)
        g = np.zeros((len(az), a.shape[1]))
        gd = np.zeros_like(g)
        rate = np.asarray(rate, dtype=float)[:, None]
        # W(psi) q = sum_h cos(h psi) a_h q + sin(h psi) b_h q: one product per harmonic
        for h, ah, bh in zip(hs, a, b, strict=True):
            c, s = np.cos(h * az)[:, None], np.sin(h * az)[:, None]
            aq, bq = Q @ ah.T, Q @ bh.T
            g += c * aq + s * bq
            gd += c * (V @ ah.T) + s * (V @ bh.T) + rate * h * (c * bq - s * aq)
        return g * sp.stiffness + gd * sp.damping

    def load_map(self, azimuth: np.ndarray) -> np.ndarray:
        """``B`` at many azimuths at once, (len(azimuth), n, n_loads)."""
        az = np.atleast_1d(np.asarray(azimuth, dtype=float))
        if not self.exact:
            return np.stack([self.model.assemble(azimuth=float(a)).B for a in az])
        a, b = self.coef["B"]
        c = np.cos(np.outer(az, self.harmonics))
        s = np.sin(np.outer(az, self.harmonics))
        return np.tensordot(c, a, axes=1) + np.tensordot(s, b, axes=1)
