"""gm.dumps / gm.dump: every shipped model and every builder written as a components file and
read back assembles to exactly the same matrices and contact rows (issue 20)."""

import glob
import math

import numpy as np
import pytest

import gearmodal as gm
from gearmodal import examples
from gearmodal.errors import ModelError

#: the gearbox models (the elastic turbine's file, an [elastic_turbine] table, is no Model)
SHIPPED = sorted(p for p in glob.glob("studies/models/*.toml")
                 if "[elastic_turbine]" not in open(p).read())
POLYGON = {"stiffness": {"x": 1e8, "y": 1e8}, "damping": {"x": 1e3, "y": 1e3},
           "clearance": {"x": 1e-4, "y": 1e-4}, "clearance_shape": "polygon", "facets": 8,
           "ramps": 2}
ROUND = {**POLYGON, "clearance_shape": "round"}
FULL = {"stiffness": {"x": 1e9, "y": 1e9, "z": 5e8, "rx": 2e7, "ry": 2e7}}


def _hand_built():
    """A model built component by component: a plain Body, renamed coordinates, a turning
    frame, a bearing with turned axes, a shaft and a group."""
    m = gm.Model("hand", input="hub")
    m.add(gm.Frame("spin", 1.0))
    m.add(gm.RigidBody(name="hub", mass=10.0, inertia=1.0, dofs="planar", frame="spin",
                       coordinate_names={"x": "zeta"}))
    m.add(gm.Body(name="disk", mass=2.0, inertia=0.1, position=(0.3, 0.1, 0.0),
                  orientation=0.7, speed_ratio=-2.0, dofs="planar", frame="spin"))
    m.add(gm.Bearing("hub_support", "hub", None, stiffness={"x": 1e7, "y": 2e7},
                     clearance={"y": 1e-5}, axes_angle=0.25, at=(0.0, 0.1)))
    m.add(gm.Bearing("disk_pin", "disk", "hub", stiffness={"x": 3e7, "y": 3e7},
                     damping={"x": 10.0}))
    m.add(gm.Shaft("drive", "hub", "disk", 1e4, 2.0))
    m.groups["spinning"] = ["hub", "disk"]
    return m


BUILT = {
    "pair torsional": lambda: examples.gear_pair(),
    "pair planar helical": lambda: examples.gear_pair("planar", helix_angle=0.2,
                                                      mesh_damping=50.0),
    "pair full": lambda: examples.gear_pair("full", helix_angle=0.2, bearing_stiffness=FULL),
    "pair alternating": lambda: examples.gear_pair(mesh_alternation={"phase": 0.3}),
    "stage planar": lambda: examples.planetary_stage(backlash=2e-4),
    "stage torsional (pinned)": lambda: examples.planetary_stage("torsional"),
    "stage full": lambda: examples.planetary_stage(
        "full", FULL, gears=examples.planetary_gears(helix_angle=0.1, face_width=0.2)),
    "stage polygon clearance": lambda: examples.planetary_stage(carrier_bearing=POLYGON),
    "stage round clearance": lambda: examples.planetary_stage(carrier_bearing=ROUND),
    "stage alternating": lambda: examples.planetary_stage(mesh_alternation=True),
    "lin parker": lambda: gm.lin_parker_stage(
        4, mass={"carrier": 5.43, "ring": 2.35, "sun": 0.4, "planet": 0.66},
        inertia_over_r2={"carrier": 6.29, "ring": 3.0, "sun": 0.39, "planet": 0.61},
        bearing={"carrier": 1e8, "ring": 1e8, "sun": 1e8, "planet": 1e8},
        torsional={"carrier": 0.0, "ring": 1e9, "sun": 0.0},
        mesh={"sun_planet": 5e8, "ring_planet": 5e8}, pressure_angle=math.radians(24.6),
        planet_angles=[0.0, math.pi / 2, math.pi, 1.5 * math.pi], backlash=1e-4),
    "parallel": lambda: gm.parallel_stage(
        *examples.planetary_gears()[:2], mesh_stiffness=1e9, backlash=1e-4,
        position=(0.1, 0.2), angle=0.4, gear_bearing=1e9, pinion_bearing=2e9),
    "hand built": _hand_built,
}


