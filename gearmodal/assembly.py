"""Model -> matrices: mass, damping, stiffness per contact state, gyroscopic and centripetal
matrices, contact gap functions as linear maps of the state, and load maps.

The equations of motion at input speed ``Omega`` (rad/s) in contact state ``s`` are (DESIGN 2.1)::

    M q'' + (C + C_s + Omega G) q' + (K + K_s + Omega K_speed + Omega^2 K_cent) q
        = B u + f_s + Omega^2 f_cent

Every contact (a flank of a mesh, one side of a bearing dead band) ``e`` has a penetration
``p_e = W[e] @ q - offset[e]`` and is active while ``p_e > 0``; then it pushes back with
``stiffness[e] * p_e + damping[e] * p_e'`` along ``-W[e]`` (DESIGN 2.2, 2.3), so::

    K_s = sum_active k_e W_e^T W_e,   C_s = sum_active c_e W_e^T W_e,
    f_s = sum_active k_e offset_e W_e

Geometric stiffness (DESIGN 2.5a). The steady rotation loads the elements: the centrifugal
forces ``Omega^2 f_cent`` of bodies off the axis (the planets) are carried by their bearings
and meshes. A loaded element whose deflection is curved in the coordinates adds the curvature
times its force to the linearised stiffness, as a tensioned blade stiffens::

    (G1)  (K + K_s) q_1 = f_cent,   lambda_e = k_e W_e q_1     (per (rad/s)^2; springs and
                                                                 nominally active contacts)
    (G2)  K_geom = sum_e lambda_e H_e,   H_e = d2 p_e / dq dq

with ``H_e`` the curvature of the element's deflection and ``K_cent`` the centripetal softening
plus ``K_geom``. A mesh flank's deflection is mesh.py's belt gap; a joint's (joint.py) is
measured in axes turning with the body the load turns with: the carrier whose frame its body
is in (the planets' centrifugal load, and an unbalanced carrier's, turns with it), else its
body ``b``, else the ground's fixed axes. Measured so, every loaded deflection is invariant
under the free motions of the steadily turning drivetrain (a rigid rotation of the whole, the
carrier advanced in a held ring) at any configuration near the nominal one, so ``H_e xi =
-A^T W_e`` along such a motion ``xi`` (``A`` its rotation generator) and ``K_geom xi = -A^T
f_cent``: exactly the centripetal softening's ``-K_cent,centripetal xi``. The free motion is
then an exact zero of the stiffness at every speed, as physics has; without ``K_geom`` (Lin &
Parker 1999, whose centripetal-only form ``K_cent - K_geom`` keeps) it has a real positive
eigenvalue at speed. The loads of (G1) are those of the steady rotation alone (not the
torque's, nor a clearance's offset), solved in the nominal contact state by least squares
(the free rotation carries no centrifugal force).

The kernels used here are generated from ``symbolic/`` (floating-frame wheel: ``wheel.py``;
flank gaps: ``mesh.py``; joint/bearing deflections: ``joint.py``). Coefficients that rotate with a
frame against fixed supports are frozen at the input azimuth given to :func:`assemble`.
"""

from __future__ import annotations

import math
import pickle
import weakref
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from .errors import ModelError, unknown
from .frames import body_transform, centre, skew
from .model.components import GRAVITY
from .model.mesh_stiffness import MeshVariation


@dataclass
class OffsetWaves:
    """Offsets that vary with the input azimuth at orders that are not whole numbers (a gear's
    run-out turning with its spin, a mesh's transmission error at the mesh frequency): contact
    ``rows[j]``'s offset has ``Re(z[j] e^(i h[j] psi))`` added (``h >= 0`` per input radian).
    The assembled ``Contacts.offset`` holds their value at the assembly's azimuth too."""

    rows: np.ndarray
    h: np.ndarray
    z: np.ndarray

    def __len__(self) -> int:
        return len(self.rows)

    def at(self, azimuth: float, n_contacts: int) -> np.ndarray:
        """Their sum per contact at input ``azimuth`` (rad), (n_contacts,)."""
        out = np.zeros(n_contacts)
        if len(self.rows):
            np.add.at(out, self.rows, (self.z * np.exp(1j * self.h * azimuth)).real)
        return out


