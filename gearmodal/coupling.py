"""Systems coupled by constraints through Lagrange multipliers (paper section 3, DESIGN 2.5).

Each *system* supplies its unconstrained equations of motion ``B(t, q, v, a, u) = 0`` and their
tangent matrices (``M = dB/da``, ``C = dB/dv``, ``K = dB/dq``); each *constraint* supplies
``g(q_a, q_b)`` and the gradients ``G_a = dg/dq_a``, ``G_b = dg/dq_b``. The coupled equations
(paper, section 3) are::

    B_a + G_a^T lambda = 0,    B_b + G_b^T lambda = 0,    g(q_a, q_b) = 0.

That serves every case the paper lists: an internal and an external system (a turbine and a
gearbox), two external systems, constraints inside one system (``a`` and ``b`` in the same
system, or ``b`` the ground) and an external system alone (no constraint).

How the coupled equations are solved
------------------------------------
The constraint gradients at the reference configuration, stacked into ``G`` (m x n), define the
constrained motions ``q = N z`` with ``G N = 0``. ``N`` keeps a subset of the original
coordinates as the independent ones (``z`` are those DOFs, by name) and expresses the others
through them (pivoted QR picks them; :meth:`CoupledAssembly.reduced`). Projecting the equations
onto ``N`` eliminates ``lambda`` exactly (``N^T G^T = 0``)::

    N^T M N z'' + N^T C N z' + N^T K N z = N^T f,

which is again a piecewise-linear contact model, so that :func:`gearmodal.modal`,
:func:`gearmodal.campbell`, :func:`gearmodal.equilibrium` and every method of
:func:`gearmodal.simulate` (including the exact one) apply unchanged; results come back in the
original coordinates (``q = N z``) and the multipliers, the forces the constraints transmit,
are recovered from the residual of the unconstrained equations (``G^T lambda = -B``, least
squares; :meth:`CoupledAssembly.multipliers`).

*Linear* constraints (:class:`LinearConstraint`, a joint between bodies whose DOFs are small
displacements) are satisfied exactly by ``q = N z``: their drift is rounding. *Nonlinear*
constraints (the joint's exact residual with finite rotations, :class:`Joint`) are linearised
at the reference configuration, the same small-displacement assumption under which the
gearbox itself is linear (DESIGN 2.1). What that neglects is reported, not hidden: the exact
residual ``g(q)`` along a simulated trajectory is ``result.constraint_residual`` and is second
order in the displacements.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd
import scipy.linalg as sla

from .assembly import Assembly, Contacts
from .errors import ModelError
from .frames import body_transform, centre, rz
from .kernels.joint import joint_gradients_at, joint_residual
from .model.components import DIRECTIONS
from .model.model import Model

__all__ = ["Constraint", "Coupled", "CoupledAssembly", "Joint", "LinearConstraint",
           "LinearSystem", "ModelSystem", "System"]


# -- systems ------------------------------------------------------------------------------------
class System:
    """A mechanical system given by its unconstrained equations ``B(t, q, v, a, u) = 0``.

    Subclass it and implement :meth:`residual` (and, for exactness and speed, :meth:`tangents`
    and :meth:`load_map`; the defaults differentiate :meth:`residual` numerically). Set
    ``name`` (no dots), ``dof_names`` and ``load_names``. SI units: ``B`` in N or N m.

    The coupled linear analyses and the exact integrator use the system linearised at
    ``q = v = a = 0`` (``tangents()``) with the generalised force ``load_map() @ u``.
    """

    name: str = "system"
    dof_names: list[str] = []
    load_names: list[str] = []

    @property
    def n(self) -> int:
        return len(self.dof_names)

    def residual(self, t: float, q: np.ndarray, v: np.ndarray, a: np.ndarray,
                 u: np.ndarray | None = None) -> np.ndarray:
        """``B`` (n,): the unconstrained equations of motion; zero when they are satisfied."""
        raise NotImplementedError

    def _u(self, u):
        return np.zeros(len(self.load_names)) if u is None else np.asarray(u, dtype=float)

    def tangents(self, q: np.ndarray | None = None, v: np.ndarray | None = None,
                 t: float = 0.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(M, C, K) = (dB/da, dB/dv, dB/dq)`` at ``(q, v)`` (default 0), by central
        differences of :meth:`residual` (exact for a linear system up to rounding)."""
        n = self.n
        q = np.zeros(n) if q is None else np.asarray(q, dtype=float)
        v = np.zeros(n) if v is None else np.asarray(v, dtype=float)
        a = np.zeros(n)
        out = []
        for which in range(3):
            J = np.zeros((n, n))
            for i in range(n):
                args = [q, v, a]
                h = 1e-6 * max(1.0, abs(args[2 - which][i]))
                e = np.zeros(n)
                e[i] = h
                plus = [x.copy() for x in args]
                minus = [x.copy() for x in args]
                plus[2 - which] += e
                minus[2 - which] -= e
                J[:, i] = (self.residual(t, *plus) - self.residual(t, *minus)) / (2 * h)
            out.append(J)
        return out[0], out[1], out[2]

    def load_map(self) -> np.ndarray:
        """``-dB/du`` (n, n_loads): generalised force per unit value of each load."""
        n, m = self.n, len(self.load_names)
        z = np.zeros(n)
        out = np.zeros((n, m))
        for j in range(m):
            e = np.zeros(m)
            e[j] = 1.0
            out[:, j] = -(self.residual(0.0, z, z, z, e) - self.residual(0.0, z, z, z, -e)) / 2
        return out


