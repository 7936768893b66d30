"""gearmodal: wind-turbine gearbox dynamics.

Floating-frame gear models (torsional, planar or full DOF per component), assembly of the
piecewise-linear contact model, modal and Campbell analysis. SI units throughout.
"""

from . import auto, examples, io, sharing, turbine  # noqa: F401  (gm.io.read_loads, ...)
from .assembly import Assembly, assemble
from .auto import FidelityChoice
from .auto import choose as choose_fidelity
from .campbell import CampbellResult, campbell
from .coupling import (
    Constraint,
    Coupled,
    CoupledAssembly,
    Joint,
    LinearConstraint,
    LinearSystem,
    ModelSystem,
    System,
)
from .errors import GearmodalError, ModelError, SolveError, StoreError
from .integrate import Harmonic, SimulationResult, simulate
from .integrate.stepper import Drive, SpeedTorque, Stepper
from .modal import ModalResult, modal
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
    register_element,
)
from .model.components import G_STANDARD
from .model.dump import dump, dumps
from .model.toml_io import load, loads
from .precision import FidelityTable, fidelity
from .rating import Rating, rate
from .sharing import static_load_sharing
from .static import Equilibrium, balance, equilibrium
from .studies import sweep

__version__ = "0.1.0"

__all__ = ["DOF_LEVELS", "Assembly", "Bearing", "Body", "CampbellResult", "Constraint", "Coupled",
           "CoupledAssembly", "Drive", "Equilibrium", "FidelityChoice", "FidelityTable", "Frame",
           "GearmodalError", "Joint", "LinearConstraint", "LinearSystem", "ModelSystem", "System",
           "Gear", "Harmonic", "Mesh", "ModalResult", "Model", "ModelError", "RigidBody", "Shaft",
           "SolveError", "StoreError",
           "SimulationResult", "SpeedTorque", "Stepper", "simulate",
           "assemble", "balance", "campbell", "choose_fidelity", "drivetrain", "equilibrium",
           "gear_pair",
           "lin_parker_stage", "load", "loads", "dump", "dumps", "modal", "parallel_stage",
           "planetary_stage", "register_element", "static_load_sharing", "G_STANDARD",
           "sweep", "fidelity", "Rating", "rate"]
