"""Each component's types and ranges are stated once, in its ``SCHEMA``: the constructor (the
API) and the model file refuse the same values with the same bound (issue 37)."""

import math

import pytest

import gearmodal as gm
from gearmodal import Bearing, Gear, Mesh, ModelError, RigidBody
from gearmodal.model import file_schema as fs
from gearmodal.model import spec

BASE = {
    Mesh: dict(name="m", gear_a="a", gear_b="b", stiffness=1e8),
    Bearing: dict(name="brg", a="a", stiffness={"x": 1e8, "y": 1e8}),
    Gear: dict(name="g", teeth=20, module=0.01, pressure_angle=0.35, mass=1.0, inertia=0.1),
    RigidBody: dict(name="r", mass=1.0, inertia=1.0),
}


def _outside(f):
    """Values just outside each bound of field ``f`` (and the bound itself where it is open)."""
    out = []
    for bound, is_open, sign in ((f.low, f.low_open, -1.0), (f.high, f.high_open, 1.0)):
        if bound is None:
            continue
        if f.type == "integer":
            out.append(int(bound) + int(sign))
        else:
            out.append(bound if is_open else bound + sign * max(abs(bound), 1.0) * 1e-9)
    return out


CASES = [(cls, f, bad) for cls in BASE for f in cls.SCHEMA.fields
         if f.type in ("number", "angle", "integer") for bad in _outside(f)
         if f.key != "side"]  # (side is +1 or -1: a set, checked on its own)


@pytest.mark.parametrize("cls, f, bad", CASES,
                         ids=[f"{c.__name__}.{f.key}={b!r}" for c, f, b in CASES])
def test_the_api_and_the_file_refuse_the_same_values(cls, f, bad):
    base = BASE[cls]
    with pytest.raises(ModelError) as api:
        cls(**{**base, f.key: bad})
    assert api.value.field == f"{base['name']}.{f.key}"
    with pytest.raises(ModelError):
        f.read("file.key", bad)
    inside = f.low if f.low is not None and not f.low_open else None
    if inside is not None and f.key not in ("inertia_diametral",):
        cls(**{**base, f.key: inside})  # the closed bound itself is allowed by both
        f.read("file.key", inside)


@pytest.mark.parametrize("key", ["stiffness", "damping", "clearance"])
def test_a_bearing_refuses_a_negative_direction_as_its_file_does(key):
    f = Bearing.SCHEMA.by_key()[key]
    value = {"x": 1e8, "y": -1.0} if key == "stiffness" else {"x": -1.0}
    with pytest.raises(ModelError, match=rf"brg\.{key}\.[xy] = -1\.0: must be >= 0"):
        Bearing(**{**BASE[Bearing], key: value})
    with pytest.raises(ModelError, match=r"must be >= 0"):
        f.read("file.key", value)


def test_an_angle_given_in_degrees_gets_the_radians_hint():
    with pytest.raises(ModelError, match=r"g\.pressure_angle = 20\.0 rad: .*radians\(20\)"):
        Gear(**{**BASE[Gear], "pressure_angle": 20})
    m = Mesh(**{**BASE[Mesh], "pressure_angle": math.radians(20), "base_radii": [0.1, 0.2]})
    assert m.base_radii == (0.1, 0.2)  # a vector is held as a tuple whatever was given


# -- builders: each parameter declared once, in the signature ---------------------------------
def _stage_args():
    sun = Gear(21, 0.01, math.radians(20), mass=80.0, inertia=0.45)
    planet = Gear(39, 0.01, math.radians(20), mass=140.0, inertia=3.6)
    ring = Gear(99, 0.01, math.radians(20), mass=620.0, inertia=190.0, internal=True)
    return {gm.planetary_stage: dict(sun=sun, planet=planet, ring=ring, carrier_mass=1000.0,
                                     carrier_inertia=110.0, mesh_stiffness=1e9),
            gm.parallel_stage: dict(gear=Gear(82, 0.01, math.radians(20), mass=400.0,
                                              inertia=30.0),
                                    pinion=Gear(23, 0.01, math.radians(20), mass=20.0,
                                                inertia=0.2), mesh_stiffness=1e9)}


BUILDER_CASES = [(b, e, bad) for b in (gm.planetary_stage, gm.parallel_stage)
                 for e in spec.entries(b) if e.field.type in ("number", "integer")
                 for bad in _outside(e.field)]


@pytest.mark.parametrize("builder, entry, bad", BUILDER_CASES,
                         ids=[f"{b.__name__}.{e.param}={x!r}" for b, e, x in BUILDER_CASES])