@dataclass
class Contacts:
    """The unilateral contacts of a model, one row each.

    ``element`` is the mesh or bearing name, ``contact`` the flank (``front``/``back``), bearing
    side (``x+``, ``x-``, ...) or polygon facet (``facet0``, ...), ``kind`` is ``mesh`` or
    ``bearing``. ``W`` (n_contacts x n_dofs) maps the state to the deflection; ``offset`` is the
    backlash or clearance (m or rad).

    ``angle`` is the normal of a polygonal clearance's facet in its bearing's axes (rad; NaN
    for other contacts), see :mod:`gearmodal.model.clearance`.

    ``variation`` lists the mesh flanks whose stiffness alternates at the mesh frequency
    (``Mesh.alternation``, :mod:`gearmodal.model.mesh_stiffness`); their ``stiffness`` here is
    the mean, which the modal and static analyses use.

    The structure, per row, as the element gave it: ``columns`` the result force columns the
    contact's force adds to (``[(column, weight), ...]``: a flank its ``<mesh>.front``, a
    dead-band side its direction with sign, a polygon facet its x and y components);
    ``stage``, ``planet`` (body name) and ``role`` of the element (``""`` where none).
    """

    element: list[str] = field(default_factory=list)
    contact: list[str] = field(default_factory=list)
    kind: list[str] = field(default_factory=list)
    W: np.ndarray = None
    offset: np.ndarray = None
    stiffness: np.ndarray = None
    damping: np.ndarray = None
    nominal: np.ndarray = None
    angle: np.ndarray = None
    variation: MeshVariation | None = None
    waves: OffsetWaves | None = None
    columns: list = None
    stage: list = None
    planet: list = None
    role: list = None

    #: the per-row fields (one entry per contact) besides ``W``
    ROW_FIELDS = ("element", "contact", "kind", "offset", "stiffness", "damping", "nominal",
                  "angle", "columns", "stage", "planet", "role")

    def __post_init__(self):
        k = len(self.element)
        if self.angle is None:
            self.angle = np.full(k, np.nan)
        for name in ("stage", "planet", "role"):
            if getattr(self, name) is None:
                setattr(self, name, [""] * k)
        if self.columns is None:
            self.columns = [()] * k

    def take(self, rows=None, W: np.ndarray | None = None) -> Contacts:
        """A copy with only ``rows`` (default all, in order) and, if given, the state map
        ``W`` (already of those rows): every per-row field follows, the alternating
        stiffness's rows are renumbered."""
        idx = np.arange(len(self)) if rows is None else np.asarray(rows, dtype=np.int64)
        out = {}
        for name in self.ROW_FIELDS:
            val = getattr(self, name)
            out[name] = val[idx] if isinstance(val, np.ndarray) else [val[i] for i in idx]
        if W is None:
            W = self.W[idx]
        var = self.variation
        if var is not None and len(var):
            new = -np.ones(len(self), dtype=np.int64)
            new[idx] = np.arange(len(idx))
            ok = new[var.rows] >= 0
            var = MeshVariation(new[var.rows][ok], var.rate[ok], var.phase[ok],
                                var.double[ok], var.k_single[ok], var.k_double[ok])
        waves = self.waves
        if waves is not None and len(waves):
            new = -np.ones(len(self), dtype=np.int64)
            new[idx] = np.arange(len(idx))
            ok = new[waves.rows] >= 0
            waves = OffsetWaves(new[waves.rows][ok], waves.h[ok], waves.z[ok])
        return Contacts(W=W, variation=var, waves=waves, **out)

    def wave_offset(self, azimuth: float) -> np.ndarray:
        """The azimuth-varying part of the offsets (:class:`OffsetWaves`) at ``azimuth``."""
        if self.waves is None or not len(self.waves):
            return np.zeros(len(self))
        return self.waves.at(azimuth, len(self))

    def __len__(self) -> int:
        return len(self.element)

    def index(self, element: str, contact: str) -> int:
        """Row of the contact ``contact`` (``"front"``, ``"back"``, ``"x+"``...) of ``element``."""
        for i, (e, c) in enumerate(zip(self.element, self.contact, strict=True)):
            if e == element and c == contact:
                return i
        raise ModelError("contact", f"no contact {contact!r} on element {element!r}")

    def mask(self, kind: str | None = None, contact: str | None = None) -> np.ndarray:
        """Boolean mask of the contacts of a ``kind`` (mesh/bearing) and/or ``contact``."""
        k = np.array(self.kind, dtype=object)
        c = np.array(self.contact, dtype=object)
        out = np.ones(len(self), dtype=bool)
        if kind is not None:
            out &= k == kind
        if contact is not None:
            out &= c == contact
        return out

    def to_frame(self) -> pd.DataFrame:
        """One row per contact: element, contact, kind, offset_m, stiffness, damping, nominal."""
        return pd.DataFrame({"element": self.element, "contact": self.contact,
                             "kind": self.kind, "offset_m": self.offset,
                             "stiffness": self.stiffness, "damping": self.damping,
                             "nominal": self.nominal})


