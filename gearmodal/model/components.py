"""Declarative model components: frames, bodies (gears and rigid bodies), meshes, bearings, shafts.

Units are SI throughout: m, kg, kg m^2, N/m, N m/rad, N s/m, rad. Angles are in radians.

Kinematics (DESIGN 2.1, paper section 4): every body sits in a reference *frame* that rotates
about the global z axis at ``speed_ratio`` times the model's input speed. A body's small
displacements are expressed in its local axes ``A1 = Rz(orientation)`` inside that frame; its
DOF level picks which of the six local coordinates ``(x, y, z, rx, ry, theta)`` exist:

=========== ====================================
level        local DOF
=========== ====================================
torsional    theta
planar       x, y, theta
full         x, y, z, rx, ry, theta
=========== ====================================
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from ..errors import ModelError
from ..frames import body_selector
from ..kernels.wheel import (
    wheel_centrifugal_force,
    wheel_centripetal,
    wheel_gyroscopic,
    wheel_mass,
)
from . import validate as v
from .schema import NAME, REQUIRED, STRUCTURE, Field, Table

#: name of the non-rotating frame every model has
GROUND = "ground"
DOF_LEVELS = ("torsional", "planar", "full")
#: local coordinates of each level, as indices into (x, y, z, rx, ry, theta)
LEVEL_INDICES = {"torsional": (5,), "planar": (0, 1, 5), "full": (0, 1, 2, 3, 4, 5)}
LOCALNAMES = ("x", "y", "z", "rx", "ry", "theta")
DIRECTIONS = LOCALNAMES  # bearing directions, in the bearing axes


def check_structure(component) -> None:
    """Check the structure fields (``stage``, ``role``, and ``planet`` where present)."""
    f = getattr(component, "name", "") or type(component).__name__
    for key in ("stage", "role"):
        if not isinstance(getattr(component, key), str):
            raise ModelError(f"{f}.{key}", f"expected a string, got "
                                           f"{getattr(component, key)!r}")
    planet = getattr(component, "planet", None)
    if planet is not None and not isinstance(planet, str):
        raise ModelError(f"{f}.planet", f"expected a body name, got {planet!r}")


#: the load that is every body's weight (:class:`gearmodal.Model`); its value is g, m/s^2
GRAVITY = "gravity"
#: the standard acceleration of gravity, m/s^2
G_STANDARD = 9.80665

@dataclass(eq=False)
class Frame:
    """A reference frame rotating steadily about global z at ``speed_ratio`` x input speed.

    ``speed_ratio = 0`` is a non-rotating frame (housing, bedplate); the carrier frame of a
    planetary stage has ``speed_ratio = 1`` when the carrier is the input.
    """

    name: str
    speed_ratio: float = 0.0

    def __post_init__(self):
        v.name("Frame.name", self.name)
        self.speed_ratio = v.number(f"{self.name}.speed_ratio", self.speed_ratio)


@dataclass(eq=False, kw_only=True)
class Body:
    """A rigid body with up to six small local DOF (DESIGN 2.1).

    Parameters
    ----------
    mass : kg, > 0.
    inertia : polar moment of inertia about the body's own axis, kg m^2, > 0.
    inertia_diametral : moment of inertia about a diameter, kg m^2 (default ``inertia / 2``,
        a thin disk); used only at the ``full`` level.
    dofs : ``"torsional"``, ``"planar"`` or ``"full"``.
    frame : name of the frame the body's coordinates are expressed in.
    position : (x, y, z) of the body's centre in its frame, m.
    orientation : angle of the body's local axes about z in its frame, rad (``A1``).
    speed_ratio : nominal absolute spin rate over the model's input speed (sign = sense).
    rotation_scale : if given, the rotational coordinate is ``u = rotation_scale * theta`` (m),
        as in Lin & Parker's ``u = r theta``; otherwise it is ``theta`` (rad).
    coordinate_names : optional renaming of local coordinates, e.g. ``{"x": "zeta"}``.
    pinned_to : name of a body (in the same frame) whose pin carries this body's centre when
        this body's level has no translations (``torsional``), as a planet rides on its
        carrier: the centre then moves with the pin's point of that body (P1 in
        :func:`gearmodal.assembly.assemble`) instead of staying fixed in the frame. Ignored at
        ``planar``/``full``.
    stage, role : where the body belongs: its stage (``"stage1"``; ``""`` outside stages) and
        its role there (``"carrier"``, ``"sun"``, ``"planet"``, ``"ring"``, ``"gear"``,
        ``"pinion"``...). The builders set them; analyses read the structure from them.
    position_error : (x, y) offset of the body's true centre from its nominal ``position``,
        m, in its local axes (for a planet, whose ``orientation`` is its angle on the carrier:
        radial and tangential, the carrier pinhole position error). The body is supported
        about its true centre; the gaps of its meshes move by the error projected on their
        lines of action (:class:`gearmodal.Mesh`).
    thickness_error : tooth thickness error of a body that meshes, m, along the line of
        action (positive: thicker teeth). Each flank stands out by half of it: both flanks'
        gaps of each of its meshes close by half of it, the backlash by all of it.
    runout : ``(e, phase)``: the eccentricity of the body's teeth, m, turning with its nominal
        spin (``speed_ratio``), at angle ``phase`` (rad) from its local x axis at input
        azimuth 0: the gaps of its meshes move by it projected on their lines of action, at
        the body's rotation order against the mesh (:class:`gearmodal.Mesh`).
    """

    name: str = ""
    mass: float
    inertia: float
    inertia_diametral: float | None = None
    dofs: str = "torsional"
    frame: str = "ground"
    position: tuple = (0.0, 0.0, 0.0)
    orientation: float = 0.0
    speed_ratio: float = 0.0
    rotation_scale: float | None = None
    coordinate_names: dict = field(default_factory=dict)
    pinned_to: str | None = None
    stage: str = ""
    role: str = ""
    position_error: tuple = (0.0, 0.0)
    thickness_error: float = 0.0
    runout: tuple = (0.0, 0.0)

    def _label(self) -> str:
        return self.name or type(self).__name__

    def __post_init__(self):
        f = self._label()
        if self.name:
            v.name(f"{type(self).__name__}.name", self.name)
        schema = Body.SCHEMA  # types and ranges of every body's fields: their one statement
        schema.check(self, ("mass", "inertia"), f)
        if self.inertia_diametral is None:
            self.inertia_diametral = self.inertia / 2.0
        schema.check(self, ("inertia_diametral", "dofs", "position_error", "thickness_error",
                            "frame", "position", "orientation", "speed_ratio",
                            "rotation_scale", "pinned_to"), f)
        ro = tuple(self.runout) if isinstance(self.runout, (list, tuple)) else None
        if ro is None or len(ro) != 2:  # (eccentricity >= 0, phase): a range per entry
            raise ModelError(f"{f}.runout", f"= {self.runout!r}: expected [eccentricity_m, "
                             "phase_rad]")
        self.runout = (v.plausible(f"{f}.runout", v.nonnegative(f"{f}.runout", ro[0], "m"),
                                   "gap"), v.number(f"{f}.runout", ro[1], "rad"))
        if len(self.position) == 2:
            self.position = (*self.position, 0.0)
        check_structure(self)

    # -- its contribution to the assembly (DESIGN 2.1) --------------------------------------
    def contribute(self, ctx) -> None:
        """Add the body's inertia to ``ctx`` (:class:`gearmodal.assembly.Contributions`): the
        local blocks of the floating-frame kernels (mass, gyroscopic, centripetal, centrifugal
        force) on its coordinates."""
        sl = ctx.slices[self.name]
        S = body_selector(self)
        args = (self.mass, self.inertia_diametral, self.inertia, *self.position,
                self.orientation)
        of = ctx.model.frames[self.frame].speed_ratio
        ctx.M[sl, sl] = S.T @ wheel_mass(*args)[6:, 6:] @ S
        ctx.G[sl, sl] = S.T @ wheel_gyroscopic(*args, of, self.speed_ratio)[6:, 6:] @ S
        ctx.K_cent[sl, sl] = S.T @ wheel_centripetal(*args, of, self.speed_ratio)[6:, 6:] @ S
        ctx.f_cent[sl] = S.T @ wheel_centrifugal_force(*args, of, self.speed_ratio)[6:]

    # -- coordinates ---------------------------------------------------------------------
    @property
    def local_indices(self) -> tuple:
        """Indices into (x, y, z, rx, ry, theta) of this body's coordinates."""
        return LEVEL_INDICES[self.dofs]

    @property
    def coordinates(self) -> list[str]:
        """Local coordinate names at this body's DOF level (after renaming)."""
        names = []
        for i in self.local_indices:
            base = LOCALNAMES[i]
            if base == "theta" and self.rotation_scale is not None:
                base = "u"
            names.append(self.coordinate_names.get(LOCALNAMES[i], base))
        return names