def test_a_builder_and_its_file_refuse_the_same_values(builder, entry, bad):
    """The builder's signature states each parameter's range once: the API call and the file
    table made from the signature both refuse a value just outside it."""
    args = _stage_args()[builder]
    with pytest.raises(ModelError) as api:
        builder(**{**args, entry.param: bad})
    assert api.value.field == f"{builder.__name__}.{entry.param}"
    table = {gm.planetary_stage: fs.PLANETARY, gm.parallel_stage: fs.PARALLEL}[builder]
    field = (fs.CARRIER if entry.group else table).by_key()[entry.field.key]
    assert field == entry.field  # the file's field is the signature's
    with pytest.raises(ModelError):
        field.read("file.key", bad)


def test_every_builder_argument_reaches_it_from_its_file():
    """The loader calls each builder with every parameter its file table holds (no
    hand-written list to fall behind the signature)."""
    import inspect

    for builder, table in ((gm.gear_pair, fs.GEAR_PAIR), (gm.planetary_stage, fs.PLANETARY),
                           (gm.parallel_stage, fs.PARALLEL),
                           (gm.lin_parker_stage, fs.LIN_PARKER)):
        keys = {f.key for f in table.fields}
        params = set(inspect.signature(builder).parameters)
        for e in spec.entries(builder):
            assert e.param in params
            assert (e.group or e.field.key) in keys


def test_arrays_and_tuples_are_taken_where_a_list_is_expected():
    """An API caller's numpy array or tuple for a vector argument is its numbers (as before the
    schema checked them)."""
    import numpy as np

    args = _stage_args()[gm.planetary_stage]
    a = gm.planetary_stage(**args, planet_angles=np.radians([0.0, 120.0, 240.0]))
    b = gm.planetary_stage(**args, planet_angles=(0.0, 2 * math.pi / 3, 4 * math.pi / 3))
    assert a.bodies["planet2"].position == pytest.approx(b.bodies["planet2"].position)
    g = gm.parallel_stage(**_stage_args()[gm.parallel_stage], position=np.array([0.1, 0.2]))
    assert g.bodies["gear"].position[:2] == (0.1, 0.2)
    assert RigidBody(name="r", mass=1.0, inertia=1.0, position=np.zeros(3)).position \
        == (0.0, 0.0, 0.0)


def test_what_the_schema_checks_takes_what_the_api_took():
    """Found in review: a body kind with its own schema, an element kind with a stage it does
    not list, a stepper subclass, iterables and numpy booleans, a builder's TypeError."""
    from dataclasses import dataclass

    import numpy as np

    from gearmodal.model.schema import NAME, Field, Table

    @dataclass(eq=False, kw_only=True)
    class Disk(RigidBody):
        radius: float = 0.1

    b = RigidBody.SCHEMA.by_key()
    Disk.SCHEMA = Table("disk", (NAME, b["mass"], b["inertia"], b["dofs"],
                                 Field("radius", "number", "m", default=0.1)))
    assert Disk(name="d", mass=1.0, inertia=0.1).inertia_diametral == 0.05
    angles = [0.0, 2 * math.pi / 3, 4 * math.pi / 3]
    args = _stage_args()[gm.planetary_stage]
    a = gm.planetary_stage(**args, planet_angles=(x for x in angles))
    assert a.bodies["planet3"].position == pytest.approx(
        gm.planetary_stage(**args, planet_angles=angles).bodies["planet3"].position)
    assert Mesh(**BASE[Mesh], internal=np.bool_(True)).internal is True
    with pytest.raises(TypeError, match=r"^planetary_stage\(\) .*'carrier_mass'"):
        gm.planetary_stage(args["sun"], args["planet"], args["ring"], carrier_inertia=1.0,
                           mesh_stiffness=1e9)


def test_a_kind_keeps_its_stage_through_a_merge_and_a_stepper_subclass_its_class():
    from gearmodal.integrate.stepper import Stepper
    from gearmodal.scene import load_scene

    class MyStepper(Stepper):
        pass

    scene = load_scene("studies/scenes/gear_rattle.toml")
    assert type(MyStepper.from_scene(scene)) is MyStepper
    assert type(scene.stepper()) is Stepper

    from dataclasses import dataclass

    from gearmodal.model.element import Element
    from gearmodal.model.schema import NAME, REQUIRED, Field, Table

    @dataclass
    class Stop(Element):  # a kind whose schema does not list its stage
        name: str
        a: str
        stage: str = ""
        SCHEMA = Table("stops", (NAME, Field("a", "name", default=REQUIRED)))

    moved = Stop("s", "pinion").renamed(lambda n: f"stage1.{n}", "stage1")
    assert (moved.name, moved.a, moved.stage) == ("stage1.s", "stage1.pinion", "stage1")


def test_help_shows_a_builders_types_without_its_file_metadata():
    import inspect

    sig = inspect.signature(gm.planetary_stage)
    assert sig.parameters["carrier_mass"].annotation is float
    assert sig.parameters["n_planets"].default == 3
    assert "Annotated" not in str(sig) and "planet_angles" in str(sig)