@dataclass
class Assembly:
    """Assembled matrices of a model (SI units; speed in rad/s of the input body).

    Attributes
    ----------
    dof_names, load_names : names of the state and load vectors.
    M : mass matrix. C, K : damping and stiffness of the always-active elements.
    G : gyroscopic matrix per rad/s of input speed (skew-symmetric).
    K_cent : the steady rotation's stiffness per (rad/s)^2, which every solver scales by the
        speed squared: the bodies' centripetal softening (negative semi-definite) plus the
        geometric stiffness ``K_geom``.
    K_geom : the geometric stiffness per (rad/s)^2 included in ``K_cent`` (module docstring,
        (G1)-(G2)); ``K_cent - K_geom`` is the centripetal-only linearisation of Lin & Parker
        (1999) (``geometric_stiffness=False`` in :func:`gearmodal.modal`).
    K_speed : stiffness per rad/s of speed (default zero; a turning rotor's structural damping
        in multi-blade coordinates, :mod:`gearmodal.turbine.assumed_modes`).
    f_cent : centrifugal force per (rad/s)^2.
    B : load map, generalised force = ``B @ u`` for the load values ``u`` (N, N m).
    contacts : the unilateral contacts (:class:`Contacts`).
    round : the exactly round clearances (``clearance_shape="round"``): two rows per bearing,
        its x and y deflection in the bearing axes (``contact`` ``x``/``y``, ``kind``
        ``round``), with the radial clearance, stiffness and damping. Nonlinear: only the
        scipy reference integrates them (:func:`require_piecewise_linear`).
    """

    dof_names: list[str]
    load_names: list[str]
    M: np.ndarray
    C: np.ndarray
    K: np.ndarray
    G: np.ndarray
    K_cent: np.ndarray
    f_cent: np.ndarray
    B: np.ndarray
    contacts: Contacts
    azimuth: float = 0.0
    body_slices: dict = field(default_factory=dict)
    springs: Contacts | None = None
    round: Contacts | None = None
    #: the input body's rotation rate per state velocity (n,): its absolute speed is the
    #: input speed plus ``input_speed @ v`` (None: the model names no input)
    input_speed: np.ndarray | None = None
    K_geom: np.ndarray | None = None
    K_speed: np.ndarray | None = None

    def __post_init__(self):
        if self.K_geom is None:
            self.K_geom = np.zeros_like(self.K_cent)
        if self.K_speed is None:
            self.K_speed = np.zeros_like(self.K_cent)

    def speed_stiffness(self, geometric_stiffness: bool = True) -> np.ndarray:
        """The stiffness per (rad/s)^2 of the steady rotation: ``K_cent``, or without the
        geometric stiffness ``K_cent - K_geom`` (Lin & Parker's centripetal-only form)."""
        return self.K_cent if geometric_stiffness else self.K_cent - self.K_geom

    def reduction(self) -> tuple[Assembly, np.ndarray | None]:
        """``(assembly to solve, N)``: ``(self, None)``; a coupled assembly answers its
        projection on the constrained coordinates (:class:`gearmodal.coupling.CoupledAssembly`)."""
        return self, None

    def require_piecewise_linear(self, what: str) -> None:
        """Raise a :class:`ModelError` naming the bearing if the model has a round clearance,
        which ``what`` (a method, a solver) cannot handle."""
        if self.round is not None and len(self.round):
            name = self.round.element[0]
            raise ModelError(f"{name}.clearance_shape", f"= 'round' is nonlinear: {what} "
                             "needs a piecewise-linear model; integrate it with "
                             "method='scipy' (the reference) or use clearance_shape='polygon'")

    @property
    def n(self) -> int:
        return len(self.dof_names)

    def state(self, state=None) -> np.ndarray:
        """A boolean contact-state vector; ``None`` gives the nominal state (front flanks in
        contact, back flanks open, bearing clearances taken up on their + side)."""
        if state is None:
            return self.contacts.nominal.copy()
        s = np.asarray(state, dtype=bool)
        if s.shape != (len(self.contacts),):
            raise ModelError("state", f"expected {len(self.contacts)} booleans, "
                                      f"got shape {s.shape}")
        return s

    def stiffness(self, state=None, speed: float = 0.0) -> np.ndarray:
        """``K + K_s + speed K_speed + speed^2 K_cent`` for contact state ``state``; speed in
        rad/s."""
        s = self.state(state)
        W = self.contacts.W[s]
        return (self.K + (W.T * self.contacts.stiffness[s]) @ W + speed * self.K_speed
                + speed**2 * self.K_cent)

    def damping(self, state=None, speed: float = 0.0) -> np.ndarray:
        """``C + C_s + speed G`` for contact state ``state``; speed in rad/s."""
        s = self.state(state)
        W = self.contacts.W[s]
        return self.C + (W.T * self.contacts.damping[s]) @ W + speed * self.G

    def contact_force(self, state=None) -> np.ndarray:
        """``f_s = sum_active k_e offset_e W_e``: the constant part of the contact forces."""
        s = self.state(state)
        return self.contacts.W[s].T @ (self.contacts.stiffness[s] * self.contacts.offset[s])

    def penetration(self, q: np.ndarray) -> np.ndarray:
        """Penetration of every contact, ``W q - offset`` (active where > 0)."""
        return self.contacts.W @ q - self.contacts.offset

    def load_vector(self, loads: dict | None) -> np.ndarray:
        """Generalised force ``B u`` for a mapping ``{load name: value}`` (N, N m)."""
        f = np.zeros(self.n)
        if loads is not None and not hasattr(loads, "items"):
            raise ModelError("loads", f"expected {{load name: value}} (a dict), got "
                             f"{type(loads).__name__}")
        for key, value in (loads or {}).items():
            try:
                j = self.load_names.index(key)
            except ValueError:
                raise ModelError(f"loads.{key}", unknown("load", key, self.load_names)) \
                    from None
            try:
                u = float(value)
            except (TypeError, ValueError):
                raise ModelError(f"loads.{key}", f"= {value!r}: expected a number (N or N m)") \
                    from None
            if not math.isfinite(u):
                raise ModelError(f"loads.{key}", f"= {u!r}: must be finite (N or N m)")
            f += self.B[:, j] * u
        return f


