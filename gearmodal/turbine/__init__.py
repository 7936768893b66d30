"""The turbine side (DESIGN 2.5): wind, rotor aerodynamics, generator, start-up and operation.

>>> import gearmodal as gm
>>> tb = gm.turbine.load_turbine("studies/turbines/600kw_turbine.toml")
>>> run = gm.turbine.simulate_turbine(tb, gm.turbine.Wind(mean_speed=10.0), 20.0)
>>> 10.0 < run.cut_in_time < 14.0
True
"""

from .airfoil import Airfoil
from .drivetrain import DrivetrainResult, simulate_drivetrain
from .generator import InductionGenerator
from .rotor import LOAD_COLUMNS, Rotor
from .turbine import Turbine, TurbineResult, load_turbine, simulate_turbine
from .wind import Wind

__all__ = ["LOAD_COLUMNS", "Airfoil", "DrivetrainResult", "InductionGenerator", "Rotor",
           "Turbine", "TurbineResult", "Wind", "load_turbine", "simulate_drivetrain",
           "simulate_turbine"]
