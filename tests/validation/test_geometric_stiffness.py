"""The geometric stiffness of the steady rotation (DESIGN 2.5a; gearmodal.assembly (G1)-(G2)).

A free drivetrain turning steadily can be turned as a whole, or its carrier advanced with the
ring held, without any change of its internal state: that motion is neutral at every speed.
Lin & Parker's (1999) centripetal-only linearisation gives it a real positive eigenvalue at
speed (their rotational mode lifted off zero); the planet bearings' and meshes' centrifugal
preload times the curvature of their deflections removes it. Checked here:

- closed form on Lin & Parker's stage, whose free sun and carrier leave the meshes no radial
  load: each planet's bearing carries ``m Omega^2 r_c``, which adds ``m Omega^2`` to the
  ``(u_c, eta_n)`` entries and ``-m Omega^2`` to ``(u_c, u_c)`` (the potential
  ``m Omega^2 (eta_n u_c - u_c^2 / 2)`` of the preload in the bearing axes turning with the
  carrier);
- every shipped model over its Campbell speeds: no eigenvalue with a positive real part beyond
  rounding, the free rotation's below 1e-7 of the largest; the published form still has it;
- the time domain: a free stage at 1000 rpm given a push along its free rotation drifts, it
  does not grow as ``exp(47 t)``.
"""

from __future__ import annotations

import importlib.util
import math
import os
from pathlib import Path

import numpy as np
import pytest

# Lin & Parker's (1999) example stage: the published data, one copy (pytest puts this folder on
# the path: its modules have no package)
from test_lin_parker import LP  # noqa: E402

import gearmodal as gm
from gearmodal.assembly import as_assembly, reduction
from gearmodal.modal import eigensolve

ROOT = Path(__file__).resolve().parents[2]
RPM = math.pi / 30.0



def _lin_parker(n=3, angles=None):
    return gm.lin_parker_stage(n, LP["mass"], LP["inertia_over_r2"], LP["bearing"],
                               LP["torsional"], LP["mesh"], math.radians(24.6),
                               planet_angles=angles)


@pytest.mark.parametrize("n", [3, 4])
def test_lin_parker_stage_bearings_carry_the_planets_centrifugal_force(n):
    """Equally spaced planets (unequally spaced ones load the carrier's bearing too)."""
    asm = _lin_parker(n).assemble()
    names = asm.dof_names
    m = LP["mass"]["planet"]
    expected = np.zeros((asm.n, asm.n))
    uc = names.index("carrier.u")
    for k in range(1, n + 1):
        eta = names.index(f"planet{k}.eta")
        expected[uc, eta] = expected[eta, uc] = m
        expected[uc, uc] -= m
    # entries are sums of a few products of O(1) geometry with the O(1) masses; the static
    # solve behind the preload is least squares on stiffnesses of 1e8..1e9 (rounding ~1e-7
    # of m relative to the 1e9 / 1e8 spread), so 1e-6 of the planet mass
    np.testing.assert_allclose(asm.K_geom, expected, rtol=0, atol=1e-6 * m)
    # the free rotation (carrier, sun and planets rolling in the held ring) is an exact zero
    # of the stiffness at any speed: K phi = 0 with K_s phi = 0, not only phi K phi = 0
    w2, V = np.linalg.eigh(np.linalg.solve(np.sqrt(asm.M), asm.stiffness())
                           @ np.linalg.inv(np.sqrt(asm.M)))
    phi = np.linalg.solve(np.sqrt(asm.M), V[:, 0])
    assert abs(w2[0]) < 1e-9 * w2[-1]
    scale = m * np.abs(phi).max()
    assert np.abs(asm.K_cent @ phi).max() < 1e-8 * scale
    # centripetal-only: each planet's -m Omega^2 eta_n is left unbalanced
    assert np.abs(asm.speed_stiffness(False) @ phi).max() > 0.5 * scale


def _load(path):
    """A shipped model file: a gearbox model, or the elastic turbine (its own extras)."""
    if "[elastic_turbine]" in path.read_text():
        if importlib.util.find_spec("pybmodes") is None and not os.environ.get("GEARMODAL_CI"):
            pytest.skip("the elastic extra: pip install -e '.[elastic]' (CI installs it)")
        from gearmodal.turbine.structure import load_elastic_turbine

        return load_elastic_turbine(path)
    return gm.load(path)


