"""The ``[rating]`` table of a model file: what ISO 6336 and ISO 281 need beyond the dynamics.

The dynamic model has no use for a gear's profile shift, its material's endurance limits, the
oil's viscosity or a bearing's load ratings; the ratings (:mod:`gearmodal.rating`) do. They
sit in the model file's optional ``[rating]`` table, read and checked here (every key with its
unit, range and default: the file-format reference lists them), kept on the model as
``model.rating`` (a plain dict in SI units) and written back by ``gm.dumps``. They change no
matrix, so a scene's identity leaves them out.

Defaults: case-hardened steel of ISO 6336-5 quality MQ (sigma_Hlim 1500 MPa, sigma_Flim
500 MPa), ground flanks (R_z 4.8 um), ISO 1328 grade 6, an ISO VG 320 mineral oil at 70 deg C,
ISO 281's "normal cleanliness" of large bearings (e_C 0.5) and 90 % reliability, a 20-year life
(175 200 h).
"""

from __future__ import annotations

import copy
import fnmatch

from ..errors import ModelError
from .schema import Field, Table

_POS = {"low": 0.0, "low_open": True}
GEAR_RATING = Table("rating.gears.<gear>", (
    Field("profile_shift", "number", low=-1.5, high=1.5, default=0.0,
          doc="profile shift coefficient x (ISO 21771; a ring with its negative tooth number)"),
    Field("tip_alteration", "number", "m", low=-0.1, high=0.1, default=0.0,
          doc="change of the tip radius (negative: shortened)"),
    Field("dedendum", "number", low=1.0, high=1.6, default=1.25,
          doc="basic rack dedendum h_fP / m_n (ISO 53 profile A: 1.25)"),
    Field("root_radius", "number", low=0.1, high=0.5, default=0.38,
          doc="basic rack root radius rho_fP / m_n (ISO 53 profile A: 0.38)"),
    Field("sigma_Hlim", "number", "Pa", **_POS, doc="contact endurance limit (default the "
          "table's)"),
    Field("sigma_Flim", "number", "Pa", **_POS, doc="bending endurance limit (default the "
          "table's)")),
    "One gear's rating data (a table per gear body name; the planets share `<stage>.planet`).")
BEARING_RATING = Table("rating.bearings.<bearing>", (
    Field("C", "number", "N", **_POS, default=None, doc="basic dynamic load rating"),
    Field("C_u", "number", "N", **_POS, doc="fatigue load limit (default C / 10, a typical "
          "ratio of roller bearings' catalogue values)"),
    Field("pitch_diameter", "number", "m", **_POS, doc="pitch diameter d_m of the rolling "
          "elements (ISO 281's nu_1)"),
    Field("kind", "choice", choices=("roller", "ball"), default="roller",
          doc="rolling elements (life exponent 10/3 or 3)"),
    Field("label", "string", doc="what the bearing is (designation, source)")),
    "One bearing's rating data (a table per bearing element name; `*` matches, e.g. "
    "`stage1.planet*_bearing`).")