class LinearSystem(System):
    """A linear system ``M a + C v + K q = L u`` given by its matrices.

    Parameters
    ----------
    name : system name (no dots). dof_names : coordinate names.
    M, K : mass and stiffness (n x n). C : damping (default zero).
    load_names, load_map : named loads and their generalised-force map ``L`` (n x n_loads).
    G, K_cent, K_speed : terms of the input speed ``Omega`` (default zero): at speed the
        system is ``M a + (C + Omega G) v + (K + Omega K_speed + Omega^2 K_cent) q = L u``
        (a turning rotor in multi-blade coordinates); the linear analyses and the integrators
        scale them by the coupled system's input speed.
    """

    def __init__(self, name: str, dof_names, M, K, C=None, load_names=(), load_map=None, *,
                 G=None, K_cent=None, K_speed=None):
        self.name = name
        self.dof_names = list(dof_names)
        n = len(self.dof_names)
        self.M = _square(M, n, f"{name}.M")
        self.K = _square(K, n, f"{name}.K")
        self.C = np.zeros((n, n)) if C is None else _square(C, n, f"{name}.C")
        self.G, self.K_cent, self.K_speed = (
            np.zeros((n, n)) if X is None else _square(X, n, f"{name}.{label}")
            for X, label in ((G, "G"), (K_cent, "K_cent"), (K_speed, "K_speed")))
        self.load_names = list(load_names)
        L = np.zeros((n, len(self.load_names))) if load_map is None else np.asarray(
            load_map, dtype=float).reshape(n, len(self.load_names))
        self._L = L

    def residual(self, t, q, v, a, u=None):
        """``B`` at rest (the speed terms enter through the coupled assembly, scaled by the
        input speed there)."""
        return self.M @ a + self.C @ v + self.K @ q - self._L @ self._u(u)

    def tangents(self, q=None, v=None, t=0.0):
        return self.M.copy(), self.C.copy(), self.K.copy()

    def load_map(self):
        return self._L.copy()


class ModelSystem(System):
    """A :class:`gearmodal.Model` as a system (its piecewise-linear contacts included).

    ``residual`` is that of the contact state ``state`` (default nominal), at rest speed."""

    def __init__(self, model: Model, name: str | None = None):
        self.model = model
        self.name = name or model.name
        self._asm = model.assemble()
        self.dof_names = list(self._asm.dof_names)
        self.load_names = list(self._asm.load_names)

    def residual(self, t, q, v, a, u=None, state=None):
        A = self._asm
        s = A.state(state)
        return (A.M @ a + A.damping(s) @ v + A.stiffness(s) @ q - A.contact_force(s)
                - A.B @ self._u(u))

    def tangents(self, q=None, v=None, t=0.0, state=None):
        A = self._asm
        s = A.state(state)
        return A.M.copy(), A.damping(s), A.stiffness(s)

    def load_map(self):
        return self._asm.B.copy()


