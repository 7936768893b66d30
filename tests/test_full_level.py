"""The ``full`` DOF level (3 translations, 2 tilts, rotation per wheel): the fidelity ladder's
most detailed DOF rung on the 600 kW drivetrain, and the clear error when a support leaves a
tilt free."""

from __future__ import annotations

import math

import numpy as np
import pytest

import gearmodal as gm
from gearmodal.errors import ModelError

SCENE = "studies/scenes/600kw_turbine_10ms.toml"
FULL = {f"model.stages.{i}.dofs": "full" for i in range(3)}


def _frequencies(asm):
    lam = np.linalg.eigvals(np.linalg.solve(asm.M, asm.stiffness())).real
    return np.sort(np.sqrt(np.abs(lam))) / (2 * math.pi)


def test_spur_stage_full_contains_the_planar_modes():
    """With spur gears (no helix) the flank normals lie in the plane and the contact points at
    mid face width, so the out-of-plane motions (z, rx, ry) decouple: every planar frequency
    is also a frequency of the full stage, and the full stage adds one per new DOF."""
    sun = gm.Gear(21, 0.01, math.radians(20), mass=50.0, inertia=0.5, face_width=0.2)
    planet = gm.Gear(39, 0.01, math.radians(20), mass=100.0, inertia=2.0, face_width=0.2)
    ring = gm.Gear(99, 0.01, math.radians(20), mass=500.0, inertia=50.0, internal=True,
                   face_width=0.2)
    support = {"stiffness": {"x": 1e9, "y": 1e9, "z": 5e8, "rx": 2e7, "ry": 2e7,
                             "theta": 1e9}}
    f = {}
    for level in ("planar", "full"):
        stage = gm.planetary_stage(sun, planet, ring, n_planets=3, carrier_mass=300.0,
                                   carrier_inertia=20.0, mesh_stiffness=5e9,
                                   planet_bearing=support, carrier_bearing=support,
                                   sun_support=support, ring_support=support, dofs=level)
        f[level] = _frequencies(stage.assemble())
    assert len(f["full"]) == 2 * len(f["planar"])
    # each planar frequency has a full one within rounding of the eigen solver (the
    # frequencies span 10 Hz - 5 kHz; 1e-8 relative is well above eigvals' ~1e-12)
    near = np.abs(f["full"][None, :] / f["planar"][:, None] - 1).min(axis=1)
    assert near.max() < 1e-8


def test_600kw_full_has_one_free_motion_and_runs():
    """The 600 kW model file gives every support an axial and a tilt stiffness, so at the full
    level only the drivetrain rotation is free; a short turbine run applies the shaft-end
    force on the carrier and stays finite."""
    from gearmodal.scene import load_scene
    from gearmodal.static import free_modes

    sc = load_scene(SCENE, {"scene.t_end": 0.2, **FULL})
    asm = sc.model.assemble()
    assert asm.n == 65
    assert free_modes(asm).shape[1] == 1
    res = sc.simulate()
    assert "not modelled" not in res.gearbox.settings.get("shaft_end_force", "")
    assert np.all(np.isfinite(res.gearbox.forces.to_numpy()))
    assert res.gearbox.forces.filter(like=".z").abs().to_numpy().max() > 0.0


def test_free_tilt_at_full_is_named():
    """A planet bearing given as a number has no tilt stiffness: at the full level the planets'
    tilts are free and the turbine run refuses with the DOFs named."""
    from gearmodal.scene import load_scene

    sc = load_scene(SCENE, {"scene.t_end": 0.01, **FULL,
                            "model.stages.0.planet_bearing": 2.0e9})
    with pytest.raises(ModelError, match=r"nothing resists .*stage1\.planet1\.r[xy].*"
                                         r"tilts rx/ry need a stiffness table"):
        sc.simulate()
