"""Ratings: ISO 6336 gear and ISO 281 bearing ratings from a model's loads.

An analysis of results. It owns the standards' formulas (:mod:`~gearmodal.rating.iso6336`
for the gear pairs, :mod:`~gearmodal.rating.iso281` for the rolling bearings), the rating of a
whole model at a torque (:mod:`~gearmodal.rating.gearbox`: the loads from the model's static
equilibrium, the speeds and tooth load cycles from its kinematics) and its report
(:mod:`~gearmodal.rating.report`). It may import the model layer, the linear analyses and the
shared basics; the application (the command line) imports it, never the other way round.
"""

from .gearbox import Rating, rate, rate_spectrum
from .iso281 import a_iso, modified_life, rated_viscosity
from .iso6336 import GearSpec, PairRating, rate_pair

__all__ = ["GearSpec", "PairRating", "Rating", "a_iso", "modified_life", "rate", "rate_pair",
           "rate_spectrum",
           "rated_viscosity"]
