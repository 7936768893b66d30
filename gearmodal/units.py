"""The SI unit of a named quantity of a model: a coordinate, its velocity, a load, a force
column (what the stepper, the FMU and result frames name), in the FMI 2.0 spelling
(``"N.m"``, ``"rad/s"``)."""

from __future__ import annotations

from .model.components import LOCALNAMES
from .model.model import LOAD_KINDS, Model

#: FMI 2.0 unit definitions (section 2.2.2): SI base-unit exponents and factor of each unit
#: used here
BASE_UNITS = {
    "m": {"m": 1}, "rad": {"rad": 1}, "m/s": {"m": 1, "s": -1}, "rad/s": {"rad": 1, "s": -1},
    "N": {"kg": 1, "m": 1, "s": -2}, "N.m": {"kg": 1, "m": 2, "s": -2}, "s": {"s": 1},
    "m/s2": {"m": 1, "s": -2}, "rpm": {"rad": 1, "s": -1, "factor": 0.10471975511965977},
}


def coordinate_units(model: Model) -> dict[str, str]:
    """``{DOF name: "m" or "rad"}``: translations and scaled rotations (``u``) in m."""
    out = {}
    for body in model.bodies.values():
        for i, name in zip(body.local_indices, body.coordinates, strict=True):
            rot = i >= 3 and not (LOCALNAMES[i] == "theta" and body.rotation_scale is not None)
            out[f"{body.name}.{name}"] = "rad" if rot else "m"
    return out


def load_unit(name: str) -> str:
    """A load's unit: forces N, moments and torques N m, ``gravity`` m/s^2."""
    if name == "gravity":
        return "m/s2"
    kind = name.rsplit(".", 1)[-1]
    if kind == "force_u":
        return "N"
    if kind not in LOAD_KINDS:
        raise KeyError(name)
    return "N" if LOAD_KINDS[kind] < 3 else "N.m"


def force_unit(label: str) -> str:
    """A force column's unit: a mesh flank's or a spring's translation N, a spring's rotation
    N m."""
    part = label.rsplit(".", 1)[-1]
    return "N.m" if part in LOCALNAMES[3:] else "N"


def output_units(model: Model, names) -> dict[str, str]:
    """``{name: unit}`` of stepper outputs ``names``: coordinates, ``.velocity``, force
    columns, ``drive.torque``."""
    coords = coordinate_units(model)
    out = {}
    for name in names:
        if name in coords:
            out[name] = coords[name]
        elif name.endswith(".velocity") and name[:-9] in coords:
            out[name] = coords[name[:-9]] + "/s"
        elif name == "drive.torque":
            out[name] = "N.m"
        else:
            out[name] = force_unit(name)
    return out