@dataclass(eq=False, kw_only=True)
class RigidBody(Body):
    """A rigid body that is not a gear: carrier, housing, rotor, generator rotor, shaft hub."""


@dataclass(eq=False)
class Gear(Body):
    """A gear wheel.

    Parameters
    ----------
    teeth : number of teeth (>= 3; for an internal gear the ring's tooth count).
    module : normal module, m (> 0), e.g. 0.010 for 10 mm.
    pressure_angle : normal pressure angle, rad, in (0, pi/4).
    helix_angle : helix angle, rad, in (-pi/4, pi/4); signed (positive = right hand).
    face_width : m, needed only where the model uses it (full level, tilt terms).
    internal : True for a ring gear (internal teeth).
    mass, inertia, ... : as :class:`Body` (keyword-only).

    Notes
    -----
    The base radius is ``teeth * module * cos(pressure_angle) / 2`` for spur gears and
    ``teeth * m_t * cos(alpha_t) / 2`` with transverse module ``m_t = module / cos(helix)`` and
    ``tan(alpha_t) = tan(pressure_angle) / cos(helix)`` for helical gears.
    """

    teeth: int = 0
    module: float = 0.0
    pressure_angle: float = 0.0
    helix_angle: float = 0.0
    face_width: float | None = None
    internal: bool = False

    def __post_init__(self):
        f = self._label()
        Gear.SCHEMA.check(self, ("teeth", "module", "pressure_angle", "helix_angle",
                                 "face_width", "internal"), f)
        super().__post_init__()

    @property
    def transverse_pressure_angle(self) -> float:
        """Transverse pressure angle alpha_t, rad: tan(alpha_t) = tan(alpha_n) / cos(beta)."""
        return math.atan(math.tan(self.pressure_angle) / math.cos(self.helix_angle))

    @property
    def pitch_radius(self) -> float:
        """Reference (pitch) radius, m: teeth * m_t / 2."""
        return self.teeth * self.module / math.cos(self.helix_angle) / 2.0

    @property
    def base_radius(self) -> float:
        """Base-circle radius, m: pitch radius * cos(alpha_t)."""
        return self.pitch_radius * math.cos(self.transverse_pressure_angle)

    @property
    def base_helix_angle(self) -> float:
        """Base helix angle beta_b, rad: tan(beta_b) = tan(beta) cos(alpha_t)."""
        return math.atan(math.tan(self.helix_angle) * math.cos(self.transverse_pressure_angle))