def _same_assembly(a, b):
    assert a.dof_names == b.dof_names and a.load_names == b.load_names
    for name in ("M", "C", "K", "G", "K_cent", "f_cent", "B"):
        x, y = getattr(a, name), getattr(b, name)
        assert x.shape == y.shape and np.array_equal(x, y), name
    for part in ("contacts", "springs", "round"):
        ca, cb = getattr(a, part), getattr(b, part)
        assert (ca is None) == (cb is None), part
        if ca is None:
            continue
        assert (ca.element, ca.contact, ca.kind) == (cb.element, cb.contact, cb.kind), part
        for f in ("W", "offset", "stiffness", "damping", "nominal"):
            assert np.array_equal(getattr(ca, f), getattr(cb, f)), (part, f)
        assert np.array_equal(ca.angle, cb.angle, equal_nan=True), (part, "angle")
        va, vb = ca.variation, cb.variation
        assert (va is None) == (vb is None)
        if va is not None:
            for f in ("rows", "rate", "phase", "double", "k_single", "k_double"):
                assert np.array_equal(getattr(va, f), getattr(vb, f)), (part, f)


def _round_trip(m):
    text = gm.dumps(m)
    again = gm.loads(text)
    for azimuth in (0.0, 0.3):  # 0.3: the turning frames' geometry away from the start
        _same_assembly(m.assemble(azimuth=azimuth), again.assemble(azimuth=azimuth))
    assert gm.dumps(again) == text  # the text is canonical: a model's identity
    for attr in ("name", "input", "output", "gear_ratio", "rated_speed_rpm",
                 "speed_range_rpm", "groups"):
        assert getattr(again, attr) == getattr(m, attr), attr
    return text


@pytest.mark.parametrize("path", SHIPPED)
def test_every_shipped_model_round_trips_to_the_same_matrices(path):
    assert SHIPPED, "no shipped models found"
    _round_trip(gm.load(path))


@pytest.mark.parametrize("name", list(BUILT))
def test_every_builder_round_trips_to_the_same_matrices(name):
    _round_trip(BUILT[name]())


def test_drivetrain_round_trips_with_its_prefixed_names():
    text = _round_trip(gm.load("studies/models/600kw.toml"))
    assert 'name = "stage1.sun"' in text  # dotted names are a model's, kept as they are


def test_dump_writes_a_file_gm_load_reads(tmp_path):
    m = examples.planetary_stage()
    path = gm.dump(m, tmp_path / "stage.toml")
    _same_assembly(gm.load(path).assemble(), m.assemble())


def test_a_components_file_accepts_degrees_and_names_its_fields_in_errors():
    text = gm.dumps(examples.gear_pair())
    deg = text.replace("pressure_angle = 0.3490658503988659", "pressure_angle_deg = 20.0")
    assert deg != text
    assert gm.loads(deg).bodies["pinion"].pressure_angle == math.radians(20.0)
    cases = [
        (text.replace("mass = 1.0", "mass = -1.0"),
         r"bodies\[0\]\.mass = -1\.0: must be > 0 kg"),
        (text.replace("mass = 1.0", "mas = 1.0"), r"bodies\[0\]\.mas: unknown key"),
        (text.replace('kind = "gear"', 'kind = "cog"', 1), r"bodies\[0\]\.kind = 'cog'"),
        (text.replace('gear_b = "wheel"', 'gear_b = "whel"'),
         r"meshes\[0\]\.gear_b = 'whel'"),
        (deg.replace("pressure_angle_deg = 20.0", "pressure_angle_deg = 50.0", 1),
         r"bodies\[0\]\.pressure_angle_deg = 50\.0 deg: must lie in \[5\.72958e-05, 45\) deg"),
        (text.replace("teeth = 20", "teeth = 2.5"),
         r"bodies\[0\]\.teeth: expected an integer"),
        (text.replace('name = "wheel"', 'name = "pinion"'), r"bodies\[1\]\.name"),
    ]
    for bad, pattern in cases:
        assert bad != text, pattern
        with pytest.raises(ModelError, match=pattern):
            gm.loads(bad)


def test_dumps_refuses_what_is_not_a_model():
    with pytest.raises(TypeError, match="gm.Model"):
        gm.dumps(examples.gear_pair().assemble())