def as_assembly(model, cached: bool = False) -> tuple[Assembly, str]:
    """``(assembly, model name)`` of a :class:`~gearmodal.Model` or a :class:`gearmodal.Coupled`
    system (anything with ``assemble()``, assembled at azimuth 0) or of an already assembled
    :class:`Assembly` (name ``""``). ``cached``: a model's assembly from
    :func:`cached_assembly` (shared and read-only; for callers that only read it)."""
    if isinstance(model, Assembly):
        return model, ""
    if cached:
        key = _fingerprint(model)
        if key is not None:
            return _cached(model, 0.0, key), str(getattr(model, "name", ""))
    build = getattr(model, "assemble", None)
    if callable(build):
        return build(), str(getattr(model, "name", ""))
    raise TypeError(f"expected a gm.Model, gm.Coupled or gm.Assembly, got "
                    f"{type(model).__name__}")


#: per model object: (fingerprint, azimuth, read-only assembly) of its latest cached assembly
_CACHE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _fingerprint(model) -> bytes | None:
    """The whole state of a plain :class:`~gearmodal.Model` as bytes (its pickle: every
    frame, body and element field, nested tables and arrays included), or None when a cached
    assembly could be stale without the bytes changing: a subclass of Model, a component of a
    class from outside gearmodal (a user's element kind, whose ``contribute`` may change
    without its data changing), or anything that does not pickle."""
    cls = type(model)  # by name: gearmodal.model.model imports this module
    if (cls.__module__, cls.__qualname__) != ("gearmodal.model.model", "Model"):
        return None
    try:
        parts = [*model.frames.values(), *model.bodies.values(), *model.elements()]
        if any(not type(c).__module__.startswith("gearmodal.") for c in parts):
            return None
        return pickle.dumps(model, protocol=pickle.HIGHEST_PROTOCOL)
    except Exception:  # anything that does not pickle is simply not cached
        return None


def _read_only(asm: Assembly) -> Assembly:
    """Mark the arrays of ``asm`` (and of its contact tables) read-only, so that code sharing
    a cached assembly cannot change it for the next caller."""
    for obj in (asm, asm.contacts, asm.springs, asm.round):
        if obj is None:
            continue
        for val in vars(obj).values():
            if isinstance(val, np.ndarray):
                val.flags.writeable = False
    return asm


def cached_assembly(model, azimuth: float = 0.0) -> Assembly:
    """``assemble(model, azimuth)``, reused while ``model`` is unchanged: the assembly of a
    model object is kept (weakly: it goes with the model) with the model's whole state
    (:func:`_fingerprint`), and assembled again as soon as anything in it differs (any
    field of any frame, body, mesh or bearing, added or removed components). Models that
    cannot be fingerprinted are assembled every time. The shared assembly's arrays are
    read-only: callers must not change it (:func:`assemble` gives a private one)."""
    return _cached(model, azimuth, _fingerprint(model))


