"""TOML model loading (gearmodal/model/toml_io.py) and input validation of the model API.

Covers: the shipped 600 kW drivetrain, round trips TOML == API for the single-builder types
(same DOF names, components and assembled matrices), and a table of bad inputs through the API
and through TOML, each raising a ModelError that names the field and the offending value.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from gearmodal.errors import ModelError
from gearmodal.model import Bearing, Gear, Mesh, RigidBody, Shaft, builders
from gearmodal.model.toml_io import load, loads

ROOT = Path(__file__).resolve().parents[1]
MODEL_600KW = ROOT / "studies" / "models" / "600kw.toml"
DEG = math.radians


def _kernels_available() -> bool:
    try:
        import gearmodal.kernels.joint  # noqa: F401
        import gearmodal.kernels.mesh  # noqa: F401
        import gearmodal.kernels.wheel  # noqa: F401
    except ImportError:
        return False
    return True


needs_kernels = pytest.mark.skipif(not _kernels_available(),
                                   reason="generated kernels (gearmodal/kernels) not present")


# -- the shipped 600 kW drivetrain ----------------------------------------------------------
@pytest.fixture(scope="module")
def model_600kw():
    return load(MODEL_600KW)


def test_600kw_loads_with_expected_dofs(model_600kw):
    m = model_600kw
    names = m.dof_names
    for dof in ("rotor.theta", "housing.x", "housing.y", "housing.theta",
                "stage1.carrier.x", "stage1.carrier.theta", "stage1.sun.x", "stage1.ring.theta",
                "stage1.planet1.zeta", "stage1.planet2.eta", "stage1.planet3.theta",
                "stage2.gear.theta", "stage2.pinion.x", "stage3.gear.y", "stage3.pinion.theta",
                "generator.theta"):
        assert dof in names
    assert "stage1.planet4.zeta" not in names
    assert len(names) == len(set(names)) == m.n_dofs
    assert m.name == "600kw"
    assert m.input == "rotor"


def test_600kw_ratio_speeds_and_units(model_600kw):
    m = model_600kw
    assert m.gear_ratio == pytest.approx((1 + 99 / 21) * (82 / 23) * (88 / 22), rel=1e-12)
    assert m.gear_ratio == pytest.approx(81.49, abs=0.01)
    assert m.rated_speed_rpm == pytest.approx(22.1)
    assert m.speed_range_rpm == (22.0, 22.6)
    sun = m.bodies["stage1.sun"]
    assert (sun.teeth, sun.module) == (21, 0.010)
    assert sun.pressure_angle == DEG(20.0)  # degrees in the TOML, radians in the API
    assert sun.helix_angle == DEG(7.5)
    assert m.bodies["stage1.ring"].internal
    assert m.bodies["stage1.ring"].teeth == 99
    assert m.bodies["stage2.gear"].teeth == 82 and m.bodies["stage2.pinion"].teeth == 23
    assert m.bodies["stage3.gear"].teeth == 88 and m.bodies["stage3.pinion"].teeth == 22
    levels = {b.name: b.dofs for b in m.bodies.values()}
    assert levels["rotor"] == levels["generator"] == "torsional"
    assert levels["housing"] == levels["stage1.carrier"] == levels["stage3.pinion"] == "planar"


@needs_kernels
def test_600kw_housing_translation_modes_near_10_hz(model_600kw):
    from scipy.linalg import eigh

    asm = model_600kw.assemble()
    w2, phi = eigh(asm.stiffness(), asm.M)
    freqs = np.sqrt(np.clip(w2, 0.0, None)) / (2 * np.pi)
    assert freqs[0] < 0.05 < freqs[1]  # one rigid-body mode: the free drivetrain spin
    energy = phi * (asm.M @ phi)  # modal kinetic energy per DOF (columns sum to 1)
    housing = [asm.dof_names.index("housing.x"), asm.dof_names.index("housing.y")]
    share = energy[housing].sum(axis=0)
    near_10 = [i for i in range(len(freqs)) if 8.0 < freqs[i] < 12.0 and share[i] > 0.5]
    assert len(near_10) == 2, (freqs[:12], share[:12])
    # The pair spans both housing translations (x and y; with isotropic supports any rotation
    # of the pair is an equally valid eigenbasis, so test the span, not the directions).
    sv = np.linalg.svd(phi[np.ix_(housing, near_10)], compute_uv=False)
    assert sv[1] > 0.5 * sv[0]


# -- round trips: TOML == API ---------------------------------------------------------------
GEAR_PAIR_TOML = """
[model]
name = "pair"
type = "gear_pair"
rated_speed_rpm = 1500.0
speed_range_rpm = [0.0, 3000.0]

