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
from . import validate as v
from .clearance import MAX_RAMPS
from .schema import REQUIRED, Field, Table

#: name of the non-rotating frame every model has
GROUND = "ground"
DOF_LEVELS = ("torsional", "planar", "full")
#: local coordinates of each level, as indices into (x, y, z, rx, ry, theta)
LEVEL_INDICES = {"torsional": (5,), "planar": (0, 1, 5), "full": (0, 1, 2, 3, 4, 5)}
LOCAL_NAMES = ("x", "y", "z", "rx", "ry", "theta")
DIRECTIONS = LOCAL_NAMES  # bearing directions, in the bearing axes
#: how a bearing's x/y clearances combine (:class:`Bearing`)
CLEARANCE_SHAPES = ("axes", "polygon", "round")
MAX_FACETS = 720


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

    def _label(self) -> str:
        return self.name or type(self).__name__

    def __post_init__(self):
        f = self._label()
        if self.name:
            v.name(f"{type(self).__name__}.name", self.name)
        self.mass = v.positive(f"{f}.mass", self.mass, "kg")
        self.inertia = v.positive(f"{f}.inertia", self.inertia, "kg m^2")
        if self.inertia_diametral is None:
            self.inertia_diametral = self.inertia / 2.0
        self.inertia_diametral = v.positive(f"{f}.inertia_diametral", self.inertia_diametral,
                                            "kg m^2")
        v.choice(f"{f}.dofs", self.dofs, DOF_LEVELS)
        if not isinstance(self.frame, str):
            raise ModelError(f"{f}.frame", f"expected a frame name, got {self.frame!r}")
        pos = tuple(self.position)
        if len(pos) == 2:
            pos = (*pos, 0.0)
        if len(pos) != 3:
            raise ModelError(f"{f}.position", f"= {self.position!r}: expected (x, y, z) in m")
        self.position = tuple(v.number(f"{f}.position", p, "m") for p in pos)
        self.orientation = v.number(f"{f}.orientation", self.orientation, "rad")
        self.speed_ratio = v.number(f"{f}.speed_ratio", self.speed_ratio)
        if self.rotation_scale is not None:
            self.rotation_scale = v.positive(f"{f}.rotation_scale", self.rotation_scale, "m")
        if self.pinned_to is not None and not isinstance(self.pinned_to, str):
            raise ModelError(f"{f}.pinned_to", f"expected a body name, got {self.pinned_to!r}")

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
            base = LOCAL_NAMES[i]
            if base == "theta" and self.rotation_scale is not None:
                base = "u"
            names.append(self.coordinate_names.get(LOCAL_NAMES[i], base))
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
        self.teeth = v.integer(f"{f}.teeth", self.teeth, minimum=3)
        self.module = v.positive(f"{f}.module", self.module, "m")
        if self.module > 1.0:
            raise ModelError(f"{f}.module", f"= {self.module!r} m: must be <= 1 m "
                                            "(modules are in metres: 10 mm = 0.010)")
        self.pressure_angle = v.angle(f"{f}.pressure_angle", self.pressure_angle,
                                      low=1e-6, high=math.pi / 4)
        self.helix_angle = v.angle(f"{f}.helix_angle", self.helix_angle,
                                   low=-math.pi / 4, high=math.pi / 4)
        if self.face_width is not None:
            self.face_width = v.positive(f"{f}.face_width", self.face_width, "m")
        if not isinstance(self.internal, bool):
            raise ModelError(f"{f}.internal", f"expected true/false, got {self.internal!r}")
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