# -- file schema of each component (gearmodal.model.schema; the "components" model files) ----
_BODY_FIELDS = (
    NAME,
    Field("mass", "number", "kg", low=0.0, low_open=True, default=REQUIRED, doc="mass",
          limits="mass"),
    Field("inertia", "number", "kg m^2", low=0.0, low_open=True, default=REQUIRED,
          doc="polar moment of inertia about the body's own axis", limits="inertia"),
    Field("inertia_diametral", "number", "kg m^2", low=0.0, low_open=True,
          doc="moment of inertia about a diameter (default inertia / 2; full level only)",
          limits="inertia"),
    Field("dofs", "choice", choices=DOF_LEVELS, default="torsional",
          doc="DOF level: which local coordinates exist"),
    Field("frame", "name", default=GROUND, doc="frame the body's coordinates are in"),
    Field("position", "vector", "m", lengths=(2, 3), default=(0.0, 0.0, 0.0),
          doc="centre in its frame, [x, y, z]", limits="length"),
    Field("orientation", "angle", "rad", default=0.0,
          doc="angle of the local axes about z in the frame"),
    Field("speed_ratio", "number", default=0.0,
          doc="nominal spin over the input speed (sign = sense)"),
    Field("rotation_scale", "number", "m", low=0.0, low_open=True,
          doc="rotation coordinate u = rotation_scale * theta (Lin & Parker's u = r theta)"),
    Field("coordinate_names", "names", default={},
          doc="renamed local coordinates, e.g. {x = \"zeta\"}"),
    Field("pinned_to", "name", doc="body whose pin carries this torsional body's centre"),
    *STRUCTURE,
    Field("position_error", "vector", "m", lengths=(2,), default=(0.0, 0.0),
          doc="true centre minus nominal, local axes (a planet: [radial, tangential] "
              "pinhole error)", limits="gap"),
    Field("thickness_error", "number", "m", default=0.0,
          doc="tooth thickness error on the line of action (positive: thicker)",
          limits="gap"),
    Field("runout", "vector", lengths=(2,), default=(0.0, 0.0),
          doc="[eccentricity_m, phase_rad] of the teeth, turning with the body's spin"),
)
Frame.SCHEMA = Table("frames", (
    NAME, Field("speed_ratio", "number", default=0.0,
                 doc="rotation about global z over the input speed (0: not rotating)")),
    "A reference frame (`[[frames]]`); the ground frame exists in every model.")
RigidBody.SCHEMA = Table("bodies (kind = \"rigid\")", _BODY_FIELDS,
                         "A rigid body that is not a gear (carrier, housing, rotor...).",
                         extra_keys=("kind",))
Body.SCHEMA = Table("bodies (kind = \"body\")", _BODY_FIELDS, "A plain rigid body.",
                    extra_keys=("kind",))
Gear.SCHEMA = Table("bodies (kind = \"gear\")", (
    NAME,
    Field("teeth", "integer", low=3, default=REQUIRED, doc="number of teeth", limits="teeth"),
    Field("module", "number", "m", low=0.0, low_open=True, high=1.0, default=REQUIRED,
          doc="normal module (10 mm = 0.010)", limits="module",
          note="modules are in metres: 10 mm = 0.010"),
    Field("pressure_angle", "angle", "rad", low=1e-6, high=math.pi / 4, high_open=True,
          default=REQUIRED, doc="normal pressure angle", deg_floor=10.0),
    Field("helix_angle", "angle", "rad", low=-math.pi / 4, high=math.pi / 4, high_open=True,
          default=0.0, doc="helix angle, signed (positive = right hand)", deg_floor=1.0),
    Field("face_width", "number", "m", low=0.0, low_open=True, doc="face width"),
    Field("internal", "boolean", default=False, doc="internal teeth (a ring)"),
    *_BODY_FIELDS[1:]), "A gear wheel.", extra_keys=("kind",))