def _shipped():
    """Every shipped model with the speeds of its Campbell diagram (rpm): the turbines'
    0-30 (600 kW: its start-up) and 0-13 (5 MW), the stages to 3000 rpm (DESIGN 3.3)."""
    out = []
    for path in sorted((ROOT / "studies" / "models").glob("*.toml")):
        top = {"600kw": 30.0, "nrel5mw": 13.0, "nrel5mw_elastic": 13.0}.get(path.stem, 3000.0)
        out.append((path.stem, lambda p=path: _load(p), top, path.stem != "gear_pair"))
    out.append(("lin_parker_stage", _lin_parker, 3000.0, True))
    out.append(("lin_parker_unequal", lambda: _lin_parker(4, [0.0, 1.4, 3.3, 4.6]), 3000.0,
                True))
    # unequally spaced planets on a carrier, sun and ring all free to turn: the unbalanced
    # carrier presses on its bearing (the load turning with the carrier); the published
    # form happens to keep this stage's free rotations at zero
    out.append(("examples.planetary_stage", gm.examples.planetary_stage, 3000.0, False))
    return out


@pytest.mark.parametrize("name, make, top, lifted", _shipped(),
                         ids=[c[0] for c in _shipped()])
def test_no_shipped_model_has_a_spurious_unstable_eigenvalue(name, make, top, lifted):
    asm, _ = reduction(as_assembly(make())[0])  # a coupled system in its constrained coordinates
    worst = {True: (-np.inf, 0.0), False: (-np.inf, 0.0)}
    for rpm in np.linspace(0.0, top, 6):
        for geometric in (True, False):
            lam, _ = eigensolve(asm.M, asm.damping(), asm.stiffness(), asm.G, rpm * RPM,
                                asm.speed_stiffness(geometric), asm.K_speed)
            big = np.abs(lam).max()
            re, small = worst[geometric]
            worst[geometric] = (max(re, lam.real.max() / big),
                                max(small, np.abs(lam).min() / big))
    # the free rotation is neutral: its eigenvalue is rounding, below 1e-7 of the largest
    # (measured 1e-10..2e-8), and no other mode of these passive gearboxes grows
    re, small = worst[True]
    assert small < 1e-7 and re < 1e-7
    # the published centripetal-only form, wherever planets turn: the free rotation lifted off
    # zero (1.4e-6 .. 4e-3 of the largest; a real positive eigenvalue in all but the 600 kW,
    # whose gyroscopic coupling makes it a slow oscillation)
    if lifted:
        assert worst[False][1] > 1e-6


def test_modal_and_campbell_read_the_free_rotation_rigid_at_speed():
    m = gm.load(ROOT / "studies" / "models" / "planetary_clearance.toml")
    res = gm.modal(m, 1000.0)
    assert res.mode_types[0] == "rigid"
    assert res.frequencies_hz[0] < 1e-7 * res.frequencies_hz[-1]
    old = gm.modal(m, 1000.0, geometric_stiffness=False)
    assert old.mode_types[0] == "rotational"
    assert old.frequencies_hz[0] == pytest.approx(7.52, abs=0.01)  # lambda = +47.3 1/s
    camp = gm.campbell(m, np.array([0.0, 500.0, 1000.0]))
    assert np.all(camp.mode_types[:, 0] == "rigid")
    assert np.all(camp.frequencies_hz[:, 0] < 1e-7 * camp.frequencies_hz[:, -1])
    # the other modes move little: at most 1.4e-4 relative at 1000 rpm (the rotational ones)
    np.testing.assert_allclose(res.frequencies_hz[1:], old.frequencies_hz[1:], rtol=2e-4)


def test_a_push_along_the_free_rotation_drifts_in_time():
    """Planetary stage at 1000 rpm, started at its centrifugal equilibrium with the carrier
    pushed (1e-3 rad/s): the free rotation takes the push and drifts, linearly in time, so
    the largest departure from equilibrium over the last 0.1 s of 0.3 s is about three times
    that over the first 0.1 s. Centripetal-only, the push grows as exp(47.3 t): over a
    thousandfold between the two windows."""
    m = gm.load(ROOT / "studies" / "models" / "planetary_clearance.toml")
    asm, _ = as_assembly(m)
    om = 1000.0 * RPM
    q_eq = np.linalg.lstsq(asm.stiffness(speed=om), om**2 * asm.f_cent, rcond=None)[0]
    q0 = dict(zip(asm.dof_names, q_eq, strict=True))
    res = gm.simulate(m, 0.3, dt=0.01, speed_rpm=1000.0, q0=q0, v0={"carrier.theta": 1e-3})
    dev = np.abs(res.q.to_numpy() - q_eq).max(axis=1)
    t = res.q.index.to_numpy()
    first, last = dev[(t > 0) & (t <= 0.1 + 1e-9)].max(), dev[t >= 0.2 - 1e-9].max()
    assert 2.0 < last / first < 4.0
