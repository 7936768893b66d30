"""The elastic turbine as one linear system: tower, nacelle, shaft, hub and bending blades
(issue 56, DESIGN 2.5a).

Coordinates (ElastoDyn's degrees of freedom, each blade's in its own rotating axes):
``tower_fa<i>``, ``tower_ss<i>`` (the tower's assumed modes, :mod:`.bodies`), ``shaft_twist``
(the rotor's rotation against the generator, through the drivetrain's torsional stiffness),
``generator_azimuth`` (with ``generator="free"``: the generator's rotation, on the low-speed
side), and ``blade<k>_flap<i>``, ``blade<k>_edge<i>``.

Equations (assumed modes, as ElastoDyn): every material point's displacement is linear in
the coordinates, ``u = J q``; the tower's points move with its modes, the rigid bodies on the
tower top (nacelle, hub, generator) with the top's displacement and rotation
(``theta = (-sum phi'_ss q_ss, sum phi'_fa q_fa, 0)``), the blades' points with the hub plus
their own modes. Then

* mass: ``M = sum m J^T J`` over the tower's and blades' mass per length and the point masses,
  plus the rotational inertias of the hub and generator about the shaft;
* stiffness: each body's modal stiffness, the drivetrain's ``DTTorSpr`` on ``shaft_twist``,
  and gravity's: the tower carries the weight above it, ``-int N phi_i' phi_j' dz`` with
  ``N(z) = g (m_RNA + int_z^H mu)``, and tilting the tower top lowers the rotor-nacelle
  assembly's centre by ``h theta^2 / 2`` (``-g m_RNA h`` per unit tilt squared);
* damping: the deck's structural damping of each isolated mode, and ``DTTorDmp``.

Left out (and what it moves): the blades' own weight (it depends on their azimuth; it
stiffens a hanging blade and softens a standing one, about equally over three blades), the
second-order gravity terms of the rotor-nacelle assembly's horizontal offset, tower torsion and
yaw (no yaw spring in the deck). The turning rotor's terms (centrifugal stiffening,
gyroscopic and Coriolis coupling, multi-blade coordinates) are not yet derived: the model
solves at 0 rpm and refuses a speed (:meth:`ElasticTurbine.check_speed`).
"""

from __future__ import annotations

import math

import numpy as np

from ..coupling import Coupled, LinearConstraint, LinearSystem, ModelSystem
from ..errors import ModelError
from ..model.model import Model
from .bodies import BeamModes, blade_modes, tower_modes
from .elastodyn import GRAVITY, StructureDeck, read_structure

GENERATOR = ("locked", "free")


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v)