# -- constraints --------------------------------------------------------------------------------
class Constraint:
    """A constraint ``g(q_a, q_b) = 0`` between systems ``a`` and ``b`` (``b`` may equal ``a``:
    a constraint inside one system; ``None``: to the ground).

    Subclasses implement :meth:`residual` and :meth:`gradients` on the full coordinate vectors
    of the two systems (SI: m, rad). ``linear`` tells whether ``g`` is linear in the
    coordinates (then ``q = N z`` satisfies it exactly)."""

    name: str = "constraint"
    a: str = ""
    b: str | None = None
    linear: bool = False

    def bind(self, coupled: Coupled) -> None:
        """Resolve names against the coupled systems (called once by :class:`Coupled`)."""

    def residual(self, qa: np.ndarray, qb: np.ndarray | None) -> np.ndarray:
        raise NotImplementedError

    def gradients(self, qa: np.ndarray, qb: np.ndarray | None):
        """``(G_a, G_b)``: ``dg/dq_a`` (m x n_a) and ``dg/dq_b`` (m x n_b, ``None`` when ``b``
        is the ground)."""
        raise NotImplementedError


class LinearConstraint(Constraint):
    """``sum_i c_i q_i = 0`` over DOFs named ``"<system>.<dof>"``; one or two systems.

    Example: ``LinearConstraint("spline", {"turbine.hub": 1.0, "gearbox.carrier.theta": -1.0})``
    makes two rotations equal."""

    linear = True

    def __init__(self, name: str, coefficients: dict):
        if not coefficients:
            raise ModelError(f"{name}.coefficients", "needs at least one DOF")
        self.name = name
        self.coefficients = {str(k): float(v) for k, v in coefficients.items()}
        systems = list(dict.fromkeys(k.split(".", 1)[0] for k in self.coefficients))
        if len(systems) > 2:
            raise ModelError(f"{name}.coefficients", "spans more than two systems: "
                             + ", ".join(systems))
        self.a = systems[0]
        self.b = systems[1] if len(systems) == 2 else systems[0]

    def bind(self, coupled):
        self._cols = {}
        for key in self.coefficients:
            sysname, dof = key.split(".", 1)
            names = coupled.system(sysname).dof_names
            if dof not in names:
                raise ModelError(f"{self.name}.coefficients.{key}", "no such DOF; "
                                 f"{sysname} has " + ", ".join(names))
            self._cols[key] = (sysname, names.index(dof))
        self._na = coupled.system(self.a).n
        self._nb = coupled.system(self.b).n

    def gradients(self, qa, qb):
        Ga = np.zeros((1, self._na))
        Gb = np.zeros((1, self._nb))
        for key, c in self.coefficients.items():
            sysname, i = self._cols[key]
            if sysname == self.a:  # both ends in one system: all on a
                Ga[0, i] += c
            else:
                Gb[0, i] += c
        return Ga, Gb

    def residual(self, qa, qb):
        Ga, Gb = self.gradients(qa, qb)
        out = Ga @ qa
        if self.a != self.b and qb is not None:
            out = out + Gb @ qb
        return out


