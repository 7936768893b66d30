"""The :class:`Model`: a named collection of frames, bodies, meshes and bearings.

Every DOF and load has a stable dotted name: ``<body>.<coordinate>`` (``"sun.theta"``,
``"planet1.zeta"``) and ``<body>.<load>`` (``"pinion.torque"``, ``"carrier.force_x"``). Models
built by stage builders are merged into drivetrains under a prefix (``"stage1.sun.theta"``).
"""

from __future__ import annotations

import copy
import math

from ..errors import ModelError
from . import validate as v
from .bearing import Bearing
from .components import DOF_LEVELS, GRAVITY, GROUND, LEVEL_INDICES, Body, Frame
from .element import PROTOCOL, Element
from .mesh import Mesh

#: the element kinds a model holds, in assembly order: each class adds its own rows
#: (``contribute``) and names the model's table of them and its file array (``TABLE``)
ELEMENT_KINDS: list[type] = [Mesh, Bearing]


def register_element(cls: type) -> type:
    """Make ``cls`` an element kind (usable as a class decorator): models then hold its
    instances in ``model.<cls.TABLE>``, assemble them through ``contribute(ctx)`` (after the
    kinds registered before) and ``gm.dumps`` / ``gm.load`` write and read them as the array
    ``[[<cls.TABLE>]]`` with the fields of ``cls.SCHEMA``.

    The class needs ``name``, ``TABLE`` (a new name), ``SCHEMA``
    (:class:`~gearmodal.model.schema.Table`) and ``contribute(ctx)``
    (:class:`gearmodal.assembly.Contributions`); its fields of schema type ``name`` (other than
    ``name``) are body names, prefixed with the rest when a drivetrain merges a stage. What the
    model asks of it (``references``, ``renamed``, ``check_in``:
    :class:`gearmodal.model.element.Element`) comes from its ``SCHEMA`` unless it defines its
    own (or derives from ``Element`` and overrides them).
    """
    for attr in ("TABLE", "SCHEMA", "contribute"):
        if not hasattr(cls, attr):
            raise TypeError(f"an element kind needs {attr}; {cls.__name__} has none")
    for attr in PROTOCOL:  # what the model asks of every kind, from its SCHEMA by default
        if not hasattr(cls, attr):
            setattr(cls, attr, getattr(Element, attr))
    taken = {c.TABLE for c in ELEMENT_KINDS} | {"frames", "bodies", "groups", "model"}
    if cls not in ELEMENT_KINDS:
        if cls.TABLE in taken:
            raise TypeError(f"{cls.__name__}.TABLE = {cls.TABLE!r} is already used")
        ELEMENT_KINDS.append(cls)
    return cls

#: load name suffix -> index into the global (fx, fy, fz, mx, my, mz) of the body's centre
LOAD_KINDS = {"force_x": 0, "force_y": 1, "force_z": 2, "moment_x": 3, "moment_y": 4,
              "torque": 5}