def structure_matrices(deck: StructureDeck, blade: BeamModes, tower: BeamModes, *,
                       generator: str | None = "locked", azimuth: float = 0.0,
                       gravity: float = GRAVITY):
    """``(dof_names, M, C, K)`` of the parked elastic turbine (module docstring) with blade 1
    at ``azimuth`` (rad, 0: up; the rotor turns about the downwind shaft axis).

    ``generator``: ``"locked"`` or ``"free"`` with the deck's own drivetrain (``shaft_twist``
    on ``DTTorSpr``, the generator's inertia); ``None``: no drivetrain, the rotor's rotation
    ``rotor_azimuth`` free (a gearbox model supplies shaft, gears and generator)."""
    if generator is not None and generator not in GENERATOR:
        raise ModelError("generator", f"= {generator!r}: one of {', '.join(GENERATOR)}")
    nb = deck.blades
    names = [f"tower_{m}" for m in tower.names]
    names.append("rotor_azimuth" if generator is None else "shaft_twist")
    if generator == "free":
        names.append("generator_azimuth")
    for k in range(nb):
        names += [f"blade{k + 1}_{m}" for m in blade.names]
    n = len(names)
    ix = {nm: i for i, nm in enumerate(names)}
    M = np.zeros((n, n))
    K = np.zeros((n, n))
    C = np.zeros((n, n))
    t0 = 0
    tw = slice(t0, t0 + tower.n)
    # the tower: its points move along x (fore-aft) and y (side-to-side)
    M[tw, tw] += tower.mass_matrix()
    K[tw, tw] += tower.stiffness
    C[tw, tw] += tower.damping_matrix()
    # the tower top: displacement uT (3 x n) and small rotation thT (3 x n) per coordinate
    uT = np.zeros((3, n))
    thT = np.zeros((3, n))
    uT[0, tw] = tower.tip()[:, 0]
    uT[1, tw] = tower.tip()[:, 1]
    thT[0, tw] = -tower.tip_slope()[:, 1]
    thT[1, tw] = tower.tip_slope()[:, 0]

    def rigid(r: np.ndarray) -> np.ndarray:
        """(3 x n): the motion of a point fixed to the tower top at offset ``r``."""
        return uT + np.cross(thT.T, r).T

    # the nacelle: a point mass (ElastoDyn gives no inertia but the yaw's)
    rN = np.array(deck.nacelle_cm, dtype=float)
    JN = rigid(rN)
    M += deck.nacelle_mass * JN.T @ JN
    M += deck.nacelle_yaw_inertia * np.outer(thT[2], thT[2])
    es = deck.shaft_axis
    apex = deck.apex
    rot = np.zeros(n)  # the rotor's rotation about the shaft, per coordinate
    rot[ix["rotor_azimuth" if generator is None else "shaft_twist"]] = 1.0
    if generator == "free":
        rot[ix["generator_azimuth"]] = 1.0
    # the hub: a point mass at its centre, its inertia about the shaft
    hub_c = apex + deck.hub_cm * es
    JH = rigid(hub_c) + np.outer(np.cross(es, hub_c - apex), rot)
    M += deck.hub_mass * JH.T @ JH
    w_hub = es @ thT + rot
    M += deck.hub_inertia * np.outer(w_hub, w_hub)
    if generator is not None:
        # the generator: its inertia about the high-speed shaft, gear_ratio times faster
        w_gen = es @ thT
        if generator == "free":
            w_gen = w_gen + deck.gear_ratio * np.eye(n)[ix["generator_azimuth"]]
        M += deck.generator_inertia * np.outer(w_gen, w_gen)
        j = ix["shaft_twist"]
        K[j, j] += deck.shaft_stiffness
        C[j, j] += deck.shaft_damping
    # the blades: J(s) = rigid(apex + r e_r) + rot (e_s x e_r) r + phi_flap e_f + phi_edge e_e
    up = _unit(np.array([0.0, 0.0, 1.0]) - es[2] * es)
    side = np.cross(es, up)  # blade 1 turns from up towards side
    r = deck.hub_radius + blade.x
    wm = blade.weights * blade.mass
    KB = blade.stiffness
    CB = blade.damping_matrix()
    for k in range(nb):
        psi = azimuth + 2.0 * math.pi * k / nb
        e_rad = math.cos(psi) * up + math.sin(psi) * side
        e_r = math.cos(deck.precone) * e_rad + math.sin(deck.precone) * es
        e_e = _unit(np.cross(es, e_r))
        e_f = np.cross(e_r, e_e)
        cols = [ix[f"blade{k + 1}_{m}"] for m in blade.names]
        A0 = rigid(apex)  # 3 x n, the apex
        B1 = np.cross(thT.T, e_r).T + np.outer(np.cross(es, e_r), rot)  # per unit radius
        E = np.broadcast_to((A0[:, :, None] + B1[:, :, None] * r[None, None, :]),
                            (3, n, r.size)).copy()
        for a, c in enumerate(cols):
            E[:, c, :] += (np.outer(e_f, blade.disp[a, 0]) + np.outer(e_e, blade.disp[a, 1]))
        M += np.einsum("ias,ibs,s->ab", E, E, wm)
        K[np.ix_(cols, cols)] += KB
        C[np.ix_(cols, cols)] += CB
    if gravity:
        m_blade = float(np.sum(wm))
        m_rna = deck.nacelle_mass + deck.hub_mass + nb * m_blade
        if m_rna > 0:
            # the tower's compression: the weight above each section
            seg = np.concatenate([[0.0], np.cumsum(tower.weights * tower.mass)])
            above = seg[-1] - seg[1:]
            N = -gravity * (m_rna + above)  # tension, negative: compression
            K[tw, tw] += tower.slope_matrix(N)
            h = (deck.nacelle_mass * rN[2] + (deck.hub_mass + nb * m_blade) * apex[2]) / m_rna
            K -= gravity * m_rna * h * (np.outer(thT[0], thT[0]) + np.outer(thT[1], thT[1]))
    return names, 0.5 * (M + M.T), C, 0.5 * (K + K.T)


