"""The piecewise-linear system in first-order form, per contact state (DESIGN 3.2).

Within contact state ``s`` the equations of motion are linear::

    x' = A_s x + Bm F(t),   x = [q; v],   A_s = [[0, I], [-M^-1 K_s, -M^-1 C_s]],
    Bm = [0; M^-1],          F(t) = B u(t) + f_s + Omega^2 f_cent

with ``K_s``, ``C_s``, ``f_s`` from :class:`gearmodal.assembly.Assembly`. Over a step of length
``h`` with the force linear in time (first-order hold), the exact solution is (Van Loan's
augmented exponential)::

    expm([[A h, Bm h, 0], [0, 0, I], [0, 0, 0]]) = [[Phi, Ga, Gb], [0, I, I], [0, 0, I]]
    x(h) = Phi x(0) + (Ga - Gb) F(0) + Gb F(h)

:class:`Propagators` caches ``(Phi, Ga - Gb, Gb)`` per contact state and per dyadic step
``dt / 2^j``; any duration is covered by dyadic pieces plus a short remainder evaluated by the
Taylor series of the exact solution (convergent to machine precision because the remainder is
shorter than ``0.5 / rho(A_s)``).
"""

from __future__ import annotations

import math
import weakref

import numpy as np
import scipy.linalg as sla

from ..assembly import Assembly
from ..errors import ModelError

RPM = 2.0 * math.pi / 60.0
#: the Taylor remainder is used on pieces with rho(A) * length <= TAYLOR_REACH
TAYLOR_REACH = 0.5
#: number of Taylor terms kept (error ~ TAYLOR_REACH^n / n!, far below machine precision)
TAYLOR_TERMS = 28


#: per geometry (weakly): the mass factors and turning data its systems share
_SHARED: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


