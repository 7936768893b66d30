"""The tables of the builder-level model files (``type = "drivetrain"``, ``"gear_pair"``...), as
:class:`~gearmodal.model.schema.Table` s: the key checks of :mod:`gearmodal.model.toml_io` and the
file-format reference page (``docs/file-format.md``) both come from here. A builder's own table
is made from its signature (:mod:`gearmodal.model.spec`), its gear and body tables from the
components' schemas; what is written here is only what no builder or component says (the
``[model]`` table, a stage's keys in a drivetrain's ``[[stages]]``, the model types). The
component tables (``type = "components"``, what :func:`gearmodal.dumps` writes) are each
component's ``SCHEMA``.
"""

from __future__ import annotations

import dataclasses

from . import builders
from . import spec as sp
from .bearing import Bearing
from .components import DOF_LEVELS, Gear, RigidBody
from .schema import REQUIRED, Field, Table

MODEL_TYPES = ("drivetrain", "gear_pair", "planetary_stage", "parallel_stage",
               "lin_parker_stage", "components")
STAGE_TYPES = ("planetary", "parallel")


def _required(f: Field) -> Field:
    return dataclasses.replace(f, default=REQUIRED)


_NONNEG = {"low": 0.0}
# the components' own fields (their types and ranges stated once, in the component's SCHEMA)
_G, _R = Gear.SCHEMA.by_key(), RigidBody.SCHEMA.by_key()
_DOFS = Field("dofs", "choice", choices=DOF_LEVELS, doc="DOF level of the bodies")
_MASS, _INERTIA, _DIAMETRAL = _R["mass"], _R["inertia"], _R["inertia_diametral"]

MODEL = Table("model", (
    Field("type", "choice", choices=MODEL_TYPES, default=REQUIRED,
          doc="which builder makes the model (`components`: see below)"),
    Field("name", "string", doc="model name (default: the file name)"),
    Field("rated_speed_rpm", "number", "rpm", **_NONNEG, doc="rated speed of the input"),
    Field("speed_range_rpm", "vector", "rpm", lengths=(2,), **_NONNEG,
          doc="[low, high] operating range of the input"),
    Field("tilt_deg", "number", "deg", low=-90.0, high=90.0, default=0.0,
          doc="shaft tilt, rotor end up: gravity (the load `gravity`) pulls along "
              "(0, -cos tilt, sin tilt)")),
    "Every model file's `[model]` table.")
GEAR = Table("gear (sun, planet, ring, gear, pinion, wheel)", (
    _G["teeth"], _G["module"], dataclasses.replace(_G["pressure_angle"], degrees=True),
    dataclasses.replace(_G["helix_angle"], degrees=True), _G["face_width"],
    _MASS, _INERTIA, _DIAMETRAL),
    "A gear wheel; the ring is internal by definition.")
BODY = Table("body (rotor, generator, housing)", (
    _MASS, _INERTIA, _DIAMETRAL,
    dataclasses.replace(_DOFS, doc="DOF level (default torsional; the housing: planar)")),
    "A rigid body that is not a gear.")
SHAFT = sp.group_table(builders.drivetrain, "main_shaft", "shaft (main_shaft, hss_shaft)",
                       "A torsional shaft.")
_B = Bearing.SCHEMA.by_key()
SUPPORT = Table("support (a bearing given as a table)", (
    _required(_B["stiffness"]), _B["damping"], _B["clearance"], _B["clearance_shape"],
    _B["facets"], _B["ramps"]),
    "A support given as a table; a number instead is a translational stiffness in N/m on x "
    "and y (and z at `full`). A planet bearing's x/y are radial/tangential.")
#: a stage table's keys that are not its builder's: what a drivetrain's [[stages]] says of it
_STAGE_FILE = (
    Field("type", "choice", choices=STAGE_TYPES, doc="stage type (in `[[stages]]`: required)"),
    Field("name", "name", doc="DOF name prefix in a drivetrain (default `stage<k>`)"),
    Field("coupling_stiffness", "number", "N m/rad", **_NONNEG, limits="stiffness",
          doc="torsional coupling to the previous stage's output (not on the first stage; "
              "default 1e9)"))
PLANETARY = sp.file_table(
    builders.planetary_stage, "planetary stage (`[planetary_stage]` or a `[[stages]]` entry)",
    "A planetary stage, carrier input.", before=_STAGE_FILE,
    groups={"carrier": Field("carrier", "table", default=REQUIRED,
                             doc="the carrier (carrier table)")})
CARRIER = sp.group_table(builders.planetary_stage, "carrier", "carrier",
                         "A planetary stage's carrier.")
PARALLEL = sp.file_table(builders.parallel_stage,
                         "parallel stage (`[parallel_stage]` or a `[[stages]]` entry)",
                         "A parallel (speed-increasing) stage.", before=_STAGE_FILE)
GEAR_PAIR = sp.file_table(builders.gear_pair, "gear_pair", "Two external gears on bearings.")
LIN_PARKER = sp.file_table(builders.lin_parker_stage, "lin_parker_stage",
                          "Lin & Parker's (1999) planar stage in their notation.")
PER_MESH, PER_MESH_ANGLE = builders.PER_MESH, builders.PER_MESH_ANGLE
LIN_PARKER_BODIES, LIN_PARKER_CENTRAL = builders.LIN_PARKER_BODIES, builders.LIN_PARKER_CENTRAL
#: the sections of each model type: section -> required
SECTIONS = {
    "drivetrain": sp.sections(builders.drivetrain, {"model": True},
                              {"stages": True}),
    "gear_pair": {"model": True, "gear_pair": True},
    "planetary_stage": {"model": True, "planetary_stage": True},
    "parallel_stage": {"model": True, "parallel_stage": True},
    "lin_parker_stage": {"model": True, "lin_parker_stage": True},
}


def keys(table: Table) -> dict:
    """``{file key: (required, hint)}`` of a table (the loader's key checks)."""
    return {f.file_key: (f.required, f.hint) for f in table.fields}