[gear_pair]
dofs = "planar"
mesh_stiffness = 2.0e8          # N/m
backlash = 1.0e-4               # m
mesh_damping = 50.0             # N s/m
bearing = { stiffness = { x = 1.0e8, y = 2.0e8 }, clearance = { x = 2.0e-5 } }

[gear_pair.pinion]
teeth = 20
module = 0.004
pressure_angle_deg = 20.0
helix_angle_deg = 10.0
face_width = 0.04
mass = 1.0
inertia = 1.0e-3

[gear_pair.wheel]
teeth = 40
module = 0.004
pressure_angle_deg = 20.0
helix_angle_deg = -10.0
mass = 4.0
inertia = 1.6e-2
"""

LIN_PARKER_TOML = """
[model]
type = "lin_parker_stage"

[lin_parker_stage]
n_planets = 4
pressure_angle_deg = 24.6
planet_angles_deg = [0.0, 90.0, 180.0, 270.0]
backlash = 1.0e-4
mass = { carrier = 5.43, ring = 2.35, sun = 0.4, planet = 0.66 }
inertia_over_r2 = { carrier = 6.29, ring = 3.0, sun = 0.39, planet = 0.61 }
bearing = { carrier = 1.0e8, ring = 1.0e8, sun = 1.0e8, planet = 1.0e8 }
torsional = { carrier = 0.0, ring = 1.0e9, sun = 0.0 }
mesh = { sun_planet = 5.0e8, ring_planet = 5.0e8 }
"""

PLANETARY_TOML = """
[model]
type = "planetary_stage"

[planetary_stage]
n_planets = 3
mesh_stiffness = { sun_planet = 4.6e9, ring_planet = 5.0e9 }
backlash = 3.0e-4
planet_bearing = 2.0e9
carrier_bearing = { stiffness = { x = 1.0e9, y = 1.0e9 }, clearance = { x = 1.0e-4 } }
ring_support = { stiffness = { x = 5.0e9, y = 5.0e9, theta = 3.0e9 } }

[planetary_stage.carrier]
mass = 1000.0
inertia = 110.0

[planetary_stage.sun]
teeth = 21
module = 0.010
pressure_angle_deg = 20.0
helix_angle_deg = 7.5
mass = 80.0
inertia = 0.45

[planetary_stage.planet]
teeth = 39
module = 0.010
pressure_angle_deg = 20.0
helix_angle_deg = -7.5
mass = 140.0
inertia = 3.6