def _cached(model, azimuth: float, key: bytes | None) -> Assembly:
    if key is None:
        return assemble(model, azimuth)
    hit = _CACHE.get(model)
    if hit is not None and hit[1] == azimuth and hit[0] == key:
        return hit[2]
    asm = _read_only(assemble(model, azimuth))
    _CACHE[model] = (key, azimuth, asm)
    return asm


def reduction(asm: Assembly) -> tuple[Assembly, np.ndarray | None]:
    """``(assembly to solve, N)``: a coupled assembly's projection on its constrained
    coordinates ``q = N z`` (:mod:`gearmodal.coupling`), or ``(asm, None)``."""
    return asm.reduction()


def _acts(w: np.ndarray) -> bool:
    """Whether a gap or joint row acts on any coordinate: entries are lever arms and direction
    cosines (m or 1), so anything below 1e-12 is the rounding of a cancelled term."""
    return bool(np.abs(w).max(initial=0.0) > 1e-12)


def _structure(element) -> tuple:
    """(name, stage, planet, role) of an element, as its contact rows carry them."""
    return (element.name, getattr(element, "stage", ""), getattr(element, "planet", None) or "",
            getattr(element, "role", ""))


class _Rows:
    """Rows of one kind (unilateral contacts, linear springs, round clearances) as the
    elements add them: the columns of :class:`Contacts`."""

    _FIELDS = ("W", "offset", "stiffness", "damping", "nominal", "element", "contact", "angle",
               "columns", "stage", "planet", "role")

    def __init__(self):
        self.rows: list[tuple] = []
        self.variation: list[tuple] = []
        self.waves: list[tuple] = []
        self._element, self._meta = None, ()

    def __len__(self) -> int:
        return len(self.rows)

    def add(self, w, offset, k, c, nominal, element, label, angle=np.nan, columns=()):
        if element is not self._element:  # an element adds its rows in a run
            self._element, self._meta = element, _structure(element)
        meta = self._meta
        self.rows.append((w, offset, k, c, nominal, meta[0], label, angle, tuple(columns),
                          *meta[1:]))
        return len(self.rows) - 1

    def contacts(self, kind, n: int) -> Contacts:
        k = len(self.rows)
        cols = dict(zip(self._FIELDS, zip(*self.rows, strict=True), strict=True)) if k \
            else dict.fromkeys(self._FIELDS, ())
        kinds = kind if isinstance(kind, list) else [kind] * k
        out = Contacts(
            element=list(cols["element"]), contact=list(cols["contact"]), kind=kinds,
            W=np.array(cols["W"]) if k else np.zeros((0, n)),
            offset=np.array(cols["offset"], dtype=float),
            stiffness=np.array(cols["stiffness"], dtype=float),
            damping=np.array(cols["damping"], dtype=float),
            nominal=np.array(cols["nominal"], dtype=bool),
            angle=np.array(cols["angle"], dtype=float), columns=list(cols["columns"]),
            stage=list(cols["stage"]), planet=list(cols["planet"]), role=list(cols["role"]))
        if self.variation:
            v = list(zip(*self.variation, strict=True))
            out.variation = MeshVariation(np.array(v[0], dtype=np.int64),
                                          *(np.array(c, dtype=float) for c in v[1:]))
        if self.waves:
            r, h, z = zip(*self.waves, strict=True)
            out.waves = OffsetWaves(np.array(r, dtype=np.int64), np.array(h, dtype=float),
                                    np.array(z, dtype=complex))
        return out