@dataclass(eq=False)
class Mesh:
    """A gear mesh with two compression-only flanks and backlash (DESIGN 2.2).

    The front flank carries ``stiffness * d_f + damping * d_f'`` while ``d_f > 0``; the back
    flank ``stiffness * (d_b - backlash) + damping * d_b'`` while ``d_b > backlash``. ``q = 0`` is
    front flanks touching with zero force. ``side`` (+1 or -1) picks which line of action is the
    front flank: with ``side = +1`` a positive rotation of ``gear_a`` closes the front flank.
    For an internal pair ``gear_a`` is the ring.

    ``pressure_angle`` (transverse, rad), ``base_radii`` (m, m), ``helix_angle`` (base helix,
    rad) and ``internal`` override the values derived from the gears (used by
    :func:`gearmodal.lin_parker_stage`, whose bodies carry no tooth data).

    Mesh stiffness (a fidelity rung, :mod:`gearmodal.model.mesh_stiffness`): ``alternation =
    False`` (default) keeps ``stiffness`` constant. ``alternation = True`` alternates it at the
    mesh frequency between single and double tooth-pair contact, a rectangular wave (M1) whose
    mean is ``stiffness`` (ISO 6336's mean mesh stiffness c_gamma), with the double-pair
    stiffness ``stiffness_ratio`` times the single-pair one (default 1.75, which makes the mean
    ISO 6336-1's c_gamma = c' (0.75 eps + 0.25) for any contact ratio). ``contact_ratio`` is
    the transverse contact ratio eps in (1, 2): the fraction eps - 1 of each mesh period has two
    pairs in contact; by default it is computed from the gears (standard addendum of one
    module, no profile shift). ``phase`` is the fraction of a mesh period elapsed at input
    azimuth 0 (0 = the start of a double-pair zone). The wave runs on the nominal rotation of
    the gears, so it switches at known times: the exact method switches at them exactly.
    """

    name: str
    gear_a: str
    gear_b: str
    stiffness: float
    backlash: float = 0.0
    damping: float = 0.0
    side: int = 1
    pressure_angle: float | None = None
    base_radii: tuple | None = None
    helix_angle: float | None = None
    internal: bool | None = None
    alternation: bool = False
    contact_ratio: float | None = None
    stiffness_ratio: float = 1.75
    phase: float = 0.0

    def __post_init__(self):
        f = self.name
        v.name("Mesh.name", self.name)
        if not isinstance(self.alternation, bool):
            raise ModelError(f"{f}.alternation", f"expected true/false, got "
                             f"{self.alternation!r}")
        if self.contact_ratio is not None:
            self.contact_ratio = v.number(f"{f}.contact_ratio", self.contact_ratio)
            if not 1.0 < self.contact_ratio < 2.0:
                raise ModelError(f"{f}.contact_ratio", f"= {self.contact_ratio!r}: must lie in "
                                 "(1, 2) (single/double tooth-pair alternation)")
        self.stiffness_ratio = v.number(f"{f}.stiffness_ratio", self.stiffness_ratio)
        if not 1.0 <= self.stiffness_ratio <= 10.0:
            raise ModelError(f"{f}.stiffness_ratio", f"= {self.stiffness_ratio!r}: must lie in "
                             "[1, 10] (double-pair over single-pair stiffness)")
        self.phase = v.number(f"{f}.phase", self.phase)
        self.stiffness = v.nonnegative(f"{f}.stiffness", self.stiffness, "N/m")
        self.backlash = v.nonnegative(f"{f}.backlash", self.backlash, "m")
        self.damping = v.nonnegative(f"{f}.damping", self.damping, "N s/m")
        if self.side not in (1, -1):
            raise ModelError(f"{f}.side", f"= {self.side!r}: must be +1 or -1")
        if self.pressure_angle is not None:
            self.pressure_angle = v.angle(f"{f}.pressure_angle", self.pressure_angle,
                                          low=1e-6, high=math.pi / 2)