class Joint(Constraint):
    """A rigid joint between a point of body ``a`` and a point of body ``b`` (or the ground).

    Parameters
    ----------
    name : constraint name.
    a, b : ``"<system>.<body>"`` (``b = None``: the ground). Both systems must be
        :class:`gearmodal.Model` systems.
    directions : constrained directions in joint axes, any of ``x, y, z, rx, ry, theta``
        (default all six; directions that move no DOF of either body are dropped).
    at : offset of the joint point from ``a``'s centre, m (global axes at azimuth 0).
    axes_angle : joint axes ``Rz(axes_angle)``, rad.

    Notes
    -----
    The exact residual (finite rotations) and its gradients come from the generated kernels
    ``joint_residual`` / ``joint_gradients_at`` (``symbolic/joint.py``); the coupled linear
    analyses use the gradients at the reference configuration.
    """

    linear = False

    def __init__(self, name: str, a: str, b: str | None = None, directions=DIRECTIONS,
                 at=(0.0, 0.0, 0.0), axes_angle: float = 0.0):
        self.name = name
        self.a_ref, self.b_ref = a, b
        bad = [d for d in directions if d not in DIRECTIONS]
        if bad or not directions:
            raise ModelError(f"{name}.directions", f"= {list(directions)!r}: choose from "
                             + ", ".join(DIRECTIONS))
        self.directions = [d for d in DIRECTIONS if d in directions]
        self.at = tuple(float(x) for x in at)
        self.axes_angle = float(axes_angle)
        self.a = a.split(".", 1)[0]
        self.b = b.split(".", 1)[0] if b is not None else None

    def _body(self, coupled, ref, field_name):
        if "." not in ref:
            raise ModelError(f"{self.name}.{field_name}", f"= {ref!r}: expected "
                             "'<system>.<body>'")
        sysname, body = ref.split(".", 1)
        sysm = coupled.system(sysname)
        if not isinstance(sysm, ModelSystem):
            raise ModelError(f"{self.name}.{field_name}", f"= {ref!r}: system {sysname!r} "
                             "has no bodies; use a LinearConstraint on its DOFs")
        model = sysm.model
        if body not in model.bodies:
            raise ModelError(f"{self.name}.{field_name}", f"= {ref!r}: no body {body!r} in "
                             f"{sysname!r}; bodies: " + ", ".join(model.bodies))
        b = model.bodies[body]
        names = sysm.dof_names
        cols = [names.index(f"{body}.{c}") for c in b.coordinates]
        return model, b, cols

    def bind(self, coupled, azimuth: float = 0.0):
        self._a = self._body(coupled, self.a_ref, "a")
        self._b = self._body(coupled, self.b_ref, "b") if self.b_ref is not None else None
        self._na = coupled.system(self.a).n
        self._nb = coupled.system(self.b).n if self.b is not None else 0
        self.set_azimuth(azimuth)

    def set_azimuth(self, azimuth: float) -> None:
        """Freeze the joint geometry at input azimuth ``azimuth`` (rad)."""
        ma, ba, _ = self._a
        fa = ma.frames[ba.frame]
        pa = rz(fa.speed_ratio * azimuth) @ np.asarray(self.at)
        ca = centre(ma, ba, azimuth)
        self._Ta = body_transform(ma, ba, azimuth)
        if self._b is not None:
            mb, bb, _ = self._b
            cb = centre(mb, bb, azimuth)
            self._Tb = body_transform(mb, bb, azimuth)
        else:
            cb = np.zeros(3)
        pb = ca + pa - cb
        self._geo = (pa[0], pa[1], pa[2], pb[0], pb[1], pb[2], self.axes_angle)
        self._rows = [DIRECTIONS.index(d) for d in self.directions]

    def _six(self, qa, qb):
        qa6 = self._Ta @ np.asarray(qa)[self._a[2]]
        qb6 = self._Tb @ np.asarray(qb)[self._b[2]] if self._b is not None else np.zeros(6)
        return qa6, qb6

    def residual(self, qa, qb):
        qa6, qb6 = self._six(qa, qb)
        return joint_residual(qa6, qb6, *self._geo)[self._rows]

    def gradients(self, qa, qb):
        qa6, qb6 = self._six(qa, qb)
        Ga6, Gb6 = joint_gradients_at(qa6, qb6, *self._geo)
        Ga = np.zeros((len(self._rows), self._na))
        Ga[:, self._a[2]] = Ga6[self._rows] @ self._Ta
        if self._b is None:
            return Ga, None
        Gb = np.zeros((len(self._rows), self._nb))
        Gb[:, self._b[2]] = Gb6[self._rows] @ self._Tb
        return Ga, Gb