class Contributions:
    """What the elements of a model add up to at one input azimuth: the collector
    :func:`assemble` hands to each body's and element's ``contribute(ctx)`` (as ROSS's
    elements each give their matrices and the rotor adds them up).

    Attributes an element reads: ``model``, ``azimuth`` (rad), ``probe`` (a generic azimuth
    to tell whether a row acts at every azimuth), ``n`` (DOF), ``slices`` (body name -> its
    coordinates). Arrays it adds to: ``M``, ``G``, ``K_cent``, ``f_cent`` (a body's own
    block), ``K``, ``C`` (through :meth:`spring`). Rows: :meth:`contact`, :meth:`spring`,
    :meth:`round_row`; geometry: :meth:`centre`, :meth:`row`.
    """

    def __init__(self, model, azimuth: float, slices: dict, n: int):
        self.model, self.azimuth, self.slices, self.n = model, azimuth, slices, n
        self.probe = azimuth + 1.2345678901
        self.M, self.G, self.K_cent = np.zeros((n, n)), np.zeros((n, n)), np.zeros((n, n))
        self.K, self.C = np.zeros((n, n)), np.zeros((n, n))
        self.f_cent = np.zeros(n)
        self.contacts, self.springs, self.round = _Rows(), _Rows(), _Rows()
        self.kinds: list[str] = []  # of the contacts: "mesh", "bearing"
        #: the springs and nominally active contacts whose rows are curved: (w, k, idx, H)
        self.curved: list[tuple] = []
        self._transforms: dict = {}
        self._centres: dict = {}

    def transform(self, body, azimuth: float | None = None) -> np.ndarray:
        """The body's T (6 x n_b) at ``azimuth`` (default the assembly's)."""
        az = self.azimuth if azimuth is None else azimuth
        key = (body.name, az)
        if key not in self._transforms:
            self._transforms[key] = body_transform(self.model, body, az)
        return self._transforms[key]

    def centre(self, body, azimuth: float | None = None) -> np.ndarray:
        """The body's centre (m, global axes) at ``azimuth`` (default the assembly's)."""
        az = self.azimuth if azimuth is None else azimuth
        key = (body.name, az)
        if key not in self._centres:
            self._centres[key] = centre(self.model, body, az)
        return self._centres[key]

    def row(self, parts, azimuth: float | None = None) -> np.ndarray:
        """A row of the state from ``[(body, J6), ...]``: ``sum J6 @ T_body`` on each body's
        coordinates (J6: the row's gradient in the body centre's global 6-vector)."""
        az = self.azimuth if azimuth is None else azimuth
        cache, w = self._transforms, np.zeros(self.n)
        for body, J in parts:
            T = cache.get((body.name, az))
            if T is None:
                T = cache[(body.name, az)] = body_transform(self.model, body, az)
            w[self.slices[body.name]] += J @ T
        return w

    def curvature(self, parts) -> tuple[np.ndarray, np.ndarray] | None:
        """A row's curvature in the state, from ``([(body, rows), ...], H)``: ``H`` the Hessian
        of the row in the listed parts of the bodies' global 6-vectors, side by side (``rows``
        a slice of a body's ``(ux, uy, uz, rx, ry, rz)``; a body may appear in several parts).
        Returns ``(idx, T^T H T)`` on the state indices ``idx`` of those bodies' coordinates,
        or None when it is zero."""
        blocks, H6 = parts
        if not np.any(H6):
            return None
        bodies = list(dict.fromkeys(b.name for b, _ in blocks))
        ranges = [range(self.n)[self.slices[b]] for b in bodies]
        idx = np.concatenate([np.arange(r.start, r.stop, r.step) for r in ranges])
        start = dict(zip(bodies, np.cumsum([0] + [len(r) for r in ranges]), strict=False))
        T = np.zeros((H6.shape[0], len(idx)))
        row = 0
        for body, rows in blocks:
            t = self.transform(body)[rows]
            c0 = start[body.name]
            T[row:row + t.shape[0], c0:c0 + t.shape[1]] += t
            row += t.shape[0]
        H = T.T @ H6 @ T
        return (idx, H) if np.any(H) else None

    def contact(self, w, offset: float, k: float, c: float, nominal: bool, element,
                label: str, kind: str, *, columns, angle: float = np.nan,
                variation=None, waves=(), curvature=None) -> int:
        """A unilateral contact of ``element``: penetration ``w q - offset``, force
        ``k p + c p'`` while ``p > 0``, added with ``weight`` to each result force column of
        ``columns`` (``[(column, weight), ...]``); ``variation`` an alternating stiffness
        ``(rate, phase, double, k_single, k_double)``; ``waves`` ``[(h, z), ...]`` offset
        terms ``Re(z e^(i h psi))`` (:class:`OffsetWaves`; ``offset`` includes their value at
        this azimuth); ``curvature`` the row's ``([bodies], H6)`` (:meth:`curvature`), for the
        geometric stiffness of the force it carries. Returns the contact's row."""
        rows = self.contacts  # _Rows.add inlined: polygons add hundreds of rows
        if element is not rows._element:
            rows._element, rows._meta = element, _structure(element)
        meta = rows._meta
        rows.rows.append((w, offset, k, c, nominal, meta[0], label, angle, tuple(columns),
                          *meta[1:]))
        self.kinds.append(kind)
        i = len(rows.rows) - 1
        if variation is not None:
            rows.variation.append((i, *variation))
        for h, z in waves:
            rows.waves.append((i, h, z))
        if curvature is not None and nominal:
            self._curved(w, k, curvature)
        return i

    def _curved(self, w, k: float, curvature) -> None:
        got = self.curvature(curvature)
        if got is not None:
            self.curved.append((w, k, *got))

    def spring(self, w, k: float, c: float, element, direction: str, acts: bool,
               curvature=None) -> None:
        """An always-active spring-damper on the deflection ``w q``: ``k w w^T`` and
        ``c w w^T``; listed (for its force column ``<element>.<direction>``) if it ``acts``;
        ``curvature`` as for :meth:`contact`."""
        if curvature is not None:
            self._curved(w, k, curvature)
        ww = np.outer(w, w)
        self.K += k * ww
        if c:
            self.C += c * ww
        if acts:
            self.springs.add(w, 0.0, k, c, True, element, direction)

    def round_row(self, w, element, label: str, clearance: float, k: float, c: float):
        """One of the two (x, y) rows of an exactly round clearance (nonlinear: scipy)."""
        self.round.add(w, clearance, k, c, False, element, label)