@dataclass(eq=False)
class Bearing:
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

    def __post_init__(self):
        f = self.name
        v.name("Bearing.name", self.name)
        for label, d, unit in (("stiffness", self.stiffness, "N/m or N m/rad"),
                               ("damping", self.damping, "N s/m or N m s/rad"),
                               ("clearance", self.clearance, "m or rad")):
            if not isinstance(d, dict):
                raise ModelError(f"{f}.{label}", f"expected a table keyed by direction "
                                                 f"({', '.join(DIRECTIONS)}), got {d!r}")
            for key in list(d):
                if key not in DIRECTIONS:
                    raise ModelError(f"{f}.{label}.{key}", "unknown direction; allowed: "
                                     + ", ".join(DIRECTIONS))
                d[key] = v.nonnegative(f"{f}.{label}.{key}", d[key], unit)
        for key in list(self.damping) + list(self.clearance):
            if key not in self.stiffness:
                raise ModelError(f"{f}.stiffness.{key}", "missing: damping or clearance is "
                                 f"given for direction {key!r} but no stiffness")
        at = tuple(self.at)
        if len(at) == 2:
            at = (*at, 0.0)
        if len(at) != 3:
            raise ModelError(f"{f}.at", f"= {self.at!r}: expected (x, y, z) in m")
        self.at = tuple(v.number(f"{f}.at", p, "m") for p in at)
        self.axes_angle = v.number(f"{f}.axes_angle", self.axes_angle, "rad")
        v.choice(f"{f}.clearance_shape", self.clearance_shape, CLEARANCE_SHAPES)
        self.facets = v.integer(f"{f}.facets", self.facets, minimum=3)
        if self.facets > MAX_FACETS:
            raise ModelError(f"{f}.facets", f"= {self.facets}: must be <= {MAX_FACETS}")
        self.ramps = v.integer(f"{f}.ramps", self.ramps, minimum=1)
        if self.ramps > MAX_RAMPS:
            raise ModelError(f"{f}.ramps", f"= {self.ramps}: must be <= {MAX_RAMPS}")
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


def Shaft(name: str, a: str, b: str, stiffness: float, damping: float = 0.0) -> Bearing:
    """A torsional shaft or coupling between bodies ``a`` and ``b``.

    ``stiffness`` in N m/rad and ``damping`` in N m s/rad act on the relative rotation
    ``theta_a - theta_b``.
    """
    k = v.nonnegative(f"{name}.stiffness", stiffness, "N m/rad")
    c = v.nonnegative(f"{name}.damping", damping, "N m s/rad")
    return Bearing(name, a, b, stiffness={"theta": k}, damping={"theta": c} if c else {})


# -- file schema of each component (gearmodal.model.schema; the "components" model files) ----
_NAME = Field("name", "name", default=REQUIRED, doc="unique name; dots separate the prefixes "
              "a drivetrain adds (`stage1.sun`)")
_BODY_FIELDS = (
    _NAME,
    Field("mass", "number", "kg", low=0.0, low_open=True, default=REQUIRED, doc="mass"),
    Field("inertia", "number", "kg m^2", low=0.0, low_open=True, default=REQUIRED,
          doc="polar moment of inertia about the body's own axis"),
    Field("inertia_diametral", "number", "kg m^2", low=0.0, low_open=True,
          doc="moment of inertia about a diameter (default inertia / 2; full level only)"),
    Field("dofs", "choice", choices=DOF_LEVELS, default="torsional",
          doc="DOF level: which local coordinates exist"),
    Field("frame", "name", default=GROUND, doc="frame the body's coordinates are in"),
    Field("position", "vector", "m", lengths=(2, 3), default=(0.0, 0.0, 0.0),
          doc="centre in its frame, [x, y, z]"),
    Field("orientation", "angle", "rad", default=0.0,
          doc="angle of the local axes about z in the frame"),
    Field("speed_ratio", "number", default=0.0,
          doc="nominal spin over the input speed (sign = sense)"),
    Field("rotation_scale", "number", "m", low=0.0, low_open=True,
          doc="rotation coordinate u = rotation_scale * theta (Lin & Parker's u = r theta)"),
    Field("coordinate_names", "names", default={},
          doc="renamed local coordinates, e.g. {x = \"zeta\"}"),
    Field("pinned_to", "name", doc="body whose pin carries this torsional body's centre"),
)
Frame.SCHEMA = Table("frames", (
    _NAME, Field("speed_ratio", "number", default=0.0,
                 doc="rotation about global z over the input speed (0: not rotating)")),
    "A reference frame (`[[frames]]`); the ground frame exists in every model.")
RigidBody.SCHEMA = Table("bodies (kind = \"rigid\")", _BODY_FIELDS,
                         "A rigid body that is not a gear (carrier, housing, rotor...).",
                         extra_keys=("kind",))
Body.SCHEMA = Table("bodies (kind = \"body\")", _BODY_FIELDS, "A plain rigid body.",
                    extra_keys=("kind",))
