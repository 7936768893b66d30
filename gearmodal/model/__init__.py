"""Model layer: declarative components, builders, validation and TOML loading."""

from .bearing import Bearing, Shaft
from .builders import drivetrain, gear_pair, lin_parker_stage, parallel_stage, planetary_stage
from .components import DOF_LEVELS, Body, Frame, Gear, RigidBody
from .mesh import Mesh
from .model import Model, register_element

__all__ = ["DOF_LEVELS", "Bearing", "Body", "Frame", "Gear", "Mesh", "Model", "RigidBody",
           "Shaft", "drivetrain", "gear_pair", "lin_parker_stage", "parallel_stage",
           "planetary_stage", "register_element"]
