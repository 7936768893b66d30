"""Model layer: declarative components, builders, validation and TOML loading."""

from .builders import drivetrain, gear_pair, lin_parker_stage, parallel_stage, planetary_stage
from .components import DOF_LEVELS, Bearing, Body, Frame, Gear, Mesh, RigidBody, Shaft
from .model import Model

__all__ = ["DOF_LEVELS", "Bearing", "Body", "Frame", "Gear", "Mesh", "Model", "RigidBody",
           "Shaft", "drivetrain", "gear_pair", "lin_parker_stage", "parallel_stage",
           "planetary_stage"]