Gear.SCHEMA = Table("bodies (kind = \"gear\")", (
    _NAME,
    Field("teeth", "integer", low=3, default=REQUIRED, doc="number of teeth"),
    Field("module", "number", "m", low=0.0, low_open=True, high=1.0, default=REQUIRED,
          doc="normal module (10 mm = 0.010)"),
    Field("pressure_angle", "angle", "rad", low=1e-6, high=math.pi / 4, high_open=True,
          default=REQUIRED, doc="normal pressure angle"),
    Field("helix_angle", "angle", "rad", low=-math.pi / 4, high=math.pi / 4, high_open=True,
          default=0.0, doc="helix angle, signed (positive = right hand)"),
    Field("face_width", "number", "m", low=0.0, low_open=True, doc="face width"),
    Field("internal", "boolean", default=False, doc="internal teeth (a ring)"),
    *_BODY_FIELDS[1:]), "A gear wheel.", extra_keys=("kind",))
Mesh.SCHEMA = Table("meshes", (
    _NAME,
    Field("gear_a", "name", default=REQUIRED, doc="first gear (the ring of an internal pair)"),
    Field("gear_b", "name", default=REQUIRED, doc="second gear"),
    Field("stiffness", "number", "N/m", low=0.0, default=REQUIRED,
          doc="mesh stiffness along the line of action (the mean if alternating)"),
    Field("backlash", "number", "m", low=0.0, default=0.0, doc="backlash on the line of action"),
    Field("damping", "number", "N s/m", low=0.0, default=0.0, doc="mesh damping"),
    Field("side", "integer", low=-1, high=1, default=1,
          doc="+1 or -1: which line of action is the front flank"),
    Field("pressure_angle", "angle", "rad", low=1e-6, high=math.pi / 2, high_open=True,
          doc="transverse pressure angle (default: from the gears)"),
    Field("base_radii", "vector", "m", lengths=(2,), low=0.0,
          doc="[a, b] base radii (default: from the gears)"),
    Field("helix_angle", "angle", "rad", doc="base helix angle (default: from the gears)"),
    Field("internal", "boolean", doc="internal pair (default: gear_a is an internal gear)"),
    Field("alternation", "boolean", default=False,
          doc="stiffness alternates between single and double tooth-pair contact"),
    Field("contact_ratio", "number", low=1.0, high=2.0, low_open=True, high_open=True,
          doc="transverse contact ratio (default: from the gears)"),
    Field("stiffness_ratio", "number", low=1.0, high=10.0, default=1.75,
          doc="double-pair over single-pair stiffness"),
    Field("phase", "number", default=0.0,
          doc="fraction of a mesh period elapsed at input azimuth 0")),
    "A gear mesh with two compression-only flanks and backlash (`[[meshes]]`).")
Bearing.SCHEMA = Table("bearings", (
    _NAME,
    Field("a", "name", default=REQUIRED, doc="body a"),
    Field("b", "name", doc="body b (default: the ground)"),
    Field("stiffness", "directions", "N/m or N m/rad", low=0.0, default={},
          doc="per direction x, y, z, rx, ry, theta"),
    Field("damping", "directions", "N s/m or N m s/rad", low=0.0, default={},
          doc="per direction"),
    Field("clearance", "directions", "m or rad", low=0.0, default={},
          doc="dead band on each side, per direction"),
    Field("at", "vector", "m", lengths=(2, 3), default=(0.0, 0.0, 0.0),
          doc="point where it acts, from a's centre in a's frame"),
    Field("axes_angle", "angle", "rad", default=0.0, doc="bearing axes about z"),
    Field("axes_frame", "name", doc="frame of the bearing axes (default: b's, or the ground)"),
    Field("clearance_shape", "choice", choices=CLEARANCE_SHAPES, default="axes",
          doc="how the x/y clearances combine"),
    Field("facets", "integer", low=3, high=MAX_FACETS, default=16,
          doc="facets of a polygon clearance"),
    Field("ramps", "integer", low=1, high=MAX_RAMPS, default=4,
          doc="contacts per facet of a polygon clearance")),
    "A spring-damper per direction between bodies a and b, with optional clearance "
    "(`[[bearings]]`; shafts are bearings on theta).")