[planetary_stage.ring]
teeth = 99
module = 0.010
pressure_angle_deg = 20.0
helix_angle_deg = -7.5
mass = 620.0
inertia = 190.0
"""


def _pair_api():
    p = Gear(20, 0.004, DEG(20.0), DEG(10.0), 0.04, mass=1.0, inertia=1e-3)
    w = Gear(40, 0.004, DEG(20.0), DEG(-10.0), mass=4.0, inertia=1.6e-2)
    return builders.gear_pair(p, w, 2e8, 1e-4, mesh_damping=50.0, dofs="planar",
                              bearing_stiffness={"stiffness": {"x": 1e8, "y": 2e8},
                                                 "clearance": {"x": 2e-5}})


def _lin_parker_api():
    return builders.lin_parker_stage(
        4, mass={"carrier": 5.43, "ring": 2.35, "sun": 0.4, "planet": 0.66},
        inertia_over_r2={"carrier": 6.29, "ring": 3.0, "sun": 0.39, "planet": 0.61},
        bearing={"carrier": 1e8, "ring": 1e8, "sun": 1e8, "planet": 1e8},
        torsional={"carrier": 0.0, "ring": 1e9, "sun": 0.0},
        mesh={"sun_planet": 5e8, "ring_planet": 5e8}, pressure_angle=DEG(24.6),
        planet_angles=[DEG(0.0), DEG(90.0), DEG(180.0), DEG(270.0)], backlash=1e-4)


def _planetary_api():
    sun = Gear(21, 0.010, DEG(20.0), DEG(7.5), mass=80.0, inertia=0.45)
    planet = Gear(39, 0.010, DEG(20.0), DEG(-7.5), mass=140.0, inertia=3.6)
    ring = Gear(99, 0.010, DEG(20.0), DEG(-7.5), internal=True, mass=620.0, inertia=190.0)
    return builders.planetary_stage(
        sun, planet, ring, n_planets=3, carrier_mass=1000.0, carrier_inertia=110.0,
        mesh_stiffness={"sun_planet": 4.6e9, "ring_planet": 5.0e9}, backlash=3e-4,
        planet_bearing=2e9,
        carrier_bearing={"stiffness": {"x": 1e9, "y": 1e9}, "clearance": {"x": 1e-4}},
        ring_support={"stiffness": {"x": 5e9, "y": 5e9, "theta": 3e9}})


_BODY_FIELDS = ("mass", "inertia", "inertia_diametral", "dofs", "frame", "position",
                "orientation", "speed_ratio", "rotation_scale", "coordinate_names")
_GEAR_FIELDS = ("teeth", "module", "pressure_angle", "helix_angle", "face_width", "internal")


def _assert_same_model(a, b):
    assert a.dof_names == b.dof_names
    assert a.load_names == b.load_names
    assert a.input == b.input
    assert list(a.bodies) == list(b.bodies)
    for name, ba in a.bodies.items():
        bb = b.bodies[name]
        assert type(ba) is type(bb)
        fields = _BODY_FIELDS + (_GEAR_FIELDS if isinstance(ba, Gear) else ())
        for f in fields:
            assert getattr(ba, f) == getattr(bb, f), (name, f)
    assert {n: vars(m) for n, m in a.meshes.items()} == {n: vars(m) for n, m in b.meshes.items()}
    assert ({n: vars(br) for n, br in a.bearings.items()}
            == {n: vars(br) for n, br in b.bearings.items()})
    assert {n: f.speed_ratio for n, f in a.frames.items()} == \
        {n: f.speed_ratio for n, f in b.frames.items()}


ROUND_TRIPS = [("gear_pair", GEAR_PAIR_TOML, _pair_api),
               ("lin_parker_stage", LIN_PARKER_TOML, _lin_parker_api),
               ("planetary_stage", PLANETARY_TOML, _planetary_api)]


@pytest.mark.parametrize("kind, text, api", ROUND_TRIPS, ids=[r[0] for r in ROUND_TRIPS])
def test_round_trip_equals_api(kind, text, api):
    _assert_same_model(loads(text), api())


def test_round_trip_model_data():
    m = loads(GEAR_PAIR_TOML)
    assert m.name == "pair"
    assert m.rated_speed_rpm == 1500.0 and m.speed_range_rpm == (0.0, 3000.0)
    assert m.dof_names == ["pinion.x", "pinion.y", "pinion.theta",
                           "wheel.x", "wheel.y", "wheel.theta"]
    assert loads(LIN_PARKER_TOML).name == "lin_parker_stage"  # default name: the type


@needs_kernels
@pytest.mark.parametrize("kind, text, api", ROUND_TRIPS, ids=[r[0] for r in ROUND_TRIPS])
def test_round_trip_same_matrices(kind, text, api):
    a, b = loads(text).assemble(azimuth=0.3), api().assemble(azimuth=0.3)
    assert a.dof_names == b.dof_names
    for attr in ("M", "C", "K", "G", "K_cent", "f_cent", "B"):
        np.testing.assert_array_equal(getattr(a, attr), getattr(b, attr), err_msg=attr)
    for attr in ("W", "offset", "stiffness", "damping", "nominal"):
        np.testing.assert_array_equal(getattr(a.contacts, attr), getattr(b.contacts, attr),
                                      err_msg=attr)
    np.testing.assert_array_equal(a.stiffness(), b.stiffness())


def test_load_names_the_file_in_errors(tmp_path):
    bad = tmp_path / "bad_pair.toml"
    bad.write_text(GEAR_PAIR_TOML.replace("mass = 4.0", "mass = -4.0"))
    with pytest.raises(ModelError, match=r"^gear_pair\.wheel\.mass = -4\.0: .*bad_pair\.toml"):
        load(bad)
    broken = tmp_path / "broken.toml"
    broken.write_text("[model]\ntype = \"gear_pair\"\nname = \n")
    with pytest.raises(ModelError, match=r"broken\.toml: TOML syntax error at line 3"):
        load(broken)
    with pytest.raises(ModelError, match=r"missing\.toml: cannot read"):
        load(tmp_path / "missing.toml")


# -- bad inputs: API and TOML, each naming the field and the value --------------------------
def _gear(**kw):
    args = {"teeth": 21, "module": 0.010, "pressure_angle": DEG(20.0), "helix_angle": 0.0,
            "name": "sun", "mass": 80.0, "inertia": 0.45}
    args.update(kw)
    return Gear(**args)


def _stage(**kw):
    args = {"sun": _gear(), "planet": _gear(teeth=39, name="planet"),
            "ring": _gear(teeth=99, name="ring", internal=True), "carrier_mass": 1000.0,
            "carrier_inertia": 110.0, "mesh_stiffness": 4.6e9}
    args.update(kw)
    return builders.planetary_stage(**args)


API_CASES = [
    ("gear-mass-negative", lambda: _gear(mass=-80.0), r"sun\.mass = -80\.0: must be > 0"),
    ("gear-mass-zero", lambda: _gear(mass=0), r"sun\.mass = 0\.0: must be > 0"),
    ("gear-inertia-negative", lambda: _gear(inertia=-0.45), r"sun\.inertia = -0\.45"),
    ("gear-teeth-negative", lambda: _gear(teeth=-21), r"sun\.teeth = -21: must be an integer"),
    ("gear-teeth-zero", lambda: _gear(teeth=0), r"sun\.teeth = 0: must be an integer >= 3"),
    ("gear-module-zero", lambda: _gear(module=0.0), r"sun\.module = 0\.0: must lie in \(0, 1\] m"),
    ("gear-module-in-mm", lambda: _gear(module=10),
     r"sun\.module = 10\.0: must lie in \(0, 1\] m \(modules are in metres"),
    ("gear-pressure-angle-degrees", lambda: _gear(pressure_angle=20),
     r"sun\.pressure_angle = 20\.0 rad: .*did you mean 0\.349066 = radians\(20\)"),
    ("gear-helix-angle-degrees", lambda: _gear(helix_angle=7.5),
     r"sun\.helix_angle = 7\.5 rad: .*radians\(7\.5\)"),
    ("gear-teeth-string", lambda: _gear(teeth="21"),
     r"sun\.teeth: expected an integer, got str '21'"),
    ("gear-mass-bool", lambda: _gear(mass=True),
     r"sun\.mass: expected a number in kg, got bool True"),
    ("rigid-body-dofs", lambda: RigidBody(name="housing", mass=5e3, inertia=1.5e3, dofs="6dof"),
     r"housing\.dofs = '6dof': must be one of 'torsional', 'planar', 'full'"),
    ("bearing-stiffness-negative",
     lambda: Bearing("planet_bearing", "planet", "carrier", stiffness={"x": -2e9}),
     r"planet_bearing\.stiffness\.x = -2000000000\.0: must be >= 0"),
    ("bearing-clearance-negative",
     lambda: Bearing("carrier_bearing", "carrier", stiffness={"x": 1e9}, clearance={"x": -1e-4}),
     r"carrier_bearing\.clearance\.x = -0\.0001: must be >= 0"),
    ("bearing-unknown-direction", lambda: Bearing("b", "carrier", stiffness={"q": 1e9}),
     r"b\.stiffness\.q: unknown direction; allowed: x, y, z, rx, ry, theta"),
    ("mesh-backlash-negative", lambda: Mesh("sun_planet1", "sun", "planet1", 4.6e9, -3e-4),
     r"sun_planet1\.backlash = -0\.0003: must be >= 0 m"),
    ("mesh-stiffness-string", lambda: Mesh("mesh", "pinion", "wheel", "stiff"),
     r"mesh\.stiffness: expected a number in N/m, got str 'stiff'"),
    ("shaft-stiffness-negative", lambda: Shaft("main_shaft", "rotor", "carrier", -4.8e7),
     r"main_shaft\.stiffness = -48000000\.0: must be >= 0 N m/rad"),
    ("stage-ring-teeth", lambda: _stage(ring=_gear(teeth=98, name="ring", internal=True)),
     r"planetary_stage\.ring\.teeth = 98: ring teeth must equal sun \+ 2 \* planet "
     r"\(21 \+ 2 \* 39 = 99\)"),
    ("stage-unequal-spacing", lambda: _stage(n_planets=7),
     r"planetary_stage\.n_planets = 7: planets cannot be equally spaced"),
    ("stage-dofs", lambda: _stage(dofs="3d"), r"planetary_stage\.dofs = '3d'"),
    ("stage-backlash-negative", lambda: _stage(backlash=-1e-4),
     r"planetary_stage\.backlash = -0\.0001: must be >= 0"),
    ("pair-mesh-stiffness-negative",
     lambda: builders.gear_pair(_gear(teeth=20, name="p"), _gear(teeth=40, name="w"), -2e8, 0.0),
     r"gear_pair\.mesh_stiffness = -200000000\.0: must be >= 0"),
    ("pair-dofs", lambda: builders.gear_pair(_gear(teeth=20), _gear(teeth=40), 2e8, 0.0,
                                             dofs="spatial"),
     r"gear_pair\.dofs = 'spatial'"),
]


@pytest.mark.parametrize("build, pattern", [c[1:] for c in API_CASES],
                         ids=[c[0] for c in API_CASES])
def test_api_bad_input(build, pattern):
    with pytest.raises(ModelError, match=pattern):
        build()


def _edit(text: str, old: str, new: str) -> str:
    assert text.count(old) >= 1, old
    return text.replace(old, new, 1)


TOML_CASES = [
    # (id, base document, old, new, regex naming the TOML field and the value)
    ("mass-negative", GEAR_PAIR_TOML, "mass = 4.0", "mass = -4.0",
     r"^gear_pair\.wheel\.mass = -4\.0: must be > 0 kg$"),
    ("mass-zero", GEAR_PAIR_TOML, "mass = 1.0", "mass = 0.0",
     r"^gear_pair\.pinion\.mass = 0\.0: must be > 0 kg$"),
    ("inertia-negative", PLANETARY_TOML, "inertia = 3.6", "inertia = -3.6",
     r"^planetary_stage\.planet\.inertia = -3\.6: must be > 0"),
    ("carrier-inertia-zero", PLANETARY_TOML, "inertia = 110.0", "inertia = 0",
     r"^planetary_stage\.carrier\.inertia = 0\.0: must be > 0"),
    ("teeth-zero", GEAR_PAIR_TOML, "teeth = 40", "teeth = 0",
     r"^gear_pair\.wheel\.teeth = 0: must be an integer >= 3"),
    ("teeth-float", GEAR_PAIR_TOML, "teeth = 40", "teeth = 40.5",
     r"^gear_pair\.wheel\.teeth: expected an integer, got float 40\.5"),
    ("module-negative", GEAR_PAIR_TOML, "module = 0.004", "module = -0.004",
     r"^gear_pair\.pinion\.module = -0\.004: must lie in \(0, 1\] m"),
    ("module-zero", PLANETARY_TOML, "module = 0.010", "module = 0",
     r"^planetary_stage\.sun\.module = 0\.0: must lie in \(0, 1\] m"),
    ("mesh-stiffness-negative", GEAR_PAIR_TOML, "mesh_stiffness = 2.0e8", "mesh_stiffness = -2e8",
     r"^gear_pair\.mesh_stiffness = -200000000\.0: must be >= 0 N/m"),
    ("mesh-stiffness-table-negative", PLANETARY_TOML, "ring_planet = 5.0e9", "ring_planet = -5e9",
     r"^planetary_stage\.mesh_stiffness\.ring_planet = -5000000000\.0: must be >= 0"),
    ("bearing-stiffness-negative", GEAR_PAIR_TOML, "y = 2.0e8", "y = -2.0e8",
     r"^gear_pair\.bearing\.stiffness\.y = -200000000\.0: must be >= 0"),
    ("planet-bearing-negative", PLANETARY_TOML, "planet_bearing = 2.0e9",
     "planet_bearing = -2.0e9", r"^planetary_stage\.planet_bearing = -2000000000\.0"),
    ("clearance-negative", PLANETARY_TOML, "clearance = { x = 1.0e-4 }",
     "clearance = { x = -1.0e-4 }",
     r"^planetary_stage\.carrier_bearing\.clearance\.x = -0\.0001: must be >= 0"),
    ("backlash-negative", GEAR_PAIR_TOML, "backlash = 1.0e-4", "backlash = -1.0e-4",
     r"^gear_pair\.backlash = -0\.0001: must be >= 0 m"),
    ("planetary-backlash-negative", PLANETARY_TOML, "backlash = 3.0e-4", "backlash = -3.0e-4",
     r"^planetary_stage\.backlash = -0\.0003: must be >= 0 m"),
    ("lin-parker-backlash-negative", LIN_PARKER_TOML, "backlash = 1.0e-4", "backlash = -1e-4",
     r"^lin_parker_stage\.backlash = -0\.0001: must be >= 0 m"),
    ("string-for-number", GEAR_PAIR_TOML, "inertia = 1.6e-2", 'inertia = "1.6e-2"',
     r"^gear_pair\.wheel\.inertia: expected a number in kg m\^2, got str '1\.6e-2'"),
    ("boolean-for-number", PLANETARY_TOML, "mass = 620.0", "mass = true",
     r"^planetary_stage\.ring\.mass: expected a number in kg, got bool True"),
    ("boolean-for-angle", GEAR_PAIR_TOML, "helix_angle_deg = 10.0", "helix_angle_deg = false",
     r"^gear_pair\.pinion\.helix_angle_deg: expected a number in deg, got bool False"),
    ("lin-parker-mass-negative", LIN_PARKER_TOML, "sun = 0.4", "sun = -0.4",
     r"^lin_parker_stage\.mass\.sun = -0\.4: must be > 0 kg"),
    ("lin-parker-unknown-key", LIN_PARKER_TOML, "ring_planet = 5.0e8 }",
     "ring_planet = 5.0e8, carrier_planet = 1.0 }",
     r"^lin_parker_stage\.mesh\.carrier_planet: unknown key; allowed: sun_planet, ring_planet"),
    ("unknown-key", GEAR_PAIR_TOML, "face_width = 0.04", "face_widht = 0.04",
     r"^gear_pair\.pinion\.face_widht: unknown key; allowed: teeth, module, pressure_angle_deg"),
    ("angle-without-deg", GEAR_PAIR_TOML, "helix_angle_deg = 10.0", "helix_angle = 0.17",
     r"^gear_pair\.pinion\.helix_angle: unknown key \(angles are given in degrees: "
     r"helix_angle_deg\)"),
    ("unknown-section", GEAR_PAIR_TOML, "[gear_pair.wheel]", "[wheel]",
     r"^wheel: unknown section for type = 'gear_pair'; allowed: model, gear_pair, rating$"),
    ("ring-teeth", PLANETARY_TOML, "teeth = 99", "teeth = 98",
     r"^planetary_stage\.ring\.teeth = 98: ring teeth must equal sun \+ 2 \* planet "
     r"\(21 \+ 2 \* 39 = 99\), or give the stage's centre_distance \(profile-shifted "
     r"gears\)$"),
    ("unequal-spacing", PLANETARY_TOML, "n_planets = 3", "n_planets = 7",
     r"^planetary_stage\.n_planets = 7: planets cannot be equally spaced, .*give "
     r"planet_angles_deg$"),
    ("planet-angles-count", LIN_PARKER_TOML, "[0.0, 90.0, 180.0, 270.0]", "[0.0, 180.0]",
     r"^lin_parker_stage\.planet_angles_deg: gives 2 angles for 4 planets"),
    ("missing-model-section", GEAR_PAIR_TOML, '[model]\nname = "pair"\ntype = "gear_pair"',
     "[misc]", r"^model: missing section \[model\]"),
    ("missing-builder-section", '[model]\ntype = "lin_parker_stage"\n', "", "",
     r"^lin_parker_stage: missing section \[lin_parker_stage\] \(required for type = "
     r"'lin_parker_stage'\)$"),
    ("misnamed-builder-section", LIN_PARKER_TOML, "[lin_parker_stage]", "[lin_parker]",
     r"^lin_parker: unknown section for type = 'lin_parker_stage'"),
    ("missing-gear-table", GEAR_PAIR_TOML[:GEAR_PAIR_TOML.index("[gear_pair.wheel]")], "", "",
     r"^gear_pair\.wheel: missing: required key \(table\)$"),
    ("missing-key", PLANETARY_TOML, "mass = 1000.0\n", "",
     r"^planetary_stage\.carrier\.mass: missing: required key \(kg\)$"),
    ("missing-type", GEAR_PAIR_TOML, 'type = "gear_pair"', "",
     r"^model\.type: missing: required key"),
    ("unknown-model-type", GEAR_PAIR_TOML, 'type = "gear_pair"', 'type = "gearpair"',
     r"^model\.type = 'gearpair': must be one of 'drivetrain', 'gear_pair'"),
    ("bad-dofs", GEAR_PAIR_TOML, 'dofs = "planar"', 'dofs = "2d"',
     r"^gear_pair\.dofs = '2d': must be one of 'torsional', 'planar', 'full'$"),
    ("pressure-angle-out-of-range", GEAR_PAIR_TOML, "pressure_angle_deg = 20.0",
     "pressure_angle_deg = 60.0",
     r"^gear_pair\.pinion\.pressure_angle_deg = 60\.0 deg: must lie in \[5\.72958e-05, 45\) "
     r"deg$"),
    ("speed-range", GEAR_PAIR_TOML, "[0.0, 3000.0]", "[3000.0, 0.0]",
     r"^model\.speed_range_rpm = \[3000\.0, 0\.0\]: high must exceed low"),
    ("rated-speed-outside-range", GEAR_PAIR_TOML, "rated_speed_rpm = 1500.0",
     "rated_speed_rpm = 4000.0", r"^model\.rated_speed_rpm = 4000\.0: outside speed_range_rpm"),
    ("support-table-shape", PLANETARY_TOML, "stiffness = { x = 5.0e9, y = 5.0e9, theta = 3.0e9 }",
     "stiffness = 5.0e9",
     r"^planetary_stage\.ring_support\.stiffness: expected a table keyed by direction .*"
     r"got float 5000000000\.0"),
    ("syntax-error", GEAR_PAIR_TOML, "backlash = 1.0e-4", "backlash 1.0e-4",
     r"^<string>: TOML syntax error at line 11, column \d+: "),
    ("duplicate-key", GEAR_PAIR_TOML, "backlash = 1.0e-4", "backlash = 1.0e-4\nbacklash = 0.0",
     r"^<string>: TOML syntax error at line 12, column \d+: Cannot overwrite a value"),
]


@pytest.mark.parametrize("base, old, new, pattern", [c[1:] for c in TOML_CASES],
                         ids=[c[0] for c in TOML_CASES])
def test_toml_bad_input(base, old, new, pattern):
    with pytest.raises(ModelError, match=pattern):
        loads(_edit(base, old, new))


DRIVETRAIN_CASES = [
    ("ring-teeth-in-stage", "teeth = 99 ", "teeth = 98 ",
     r"^stages\[0\]\.ring\.teeth = 98: ring teeth must equal sun \+ 2 \* planet "
     r"\(21 \+ 2 \* 39 = 99\)"),
    ("stage-type", 'type = "parallel"', 'type = "helical"',
     r"^stages\[1\]\.type = 'helical': must be one of 'planetary', 'parallel'"),
    ("coupling-negative", "coupling_stiffness = 6.0e6", "coupling_stiffness = -6.0e6",
     r"^stages\[1\]\.coupling_stiffness = -6000000\.0: must be >= 0 N m/rad"),
    ("suspension-negative", "stiffness = { x = 2.0e7,", "stiffness = { x = -2.0e7,",
     r"^suspension\.stiffness\.x = -20000000\.0: must be >= 0"),
    ("missing-suspension", "[suspension]", "[suspension_]", r"^suspension_: unknown section"),
    ("main-shaft-string", "stiffness = 4.8e7", 'stiffness = "4.8e7"',
     r"^main_shaft\.stiffness: expected a number in N m/rad, got str '4\.8e7'"),
]


@pytest.mark.parametrize("old, new, pattern", [c[1:] for c in DRIVETRAIN_CASES],
                         ids=[c[0] for c in DRIVETRAIN_CASES])
def test_drivetrain_bad_input(old, new, pattern):
    with pytest.raises(ModelError, match=pattern):
        loads(_edit(MODEL_600KW.read_text(), old, new))


def test_drivetrain_missing_hss_shaft():
    text = MODEL_600KW.read_text()
    start = text.index("[hss_shaft]")
    text = text[:start] + text[text.index("[housing]"):]
    with pytest.raises(ModelError, match=r"^hss_shaft: missing section \[hss_shaft\]"):
        loads(text)