class ElasticTurbine(Coupled):
    """The elastic turbine (tower, nacelle, shaft, hub, bending blades) as a coupled system
    that :func:`gearmodal.modal` solves; build one with :func:`elastic_turbine` or
    :func:`gearmodal.turbine.nrel5mw.flexible`.

    With ``gearbox=None`` the drivetrain is the deck's: ``shaft_twist`` on ``DTTorSpr`` and
    the generator's inertia. With a :class:`gearmodal.Model` of a drivetrain (its ``rotor``
    body, main shaft, gear stages, housing and ``generator``) the gearbox sits between rotor and
    generator: the system ``gearbox`` is that model, its rotor's rotation is the turbine's
    ``rotor_azimuth`` (a :class:`~gearmodal.coupling.LinearConstraint`), the model's rotor
    inertia is taken out of the turbine's (the constraint makes them one body: counted once)
    and ``generator="locked"`` holds the generator's rotation. The gearbox's frame is the
    nacelle: the tower top's motion reaches the gearbox through the shaft; the inertia of the
    gearbox's bodies in the moving nacelle is in the deck's nacelle mass, not in the gearbox
    model.

    Its ``deck`` is the :class:`~gearmodal.turbine.elastodyn.StructureDeck`, ``blade`` and
    ``tower`` their :class:`~gearmodal.turbine.bodies.BeamModes`, ``generator`` ``"locked"`` or
    ``"free"``, ``gearbox`` the gearbox model or None.
    """

    def __init__(self, deck: StructureDeck, blade: BeamModes, tower: BeamModes, *,
                 generator: str = "locked", gearbox: Model | None = None,
                 gravity: float = GRAVITY, name: str = "elastic turbine"):
        g = float(gravity)
        if not math.isfinite(g) or g < 0:
            raise ModelError("gravity", f"= {gravity!r}: must be a finite number >= 0 m/s^2")
        if generator not in GENERATOR:
            raise ModelError("generator", f"= {generator!r}: one of {', '.join(GENERATOR)}")
        self.deck, self.blade, self.tower = deck, blade, tower
        self.generator, self.gravity, self.gearbox = generator, g, gearbox
        if gearbox is None:
            names, M, C, K = structure_matrices(deck, blade, tower, generator=generator,
                                                gravity=g)
            super().__init__([LinearSystem("turbine", names, M, K, C)], [], name=name)
            return
        if not isinstance(gearbox, Model):
            raise ModelError("gearbox", f"expected a gm.Model of a drivetrain or None, got "
                             f"{type(gearbox).__name__}")
        rotor = _body_with_role(gearbox, "rotor")
        gen = _body_with_role(gearbox, "generator")
        names, M, C, K = structure_matrices(deck, blade, tower, generator=None, gravity=g)
        j = names.index("rotor_azimuth")
        M[j, j] -= float(gearbox.bodies[rotor].inertia)
        constraints = [LinearConstraint("hub", {"turbine.rotor_azimuth": 1.0,
                                                f"gearbox.{rotor}.theta": -1.0})]
        if generator == "locked":
            constraints.append(LinearConstraint("generator_lock",
                                                {f"gearbox.{gen}.theta": 1.0}))
        super().__init__([ModelSystem(gearbox, "gearbox"),
                          LinearSystem("turbine", names, M, K, C)], constraints, name=name)

    def check_speed(self, speed_rpm: float) -> None:
        """Refuse a speed: the turning rotor's terms are not in the model yet."""
        if float(speed_rpm) != 0.0:
            raise ModelError("speed_rpm", f"= {speed_rpm!r}: the elastic turbine solves parked "
                             "(0 rpm) so far; its turning rotor (centrifugal stiffening, "
                             "multi-blade coordinates) is not derived yet. Use the rigid "
                             "turbine at speed")


def _body_with_role(model: Model, role: str) -> str:
    found = [k for k, b in model.bodies.items() if b.role == role]
    if len(found) != 1:
        raise ModelError("gearbox", f"model {model.name!r} needs exactly one body with role "
                         f"{role!r} (a drivetrain: [rotor] and [generator]); found "
                         f"{len(found)}")
    if f"{found[0]}.theta" not in model.dof_names:
        raise ModelError("gearbox", f"{found[0]} of model {model.name!r} has no rotation "
                         "(theta)")
    return found[0]


def elastic_turbine(deck_path, *, gearbox: Model | None = None, generator: str = "locked",
                    flap: int = 2, edge: int = 1, fore_aft: int = 2, side_to_side: int = 2,
                    shapes: str = "computed", gravity: float = GRAVITY) -> ElasticTurbine:
    """The elastic turbine of the ElastoDyn deck at ``deck_path`` (its main file).

    Parameters
    ----------
    gearbox : None (the deck's two-mass drivetrain) or a :class:`gearmodal.Model` of a
        drivetrain between rotor and generator (:class:`ElasticTurbine`).
    generator : ``"locked"`` (the generator held: the definition report's Table 9-1) or
        ``"free"`` (it turns: a rigid rotation and the drivetrain's free torsion).
    flap, edge : the blade's flapwise and edgewise modes (ElastoDyn: 2 and 1).
    fore_aft, side_to_side : the tower's modes (ElastoDyn: 2 and 2).
    shapes : ``"computed"`` (pybmodes' finite-element modes, default) or ``"elastodyn"`` (the
        deck's polynomial shapes; :mod:`gearmodal.turbine.bodies`).
    gravity : m/s^2 (0: no gravity stiffness).
    """
    deck = read_structure(deck_path)
    return ElasticTurbine(deck, blade_modes(deck, flap, edge, shapes),
                          tower_modes(deck, fore_aft, side_to_side, shapes),
                          generator=generator, gearbox=gearbox, gravity=gravity)