def assemble(model, azimuth: float = 0.0) -> Assembly:
    """Assemble ``model`` at input azimuth ``azimuth`` (rad; geometry of frames turning against
    each other is frozen there). Returns an :class:`Assembly`.

    Each body adds its inertia, each element (mesh, bearing...: ``model.elements()``) its
    rows, through ``contribute(ctx)`` on a :class:`Contributions`; loads are unit forces and
    moments at the body centres.
    """
    model.check()
    pinned = [b.name for b in model.bodies.values()
              if b.pinned_to is not None and 0 not in b.local_indices]
    if pinned:
        return _on_pins(model, pinned, azimuth)
    bodies = list(model.bodies.values())
    slices, start = {}, 0
    for b in bodies:
        nb = len(b.local_indices)
        slices[b.name] = slice(start, start + nb)
        start += nb
    n = start
    ctx = Contributions(model, azimuth, slices, n)
    for b in bodies:
        b.contribute(ctx)
    for element in model.elements():
        element.contribute(ctx)

    # Loads by name: generalised force of a unit force/moment at the body centre.
    load_names, cols = [], []
    for b in bodies:
        T = ctx.transform(b)
        for lname, idx in model.load_directions(b):
            col = np.zeros(n)
            col[slices[b.name]] = T[idx]
            if lname.endswith(".force_u"):
                col[slices[b.name]] *= b.rotation_scale
            load_names.append(lname)
            cols.append(col)
    # gravity (the load "gravity", value g in m/s^2): every body's weight at its centre,
    # sum_b m_b T_b^T d with d the ground-axes direction (model.gravity_direction); in a
    # turning frame T_b turns with the azimuth, so the weight is a rotating load there
    d = np.array([*model.gravity_direction, 0.0, 0.0, 0.0])
    col = np.zeros(n)
    for b in bodies:
        col[slices[b.name]] += b.mass * (d @ ctx.transform(b))
    load_names.append(GRAVITY)
    cols.append(col)
    B = np.array(cols).T if cols else np.zeros((n, 0))
    contacts = ctx.contacts.contacts(ctx.kinds, n)
    springs = ctx.springs.contacts("spring", n)
    K_geom = _geometric_stiffness(ctx, contacts)
    nr = len(ctx.round)
    round_ = ctx.round.contacts("round", n) if nr else None
    return Assembly(dof_names=model.dof_names, load_names=load_names, M=ctx.M, C=ctx.C,
                    K=ctx.K, G=ctx.G, K_cent=ctx.K_cent + K_geom, f_cent=ctx.f_cent, B=B,
                    contacts=contacts, azimuth=azimuth, body_slices=slices, springs=springs,
                    round=round_, input_speed=_input_speed(model, slices, n), K_geom=K_geom)


def _geometric_stiffness(ctx: Contributions, contacts: Contacts) -> np.ndarray:
    """``K_geom`` per (rad/s)^2, (G1)-(G2) of the module docstring."""
    n = ctx.n
    K_geom = np.zeros((n, n))
    if not ctx.curved or not np.any(ctx.f_cent):
        return K_geom
    s = contacts.nominal
    W = contacts.W[s]
    Ks = ctx.K + (W.T * contacts.stiffness[s]) @ W
    q1 = np.linalg.lstsq(Ks, ctx.f_cent, rcond=None)[0]  # (G1)
    for w, k, idx, H in ctx.curved:  # (G2)
        force = k * float(w @ q1)
        if force:
            K_geom[np.ix_(idx, idx)] += force * H
    return 0.5 * (K_geom + K_geom.T)


