"""The structure of a turbine as an OpenFAST ElastoDyn deck describes it (issue 56).

ElastoDyn's main file gives the rigid bodies and their places (nacelle, hub, generator, the
shaft's tilt and overhang, the blades' precone), its blade and tower files the distributed
properties (mass and bending stiffness per length, structural damping per mode) that the
elastic bodies' modes are computed from (:mod:`gearmodal.turbine.bodies`). The files are read by
``pybmodes`` (the ``elastic`` extra), the finite-element modal code made for these decks:
``read_elastodyn_main``, ``read_elastodyn_blade`` and ``read_elastodyn_tower``. Nothing is
copied by hand.

Units are SI and angles radians; the frame is ElastoDyn's: ``x`` downwind, ``y`` to the left
looking downwind, ``z`` up, origin at the tower top (the yaw bearing).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import ModelError

#: standard gravity, m/s^2 (the NREL 5 MW deck's ``Gravity``)
GRAVITY = 9.80665


@dataclass(frozen=True)
class StructureDeck:
    """The rigid bodies and the places of an ElastoDyn turbine (SI units, angles in rad).

    Attributes
    ----------
    path : the ElastoDyn main file. blades : count. tip_radius, hub_radius : m.
    precone : rad (negative: the blades lean upwind). shaft_tilt : rad (ElastoDyn's sign:
    negative lifts the rotor's upwind end). overhang : m from the yaw axis to the rotor apex
    along the shaft (negative upwind). twr2shft : m, the shaft above the tower top.
    tower_height, tower_base : m (the tower's flexible length is their difference).
    nacelle_mass : kg, its centre ``nacelle_cm`` (m, tower-top axes); nacelle_yaw_inertia :
    kg m^2 about the yaw axis. hub_mass : kg at the apex (``hub_cm`` m along the shaft);
    hub_inertia : kg m^2 about the shaft. generator_inertia : kg m^2 about the high-speed
    shaft. gear_ratio : generator per rotor speed. shaft_stiffness, shaft_damping : the
    drivetrain's torsion on the low-speed side, N m/rad and N m s/rad. rated_rotor_speed_rpm :
    ElastoDyn's ``RotSpeed``. blade_file, tower_file : the distributed-property files.
    """

    path: Path
    blades: int
    tip_radius: float
    hub_radius: float
    precone: float
    shaft_tilt: float
    overhang: float
    twr2shft: float
    tower_height: float
    tower_base: float
    nacelle_mass: float
    nacelle_cm: tuple[float, float, float]
    nacelle_yaw_inertia: float
    hub_mass: float
    hub_cm: float
    hub_inertia: float
    generator_inertia: float
    gear_ratio: float
    shaft_stiffness: float
    shaft_damping: float
    rated_rotor_speed_rpm: float
    blade_file: Path
    tower_file: Path

    @property
    def blade_length(self) -> float:
        """The blade's flexible length, root to tip (m)."""
        return self.tip_radius - self.hub_radius

    @property
    def tower_length(self) -> float:
        """The tower's flexible length, base to top (m)."""
        return self.tower_height - self.tower_base

    @property
    def shaft_axis(self) -> np.ndarray:
        """Unit vector along the shaft, pointing downwind (tower-top axes)."""
        return np.array([math.cos(self.shaft_tilt), 0.0, math.sin(self.shaft_tilt)])

    @property
    def apex(self) -> np.ndarray:
        """The rotor apex from the tower top (m): ``overhang`` along the shaft, ``twr2shft``
        up (ElastoDyn's geometry)."""
        return self.overhang * self.shaft_axis + np.array([0.0, 0.0, self.twr2shft])


def elastodyn_of(fst) -> Path:
    """The ElastoDyn main file an OpenFAST ``.fst`` names (its ``EDFile``), beside it."""
    fst = Path(fst)
    if not fst.is_file():
        raise ModelError("deck", f"= {str(fst.parent)!r}: no {fst.name} there")
    for line in fst.read_text(errors="replace").splitlines():
        tok = line.split()
        if len(tok) >= 2 and tok[1] == "EDFile":
            return fst.parent / tok[0].strip('"')
    raise ModelError("deck", f"{fst}: no EDFile line")


def servodyn_yaw(fst) -> tuple[float, float]:
    """``(YawSpr, YawDamp)``: the yaw bearing's spring (N m/rad) and damper (N m s/rad) from the
    ServoDyn file an OpenFAST ``.fst`` names (its ``ServoFile``)."""
    fst = Path(fst)
    if not fst.is_file():
        raise ModelError("deck", f"= {str(fst.parent)!r}: no {fst.name} there")
    servo = None
    for line in fst.read_text(errors="replace").splitlines():
        tok = line.split()
        if len(tok) >= 2 and tok[1] == "ServoFile":
            servo = fst.parent / tok[0].strip('"')
    if servo is None or not servo.is_file():
        raise ModelError("deck", f"{fst.name}: no ServoDyn file (ServoFile) beside it")
    found: dict[str, float] = {}
    for line in servo.read_text(errors="replace").splitlines():
        tok = line.split()
        if len(tok) >= 2 and tok[1] in ("YawSpr", "YawDamp"):
            try:
                found[tok[1]] = float(tok[0].replace("D", "E"))
            except ValueError:
                raise ModelError(f"deck.{tok[1]}", f"= {tok[0]!r} in {servo.name}: not a "
                                 "number") from None
    for key in ("YawSpr", "YawDamp"):
        if key not in found:
            raise ModelError(f"deck.{key}", f"missing in {servo.name}")
    return (_positive("deck.YawSpr", found["YawSpr"]),
            _positive("deck.YawDamp", found["YawDamp"], allow_zero=True))


def _pybmodes_reader():
    try:
        from pybmodes.io import elastodyn_reader
    except ImportError:
        raise ModelError("deck", "the elastic turbine's bodies need pybmodes: pip install "
                         "-e '.[elastic]'") from None
    return elastodyn_reader


def _positive(name: str, value: float, allow_zero: bool = False) -> float:
    value = float(value)
    ok = math.isfinite(value) and (value >= 0 if allow_zero else value > 0)
    if not ok:
        raise ModelError(name, f"= {value!r}: must be a finite number "
                         f"{'>= 0' if allow_zero else '> 0'}")
    return value


def read_structure(path) -> StructureDeck:
    """The ElastoDyn main file at ``path`` (its blade and tower files beside it), read by
    pybmodes; every value is checked (finite, positive where it must be)."""
    path = Path(path)
    if not path.is_file():
        raise ModelError("deck", f"= {str(path)!r}: no such ElastoDyn file")
    reader = _pybmodes_reader()
    try:
        m = reader.read_elastodyn_main(path)
    except (ValueError, IndexError, KeyError) as e:
        raise ModelError("deck", f"= {str(path)!r}: not a readable ElastoDyn main file "
                         f"({e})") from None
    s = m.scalars

    def scalar(key: str) -> float:
        if key not in s:
            raise ModelError(f"deck.{key}", f"missing in {path.name}")
        try:
            return float(str(s[key]).replace("D", "E"))
        except ValueError:
            raise ModelError(f"deck.{key}", f"= {s[key]!r} in {path.name}: not a number") \
                from None

    nb = int(m.num_bl)
    if nb < 2:
        raise ModelError("deck.NumBl", f"= {nb}: the elastic rotor needs 2 or more blades")
    cones = {float(c) for c in m.pre_cone[:nb]}
    if len(cones) != 1:
        raise ModelError("deck.PreCone", f"= {sorted(cones)}: the blades must share one precone "
                         "(an isotropic rotor)")
    if len(set(m.bld_file[:nb])) != 1:
        raise ModelError("deck.BldFile", "the blades must share one blade file (an isotropic "
                         "rotor)")
    deck = StructureDeck(
        path=path, blades=nb,
        tip_radius=_positive("deck.TipRad", m.tip_rad),
        hub_radius=_positive("deck.HubRad", m.hub_rad, allow_zero=True),
        precone=math.radians(cones.pop()), shaft_tilt=math.radians(float(m.shft_tilt)),
        overhang=float(m.overhang), twr2shft=float(m.twr2shft),
        tower_height=_positive("deck.TowerHt", m.tower_ht),
        tower_base=float(m.tower_bs_ht),
        nacelle_mass=_positive("deck.NacMass", m.nac_mass, allow_zero=True),
        nacelle_cm=(float(m.nac_cm_xn), float(m.nac_cm_yn), float(m.nac_cm_zn)),
        nacelle_yaw_inertia=_positive("deck.NacYIner", m.nac_y_iner, allow_zero=True),
        hub_mass=_positive("deck.HubMass", m.hub_mass, allow_zero=True),
        hub_cm=float(m.hub_cm),
        hub_inertia=_positive("deck.HubIner", m.hub_iner, allow_zero=True),
        generator_inertia=_positive("deck.GenIner", m.gen_iner, allow_zero=True),
        gear_ratio=_positive("deck.GBRatio", scalar("GBRatio")),
        shaft_stiffness=_positive("deck.DTTorSpr", scalar("DTTorSpr")),
        shaft_damping=_positive("deck.DTTorDmp", scalar("DTTorDmp"), allow_zero=True),
        rated_rotor_speed_rpm=_positive("deck.RotSpeed", m.rot_speed_rpm, allow_zero=True),
        blade_file=path.parent / str(m.bld_file[0]).strip('"'),
        tower_file=path.parent / str(m.twr_file).strip('"'))
    for f in (deck.blade_file, deck.tower_file):
        if not f.is_file():
            raise ModelError("deck", f"{path.name} names {f.name}, which is not beside it")
    if deck.tip_radius <= deck.hub_radius:
        raise ModelError("deck.TipRad", f"= {deck.tip_radius}: must exceed HubRad "
                         f"({deck.hub_radius})")
    if deck.tower_length <= 0:
        raise ModelError("deck.TowerHt", f"= {deck.tower_height}: must exceed TowerBsHt "
                         f"({deck.tower_base})")
    for name, v in (("OverHang", deck.overhang), ("Twr2Shft", deck.twr2shft),
                    ("ShftTilt", deck.shaft_tilt), ("PreCone", deck.precone),
                    ("HubCM", deck.hub_cm), ("TowerBsHt", deck.tower_base),
                    *zip(("NacCMxn", "NacCMyn", "NacCMzn"), deck.nacelle_cm, strict=True)):
        if not math.isfinite(v):
            raise ModelError(f"deck.{name}", f"= {v!r}: must be a finite number")
    return deck


def read_blade_file(deck: StructureDeck):
    """pybmodes' record of the deck's blade file (distributed properties, damping, ElastoDyn's
    own mode-shape polynomials)."""
    try:
        return _pybmodes_reader().read_elastodyn_blade(deck.blade_file)
    except (ValueError, IndexError, KeyError) as e:
        raise ModelError("deck.BldFile", f"= {deck.blade_file.name}: not a readable ElastoDyn "
                         f"blade file ({e})") from None


def read_tower_file(deck: StructureDeck):
    """pybmodes' record of the deck's tower file."""
    try:
        return _pybmodes_reader().read_elastodyn_tower(deck.tower_file)
    except (ValueError, IndexError, KeyError) as e:
        raise ModelError("deck.TwrFile", f"= {deck.tower_file.name}: not a readable ElastoDyn "
                         f"tower file ({e})") from None