class Model:
    """A gearbox or drivetrain model.

    Parameters
    ----------
    name : model name, used in reports.
    input : name of the input body: the model's speed is this body's speed (the carrier of a
        planetary stage, the rotor of a drivetrain); other bodies turn at ``speed_ratio`` times
        it.
    rated_speed_rpm, speed_range_rpm : optional operating data used by reports (rpm of the input).
    tilt_deg : the shaft's tilt, deg (the rotor end up; default 0): gravity, the load
        ``"gravity"`` (its value is g in m/s^2, e.g. ``loads={"gravity": 9.81}``), pulls every
        body along ``(0, -cos(tilt), sin(tilt))`` in ground axes (``y`` up, ``z`` along the shaft
        from the rotor to the generator).
    """

    def __init__(self, name: str = "model", input: str | None = None,
                 rated_speed_rpm: float | None = None,
                 speed_range_rpm: tuple | None = None, tilt_deg: float = 0.0):
        self.name = name
        self.input = input
        self.rated_speed_rpm = rated_speed_rpm
        self.speed_range_rpm = speed_range_rpm
        self.tilt_deg = v.number("model.tilt_deg", tilt_deg, "deg", minimum=-90.0,
                                 maximum=90.0)
        self.frames: dict[str, Frame] = {GROUND: Frame(GROUND, 0.0)}
        self.bodies: dict[str, Body] = {}
        self.meshes: dict[str, Mesh] = {}
        self.bearings: dict[str, Bearing] = {}
        self.groups: dict[str, list[str]] = {}
        self.output: str | None = None
        self.gear_ratio: float | None = None
        #: the ratings' data (the file's ``[rating]`` table, :mod:`gearmodal.model.rating_data`)
        self.rating: dict | None = None

    # -- building -------------------------------------------------------------------------
    def add(self, component):
        """Add a frame, body or element (mesh, bearing...); returns it. Names must be unique
        per kind, and bodies and elements share one name space."""
        if isinstance(component, Frame):
            table, kind = self.frames, "frame"
        elif isinstance(component, Body):
            if not component.name:
                raise ModelError("Body.name", "a body needs a name before it is added to a model")
            table, kind = self.bodies, "body"
        elif isinstance(component, tuple(ELEMENT_KINDS)):
            table, kind = self.elements_of(type(component)), type(component).__name__.lower()
        else:
            raise TypeError(f"cannot add {type(component).__name__} to a Model")
        if component.name in table:
            raise ModelError(component.name, f"a {kind} of this name is already in the model")
        if kind != "frame" and kind != "body" and component.name in self.bodies:
            raise ModelError(component.name, "name already used by a body")
        if kind == "body" and any(component.name in self.elements_of(c) for c in ELEMENT_KINDS):
            raise ModelError(component.name, "name already used by a mesh or bearing")
        table[component.name] = component
        return component

    def elements_of(self, cls) -> dict:
        """The model's table of an element kind (``self.meshes``, ``self.bearings``...)."""
        return self.__dict__.setdefault(cls.TABLE, {})

    def elements(self):
        """Every element (meshes, then bearings...), in assembly order."""
        for cls in ELEMENT_KINDS:
            yield from self.elements_of(cls).values()

    def merge(self, other: Model, prefix: str, ground: str | None = None) -> Model:
        """Copy ``other``'s components into this model, names prefixed by ``prefix + '.'``.

        References to the ground in ``other`` are redirected to body ``ground`` when given (a
        stage mounted in a housing). Returns ``self``.
        """
        def p(n):
            return f"{prefix}.{n}" if n else n

        # copies keep the validated fields; constructors would re-check the dotted names
        for fr in other.frames.values():
            if fr.name != GROUND:
                nf = copy.copy(fr)
                nf.name = p(fr.name)
                self.add(nf)
        def stage(c):  # what a stage model calls its own is the prefix's
            return p(c.stage) if c.stage else prefix

        for b in other.bodies.values():
            nb = copy.copy(b)
            nb.name, nb.stage = p(b.name), stage(b)
            nb.frame = b.frame if b.frame == GROUND else p(b.frame)
            nb.coordinate_names = dict(b.coordinate_names)
            if b.pinned_to is not None:
                nb.pinned_to = p(b.pinned_to)
            self.bodies[self._free(nb.name)] = nb
        for cls in ELEMENT_KINDS:  # each kind renames its own (element.Element.renamed)
            table = self.elements_of(cls)
            for e in other.elements_of(cls).values():
                ne = e.renamed(p, prefix, ground)
                table[self._free(ne.name)] = ne
        for g, members in other.groups.items():
            self.groups[p(g)] = [p(m) for m in members]
        return self

    def _free(self, name: str) -> str:
        if name in self.bodies or any(name in self.elements_of(c) for c in ELEMENT_KINDS):
            raise ModelError(name, "name already used in the model")
        return name

    # -- naming ---------------------------------------------------------------------------
    @property
    def dof_names(self) -> list[str]:
        """All DOF names, in assembly order (bodies in insertion order)."""
        return [f"{b.name}.{c}" for b in self.bodies.values() for c in b.coordinates]

    @property
    def n_dofs(self) -> int:
        return sum(len(LEVEL_INDICES[b.dofs]) for b in self.bodies.values())

    def load_directions(self, body: Body) -> list[tuple[str, int]]:
        """(load name, global direction index) pairs available on ``body`` at its DOF level."""
        out = []
        for kind, idx in LOAD_KINDS.items():
            if idx in body.local_indices or (idx < 5 and _moves(body, idx)):
                if kind == "torque" and body.rotation_scale is not None:
                    out.append((f"{body.name}.force_u", idx))
                else:
                    out.append((f"{body.name}.{kind}", idx))
        return out

    @property
    def load_names(self) -> list[str]:
        """All load names, e.g. ``"pinion.torque"`` (N m), ``"carrier.force_x"`` (N), and
        ``"gravity"`` (m/s^2: the weight of every body, :attr:`gravity_direction`)."""
        return [n for b in self.bodies.values() for n, _ in self.load_directions(b)] \
            + [GRAVITY]

    @property
    def gravity_direction(self) -> tuple[float, float, float]:
        """Unit vector of gravity in ground axes: ``(0, -cos(tilt), sin(tilt))``."""
        t = math.radians(getattr(self, "tilt_deg", 0.0))
        return (0.0, -math.cos(t), math.sin(t))

    # -- checks ---------------------------------------------------------------------------
    def check(self) -> Model:
        """Check references between components; raise :class:`ModelError` naming the field."""
        if not self.bodies:
            raise ModelError(f"{self.name}.bodies", "the model has no bodies")
        if self.input is not None and self.input not in self.bodies:
            raise ModelError(f"{self.name}.input", f"= {self.input!r}: no such body; bodies: "
                             + ", ".join(self.bodies))
        for b in self.bodies.values():
            if b.frame not in self.frames:
                raise ModelError(f"{b.name}.frame", f"= {b.frame!r}: no such frame; frames: "
                                 + ", ".join(self.frames))
            if b.pinned_to is not None:
                h = self.bodies.get(b.pinned_to)
                if h is None or h is b or h.pinned_to is not None or h.frame != b.frame:
                    raise ModelError(f"{b.name}.pinned_to", f"= {b.pinned_to!r}: must name "
                                     f"another body in frame {b.frame!r} that is not itself "
                                     "pinned")
        tables = {"bodies": (self.bodies, "body"), "frames": (self.frames, "frame")}
        for e in self.elements():  # each kind names what it refers to and checks the rest
            for key, ref, where in e.references():
                table, what = tables[where]
                if ref not in table:
                    raise ModelError(f"{e.name}.{key}", f"= {ref!r}: no such {what}")
            e.check_in(self)
        return self

    def set_dofs(self, level: str, bodies=None) -> Model:
        """Set the DOF level of all (or the named) bodies; returns ``self``."""
        from .validate import choice
        choice("dofs", level, DOF_LEVELS)
        for name in bodies if bodies is not None else list(self.bodies):
            if name not in self.bodies:
                raise ModelError("dofs", f"no body {name!r}")
            self.bodies[name].dofs = level
        return self

    def copy(self) -> Model:
        """A deep copy (components are mutable dataclasses)."""
        return copy.deepcopy(self)

    def summary(self) -> str:
        """A short text summary: bodies, DOF count, meshes, bearings."""
        levels = {}
        for b in self.bodies.values():
            levels[b.dofs] = levels.get(b.dofs, 0) + 1
        lv = ", ".join(f"{n} {k}" for k, n in levels.items())
        return (f"{self.name}: {len(self.bodies)} bodies ({lv}), {self.n_dofs} DOF, "
                f"{len(self.meshes)} meshes, {len(self.bearings)} bearings/shafts")

    def __repr__(self) -> str:
        return f"<Model {self.summary()}>"

    def assemble(self, azimuth: float = 0.0):
        """Assemble the linear(ised) matrices: see :func:`gearmodal.assembly.assemble`."""
        from ..assembly import assemble
        return assemble(self, azimuth=azimuth)


def _moves(body: Body, idx: int) -> bool:
    """True if the body has the local coordinate that a global direction idx (0-4) acts on.

    Local x/y mix under the frame rotation, so a force_x exists when x and y both exist.
    """
    if idx in (0, 1):
        return 0 in body.local_indices
    if idx in (3, 4):
        return 3 in body.local_indices
    return idx in body.local_indices
