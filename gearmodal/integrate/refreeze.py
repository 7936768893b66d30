"""Cheap refreezing of azimuth-dependent geometry (DESIGN 3.2, rotating geometry).

A model whose frames turn against each other (a carrier against a fixed housing) assembles to
matrices that depend on the input azimuth ``psi`` only through the frame rotations
``Rz(r_f psi)``. With frame speed ratios 0 and 1 (the usual planetary carrier input) every
assembled entry is a trigonometric polynomial in ``psi``: the gap and load rows are products of
at most two rotations (a frame rotation and a line of action turning with a planet centre), so
of degree 2, and the stiffness ``sum k w w^T`` is of degree 4. :class:`AzimuthAssembler`
samples the assembly at ``2 D + 1`` equally spaced azimuths, takes their discrete Fourier
coefficients (exact interpolation of a degree-``D`` trigonometric polynomial), checks the
interpolant against a direct assembly at an azimuth off the sample grid, and then evaluates any
azimuth for the cost of a few array sums instead of a full assembly. Models for which the check
fails (other frame speed ratios) are assembled directly at every refreeze.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..assembly import Assembly

#: trigonometric degree of the interpolant (module docstring)
DEGREE = 4
#: off-grid azimuth of the check (rad), and the check's tolerance relative to each array's size
CHECK_AZIMUTH = 0.4142135623730951
CHECK_RTOL = 1e-10

_FIELDS = ("M", "C", "K", "G", "K_cent", "f_cent", "B")


def _arrays(asm: Assembly) -> dict[str, np.ndarray]:
    out = {f: getattr(asm, f) for f in _FIELDS}
    out["contacts.W"] = asm.contacts.W
    out["contacts.offset"] = asm.contacts.offset
    if asm.springs is not None:
        out["springs.W"] = asm.springs.W
    return out


class AzimuthAssembler:
    """``assemble(azimuth)`` of ``model`` by exact trigonometric interpolation (module
    docstring), falling back to direct assembly when the model's geometry is not such a
    polynomial. ``exact`` tells which path is taken."""

    def __init__(self, model, degree: int = DEGREE):
        self.model = model
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
        check = model.assemble(azimuth=CHECK_AZIMUTH)
        got = self._values(CHECK_AZIMUTH)
        self.exact = all(
            np.allclose(got[k], v, rtol=0, atol=CHECK_RTOL * max(np.abs(v).max(initial=0), 1e-30))
            for k, v in _arrays(check).items())

    def _values(self, azimuth: float) -> dict[str, np.ndarray]:
        c = np.cos(self.harmonics * azimuth)
        s = np.sin(self.harmonics * azimuth)
        return {k: np.tensordot(c, a, axes=1) + np.tensordot(s, b, axes=1)
                for k, (a, b) in self.coef.items()}

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
        return dataclasses.replace(t, **{f: v[f] for f in _FIELDS}, contacts=contacts,
                                   springs=springs, azimuth=float(azimuth))

    def load_map(self, azimuth: np.ndarray) -> np.ndarray:
        """``B`` at many azimuths at once, (len(azimuth), n, n_loads)."""
        az = np.atleast_1d(np.asarray(azimuth, dtype=float))
        if not self.exact:
            return np.stack([self.model.assemble(azimuth=float(a)).B for a in az])
        a, b = self.coef["B"]
        c = np.cos(np.outer(az, self.harmonics))
        s = np.sin(np.outer(az, self.harmonics))
        return np.tensordot(c, a, axes=1) + np.tensordot(s, b, axes=1)


class QuasiStaticTransport:
    """Carry a state across a refreeze without an artificial jolt.

    A frozen segment holds the geometry at its middle azimuth; the true geometry turns
    continuously. A static deflection across frames turning against each other (a housing
    sagging on its suspension under the rotor weight, seen from the rotating carrier) is
    therefore held fixed in the rotating axes during a segment, and at the refreeze the
    coupling rows turn by the segment's angle: the elastic forces would jump by about ``k |q|
    dpsi`` (28 kN for the 600 kW carrier bearing at 1.45 deg) and ring the gearbox. Since the
    geometry turns slowly against the elastic frequencies (0.4 Hz against 10 Hz and above),
    the true response to it is quasi-static, so at a refreeze the state is shifted by the change
    of the static solution from the old to the new frozen system, in the current contact state
    ``s``::

        q <- q + q_st(new) - q_st(old),   K_s q_st = F + f_s - M R (R^T M R)^-1 R^T (F + f_s)

    with ``R`` the free (rigid-body) modes (d'Alembert: an accelerating drivetrain) and ``q_st``
    M-orthogonal to them. Its cost is two linear solves per refreeze; its benefit is measured
    in ``benchmarks/turbine_speed.py`` against a finely refrozen reference.
    """

    def __init__(self, free: np.ndarray, M: np.ndarray):
        self.R = free
        self.MR = M @ free
        if free.shape[1]:
            self.RtMR_inv = np.linalg.inv(free.T @ self.MR)
            # basis of the complement of the free modes (Euclidean), for a regular solve
            self.Q = np.linalg.qr(free, mode="complete")[0][:, free.shape[1]:]
        else:
            self.RtMR_inv = np.zeros((0, 0))
            self.Q = np.eye(M.shape[0])

    def _stiffness(self, system, s):
        # without the centripetal softening: Lin & Parker's -m Omega^2 terms also soften the
        # free rotation (the centrifugal preload that balances them is not modelled), which
        # makes the static problem nearly singular along it at speed
        K, _, f = system.matrices(s)
        K = K - (system.K0 - system.asm.K)
        H = self.Q.T @ K @ self.Q
        return H, f, float(np.linalg.cond(H))

    def static(self, system, s: np.ndarray, F: np.ndarray) -> np.ndarray:
        """Static deflection of ``system`` in contact state ``s`` under the generalised force
        ``F`` (d'Alembert-balanced on the free modes, M-orthogonal to them)."""
        H, f, _ = self._stiffness(system, s)
        return self._solve(H, f, F)

    def _solve(self, H, f, F):
        g = F + f
        g = g - self.MR @ (self.RtMR_inv @ (self.R.T @ g))
        q = self.Q @ np.linalg.solve(H, self.Q.T @ g)
        return q - self.R @ (self.RtMR_inv @ (self.MR.T @ q))

    def shift(self, old, new, s: np.ndarray, F_old: np.ndarray, F_new: np.ndarray):
        """``q_st(new) - q_st(old)`` in contact state ``s``. A state that holds the structure
        poorly (a gear free in its backlash: the static problem is singular or nearly so,
        condition above ``1e3`` times that of the nominal state) is replaced by the nominal
        state (front flanks closed), which moves the bearing and support deflections the
        same way; the tooth deflections then carry over unchanged."""
        nominal = new.asm.contacts.nominal
        states = [s] if np.array_equal(s, nominal) else [s, nominal]
        ref = self._stiffness(new, nominal)[2]
        for state in states:
            Hn, fn, cn = self._stiffness(new, state)
            if cn > 1e3 * ref and state is not nominal:
                continue
            Ho, fo, _ = self._stiffness(old, state)
            return self._solve(Hn, fn, F_new) - self._solve(Ho, fo, F_old)
        return np.zeros(len(F_new))
