"""The bearing element: a spring-damper per direction between two bodies (or a body and the
ground), with dead-band, polygonal or round clearance (DESIGN 2.3); shafts are bearings on the
relative rotation."""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from ..errors import ModelError
from ..frames import rz
from ..kernels.joint import bearing_gap_jacobians, joint_curvatures, joint_gradients
from . import validate as v
from .clearance import MAX_RAMPS, polygon_ramps
from .components import DIRECTIONS, GROUND, check_structure
from .element import Element
from .schema import NAME, REQUIRED, STRUCTURE, Field, Table

__all__ = ["CLEARANCE_SHAPES", "MAX_FACETS", "Bearing", "Shaft"]

#: how a bearing's x/y clearances combine (:class:`Bearing`)
CLEARANCE_SHAPES = ("axes", "polygon", "round")
MAX_FACETS = 720
#: the plausibility limits (validate.LIMITS) of a bearing's tables


def _acts(w: np.ndarray) -> bool:
    """Whether a joint row acts on any coordinate: entries are lever arms and direction
    cosines (m or 1), so anything below 1e-12 is the rounding of a cancelled term."""
    return bool(np.abs(w).max(initial=0.0) > 1e-12)


@dataclass(eq=False)
class Bearing(Element):
    """A spring-damper between body ``a`` and body ``b`` (or ground), per direction (DESIGN 2.3).

    ``stiffness``, ``damping`` and ``clearance`` are dicts keyed by direction ``x, y, z`` (N/m,
    N s/m, m) and ``rx, ry, theta`` (N m/rad, N m s/rad, rad), in the bearing axes: the axes of
    ``axes_frame`` (default: b's frame, or the ground) turned by ``axes_angle`` about z.
    ``clearance`` is the free play on each side of the centred position (a dead band): a
    direction with clearance ``c`` pushes back with ``k (d - c)`` when ``d > c`` and with
    ``k (d + c)`` when ``d < -c``, where ``d`` is the deflection of a relative to b.
    ``at`` is the point where the bearing acts, as an offset from a's centre in a's frame, m.

    ``clearance_shape`` sets how the ``x``/``y`` clearances combine (DESIGN 2.3):

    * ``"axes"`` (default): an independent dead band per direction (a square clearance whose
      corners engage both directions);
    * ``"polygon"``: the round clearance ``clearance["x"]`` as ``facets`` directions at
      ``2 pi i / facets`` in the bearing axes, each with ``ramps`` compression-only contacts
      fitted so that their sum matches the round law (:mod:`gearmodal.model.clearance`):
      piecewise linear (every integrator), continuous and conservative; it converges to
      round as ``facets`` and ``ramps`` grow. Open in the nominal contact state.
    * ``"round"``: the exactly round clearance, ``k (|d| - c)`` along ``d / |d|``: nonlinear,
      so only ``method="scipy"`` integrates it (the reference for the polygon).

    ``"polygon"`` and ``"round"`` need equal ``x`` and ``y`` stiffness, damping and clearance.
    """

    name: str
    a: str
    b: str | None = None
    stiffness: dict = field(default_factory=dict)
    damping: dict = field(default_factory=dict)
    clearance: dict = field(default_factory=dict)
    at: tuple = (0.0, 0.0, 0.0)
    axes_angle: float = 0.0
    axes_frame: str | None = None
    clearance_shape: str = "axes"
    facets: int = 16
    ramps: int = 4
    stage: str = ""
    role: str = ""
    planet: str | None = None

    TABLE: ClassVar[str] = "bearings"
    SCHEMA: ClassVar[Table]

    def __post_init__(self):
        f = self.name
        v.name("Bearing.name", self.name)
        check_structure(self)
        # types and ranges: the schema's (one statement for the file and the API)
        Bearing.SCHEMA.check(self, ("a", "b", "stiffness", "damping", "clearance", "at",
                                    "axes_angle", "axes_frame", "clearance_shape", "facets",
                                    "ramps"))
        for key in list(self.damping) + list(self.clearance):
            if key not in self.stiffness:
                raise ModelError(f"{f}.stiffness.{key}", "missing: damping or clearance is "
                                 f"given for direction {key!r} but no stiffness")
        if len(self.at) == 2:
            self.at = (*self.at, 0.0)
        if self.clearance_shape != "axes":
            for label, d in (("clearance", self.clearance), ("stiffness", self.stiffness),
                             ("damping", self.damping)):
                if d.get("x", 0.0) != d.get("y", 0.0):
                    raise ModelError(f"{f}.{label}", f"x = {d.get('x', 0.0)!r} and y = "
                                     f"{d.get('y', 0.0)!r} differ: a {self.clearance_shape} "
                                     "clearance needs equal x and y values")
            if not self.clearance.get("x", 0.0) > 0.0:
                raise ModelError(f"{f}.clearance.x", "missing: a "
                                 f"{self.clearance_shape} clearance needs a radial clearance "
                                 "> 0 m in x and y")

    # -- in a model ---------------------------------------------------------------------
    def references(self) -> list[tuple[str, str, str]]:
        out = [("a", self.a, "bodies")]
        if self.b is not None:
            out.append(("b", self.b, "bodies"))
        if self.axes_frame is not None:
            out.append(("axes_frame", self.axes_frame, "frames"))
        return out

    def renamed(self, p, prefix: str, ground: str | None = None) -> Bearing:
        new = copy.copy(self)
        new.name, new.a = p(self.name), p(self.a)
        new.stage = p(self.stage) if self.stage else prefix
        new.planet = p(self.planet) if self.planet else self.planet
        new.b = p(self.b) if self.b is not None else ground
        if self.axes_frame is not None and self.axes_frame != GROUND:
            new.axes_frame = p(self.axes_frame)
        new.stiffness, new.damping = dict(self.stiffness), dict(self.damping)
        new.clearance = dict(self.clearance)
        return new

    # -- its contribution to the assembly (DESIGN 2.3) --------------------------------------
    def _curvatures(self, ctx):
        """``curvature(i)``: the ``(parts, H)`` of direction ``i``'s joint deflection at the
        assembly's azimuth (joint.py's curvatures; for :meth:`Contributions.curvature`).

        The deflection is measured in axes that turn with the body the centrifugal load
        turns with (joint.py): a's frame's own body where a's frame turns and has one (the
        carrier of a planetary stage's frame, which the planets' load follows), else b, else
        the ground's fixed axes."""
        model = ctx.model
        a = model.bodies[self.a]
        b = model.bodies[self.b] if self.b is not None else None
        az = ctx.azimuth
        pa = rz(model.frames[a.frame].speed_ratio * az) @ np.asarray(self.at, dtype=float)
        cb = ctx.centre(b, az) if b is not None else np.zeros(3)
        pb = ctx.centre(a, az) + pa - cb
        axes_frame = self.axes_frame or (b.frame if b is not None else GROUND)
        gamma = model.frames[axes_frame].speed_ratio * az + self.axes_angle
        H = joint_curvatures(pa[0], pa[1], pa[2], pb[0], pb[1], pb[2], gamma).reshape(6, 15, 15)
        x = model.bodies.get(a.frame) if model.frames[a.frame].speed_ratio != 0.0 else None
        x = x if x is not None else b
        keep = list(range(6)) + (list(range(6, 12)) if b is not None else []) \
            + (list(range(12, 15)) if x is not None else [])
        parts = [(a, slice(0, 6))] + ([(b, slice(0, 6))] if b is not None else []) \
            + ([(x, slice(3, 6))] if x is not None else [])
        if len(keep) != 15:  # the Hessians on the parts present (one index grid for all)
            H = H[(slice(None), *np.ix_(keep, keep))]
        return lambda i: (parts, H[i])

    def _rows(self, ctx, azimuth: float):
        """``(spring_row(i), gap_row(j))`` at ``azimuth``: the joint deflection ``g_i`` of
        direction ``i`` and the dead-band side ``j`` (2 i: +, 2 i + 1: -) as rows of the state
        (joint.py's gradients and gap Jacobians)."""
        model = ctx.model
        a = model.bodies[self.a]
        b = model.bodies[self.b] if self.b is not None else None
        fa = model.frames[a.frame]
        pa = rz(fa.speed_ratio * azimuth) @ np.asarray(self.at, dtype=float)
        cb = ctx.centre(b, azimuth) if b is not None else np.zeros(3)
        pb = ctx.centre(a, azimuth) + pa - cb
        axes_frame = self.axes_frame or (b.frame if b is not None else GROUND)
        gamma = model.frames[axes_frame].speed_ratio * azimuth + self.axes_angle
        Ga, Gb = joint_gradients(pa[0], pa[1], pa[2], pb[0], pb[1], pb[2], gamma)
        Ja, Jb = bearing_gap_jacobians(pa[0], pa[1], pa[2], pb[0], pb[1], pb[2], gamma)

        def row(Ra, Rb, j):
            parts = [(a, Ra[j])] + ([(b, Rb[j])] if b is not None else [])
            return ctx.row(parts, azimuth)
        return (lambda j: row(Ga, Gb, j)), (lambda j: row(Ja, Jb, j))

    def contribute(self, ctx) -> None:
        """Add the bearing to ``ctx`` (:class:`gearmodal.assembly.Contributions`): a linear
        spring per direction without clearance, two dead-band contacts per direction with
        one, a polygon clearance's facet ramps (R2) or a round clearance's x/y rows (R1).

        A direction that acts on no coordinate present at these DOF levels is left out;
        whether it acts is decided at this azimuth and at a generic one, so that every azimuth
        of a turning frame gives the same rows (a torsional carrier's pin moves along x except
        where sin = 0)."""
        spring_row, gap_row = self._rows(ctx, ctx.azimuth)
        spring_row2, gap_row2 = self._rows(ctx, ctx.probe)
        curvature = self._curvatures(ctx)
        radial, acts = (), False
        if self.clearance_shape != "axes":  # x and y make one radial clearance
            radial = ("x", "y")
            gx, gy = gap_row(0), gap_row(2)  # the x and y deflection rows (joint.py)
            acts = _acts(gx) or _acts(gy) or _acts(gap_row2(0)) or _acts(gap_row2(2))
        if self.clearance_shape == "polygon" and acts:
            # facet i: the deflection along its normal (cos a_i, sin a_i) in the bearing
            # axes, with the ramps of clearance.polygon_ramps (R2); damping shared in
            # proportion to stiffness; its force resolved on the bearing's x and y
            kr, cr = self.stiffness["x"], self.damping.get("x", 0.0)
            offsets, kms = polygon_ramps(self.clearance["x"], kr, self.facets, self.ramps)
            x, y = f"{self.name}.x", f"{self.name}.y"
            for i in range(self.facets):
                a_i = 2.0 * math.pi * i / self.facets
                w = math.cos(a_i) * gx + math.sin(a_i) * gy
                cols = ((x, math.cos(a_i)), (y, math.sin(a_i)))
                for m_, (o, km) in enumerate(zip(offsets, kms, strict=True)):
                    ctx.contact(w, o, km, cr * km / kr if kr else 0.0, False, self,
                                f"facet{i}_{m_}", "bearing", columns=cols, angle=a_i)
        elif self.clearance_shape == "round" and acts:
            # (R1) of clearance.py on the x and y deflection rows
            for lab, w in (("x", gx), ("y", gy)):
                ctx.round_row(w, self, lab, self.clearance["x"], self.stiffness["x"],
                              self.damping.get("x", 0.0))
        for key, k in self.stiffness.items():
            if key in radial:
                continue
            i = DIRECTIONS.index(key)
            c = self.damping.get(key, 0.0)
            gap = self.clearance.get(key, 0.0)
            if gap == 0.0:
                # no dead band: a linear spring on the joint deflection g_i
                w = spring_row(i)
                ctx.spring(w, k, c, self, key, acts=_acts(w) or _acts(spring_row2(i)),
                           curvature=curvature(i))
                continue
            parts, H = curvature(i)
            for j, side, sign in ((2 * i, "+", 1.0), (2 * i + 1, "-", -1.0)):
                w = gap_row(j)
                if _acts(w) or _acts(gap_row2(j)):
                    ctx.contact(w, gap, k, c, side == "+", self, f"{key}{side}", "bearing",
                                columns=[(f"{self.name}.{key}", sign)],
                                curvature=(parts, sign * H))