RATING = Table("rating", (
    Field("input_torque", "number", "N m", **_POS,
          doc="the nominal torque at the model's input that `gearmodal rate` rates at"),
    Field("life_h", "number", "h", **_POS, default=175200.0, doc="required life"),
    Field("application_factor", "number", low=1.0, high=3.0, default=1.0,
          doc="K_A on the given torque (1.0 for a load spectrum; ~1.25 on a nominal torque)"),
    Field("k_gamma", "any", default="standard",
          doc="planets' mesh load factor: `standard` (IEC 61400-4: 1.1 for 3 planets, 1.25 "
              "for 4, 1.35 for 5, 1.44 for 6, 1.47 for 7), `model` (the static equilibrium's "
              "worst planet over the mean) or a number"),
    Field("accuracy_grade", "number", low=1.0, high=12.0, default=6.0,
          doc="ISO 1328-1:1995 grade of every gear"),
    Field("lubricant_viscosity_40", "number", "mm^2/s", **_POS, default=320.0,
          doc="oil viscosity at 40 deg C (ISO VG 320)"),
    Field("lubricant_viscosity_100", "number", "mm^2/s", **_POS, default=24.0,
          doc="oil viscosity at 100 deg C (a mineral VG 320)"),
    Field("oil_temperature_C", "number", "deg C", low=-40.0, high=150.0, default=70.0,
          doc="bearings' operating temperature (their viscosity ratio)"),
    Field("long_life", "choice", choices=("reference", "optimum"), default="reference",
          doc="life factors beyond the knee: to 0.85 at 1e10 cycles, or 1.0"),
    Field("sigma_Hlim", "number", "Pa", **_POS, default=1.5e9,
          doc="contact endurance limit (ISO 6336-5, case-hardened MQ)"),
    Field("sigma_Flim", "number", "Pa", **_POS, default=5.0e8,
          doc="bending endurance limit (ISO 6336-5, case-hardened MQ)"),
    Field("flank_Rz", "number", "m", **_POS, default=4.8e-6, doc="flank roughness R_z"),
    Field("root_Rz", "number", "m", **_POS, default=10.0e-6, doc="tooth root roughness R_z"),
    Field("tip_relief", "number", "m", low=0.0, default=0.0, doc="tip relief C_a (in K_v)"),
    Field("contamination", "number", low=0.0, high=1.0, low_open=True, default=0.5,
          doc="ISO 281 contamination factor e_C"),
    Field("reliability", "number", low=90.0, high=99.95, default=90.0,
          doc="bearing reliability, percent (ISO 281's a1)"),
    Field("gears", "table", default={}, doc="per gear: a `rating.gears.<gear>` table"),
    Field("bearings", "table", default={}, doc="per bearing: a `rating.bearings.<bearing>` "
          "table; bearings not listed are not rated")),
    "The ratings' data (optional; `gearmodal rate`, `gm.rate`).")


def read(path: str, value) -> dict:
    """The ``[rating]`` table checked, with its defaults: a dict in SI units."""
    out = RATING.read(path, value)
    k = out["k_gamma"]
    if not (k in ("standard", "model") or (isinstance(k, (int, float))
                                           and not isinstance(k, bool) and 1.0 <= k <= 3.0)):
        raise ModelError(f"{path}.k_gamma", f"= {k!r}: 'standard', 'model' or a number in "
                         "[1, 3]")
    out["gears"] = {name: GEAR_RATING.read(f"{path}.gears.{name}", t)
                    for name, t in out["gears"].items()}
    out["bearings"] = {name: BEARING_RATING.read(f"{path}.bearings.{name}", t)
                       for name, t in out["bearings"].items()}
    for name, t in out["bearings"].items():
        if "C" not in t:
            raise ModelError(f"{path}.bearings.{name}.C", "missing: required key (N)")
    return out


def write(rating: dict) -> dict:
    """The file table of a ``model.rating`` dict (defaults left out)."""
    top = RATING.write({k: v for k, v in rating.items() if k not in ("gears", "bearings")})
    if rating.get("gears"):
        top["gears"] = {n: GEAR_RATING.write(t) or {} for n, t in rating["gears"].items()}
    if rating.get("bearings"):
        top["bearings"] = {n: BEARING_RATING.write(t) for n, t in rating["bearings"].items()}
    return top


def check_names(rating: dict, model) -> None:
    """Every gear named is a gear body (or a stage's planets, ``<stage>.planet``) and every
    bearing pattern matches a bearing element of ``model``."""
    for name in rating.get("gears", {}):
        if name not in model.bodies and not any(b.startswith(name) for b in model.bodies):
            raise ModelError(f"rating.gears.{name}", "no such gear body; bodies: "
                             + ", ".join(b for b in model.bodies)[:300])
    for pattern in rating.get("bearings", {}):
        if not fnmatch.filter(model.bearings, pattern):
            raise ModelError(f"rating.bearings.{pattern}", "matches no bearing; bearings: "
                             + ", ".join(model.bearings)[:300])


def defaults() -> dict:
    """The ``[rating]`` defaults (a model without the table is rated with these)."""
    return copy.deepcopy(read("rating", {}))
