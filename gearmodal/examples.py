"""Small example models, built with the public builders: the gear pair and planetary stage the
tests, the benchmarks and the documentation share (one definition each).

>>> import gearmodal as gm
>>> gm.examples.gear_pair().dof_names
['pinion.theta', 'wheel.theta']
>>> gm.examples.planetary_stage(dofs="torsional").n_dofs
6
"""

from __future__ import annotations

import math

from .model.builders import gear_pair as _gear_pair
from .model.builders import planetary_stage as _planetary_stage
from .model.components import Gear
from .model.model import Model

__all__ = ["disk_pair", "gear_pair", "planetary_gears", "planetary_stage"]

DEG20 = math.radians(20.0)


def gear_pair(dofs: str = "torsional", *, pinion_mass: float = 1.0,
              pinion_inertia: float = 1e-3, wheel_mass: float = 4.0,
              wheel_inertia: float = 1.6e-2, mesh_stiffness: float = 2e8,
              backlash: float = 1e-4, mesh_damping: float = 0.0, helix_angle: float = 0.0,
              bearing_stiffness=None, **kw) -> Model:
    """A spur (or helical) pair: 20 and 40 teeth, module 4 mm, 20 deg pressure angle; pinion
    1 kg, 1e-3 kg m^2, wheel 4 kg, 1.6e-2 kg m^2; mesh 2e8 N/m, backlash 0.1 mm.

    ``helix_angle`` (rad) makes the pinion right-handed and the wheel left-handed. At
    ``planar``/``full`` the wheels sit on bearings of ``bearing_stiffness`` (default 1e9 N/m).
    Other keywords go to :func:`gearmodal.gear_pair`.
    """
    p = Gear(20, 0.004, DEG20, helix_angle, mass=pinion_mass, inertia=pinion_inertia)
    w = Gear(40, 0.004, DEG20, -helix_angle, mass=wheel_mass, inertia=wheel_inertia)
    if bearing_stiffness is None and dofs != "torsional":
        bearing_stiffness = 1e9
    return _gear_pair(p, w, mesh_stiffness=mesh_stiffness, backlash=backlash,
                      mesh_damping=mesh_damping, dofs=dofs,
                      bearing_stiffness=bearing_stiffness, **kw)


def disk_pair(mass: float, mesh_stiffness: float, backlash: float,
              mesh_damping: float = 0.0) -> Model:
    """The :func:`gear_pair` whose wheels are uniform disks of about their base radii
    (pinion ``mass``, wheel ``4 mass``; inertia ``m r^2 / 2`` with r = 37.6 and 75.2 mm): the
    pair of the integrator's stability map (DESIGN 3.3), scaled by mass and stiffness."""
    return gear_pair(pinion_mass=mass, pinion_inertia=mass * 0.0376**2 / 2,
                     wheel_mass=4 * mass, wheel_inertia=4 * mass * 0.0752**2 / 2,
                     mesh_stiffness=mesh_stiffness, backlash=backlash,
                     mesh_damping=mesh_damping)


def planetary_gears(*, masses=(50.0, 100.0, 500.0), inertias=(0.5, 2.0, 50.0),
                    helix_angle: float = 0.0, face_width: float | None = None):
    """(sun, planet, ring): 21, 39 and 99 teeth, module 10 mm, 20 deg, with ``masses`` and
    ``inertias`` (kg, kg m^2) in that order; ``helix_angle`` (rad) on the sun, the opposite
    hand on planet and ring."""
    ms, mp, mr = masses
    js, jp, jr = inertias
    sun = Gear(21, 0.01, DEG20, helix_angle, face_width, mass=ms, inertia=js)
    planet = Gear(39, 0.01, DEG20, -helix_angle, face_width, mass=mp, inertia=jp)
    ring = Gear(99, 0.01, DEG20, -helix_angle, face_width, internal=True, mass=mr,
                inertia=jr)
    return sun, planet, ring


#: unequal planet angles the teeth can assemble (multiples of 360 / (21 + 99) = 3 deg), so
#: that no symmetry hides an error
ANGLES = tuple(math.radians(a) for a in (0.0, 117.0, 243.0))


def planetary_stage(dofs: str = "planar", support=1e9, *, angles=ANGLES,
                    carrier_mass: float = 300.0, carrier_inertia: float = 20.0,
                    mesh_stiffness=5e9, gears=None, **kw) -> Model:
    """A three-planet stage of :func:`planetary_gears` at ``angles`` (rad; by default
    :data:`ANGLES`, unequal), every bearing and support ``support`` (N/m or a table).
    Other keywords go to :func:`gearmodal.planetary_stage`."""
    sun, planet, ring = gears if gears is not None else planetary_gears()
    supports = {k: support for k in ("planet_bearing", "carrier_bearing", "sun_support",
                                     "ring_support")}
    supports.update({k: kw.pop(k) for k in list(kw) if k in supports})
    return _planetary_stage(sun, planet, ring, n_planets=len(angles),
                            planet_angles=list(angles), carrier_mass=carrier_mass,
                            carrier_inertia=carrier_inertia, mesh_stiffness=mesh_stiffness,
                            dofs=dofs, **supports, **kw)
