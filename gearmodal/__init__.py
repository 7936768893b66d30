"""gearmodal: wind-turbine gearbox dynamics.

Floating-frame gear models (torsional, planar or full DOF per component), assembly of the
piecewise-linear contact model, modal and Campbell analysis. SI units throughout.
"""

from .assembly import Assembly, assemble
from .errors import ModelError
from .model import (
    DOF_LEVELS,
    Bearing,
    Body,
    Frame,
    Gear,
    Mesh,
    Model,
    RigidBody,
    Shaft,
    drivetrain,
    gear_pair,
    lin_parker_stage,
    parallel_stage,
    planetary_stage,
)

__version__ = "0.1.0"

__all__ = ["DOF_LEVELS", "Assembly", "Bearing", "Body", "Frame", "Gear", "Mesh", "Model",
           "ModelError", "RigidBody", "Shaft", "assemble", "drivetrain", "gear_pair",
           "lin_parker_stage", "parallel_stage", "planetary_stage"]