def _input_speed(model, slices: dict, n: int) -> np.ndarray | None:
    """:attr:`Assembly.input_speed`: the input body's ``theta`` (its last local coordinate;
    ``u = rotation_scale theta`` where scaled), or None without an input or a rotation."""
    b = model.bodies.get(model.input) if model.input is not None else None
    if b is None or b.local_indices[-1] != 5:
        return None
    row = np.zeros(n)
    row[slices[b.name].stop - 1] = 1.0 / (b.rotation_scale or 1.0)
    return row


def _on_pins(model, pinned: list[str], azimuth: float) -> Assembly:
    """Assembly of a model whose torsional bodies ``pinned`` ride on their hosts' pins
    (``Body.pinned_to``). The model is assembled with those bodies at ``planar`` and their
    centre translations eliminated as the motion of the host's point at their centre:

        (P1)  u_pin = T_h,u q_h + (T_h,r q_h) x (c_b - c_h),   [x_b, y_b] = R_b^+ u_pin

    (``T_h`` the host's body transform, rows u translation and r rotation; ``c`` centres;
    ``R_b`` the body's local x/y axes). With ``q = N z`` every matrix is projected
    (``N^T M N``, ``W N``...), so a planet's mass adds ``m r^2`` to its carrier's rotation and
    its bearing to the carrier, whose deflection vanishes, drops out. It is the stiff-bearing
    limit of the planar stage, including Lin & Parker's centripetal softening: at speed the
    planets' ``-m Omega^2`` on their translations projects to ``-m r^2 Omega^2`` on the
    carrier's rotation (as in the planar stage, whose bearings hold the planets)."""
    mx = model.copy()
    for name in pinned:
        mx.bodies[name].dofs = "planar"
        mx.bodies[name].pinned_to = None
    full = assemble(mx, azimuth)
    n = full.n
    sl = full.body_slices
    keep = np.ones(n, dtype=bool)
    for name in pinned:
        keep[[sl[name].start, sl[name].start + 1]] = False  # planar order: x, y, theta
    idx = np.flatnonzero(keep)
    pos = np.full(n, -1)
    pos[idx] = np.arange(len(idx))
    N = np.zeros((n, len(idx)))
    N[idx, np.arange(len(idx))] = 1.0
    for name in pinned:
        b, h = model.bodies[name], model.bodies[model.bodies[name].pinned_to]
        Th = body_transform(model, h, azimuth)
        arm = centre(model, b, azimuth) - centre(model, h, azimuth)
        G = Th[:3] - skew(arm) @ Th[3:]  # (P1): w x arm = -arm x w
        R = body_transform(mx, mx.bodies[name], azimuth)[:3, :2]
        hcols = pos[sl[h.name].start:sl[h.name].stop]
        N[np.ix_([sl[name].start, sl[name].start + 1], hcols)] = np.linalg.pinv(R) @ G

    def red(c: Contacts | None) -> Contacts | None:
        if c is None:
            return None
        W = proj(c.W, left=False)
        rows = [i for i in range(len(c)) if _acts(W[i])]
        return c.take(rows, W[rows].reshape(len(rows), len(idx)))

    def proj(X: np.ndarray, left: bool = True, right: bool = True) -> np.ndarray:
        """N^T X N (or one side); entries below 1e-13 of X's largest are the rounding of
        cancelled terms (a planet's gyroscopic coupling on a torsional carrier) and are set
        to 0, so that fields which do not turn with the azimuth stay exactly constant."""
        Y = (N.T @ X) if left else X
        Y = (Y @ N) if right else Y
        Y = np.array(Y, dtype=float)
        Y[np.abs(Y) < 1e-13 * np.abs(X).max(initial=0.0)] = 0.0
        return Y

    loads = set(model.load_names)
    cols = [j for j, ln in enumerate(full.load_names) if ln in loads]
    slices = {}
    for name, s_ in sl.items():
        kept = pos[s_.start:s_.stop]
        kept = kept[kept >= 0]
        slices[name] = slice(int(kept[0]), int(kept[-1]) + 1)
    return Assembly(dof_names=[full.dof_names[i] for i in idx],
                    load_names=[full.load_names[j] for j in cols], M=proj(full.M),
                    C=proj(full.C), K=proj(full.K), G=proj(full.G), K_cent=proj(full.K_cent),
                    K_speed=proj(full.K_speed),
                    K_geom=proj(full.K_geom),
                    f_cent=proj(full.f_cent, right=False), B=proj(full.B[:, cols], right=False),
                    contacts=red(full.contacts), azimuth=azimuth,
                    body_slices=slices, springs=red(full.springs), round=red(full.round),
                    input_speed=None if full.input_speed is None else full.input_speed @ N)