# -- the coupled system -------------------------------------------------------------------------
@dataclass
class CoupledAssembly(Assembly):
    """The block-diagonal assembly of all systems (coordinates ``"<system>.<dof>"``) with the
    constraint gradients ``Gc`` (m x n) and the constrained basis ``N`` (n x r, ``Gc N = 0``);
    :meth:`reduced` is the assembly in the independent coordinates ``z`` (``q = N z``)."""

    Gc: np.ndarray | None = None
    N: np.ndarray | None = None
    independent: np.ndarray | None = None
    constraint_names: list = field(default_factory=list)
    _reduced: Assembly | None = None

    def reduction(self) -> tuple[Assembly, np.ndarray]:
        """``(the assembly in z, N)``: :meth:`reduced` and the basis ``q = N z``."""
        return self.reduced(), self.N

    def reduced(self) -> Assembly:
        """The coupled equations projected on ``q = N z`` (module docstring)."""
        if self._reduced is None:
            N = self.N

            def red(c: Contacts | None):
                if c is None:
                    return None
                return c.take(W=c.W @ N)

            self._reduced = Assembly(
                dof_names=[self.dof_names[i] for i in self.independent],
                load_names=list(self.load_names), M=N.T @ self.M @ N, C=N.T @ self.C @ N,
                K=N.T @ self.K @ N, G=N.T @ self.G @ N, K_cent=N.T @ self.K_cent @ N,
                K_geom=N.T @ self.K_geom @ N, K_speed=N.T @ self.K_speed @ N,
                f_cent=N.T @ self.f_cent, B=N.T @ self.B, contacts=red(self.contacts),
                azimuth=self.azimuth, body_slices={}, springs=red(self.springs),
                round=red(self.round))
        return self._reduced

    def expand(self, z: np.ndarray) -> np.ndarray:
        """Original coordinates ``q = N z`` (z along the last axis)."""
        return np.asarray(z) @ self.N.T

    def multipliers(self, q: np.ndarray, v: np.ndarray, a: np.ndarray, u: np.ndarray,
                    state: np.ndarray, speed: float = 0.0,
                    contact_forces: np.ndarray | None = None) -> np.ndarray:
        """Constraint forces ``lambda`` (rows: times) from ``Gc^T lambda = -B`` (least squares,
        exact when the motion satisfies the coupled equations). ``q, v, a`` (times x n),
        ``u`` (times x loads), ``state`` (times x contacts), speed in rad/s;
        ``contact_forces`` (times x contacts) when already known."""
        q, v, a = np.atleast_2d(q), np.atleast_2d(v), np.atleast_2d(a)
        u = np.atleast_2d(u)
        c = self.contacts
        Fc = contact_forces
        if Fc is None:
            Fc = np.where(np.atleast_2d(state), c.stiffness * (q @ c.W.T - c.offset)
                          + c.damping * (v @ c.W.T), 0.0)
        Bres = (a @ self.M.T + v @ (self.C + speed * self.G).T
                + q @ (self.K + speed * self.K_speed + speed**2 * self.K_cent).T + Fc @ c.W
                - u @ self.B.T - speed**2 * self.f_cent)
        lam, *_ = np.linalg.lstsq(self.Gc.T, -Bres.T, rcond=None)
        return lam.T