def Shaft(name: str, a: str, b: str, stiffness: float, damping: float = 0.0) -> Bearing:
    """A torsional shaft or coupling between bodies ``a`` and ``b``.

    ``stiffness`` in N m/rad and ``damping`` in N m s/rad act on the relative rotation
    ``theta_a - theta_b``.
    """
    k = v.plausible(f"{name}.stiffness", v.nonnegative(f"{name}.stiffness", stiffness,
                                                         "N m/rad"), "stiffness")
    c = v.plausible(f"{name}.damping", v.nonnegative(f"{name}.damping", damping, "N m s/rad"),
                    "damping")
    return Bearing(name, a, b, stiffness={"theta": k}, damping={"theta": c} if c else {})



Bearing.SCHEMA = Table("bearings", (
    NAME,
    Field("a", "name", default=REQUIRED, doc="body a"),
    Field("b", "name", doc="body b (default: the ground)"),
    Field("stiffness", "directions", "N/m or N m/rad", low=0.0, default={},
          doc="per direction x, y, z, rx, ry, theta", limits="stiffness"),
    Field("damping", "directions", "N s/m or N m s/rad", low=0.0, default={},
          doc="per direction", limits="damping"),
    Field("clearance", "directions", "m or rad", low=0.0, default={},
          doc="dead band on each side, per direction", limits="gap"),
    Field("at", "vector", "m", lengths=(2, 3), default=(0.0, 0.0, 0.0),
          doc="point where it acts, from a's centre in a's frame", limits="length"),
    Field("axes_angle", "angle", "rad", default=0.0, doc="bearing axes about z"),
    Field("axes_frame", "name", doc="frame of the bearing axes (default: b's, or the ground)"),
    Field("clearance_shape", "choice", choices=CLEARANCE_SHAPES, default="axes",
          doc="how the x/y clearances combine"),
    Field("facets", "integer", low=3, high=MAX_FACETS, default=16,
          doc="facets of a polygon clearance"),
    Field("ramps", "integer", low=1, high=MAX_RAMPS, default=4,
          doc="contacts per facet of a polygon clearance"),
    *STRUCTURE, Field("planet", "name", doc="the planet this bearing carries")),
    "A spring-damper per direction between bodies a and b, with optional clearance "
    "(`[[bearings]]`; shafts are bearings on theta).")