class PiecewiseLinearSystem:
    """First-order matrices of an assembled model at a frozen input speed.

    Parameters
    ----------
    asm : the assembled model (at the run's start azimuth when ``geometry`` is given).
    speed_rpm : input speed; gyroscopic, centripetal and centrifugal terms are frozen at it,
        and the input azimuth turns at it.
    geometry : an :class:`~gearmodal.integrate.azimuth.AzimuthAssembler` of the model whose
        frames turn against each other: the system is then time-periodic, its constant part
        held here (``K0``, ``C0``, ``W``, ``offset`` with the turning contacts' rows zero) and
        its turning harmonics in ``periodic`` (:mod:`gearmodal.integrate.periodic`), integrated
        exactly by the Taylor propagator; :meth:`at` gives the frozen matrices at any azimuth
        (the reference methods).
    spectral_bound : the spectral bound of a system that differs from this one only in its
        speed terms (1/s; :func:`~gearmodal.integrate.exact.shared_bounds`), reused with a
        small margin instead of computing a new bound.
    state_bound : that system's per-state bounds, reused likewise.
    grounded : ``(dof, stiffness, damping)`` springs from coordinates to ground (N/m or N m/rad,
        N s/m or N m s/rad): the spring-damper through which a co-simulation host drives a
        shaft (:class:`~gearmodal.integrate.stepper.Drive`). On a coordinate about a wheel's
        own axis it is the same in every frame, so a turning system holds it in its constant
        part.
    load_columns : on a turning system, the run's forces given as values of these columns of
        the load map, the constant centrifugal force last (:meth:`_use_loads`: the map turns,
        the loads stay in their own axes); a frozen system takes generalised forces and
        ignores it.
    azimuth0 : the input azimuth at the start of the stretch this system is integrated over
        (rad; its tables' times count from there).

    The system is a value: nothing changes it after construction. The integration methods
    keep what they compute for it (propagators, spectral bounds) in their own caches
    (:func:`gearmodal.integrate.exact.shared_bounds`).
    """

    def __init__(self, asm: Assembly, speed_rpm: float = 0.0, inputs: np.ndarray | None = None,
                 geometry=None, spectral_bound: float | None = None, state_bound=None,
                 grounded: tuple = (), load_columns: list[int] | None = None,
                 azimuth0: float = 0.0):
        self.asm = asm
        # a bound of the spectral radius known from a system that differs from this one only
        # in its speed terms (the turbine's re-basing): the Taylor integrator takes it with a
        # margin instead of computing one (taylor.RHO_SPEED)
        self.rho_base = spectral_bound
        # and its per-state bounds (gearmodal.integrate.taylor.StateBound), likewise reused
        self.state_bound_base = state_bound
        n = asm.n
        self.n = n
        om = float(speed_rpm) * RPM
        self.speed_rpm = float(speed_rpm)
        # the factors and the turning data depend on the mass and the geometry only: a system
        # re-based to another speed on the same assembly and geometry (the turbine run) reuses
        # them (_SHARED, keyed by the geometry and holding the mass array it was made from)
        shared = _SHARED.get(geometry) if geometry is not None else None
        if shared is not None and shared["M"] is asm.M:
            self.Linv, self.Minv = shared["Linv"], shared["Minv"]
        else:
            try:
                L = np.linalg.cholesky(asm.M)
            except np.linalg.LinAlgError:
                raise ModelError("mass", "the mass matrix is not positive definite") from None
            # M = L L^T, M^-1 = Linv^T Linv (numpy's inverse of the small triangular factor:
            # the scipy wrappers' checks cost more than the solves at these sizes)
            self.Linv = np.linalg.inv(L)
            self.Minv = self.Linv.T @ self.Linv
            shared = None
        self.geometry = None
        self.periodic = None
        self.GT = np.zeros((1, 0, 0), dtype=complex)  # turning load harmonics (_use_loads)
        self.load_columns = None
        K, C, W, off = asm.K, asm.C, asm.contacts.W, asm.contacts.offset
        if geometry is not None:
            from .periodic import periodic_data

            if shared is None:
                shared = {"M": asm.M, "Linv": self.Linv, "Minv": self.Minv,
                          "periodic": periodic_data(geometry, self.Minv)}
                _SHARED[geometry] = shared
            const, self.periodic = shared["periodic"]
            if self.periodic is not None:
                self.geometry = geometry
                K, C = const["K"], const["C"]
                W, off = const["contacts.W"], const["contacts.offset"]
        self.K0 = K + om**2 * asm.K_cent + om * asm.K_speed
        self.C0 = C + om * asm.G
        self.C_extra = None  # grounded
        self.K_extra = None  # grounded
        for dof, kg, cg in grounded:
            if self.K_extra is None:
                self.K_extra, self.C_extra = np.zeros((n, n)), np.zeros((n, n))
            self.K_extra[dof, dof] += kg
            self.C_extra[dof, dof] += cg
        if self.K_extra is not None:
            self.K0 = self.K0 + self.K_extra
            self.C0 = self.C0 + self.C_extra
        self.f_const = om**2 * asm.f_cent
        c = asm.contacts
        self.W = np.ascontiguousarray(W)
        self.offset = np.array(off, dtype=float)
        self.k = c.stiffness.copy()
        self.c = c.damping.copy()
        self.names = [f"{e}:{f}" for e, f in zip(c.element, c.contact, strict=True)]
        # alternating mesh stiffness (Mesh.alternation): ``k`` holds the means; a run takes
        # the values at its start azimuth and the schedule of changes (stiffness_at, schedule)
        self.variation = c.variation
        self.omega = om
        self.k_max = self.k
        if self.variation is not None and len(self.variation):
            vr = self.variation
            self.k_max = self.k.copy()
            self.k_max[vr.rows] = np.maximum(vr.k_single, vr.k_double)
        # Optional input basis P (n x m, orthonormal): every generalised force of a run lies in
        # span(P), so the exact propagators need only the m columns Minv P instead of Minv
        # (Van Loan's augmented matrix 2n + 2m instead of 4n). The contacts' constant forces
        # (gaps with an offset) are added to the span, so every contact state's f_s is in it.
        self.P = None
        self.MinvU = self.Minv
        if inputs is not None:
            self._set_inputs(inputs)
        if load_columns is not None and self.turning:
            self._use_loads(load_columns)
        #: input azimuth at the start of the system's stretch (rad)
        self.azimuth0 = float(azimuth0)

    @property
    def turning(self) -> bool:
        """True when the geometry turns (a time-periodic system, ``periodic`` set)."""
        return self.periodic is not None

    def _use_loads(self, columns: list[int], constant: bool = True) -> None:
        """Forces of a run are given as values of the load map's ``columns`` (a grid (rows,
        m) with m = ``len(columns)`` plus one when ``constant``: then the last column
        multiplies the constant centrifugal force ``f_const``, give it 1); a turning load map
        is followed exactly (the loads are fixed in their own axes, the map turns)."""
        from .periodic import load_harmonics

        extra = self.f_const[:, None] if constant else None
        if self.geometry is not None:
            self.MinvU, self.GT = load_harmonics(self.geometry, self.Minv, list(columns), extra)
        else:
            B = self.asm.B[:, list(columns)]
            cols = np.concatenate([B] + ([extra] if extra is not None else []), axis=1)
            self.MinvU = np.ascontiguousarray(self.Minv @ cols)
            self.GT = np.zeros((1, 0, 0), dtype=complex)
        self.load_columns = (list(columns), constant)

    def generalized_force(self, u: np.ndarray, azimuth: float) -> np.ndarray:
        """The generalised force (n,) of one row ``u`` of the force grid at input ``azimuth``
        (rad): the load values when the system takes load columns (the load map at that
        azimuth), else ``u`` itself."""
        if self.load_columns is None:
            return u
        cols, constant = self.load_columns
        B = self.at(azimuth, ("B",))["B"][:, cols]
        F = B @ u[:len(cols)]
        return F + self.f_const * u[-1] if constant else F

    def at(self, azimuth: float, only: tuple | None = None) -> dict:
        """Frozen matrices at input ``azimuth`` (rad): ``K0``, ``C0``, ``W``, ``offset``, ``B``
        (the reference methods of a turning system evaluate them at each instant); ``only``:
        just these of ``W``, ``offset``, ``B`` (a turning system evaluates no others)."""
        if self.geometry is None:
            return {"K0": self.K0, "C0": self.C0, "W": self.asm.contacts.W,
                    "offset": self.asm.contacts.offset, "B": self.asm.B}
        if only is not None:
            names = {"W": "contacts.W", "offset": "contacts.offset", "B": "B"}
            v = self.geometry._values(float(azimuth), [names[k] for k in only])
            return {k: v[names[k]] for k in only}
        v = self.geometry._values(float(azimuth))
        om = self.omega
        C0 = v["C"] + om * self.asm.G
        K0 = v["K"] + om**2 * self.asm.K_cent + om * self.asm.K_speed
        if self.C_extra is not None:
            C0 = C0 + self.C_extra
        if self.K_extra is not None:
            K0 = K0 + self.K_extra
        return {"K0": K0, "C0": C0,
                "W": v["contacts.W"], "offset": v["contacts.offset"], "B": v["B"]}

    def _set_inputs(self, inputs: np.ndarray) -> None:
        """Set the input basis from spanning columns ``inputs`` (n, k): every generalised force
        given to the exact method must then lie in their span (with the contacts' constant
        forces)."""
        if self.turning:
            raise ModelError("inputs", "a turning system takes its forces as load values "
                             "(load_columns), not in an input basis")
        n = self.n
        cols = [np.asarray(inputs, dtype=float).reshape(n, -1)]
        hit = self.offset != 0.0
        if np.any(hit):
            cols.append((self.W[hit] * (self.k[hit] * self.offset[hit])[:, None]).T)
        U = np.concatenate(cols, axis=1)
        U = U[:, np.abs(U).max(axis=0) > 0]
        Q, R, _ = sla.qr(U, mode="economic", pivoting=True)
        d = np.abs(np.diag(R))
        rank = int(np.sum(d > 1e-12 * max(d.max(initial=0.0), 1e-300)))
        if rank < n:  # else the basis saves nothing
            self.P = np.ascontiguousarray(Q[:, :rank])
            self.MinvU = np.ascontiguousarray(self.Minv @ self.P)

    def reduce(self, F: np.ndarray) -> np.ndarray:
        """Generalised forces (rows, n) in the input basis (rows, m); checks that they lie in
        it (a force outside it would be silently dropped)."""
        if self.P is None:
            return F
        Fr = F @ self.P
        scale = max(float(np.abs(F).max(initial=0.0)), 1e-300)
        if np.abs(F - Fr @ self.P.T).max(initial=0.0) > 1e-9 * scale:
            raise ModelError("inputs", "a generalised force lies outside the system's input "
                             "basis; give the basis every load column the run uses")
        return np.ascontiguousarray(Fr)

    @property
    def n_contacts(self) -> int:
        return len(self.offset)

    @property
    def alternating(self) -> bool:
        """True if some mesh stiffness alternates (a time-dependent contact stiffness)."""
        return self.variation is not None and len(self.variation) > 0

    def stiffness_at(self, azimuth: float) -> np.ndarray:
        """Contact stiffnesses at input azimuth ``azimuth`` (rad): the means, with the
        alternating mesh flanks at their value there (mesh_stiffness M1)."""
        if not self.alternating:
            return self.k
        return self.variation.table(self.k, azimuth, self.omega < 0)[0]

    def schedule(self, azimuth0: float, duration: float):
        """Stiffness changes ``(times, rows, k)`` over ``(0, duration]`` s of a run starting at
        input azimuth ``azimuth0`` (rad) and turning at the frozen speed."""
        if not self.alternating:
            return np.zeros(0), np.zeros(0, dtype=np.int64), np.zeros(0)
        return self.variation.schedule(azimuth0, self.omega, duration)

    def matrices(self, s: np.ndarray, k: np.ndarray | None = None, frozen: dict | None = None):
        """``(K_s, C_s, f_s)`` of contact state ``s`` (booleans), with contact stiffnesses
        ``k`` (default: the system's); ``frozen``: the matrices of :meth:`at` (default: the
        constant part)."""
        k = self.k if k is None else k
        K0, C0, W, off = ((self.K0, self.C0, self.W, self.offset) if frozen is None else
                          (frozen["K0"], frozen["C0"], frozen["W"], frozen["offset"]))
        W = W[s]
        K = K0 + (W.T * k[s]) @ W
        C = C0 + (W.T * self.c[s]) @ W
        f = W.T @ (k[s] * off[s])
        return K, C, f

    def first_order(self, s: np.ndarray, k: np.ndarray | None = None,
                    frozen: dict | None = None):
        """``(A_s, f_s)``: the state matrix and the constant contact force of state ``s``."""
        n = self.n
        K, C, f = self.matrices(s, k, frozen)
        A = np.zeros((2 * n, 2 * n))
        A[:n, n:] = np.eye(n)
        A[n:, :n] = -self.Minv @ K
        A[n:, n:] = -self.Minv @ C
        return A, f

    def spectral_bound(self, s: np.ndarray) -> float:
        """An upper bound of the spectral radius of ``A_s``, 1/s.

        An eigenpair satisfies ``(lam^2 M + lam C_s + K_s) x = 0``; with ``y = L^T x``
        (``M = L L^T``, ``|y| = 1``) and ``K^ = L^-1 K_s L^-T``, ``C^ = L^-1 C_s L^-T``:
        ``|lam|^2 <= |lam| |C^| + |K^|``, so ``|lam| <= (c + sqrt(c^2 + 4 k)) / 2`` with the
        spectral norms ``c``, ``k``. Tight for lightly damped systems (it is the highest
        natural frequency when ``C = 0``) and ~4x cheaper than the eigenvalues of ``A_s``."""
        if self.n == 0:
            return 0.0
        K, C, _ = self.matrices(s)
        Li = self.Linv
        Kh = Li @ K @ Li.T
        # |K^| by its eigenvalues when symmetric (cheaper than the SVD); |C^| <= its Frobenius
        # norm, a bound as valid and tight when the damping is light
        if np.allclose(Kh, Kh.T, rtol=0, atol=1e-12 * np.abs(Kh).max(initial=1e-300)):
            k = float(np.abs(np.linalg.eigvalsh(0.5 * (Kh + Kh.T))).max(initial=0.0))
        else:
            k = np.linalg.norm(Kh, 2)
        c = np.linalg.norm(Li @ C @ Li.T)
        return float(0.5 * (c + math.sqrt(c * c + 4.0 * k)))

    def penetration(self, x: np.ndarray, azimuth: float | None = None) -> np.ndarray:
        """Penetration ``W q - offset`` of every contact (a turning system: at input
        ``azimuth``, rad, default the run's start)."""
        if self.geometry is not None:
            f = self.at(self.azimuth0 if azimuth is None else azimuth, ("W", "offset"))
            return f["W"] @ x[: self.n] - f["offset"]
        return self.W @ x[: self.n] - self.offset

    def rate(self, x: np.ndarray, azimuth: float | None = None) -> np.ndarray:
        """Penetration rate, the time derivative of the gap: ``W v``, plus for a turning row
        ``Omega (W'(psi) q - offset'(psi))`` at input ``azimuth`` (rad; default the run's
        start). (The contact's damping force acts on ``W v`` only: :meth:`velocity_term`.)"""
        if self.geometry is None:
            return self.W @ x[self.n:]
        psi = self.azimuth0 if azimuth is None else azimuth
        Wd, od = self._row_derivatives(psi)
        return self.velocity_term(x, psi) + self.omega * (Wd @ x[: self.n] - od)

    def velocity_term(self, x: np.ndarray, azimuth: float | None = None) -> np.ndarray:
        """``W(psi) v``: the velocity on which a contact's damping acts (the assembled
        equations' ``C = sum c w w^T``)."""
        if self.geometry is None:
            return self.W @ x[self.n:]
        return self.at(self.azimuth0 if azimuth is None else azimuth, ("W",))["W"] @ x[self.n:]

    def _row_derivatives(self, azimuth: float) -> tuple[np.ndarray, np.ndarray]:
        """``dW/dpsi`` and ``d offset/dpsi`` of the contact rows at ``azimuth``."""
        g = self.geometry
        hs = g.harmonics
        c, s = np.cos(hs * azimuth), np.sin(hs * azimuth)
        out = []
        for key in ("contacts.W", "contacts.offset"):
            if key in g.constant:
                out.append(np.zeros_like(g.constant[key]))
            else:
                a, b = g.coef[key]
                out.append(np.tensordot(-hs * s, a, axes=1) + np.tensordot(hs * c, b, axes=1))
        return out[0], out[1]

    def gaps(self, X: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Penetrations ``W q - offset`` and their velocity terms ``W v`` of every contact for
        states ``X`` (rows, 2n) at times ``t`` (s from the run's start), the turning rows at
        each time's azimuth."""
        n = self.n
        P = X[:, :n] @ self.W.T - self.offset
        R = X[:, n:] @ self.W.T
        if self.turning:
            pr = self.periodic
            az = self.azimuth0 + self.omega * np.asarray(t, dtype=float)
            E = np.exp(1j * np.outer(az, pr.harm))
            Wt = np.einsum("th,hej->tej", E, pr.TW).real
            P[:, pr.tc_idx] = (np.einsum("tej,tj->te", Wt, X[:, pr.tcols])
                               - (E @ pr.TOFF).real)
            R[:, pr.tc_idx] = np.einsum("tej,tj->te", Wt, X[:, n + pr.tcols])
        return P, R

    def spring_forces(self, X: np.ndarray, t: np.ndarray) -> np.ndarray | None:
        """Forces ``k w q + c w v`` of the always-active springs (rows, springs) at times ``t``
        (s from the run's start), their rows at each time's azimuth (the forces of the
        equations of motion, whose damping is ``C(psi) v``); ``None`` without springs."""
        sp = self.asm.springs
        if sp is None or not len(sp):
            return None
        n = self.n
        if self.geometry is None:
            return (X[:, :n] @ sp.W.T) * sp.stiffness + (X[:, n:] @ sp.W.T) * sp.damping
        az = self.azimuth0 + self.omega * np.asarray(t, dtype=float)
        return self.geometry.spring_forces(az, np.zeros(len(az)), X[:, :n], X[:, n:])

    def forces(self, x: np.ndarray, s: np.ndarray) -> np.ndarray:
        """Contact forces ``k p + c p'`` of the active contacts (0 for open ones), N or N m."""
        p = self.penetration(x)
        r = self.rate(x)
        return np.where(s, self.k * p + self.c * r, 0.0)

    def energy(self, x: np.ndarray, s: np.ndarray | None = None) -> float:
        """Mechanical energy: kinetic + always-active springs + compressed contacts, J.

        Conserved by the undamped, unloaded system (centripetal terms act as springs); a
        turning system (time-periodic) has no such invariant and is refused."""
        if self.turning:
            raise ModelError("energy", "a turning (time-periodic) system conserves no "
                             "mechanical energy of its frozen matrices")
        n = self.n
        q, v = x[:n], x[n:]
        p = np.maximum(self.penetration(x), 0.0)
        return float(0.5 * v @ self.asm.M @ v + 0.5 * q @ self.K0 @ q
                     + 0.5 * np.sum(self.k * p * p) - self.f_const @ q)


def double_step(Phi: np.ndarray, G0: np.ndarray, G1: np.ndarray):
    """Propagators of the step ``2h`` from those of ``h`` (first-order hold), exactly.

    Two steps with the force linear from F0 over Fm = (F0 + F2) / 2 to F2::

        x(2h) = Phi^2 x0 + Phi G0 F0 + (Phi G1 + G0) Fm + G1 F2
        => Phi' = Phi^2,  G0' = Phi G0 + (Phi G1 + G0) / 2,  G1' = (Phi G1 + G0) / 2 + G1

    (the squaring step of scaling-and-squaring, carried to the hold terms)."""
    H = 0.5 * (Phi @ G1 + G0)
    return Phi @ Phi, Phi @ G0 + H, H + G1


class Propagators:
    """Per contact state: ``A_s``, ``f_s``, a bound of the spectral radius
    (:meth:`PiecewiseLinearSystem.spectral_bound`) and dyadic step propagators."""

    @property
    def system(self) -> PiecewiseLinearSystem:
        """The system (held weakly)."""
        return self._system()

    def __init__(self, system: PiecewiseLinearSystem, dt: float):
        self._system = weakref.ref(system)  # weakly: see TaylorIntegrator
        self.dt = float(dt)
        self._states: dict[bytes, dict] = {}
        self.n_exponentials = 0

    def state(self, s: np.ndarray) -> dict:
        key = s.tobytes()
        d = self._states.get(key)
        if d is None:
            A, f = self.system.first_order(s)
            if self.system.P is not None:
                f = self.system.P.T @ f  # in the input basis (f_s is in its span)
            rho = max(self.system.spectral_bound(s), 1e-300)
            d = {"A": A, "f": f, "rho": rho, "levels": {}}
            self._states[key] = d
        return d

    def level(self, s: np.ndarray, j: int):
        """``(Phi, G0, G1)`` for the step ``dt / 2**j`` in state ``s``: x(h) = Phi x0 + G0 F0
        + G1 F1 (F the generalised force, first-order hold).

        One augmented exponential per state, at the finest level the state needs (its Taylor
        level, or ``j`` if finer); coarser levels follow by exact doubling, see
        :func:`double_step`."""
        d = self.state(s)
        levels = d["levels"]
        got = levels.get(j)
        if got is None:
            finer = [k for k in levels if k > j]
            if finer:
                k = min(finer)
            else:
                k = max(j, self.taylor_level(s))
                levels[k] = self._exponential(d["A"], self.dt / 2**k)
            while k > j:
                levels[k - 1] = double_step(*levels[k])
                k -= 1
            got = levels[j]
        return got

    def _exponential(self, A: np.ndarray, h: float):
        """Van Loan's augmented exponential (module docstring) over one step ``h``."""
        sys = self.system
        N, n = 2 * sys.n, sys.n
        m = sys.MinvU.shape[1]  # n, or the input basis' size
        Z = np.zeros((N + 2 * m, N + 2 * m))
        Z[:N, :N] = A * h
        Z[n:N, N:N + m] = sys.MinvU * h
        Z[N:N + m, N + m:] = np.eye(m)
        E = sla.expm(Z)
        self.n_exponentials += 1
        Ga = E[:N, N:N + m]
        Gb = E[:N, N + m:]
        return (np.ascontiguousarray(E[:N, :N]), np.ascontiguousarray(Ga - Gb),
                np.ascontiguousarray(Gb))

    def resolve_level(self, s: np.ndarray) -> int:
        """Smallest dyadic level whose step is at most half the fastest period of state ``s``
        (``rho h <= pi``): over such a piece every modal component of a gap has at most one
        extremum, so the end values and rates bracket every crossing."""
        d = self.state(s)
        j = d.get("resolve")
        if j is None:
            j = 0
            while d["rho"] * self.dt / 2**j > math.pi and j < 60:
                j += 1
            d["resolve"] = j
        return j

    def taylor_level(self, s: np.ndarray) -> int:
        """Smallest dyadic level whose step is within the Taylor reach of state ``s``."""
        rho = self.state(s)["rho"]
        j = 0
        while rho * self.dt / 2**j > TAYLOR_REACH and j < 60:
            j += 1
        return j
