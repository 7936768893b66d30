"""The elastic turbine as one coupled system: tower, nacelle, shaft, hub and bending blades,
the deck's drivetrain or a gearbox model between rotor and generator (issue 56, DESIGN 2.5a).

The equations are :mod:`gearmodal.turbine.assumed_modes`' (ElastoDyn's assumed modes, the
blades in multi-blade coordinates, the turning rotor's Coriolis, gyroscopic, spin-softening and
centrifugal terms), so that :func:`gearmodal.modal` and :func:`gearmodal.campbell` solve it at
any rotor speed in the fixed frame, as OpenFAST's linearisation reads after its multi-blade
transformation.
"""

from __future__ import annotations

import math

from ..coupling import Coupled, LinearConstraint, LinearSystem, ModelSystem
from ..errors import ModelError
from ..model.model import Model
from .assumed_modes import GENERATOR, turning_matrices
from .bodies import BeamModes, blade_modes, tower_modes
from .elastodyn import GRAVITY, StructureDeck, read_structure


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

    ``speed_range_rpm``: the operating range the Campbell diagram marks (default: the
    gearbox model's; none without one). ``yaw_stiffness``, ``yaw_damping``: the yaw bearing
    (N m/rad, N m s/rad), the coordinate ``nacelle_yaw``; None: the nacelle held in yaw.

    Its ``deck`` is the :class:`~gearmodal.turbine.elastodyn.StructureDeck`, ``blade`` and
    ``tower`` their :class:`~gearmodal.turbine.bodies.BeamModes`, ``generator`` ``"locked"`` or
    ``"free"``, ``gearbox`` the gearbox model or None. ``geometric_stiffness=False`` in
    :func:`gearmodal.modal` and :func:`gearmodal.campbell` is Lin & Parker's option for the
    gearbox's planets; the turbine's own terms of the steady rotation (the blades' centrifugal
    tension, the turning rotor's second-order motion) are always in.
    """

    def __init__(self, deck: StructureDeck, blade: BeamModes, tower: BeamModes, *,
                 generator: str = "locked", gearbox: Model | None = None,
                 gravity: float = GRAVITY, name: str = "elastic turbine",
                 speed_range_rpm: tuple[float, float] | None = None,
                 yaw_stiffness: float | None = None, yaw_damping: float = 0.0):
        g = _number("gravity", gravity)
        if not math.isfinite(g) or g < 0:
            raise ModelError("gravity", f"= {gravity!r}: must be a finite number >= 0 m/s^2")
        if generator not in GENERATOR:
            raise ModelError("generator", f"= {generator!r}: one of {', '.join(GENERATOR)}")
        yaw = None
        if yaw_stiffness is not None:
            k, c = _number("yaw_stiffness", yaw_stiffness), _number("yaw_damping", yaw_damping)
            if not math.isfinite(k) or k <= 0:
                raise ModelError("yaw_stiffness", f"= {yaw_stiffness!r}: a finite stiffness "
                                 "> 0 N m/rad (None: the nacelle held in yaw)")
            if not math.isfinite(c) or c < 0:
                raise ModelError("yaw_damping", f"= {yaw_damping!r}: a finite damping >= 0 "
                                 "N m s/rad")
            yaw = (k, c)
        self.deck, self.blade, self.tower = deck, blade, tower
        self.generator, self.gravity, self.gearbox = generator, g, gearbox
        if gearbox is None:
            mat = turning_matrices(deck, blade, tower, generator=generator, gravity=g, yaw=yaw)
            super().__init__([_system(mat)], [], name=name)
            self.rated_speed_rpm = deck.rated_rotor_speed_rpm or None
            self.speed_range_rpm = speed_range_rpm
            return
        if not isinstance(gearbox, Model):
            raise ModelError("gearbox", f"expected a gm.Model of a drivetrain or None, got "
                             f"{type(gearbox).__name__}")
        rotor = _body_with_role(gearbox, "rotor")
        moving = [d for d in gearbox.dof_names if d.startswith(f"{rotor}.") and
                  d != f"{rotor}.theta"]
        if moving:
            raise ModelError(f"gearbox.{rotor}.dofs", f"the turbine's hub and blades carry the "
                             f"rotor: its body in the gearbox model must only turn "
                             f"(dofs = 'torsional'), it has {', '.join(moving)}")
        gen = _body_with_role(gearbox, "generator")
        mat = turning_matrices(deck, blade, tower, generator=None, gravity=g, yaw=yaw)
        j = mat.dof_names.index("rotor_azimuth")
        mat.M[j, j] -= float(gearbox.bodies[rotor].inertia)
        constraints = [LinearConstraint("hub", {"turbine.rotor_azimuth": 1.0,
                                                f"gearbox.{rotor}.theta": -1.0})]
        if generator == "locked":
            constraints.append(LinearConstraint("generator_lock",
                                                {f"gearbox.{gen}.theta": 1.0}))
        super().__init__([ModelSystem(gearbox, "gearbox"), _system(mat)], constraints,
                         name=name)
        if speed_range_rpm is not None:
            self.speed_range_rpm = speed_range_rpm

    @property
    def load_names(self) -> list[str]:
        """The loads of the coupled systems (the gearbox's, ``gearbox.<load>``)."""
        return [f"{s.name}.{ln}" for s in self.systems.values() for ln in s.load_names]

    def summary(self) -> str:
        """One line on what the model holds (reports print it)."""
        d = self.deck
        drive = (f"gearbox {self.gearbox.name!r}" if self.gearbox is not None
                 else "the deck's two-mass drivetrain")
        return (f"{self.name}: {d.path.name}, tower {len(self.tower.names)} modes "
                f"({', '.join(self.tower.names)}), {d.blades} blades of "
                f"{len(self.blade.names)} modes ({', '.join(self.blade.names)}), {drive}, "
                f"generator {self.generator}; shapes {self.blade.source}")

    def excitation_orders(self) -> dict[str, float]:
        """The rotor's orders (1P, the blade passing nP and 2nP) and, with a gearbox, its mesh
        and planet-pass orders (:func:`gearmodal.campbell.default_orders`)."""
        from ..campbell import default_orders

        nb = self.deck.blades
        out = {"1P": 1.0, f"{nb}P": float(nb), f"{2 * nb}P": float(2 * nb)}
        if self.gearbox is not None:
            for k, v in default_orders(self.gearbox).items():
                out.setdefault(k, v)
        return out

    def check_simulation(self, speed_rpm: float) -> None:
        """Refuse a time simulation at speed: the elastic turbine's loads in time (its
        aerodynamics on the bending blades) are the next issue's; parked it is a linear
        system that :func:`gearmodal.simulate` integrates."""
        if float(speed_rpm) != 0.0:
            raise ModelError("speed_rpm", f"= {speed_rpm!r}: the elastic turbine is simulated "
                             "parked (0 rpm) so far; its modes at speed come from gm.modal and "
                             "gm.campbell, its aeroelastic run is not built yet")


def _system(mat) -> LinearSystem:
    return LinearSystem("turbine", mat.dof_names, mat.M, mat.K, mat.C, G=mat.G,
                        K_cent=mat.K_cent, K_speed=mat.K_speed)


def _number(name: str, value) -> float:
    try:
        return float(value)
    except (TypeError, ValueError):
        raise ModelError(name, f"= {value!r}: a number") from None


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
                    shapes: str = "computed", gravity: float = GRAVITY,
                    speed_range_rpm: tuple[float, float] | None = None,
                    yaw_stiffness: float | None = None,
                    yaw_damping: float = 0.0) -> ElasticTurbine:
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
    speed_range_rpm : the operating range (rpm) the Campbell diagram marks.
    yaw_stiffness, yaw_damping : the yaw bearing, N m/rad and N m s/rad (ServoDyn's YawSpr,
        YawDamp); None: the nacelle held in yaw (Table 9-1's case).
    """
    deck = read_structure(deck_path)
    return ElasticTurbine(deck, blade_modes(deck, flap, edge, shapes),
                          tower_modes(deck, fore_aft, side_to_side, shapes),
                          generator=generator, gearbox=gearbox, gravity=gravity,
                          speed_range_rpm=speed_range_rpm, yaw_stiffness=yaw_stiffness,
                          yaw_damping=yaw_damping)


#: the fields of an elastic turbine file's ``[elastic_turbine]`` table and their defaults
FILE_FIELDS = {"name": "elastic turbine", "deck": None, "gearbox": None,
               "generator": "locked", "shapes": "computed", "flap": 2, "edge": 1,
               "fore_aft": 2, "side_to_side": 2, "gravity": GRAVITY, "speed_range_rpm": None,
               "yaw_stiffness": None, "yaw_damping": 0.0}


def load_elastic_turbine(path) -> ElasticTurbine:
    """An elastic turbine from a TOML file with an ``[elastic_turbine]`` table (the same as
    :func:`elastic_turbine`'s arguments, :data:`FILE_FIELDS`): ``deck``, the ElastoDyn main
    file relative to this file (or ``"nrel5mw"``: the 5 MW deck the rosco wheel ships);
    ``gearbox``, a drivetrain model file relative to this file (optional)."""
    import tomllib
    from pathlib import Path

    from ..model.toml_io import load

    path = Path(path)
    try:
        data = tomllib.loads(path.read_text())
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as e:
        raise ModelError(str(path), f"not a readable TOML file ({e})") from None
    except RecursionError:
        raise ModelError(str(path), "TOML nested too deeply") from None
    table = data.get("elastic_turbine")
    if not isinstance(table, dict):
        raise ModelError(f"{path.name}", "needs an [elastic_turbine] table")
    extra = sorted(set(table) - set(FILE_FIELDS))
    if extra:
        raise ModelError(f"elastic_turbine.{extra[0]}", "no such field; fields: "
                         + ", ".join(FILE_FIELDS))
    f = {**FILE_FIELDS, **table}
    if not isinstance(f["deck"], str) or not f["deck"]:
        raise ModelError("elastic_turbine.deck", "the ElastoDyn main file (a path relative "
                         "to this file) or 'nrel5mw'")
    if f["deck"] == "nrel5mw":
        from .elastodyn import elastodyn_of
        from .rosco import rosco_files

        deck = elastodyn_of(rosco_files()[1] / "NREL-5MW.fst")
    else:
        deck = path.parent / f["deck"]
    gearbox = None
    if f["gearbox"] is not None:
        if not isinstance(f["gearbox"], str):
            raise ModelError("elastic_turbine.gearbox", f"= {f['gearbox']!r}: a model file "
                             "relative to this file")
        gearbox = load(path.parent / f["gearbox"])
    rng = f["speed_range_rpm"]
    if rng is not None:
        ok = (isinstance(rng, list) and len(rng) == 2
              and all(isinstance(v, (int, float)) and math.isfinite(v) for v in rng)
              and 0 <= rng[0] < rng[1])
        if not ok:
            raise ModelError("elastic_turbine.speed_range_rpm", f"= {rng!r}: two increasing "
                             "speeds >= 0 rpm")
        rng = (float(rng[0]), float(rng[1]))
    et = elastic_turbine(deck, gearbox=gearbox, generator=f["generator"], flap=f["flap"],
                         edge=f["edge"], fore_aft=f["fore_aft"],
                         side_to_side=f["side_to_side"], shapes=f["shapes"],
                         gravity=f["gravity"], speed_range_rpm=rng,
                         yaw_stiffness=f["yaw_stiffness"], yaw_damping=f["yaw_damping"])
    et.name = str(f["name"])
    return et


def is_elastic_turbine_file(path) -> bool:
    """Whether the TOML file at ``path`` describes an elastic turbine: a line opening its
    ``[elastic_turbine]`` table (read as text: any other file goes to the model reader, which
    names what is wrong with it)."""
    import re
    from pathlib import Path

    try:
        text = Path(path).read_text(errors="replace")
    except (OSError, ValueError):
        return False
    return re.search(r"^\s*\[\s*elastic_turbine\s*\]", text, re.M) is not None