class Coupled:
    """Systems and the constraints between them (paper section 3).

    Parameters
    ----------
    systems : :class:`System` objects or :class:`gearmodal.Model` (wrapped as
        :class:`ModelSystem`, named by the model's name), with unique names without dots.
    constraints : :class:`Constraint` objects (:class:`Joint`, :class:`LinearConstraint` or
        your own).
    name : name used in reports.

    Notes
    -----
    Coordinates, loads and contacts of the coupled system are named
    ``"<system>.<name in the system>"``. Pass a ``Coupled`` wherever a model is accepted:
    :func:`gearmodal.modal`, :func:`gearmodal.campbell`, :func:`gearmodal.equilibrium`,
    :func:`gearmodal.simulate`. Speeds refer to the input of the first model system.

    Examples
    --------
    A flywheel written as a plain linear system, splined to the pinion of a gear pair:

    >>> import math, gearmodal as gm
    >>> p = gm.Gear(20, 0.004, math.radians(20), mass=1.0, inertia=1e-3)
    >>> w = gm.Gear(40, 0.004, math.radians(20), mass=4.0, inertia=1.6e-2)
    >>> pair = gm.gear_pair(p, w, mesh_stiffness=2e8, backlash=1e-4)
    >>> fly = gm.LinearSystem("fly", ["theta"], M=[[1e-3]], K=[[0.0]])
    >>> spline = gm.LinearConstraint("spline", {"fly.theta": 1.0, "pair.pinion.theta": -1.0})
    >>> both = gm.Coupled([gm.ModelSystem(pair, "pair"), fly], [spline])
    >>> [round(float(f), 1) for f in gm.modal(both).frequencies_hz]
    [0.0, 2316.9]
    """

    def __init__(self, systems, constraints=(), name: str = "coupled"):
        self.name = name
        self.systems: dict[str, System] = {}
        for k, s in enumerate(systems):
            if isinstance(s, Model):
                s = ModelSystem(s)
            if not isinstance(s, System):
                raise ModelError(f"{name}.systems[{k}]", f"expected a gm.System or gm.Model, "
                                 f"got {type(s).__name__}")
            if not s.name or "." in s.name:
                raise ModelError(f"{name}.systems[{k}].name", f"= {s.name!r}: a non-empty name "
                                 "without dots")
            if s.name in self.systems:
                raise ModelError(f"{name}.systems[{k}].name", f"= {s.name!r}: used twice")
            self.systems[s.name] = s
        if not self.systems:
            raise ModelError(f"{name}.systems", "at least one system is needed")
        self.constraints = list(constraints)
        seen = set()
        for c in self.constraints:
            if not isinstance(c, Constraint):
                raise ModelError(f"{name}.constraints", f"expected gm.Constraint objects, got "
                                 f"{type(c).__name__}")
            if c.name in seen:
                raise ModelError(f"{name}.constraints", f"{c.name!r} used twice")
            seen.add(c.name)
            for end in (c.a, c.b):
                if end is not None and end not in self.systems:
                    raise ModelError(f"{c.name}", f"refers to system {end!r}; systems: "
                                     + ", ".join(self.systems))
            c.bind(self)
        models = [s for s in self.systems.values() if isinstance(s, ModelSystem)]
        first = models[0].model if models else None
        self.rated_speed_rpm = getattr(first, "rated_speed_rpm", None)
        self.speed_range_rpm = getattr(first, "speed_range_rpm", None)
        self.merged = self._merged()
        self._pivot = None

    # -- structure ------------------------------------------------------------------------------
    def system(self, name: str) -> System:
        if name not in self.systems:
            raise ModelError("system", f"= {name!r}: no such system; systems: "
                             + ", ".join(self.systems))
        return self.systems[name]

    def _merged(self) -> Model:
        """One model of all model systems, names prefixed by the system names."""
        m = Model(self.name)
        for s in self.systems.values():
            if isinstance(s, ModelSystem):
                m.merge(s.model, s.name)
                if m.input is None and s.model.input is not None:
                    m.input = f"{s.name}.{s.model.input}"
        return m

    def offsets(self) -> dict[str, int]:
        """First coupled coordinate of each system (model systems first, in order)."""
        out, k = {}, 0
        order = [s for s in self.systems.values() if isinstance(s, ModelSystem)]
        order += [s for s in self.systems.values() if not isinstance(s, ModelSystem)]
        for s in order:
            out[s.name] = k
            k += s.n
        return out

    @property
    def dof_names(self) -> list[str]:
        """Coupled coordinate names (model systems first, as :meth:`offsets`)."""
        plain = [s for s in self.systems.values() if not isinstance(s, ModelSystem)]
        return self.merged.dof_names + [f"{s.name}.{d}" for s in plain for d in s.dof_names]

    def split(self, q: np.ndarray) -> dict[str, np.ndarray]:
        """Coordinates of each system from the coupled vector ``q``."""
        off = self.offsets()
        return {k: np.asarray(q)[..., o:o + self.systems[k].n] for k, o in off.items()}

    # -- the paper's equations ----------------------------------------------------------------
    def constraint_rows(self, q: np.ndarray | None = None):
        """``(g, G)`` of all constraints at the coupled coordinates ``q`` (default 0):
        residual (m,) and gradient (m x n)."""
        off = self.offsets()
        n = sum(s.n for s in self.systems.values())
        q = np.zeros(n) if q is None else np.asarray(q, dtype=float)
        parts = self.split(q)
        gs, Gs = [], []
        for c in self.constraints:
            qa = parts[c.a]
            qb = parts[c.b] if c.b is not None else None
            Ga, Gb = c.gradients(qa, qb)
            G = np.zeros((Ga.shape[0], n))
            G[:, off[c.a]:off[c.a] + Ga.shape[1]] += Ga
            if c.b is not None and c.b != c.a and Gb is not None:
                G[:, off[c.b]:off[c.b] + Gb.shape[1]] += Gb
            elif c.b == c.a and Gb is not None and Gb.shape[1] == Ga.shape[1]:
                G[:, off[c.a]:off[c.a] + Gb.shape[1]] += Gb
            gs.append(np.atleast_1d(c.residual(qa, qb)))
            Gs.append(G)
        if not Gs:
            return np.zeros(0), np.zeros((0, n))
        return np.concatenate(gs), np.vstack(Gs)

    def residual(self, t: float, q, v, a, lam, u: dict | None = None):
        """The coupled equations of the paper: ``(B + G^T lambda, g)`` for every system at
        once (``q, v, a`` coupled vectors, ``lam`` one multiplier per constraint row, ``u``
        ``{system: load vector}``); both are zero on a solution."""
        parts = [self.split(x) for x in (q, v, a)]
        u = u or {}
        B = np.concatenate([self.systems[k].residual(t, parts[0][k], parts[1][k], parts[2][k],
                                                      u.get(k)) for k in self.offsets()])
        g, G = self.constraint_rows(q)
        return B + G.T @ np.asarray(lam, dtype=float), g

    # -- assembly -------------------------------------------------------------------------------
    def assemble(self, azimuth: float = 0.0) -> CoupledAssembly:
        """Block-diagonal assembly of all systems at input azimuth ``azimuth`` (rad), with the
        constraint gradients and the constrained basis (module docstring)."""
        if self.merged.bodies:
            base = self.merged.assemble(azimuth)
            # the multipliers are recovered from the piecewise-linear contact forces only
            base.require_piecewise_linear("a coupled system (gm.Coupled)")
        else:
            base = Assembly(dof_names=[], load_names=[], M=np.zeros((0, 0)),
                            C=np.zeros((0, 0)), K=np.zeros((0, 0)), G=np.zeros((0, 0)),
                            K_cent=np.zeros((0, 0)), f_cent=np.zeros(0), B=np.zeros((0, 0)),
                            contacts=Contacts(W=np.zeros((0, 0)), offset=np.zeros(0),
                                              stiffness=np.zeros(0), damping=np.zeros(0),
                                              nominal=np.zeros(0, dtype=bool)))
        plain = [s for s in self.systems.values() if not isinstance(s, ModelSystem)]
        n0 = base.n
        n = n0 + sum(s.n for s in plain)
        nl0 = len(base.load_names)
        loads = list(base.load_names) + [f"{s.name}.{ln}" for s in plain for ln in s.load_names]

        def grow(X, rows, cols):
            out = np.zeros((rows, cols))
            out[:X.shape[0], :X.shape[1]] = X
            return out

        M, C, K = grow(base.M, n, n), grow(base.C, n, n), grow(base.K, n, n)
        G, Kc, Kg = grow(base.G, n, n), grow(base.K_cent, n, n), grow(base.K_geom, n, n)
        Kv = grow(base.K_speed, n, n)
        B = grow(base.B, n, len(loads))
        fc = np.concatenate([base.f_cent, np.zeros(n - n0)])
        names = list(base.dof_names)
        slices = dict(base.body_slices)
        k, j = n0, nl0
        for s in plain:
            Ms, Cs, Ks = s.tangents()
            sl = slice(k, k + s.n)
            M[sl, sl], C[sl, sl], K[sl, sl] = Ms, Cs, Ks
            if isinstance(s, LinearSystem):  # its speed terms, per rad/s of the input speed
                G[sl, sl], Kc[sl, sl], Kv[sl, sl] = s.G, s.K_cent, s.K_speed
            L = np.asarray(s.load_map(), dtype=float).reshape(s.n, len(s.load_names))
            B[sl, j:j + len(s.load_names)] = L
            names += [f"{s.name}.{d}" for d in s.dof_names]
            slices[s.name] = sl
            k += s.n
            j += len(s.load_names)

        def pad(c: Contacts | None):
            if c is None:
                return None
            W = c.W if c.W is not None else np.zeros((0, n0))
            return c.take(W=grow(W, W.shape[0], n))

        for c in self.constraints:
            if isinstance(c, Joint):
                c.set_azimuth(azimuth)
        _, Gc = self.constraint_rows()
        N, ind = self._basis(Gc)
        return CoupledAssembly(
            dof_names=names, load_names=loads, M=M, C=C, K=K, G=G, K_cent=Kc, K_geom=Kg,
            K_speed=Kv,
            f_cent=fc, B=B,
            contacts=pad(base.contacts), azimuth=azimuth, body_slices=slices,
            springs=pad(base.springs), round=pad(base.round), Gc=Gc, N=N, independent=ind,
            constraint_names=[f"{c.name}.{d}" for c in self.constraints
                              for d in self._row_labels(c)])

    def _basis(self, Gc: np.ndarray):
        """``N`` with identity rows on the independent coordinates (the pivot choice is made
        once, at the first assembly, so that ``z`` keeps its meaning across refreezes)."""
        n = Gc.shape[1]
        if Gc.shape[0] == 0:
            return np.eye(n), np.arange(n)
        if self._pivot is None:
            _, R, P = sla.qr(Gc, mode="economic", pivoting=True)
            d = np.abs(np.diag(R))
            tol = max(Gc.shape) * np.finfo(float).eps * (d[0] if len(d) else 0.0)
            r = int(np.sum(d > tol))
            dep = np.sort(P[:r])
            self._pivot = (dep, np.setdiff1d(np.arange(n), dep))
        dep, ind = self._pivot
        X = -np.linalg.lstsq(Gc[:, dep], Gc[:, ind], rcond=None)[0]
        N = np.zeros((n, len(ind)))
        N[ind, np.arange(len(ind))] = 1.0
        N[dep] = X
        scale = max(np.abs(Gc).max(), 1e-300)
        if np.abs(Gc @ N).max() > 1e-9 * scale * max(1.0, np.abs(N).max()):
            raise ModelError(f"{self.name}.constraints", "the constraints cannot all be met "
                             "by the chosen coordinates (conflicting constraints?)")
        return N, ind

    def _row_labels(self, c: Constraint) -> list[str]:
        if isinstance(c, Joint):
            return list(c.directions)
        if isinstance(c, LinearConstraint):
            return ["g"]
        qa = np.zeros(self.systems[c.a].n)
        qb = np.zeros(self.systems[c.b].n) if c.b is not None else None
        return [str(i) for i in range(len(np.atleast_1d(c.residual(qa, qb))))]

    # -- results -------------------------------------------------------------------------------
    def constraint_residual(self, q: pd.DataFrame) -> pd.DataFrame:
        """Exact residual ``g`` of every constraint row along a trajectory (rows: times), m or
        rad: zero to rounding for linear constraints, second order for linearised joints."""
        Q = q.to_numpy()
        rows = []
        for i in range(len(Q)):
            parts = self.split(Q[i])
            rows.append(np.concatenate(
                [np.atleast_1d(c.residual(parts[c.a], parts[c.b] if c.b is not None else None))
                 for c in self.constraints]) if self.constraints else np.zeros(0))
        cols = [f"{c.name}.{d}" for c in self.constraints for d in self._row_labels(c)]
        return pd.DataFrame(np.array(rows).reshape(len(Q), len(cols)), index=q.index,
                            columns=cols)


def _square(X, n, label):
    X = np.asarray(X, dtype=float)
    if X.shape != (n, n):
        raise ModelError(label, f"has shape {X.shape}; expected ({n}, {n})")
    if not np.all(np.isfinite(X)):
        raise ModelError(label, "has non-finite entries")
    return X

