"""Torsional planets riding on their carrier pins (``Body.pinned_to``, P1 in
:func:`gearmodal.assembly._on_pins`): the DOF-level rung ``torsional`` of a planetary stage."""

from __future__ import annotations

import math

import numpy as np
import pytest

import gearmodal as gm
from gearmodal.errors import ModelError

SUN, PLANET, RING = gm.examples.planetary_gears()


def _stage(dofs, support, angles=gm.examples.ANGLES):
    return gm.examples.planetary_stage(dofs, support, angles=angles)


def _frequencies(asm):
    lam = np.linalg.eigvals(np.linalg.solve(asm.M, asm.stiffness())).real
    return np.sort(np.sqrt(np.abs(lam))) / (2 * math.pi)


def test_torsional_stage_is_the_stiff_bearing_limit_of_the_planar_one():
    """Eliminating the planet translations onto the carrier pins (P1) is the limit of the
    planar stage whose planet bearings and central supports grow stiff: the planar
    frequencies approach the torsional ones as 1/k (5e-4 at 1e13 N/m, 6e-6 at 1e15)."""
    asm = _stage("torsional", 1e9).assemble()
    assert asm.dof_names == ["carrier.theta", "sun.theta", "ring.theta", "planet1.theta",
                             "planet2.theta", "planet3.theta"]
    assert len(asm.springs) == 0  # the planet bearings' deflection vanishes on the pins
    ft = _frequencies(asm)
    errors = []
    for k in (1e13, 1e15):
        fp = _frequencies(_stage("planar", k).assemble())
        errors.append(np.abs(fp[2:6] / ft[2:6] - 1).max())
    assert errors[1] < 2e-5
    assert errors[0] / errors[1] == pytest.approx(100, rel=0.05)  # the 1/k convergence
    # two rigid modes: the stage's free rotation (carrier with its planets) and the ring's
    assert ft[:2].max() < 1e-3 and ft[2] > 1e3


def test_planet_mass_adds_to_the_carrier_rotation():
    """A planet on its pin carries its mass around: the carrier's rotational inertia in the
    assembled mass matrix is J_c + sum m_p r_c^2 (r_c the planet centre radius)."""
    asm = _stage("torsional", 1e9).assemble()
    r_c = (SUN.base_radius + PLANET.base_radius) / math.cos(SUN.transverse_pressure_angle)
    i = asm.dof_names.index("carrier.theta")
    assert asm.M[i, i] == pytest.approx(20.0 + 3 * 100.0 * r_c**2, rel=1e-12)


def test_pinned_to_is_checked():
    st = _stage("torsional", 1e9)
    st.bodies["planet1"].pinned_to = "nowhere"
    with pytest.raises(ModelError, match="planet1.pinned_to"):
        st.check()
    with pytest.raises(ModelError, match="pinned_to"):
        gm.RigidBody(name="b", mass=1.0, inertia=1.0, pinned_to=3)


def test_torsional_drivetrain_runs_without_the_shaft_end_force():
    """The 600 kW drivetrain with every stage torsional (the fidelity ladder's DOF rung): it
    assembles, its geometry interpolates exactly, and the turbine run goes without the
    shaft-end force (no carrier translation to take it), which its settings say."""
    from gearmodal.integrate.azimuth import AzimuthAssembler
    from gearmodal.scene import load_scene

    sc = load_scene("studies/scenes/600kw_turbine_10ms.toml",
                    {"scene.t_end": 0.2, **{f"model.stages.{i}.dofs": "torsional"
                                            for i in range(3)}})
    asm = sc.model.assemble()
    assert asm.n == 15
    assert AzimuthAssembler(sc.model).exact
    res = sc.simulate()
    assert "not modelled" in res.gearbox.settings["shaft_end_force"]
    assert np.all(np.isfinite(res.gearbox.forces.to_numpy()))
