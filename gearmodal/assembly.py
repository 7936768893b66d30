"""Model -> matrices: mass, damping, stiffness per contact state, gyroscopic and centripetal
matrices, contact gap functions as linear maps of the state, and load maps.

The equations of motion at input speed ``Omega`` (rad/s) in contact state ``s`` are (DESIGN 2.1)::

    M q'' + (C + C_s + Omega G) q' + (K + K_s + Omega^2 K_cent) q
        = B u + f_s + Omega^2 f_cent

Every contact (a flank of a mesh, one side of a bearing dead band) ``e`` has a penetration
``p_e = W[e] @ q - offset[e]`` and is active while ``p_e > 0``; then it pushes back with
``stiffness[e] * p_e + damping[e] * p_e'`` along ``-W[e]`` (DESIGN 2.2, 2.3), so::

    K_s = sum_active k_e W_e^T W_e,   C_s = sum_active c_e W_e^T W_e,
    f_s = sum_active k_e offset_e W_e

The kernels used here are generated from ``symbolic/`` (floating-frame wheel: ``wheel.py``;
flank gaps: ``mesh.py``; joint/bearing deflections: ``joint.py``). Coefficients that rotate with a
frame against fixed supports are frozen at the input azimuth given to :func:`assemble`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from .errors import ModelError
from .frames import body_selector, body_transform, centre, rz, skew
from .kernels.joint import bearing_gap_jacobians, joint_gradients
from .kernels.mesh import mesh_gap_jacobian
from .kernels.wheel import (
    wheel_centrifugal_force,
    wheel_centripetal,
    wheel_gyroscopic,
    wheel_mass,
)
from .model.clearance import polygon_ramps
from .model.components import DIRECTIONS, GROUND, Gear
from .model.mesh_stiffness import MeshVariation, variation_of


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

    def __post_init__(self):
        if self.angle is None:
            self.angle = np.full(len(self.element), np.nan)

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
    K_cent : centripetal stiffness per (rad/s)^2 (softening, negative semi-definite).
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
        """``K + K_s + speed^2 K_cent`` for contact state ``state``; speed in rad/s."""
        s = self.state(state)
        W = self.contacts.W[s]
        return self.K + (W.T * self.contacts.stiffness[s]) @ W + speed**2 * self.K_cent

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
        for key, value in (loads or {}).items():
            try:
                j = self.load_names.index(key)
            except ValueError:
                raise ModelError(f"loads.{key}", "no such load; available: "
                                 + ", ".join(self.load_names)) from None
            f += self.B[:, j] * float(value)
        return f


def as_assembly(model) -> tuple[Assembly, str]:
    """``(assembly, model name)`` of a :class:`~gearmodal.Model` or a :class:`gearmodal.Coupled`
    system (anything with ``assemble()``, assembled at azimuth 0) or of an already assembled
    :class:`Assembly` (name ``""``)."""
    if isinstance(model, Assembly):
        return model, ""
    build = getattr(model, "assemble", None)
    if callable(build):
        return build(), str(getattr(model, "name", ""))
    raise TypeError(f"expected a gm.Model, gm.Coupled or gm.Assembly, got "
                    f"{type(model).__name__}")


def reduction(asm: Assembly) -> tuple[Assembly, np.ndarray | None]:
    """``(assembly to solve, N)``: a coupled assembly's projection on its constrained
    coordinates ``q = N z`` (:mod:`gearmodal.coupling`), or ``(asm, None)``."""
    N = getattr(asm, "N", None)
    if N is None:
        return asm, None
    return asm.reduced(), N


def _acts(w: np.ndarray) -> bool:
    """Whether a gap or joint row acts on any coordinate: entries are lever arms and direction
    cosines (m or 1), so anything below 1e-12 is the rounding of a cancelled term."""
    return bool(np.abs(w).max(initial=0.0) > 1e-12)


def assemble(model, azimuth: float = 0.0) -> Assembly:
    """Assemble ``model`` at input azimuth ``azimuth`` (rad; geometry of frames turning against
    each other is frozen there). Returns an :class:`Assembly`.
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
    M = np.zeros((n, n))
    G = np.zeros((n, n))
    Kc = np.zeros((n, n))
    fc = np.zeros(n)
    T = {b.name: body_transform(model, b, azimuth) for b in bodies}
    centres = {b.name: centre(model, b, azimuth) for b in bodies}

    # Inertia of each wheel: the local block of the floating-frame kernels (DESIGN 2.1).
    for b in bodies:
        sl = slices[b.name]
        S = body_selector(b)
        args = (b.mass, b.inertia_diametral, b.inertia, *b.position, b.orientation)
        of = model.frames[b.frame].speed_ratio
        M[sl, sl] = S.T @ wheel_mass(*args)[6:, 6:] @ S
        G[sl, sl] = S.T @ wheel_gyroscopic(*args, of, b.speed_ratio)[6:, 6:] @ S
        Kc[sl, sl] = S.T @ wheel_centripetal(*args, of, b.speed_ratio)[6:, 6:] @ S
        fc[sl] = S.T @ wheel_centrifugal_force(*args, of, b.speed_ratio)[6:]

    K = np.zeros((n, n))
    C = np.zeros((n, n))
    rows, offs, ks, cs, noms, elems, labels, kinds = [], [], [], [], [], [], [], []
    angles = []
    lin_rows, lin_k, lin_c, lin_elem, lin_dir = [], [], [], [], []
    rnd = {"W": [], "element": [], "contact": [], "offset": [], "k": [], "c": []}

    def add_contact(w, off, k, c, nominal, elem, label, kind, angle=np.nan):
        angles.append(angle)
        rows.append(w)
        offs.append(off)
        ks.append(k)
        cs.append(c)
        noms.append(nominal)
        elems.append(elem)
        labels.append(label)
        kinds.append(kind)

    # Meshes: two flanks on mirrored lines of action (DESIGN 2.2).
    var_rows = []  # alternating mesh stiffness (Mesh.alternation): (row, rate, phase, ...)
    for m in model.meshes.values():
        a, b = model.bodies[m.gear_a], model.bodies[m.gear_b]
        if m.internal is not None:
            internal = 1.0 if m.internal else 0.0
        else:
            internal = 1.0 if isinstance(a, Gear) and a.internal else 0.0
        if m.base_radii is not None:
            rba, rbb = (float(r) for r in m.base_radii)
        else:
            rba, rbb = a.base_radius, b.base_radius
        if m.pressure_angle is not None:
            alpha = m.pressure_angle
        else:
            g = b if isinstance(b, Gear) else a
            alpha = g.transverse_pressure_angle
        if m.helix_angle is not None:
            beta_b = m.helix_angle
        else:
            beta_b = a.base_helix_angle if isinstance(a, Gear) else 0.0
        ca, cb = centres[a.name], centres[b.name]
        if np.hypot(*(cb - ca)[:2]) == 0.0:
            raise ModelError(m.name, f"gears {a.name!r} and {b.name!r} have the same centre")
        for flank, side, off in (("front", m.side, 0.0), ("back", -m.side, m.backlash)):
            J = mesh_gap_jacobian(ca[0], ca[1], cb[0], cb[1], rba, rbb, alpha, beta_b,
                                  float(side), internal)
            w = np.zeros(n)
            w[slices[a.name]] += J[:6] @ T[a.name]
            w[slices[b.name]] += J[6:] @ T[b.name]
            if np.any(w):
                if m.alternation:
                    var_rows.append((len(rows), *variation_of(model, m, a, b, bool(internal))))
                add_contact(w, off, m.stiffness, m.damping, flank == "front", m.name, flank,
                            "mesh")

    # Bearings, supports and shafts with per-direction dead bands (DESIGN 2.3).
    def bearing_jacobians(br, az, T_, centres_):
        a = model.bodies[br.a]
        b = model.bodies[br.b] if br.b is not None else None
        fa = model.frames[a.frame]
        pa = rz(fa.speed_ratio * az) @ np.asarray(br.at, dtype=float)
        cb = centres_[b.name] if b is not None else np.zeros(3)
        pb = centres_[a.name] + pa - cb
        axes_frame = br.axes_frame or (b.frame if b is not None else GROUND)
        gamma = model.frames[axes_frame].speed_ratio * az + br.axes_angle
        Ga, Gb = joint_gradients(pa[0], pa[1], pa[2], pb[0], pb[1], pb[2], gamma)
        Ja, Jb = bearing_gap_jacobians(pa[0], pa[1], pa[2], pb[0], pb[1], pb[2], gamma)

        def row(Ra, Rb, j):
            w = np.zeros(n)
            w[slices[a.name]] += Ra[j] @ T_[a.name]
            if b is not None:
                w[slices[b.name]] += Rb[j] @ T_[b.name]
            return w
        return lambda j: row(Ga, Gb, j), lambda j: row(Ja, Jb, j)

    # A direction that acts on no DOF present at these levels is left out; whether it acts is
    # decided at this azimuth and at a generic one, so that every azimuth of a turning frame
    # gives the same rows (a torsional carrier's pin moves along x except where sin = 0)
    probe = azimuth + 1.2345678901
    T2 = {b.name: body_transform(model, b, probe) for b in bodies}
    centres2 = {b.name: centre(model, b, probe) for b in bodies}
    for br in model.bearings.values():
        spring_row, gap_row = bearing_jacobians(br, azimuth, T, centres)
        spring_row2, gap_row2 = bearing_jacobians(br, probe, T2, centres2)
        radial, acts = (), False
        if br.clearance_shape != "axes":  # x and y make one radial clearance
            radial = ("x", "y")
            gx, gy = gap_row(0), gap_row(2)  # the x and y deflection rows (joint.py)
            acts = _acts(gx) or _acts(gy) or _acts(gap_row2(0)) or _acts(gap_row2(2))
        if br.clearance_shape == "polygon":
            # facet i: the deflection along its normal (cos a_i, sin a_i) in the bearing axes,
            # with the ramps of clearance.polygon_ramps (R2); damping shared in proportion to
            # stiffness
            if acts:
                kr, cr = br.stiffness["x"], br.damping.get("x", 0.0)
                offsets, kms = polygon_ramps(br.clearance["x"], kr, br.facets, br.ramps)
                for i in range(br.facets):
                    a_i = 2.0 * math.pi * i / br.facets
                    w = math.cos(a_i) * gx + math.sin(a_i) * gy
                    for m_, (o, km) in enumerate(zip(offsets, kms, strict=True)):
                        add_contact(w, o, km, cr * km / kr if kr else 0.0, False, br.name,
                                    f"facet{i}_{m_}", "bearing", a_i)
        elif br.clearance_shape == "round":
            # (R1) of clearance.py on the x and y deflection rows
            if acts:
                for lab, w in (("x", gx), ("y", gy)):
                    rnd["W"].append(w)
                    rnd["element"].append(br.name)
                    rnd["contact"].append(lab)
                    rnd["offset"].append(br.clearance["x"])
                    rnd["k"].append(br.stiffness["x"])
                    rnd["c"].append(br.damping.get("x", 0.0))
        for key, k in br.stiffness.items():
            if key in radial:
                continue
            i = DIRECTIONS.index(key)
            c = br.damping.get(key, 0.0)
            gap = br.clearance.get(key, 0.0)
            if gap == 0.0:
                # no dead band: a linear spring on the joint deflection g_i
                w = spring_row(i)
                K += k * np.outer(w, w)
                C += c * np.outer(w, w)
                if _acts(w) or _acts(spring_row2(i)):
                    lin_rows.append(w)
                    lin_k.append(k)
                    lin_c.append(c)
                    lin_elem.append(br.name)
                    lin_dir.append(key)
                continue
            for j, side in ((2 * i, "+"), (2 * i + 1, "-")):
                w = gap_row(j)
                if _acts(w) or _acts(gap_row2(j)):
                    add_contact(w, gap, k, c, side == "+", br.name, f"{key}{side}",
                                "bearing")

    # Loads by name: generalised force of a unit force/moment at the body centre.
    load_names, cols = [], []
    for b in bodies:
        for lname, idx in model.load_directions(b):
            col = np.zeros(n)
            col[slices[b.name]] = T[b.name][idx]
            if lname.endswith(".force_u"):
                col[slices[b.name]] *= b.rotation_scale
            load_names.append(lname)
            cols.append(col)
    B = np.array(cols).T if cols else np.zeros((n, 0))

    nc = len(rows)
    contacts = Contacts(
        element=elems, contact=labels, kind=kinds,
        W=np.array(rows) if nc else np.zeros((0, n)),
        offset=np.array(offs, dtype=float), stiffness=np.array(ks, dtype=float),
        damping=np.array(cs, dtype=float), nominal=np.array(noms, dtype=bool),
        angle=np.array(angles, dtype=float))
    if var_rows:
        cols = list(zip(*var_rows, strict=True))
        contacts.variation = MeshVariation(np.array(cols[0], dtype=np.int64),
                                           *(np.array(c, dtype=float) for c in cols[1:]))
    nl = len(lin_rows)
    springs = Contacts(
        element=lin_elem, contact=lin_dir, kind=["spring"] * nl,
        W=np.array(lin_rows) if nl else np.zeros((0, n)), offset=np.zeros(nl),
        stiffness=np.array(lin_k, dtype=float), damping=np.array(lin_c, dtype=float),
        nominal=np.ones(nl, dtype=bool))
    nr = len(rnd["W"])
    round_ = None if not nr else Contacts(
        element=rnd["element"], contact=rnd["contact"], kind=["round"] * nr,
        W=np.array(rnd["W"]), offset=np.array(rnd["offset"], dtype=float),
        stiffness=np.array(rnd["k"], dtype=float), damping=np.array(rnd["c"], dtype=float),
        nominal=np.zeros(nr, dtype=bool))
    return Assembly(dof_names=model.dof_names, load_names=load_names, M=M, C=C, K=K, G=G,
                    K_cent=Kc, f_cent=fc, B=B, contacts=contacts, azimuth=azimuth,
                    body_slices=slices, springs=springs, round=round_)


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
        new = -np.ones(len(c), dtype=np.int64)
        new[rows] = np.arange(len(rows))
        var = c.variation
        if var is not None and len(var):
            ok = new[var.rows] >= 0
            var = MeshVariation(new[var.rows][ok], var.rate[ok], var.phase[ok],
                                var.double[ok], var.k_single[ok], var.k_double[ok])
        return Contacts(element=[c.element[i] for i in rows],
                        contact=[c.contact[i] for i in rows], kind=[c.kind[i] for i in rows],
                        W=W[rows].reshape(len(rows), len(idx)), offset=c.offset[rows],
                        stiffness=c.stiffness[rows], damping=c.damping[rows],
                        nominal=c.nominal[rows], angle=c.angle[rows], variation=var)

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
                    f_cent=proj(full.f_cent, right=False), B=proj(full.B[:, cols], right=False),
                    contacts=red(full.contacts), azimuth=azimuth,
                    body_slices=slices, springs=red(full.springs), round=red(full.round))
