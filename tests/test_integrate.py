"""gm.simulate: stability at the extremes of DESIGN 3.3, the chatter cap, inputs, results."""

import math

import numpy as np
import pandas as pd
import pytest

import gearmodal as gm
from gearmodal.integrate.system import PiecewiseLinearSystem


def pair(mass, k, backlash, damping=0.0):
    return gm.examples.disk_pair(mass, k, backlash, damping)


def energy_drift(model, sim):
    S = PiecewiseLinearSystem(model.assemble())
    x = np.concatenate([sim.q.to_numpy(), sim.v.to_numpy()], axis=1)
    E = np.array([S.energy(xx) for xx in x])
    return (E.max() - E.min()) / E.max()


@pytest.mark.parametrize("k", [1e6, 1e11])
@pytest.mark.parametrize("mass", [0.1, 1e5])
@pytest.mark.parametrize("backlash", [0.0, 1e-4])
def test_extreme_stiffness_mass_backlash_undamped(k, mass, backlash):
    """Mesh stiffness 1e6..1e11 N/m, masses 0.1..1e5 kg, zero damping, zero or finite
    backlash: finite, events found, energy conserved (the propagation is exact, so the stiff
    cases are as good as the soft ones)."""
    m = pair(mass, k, backlash)
    rp = m.bodies["pinion"].base_radius
    rw = m.bodies["wheel"].base_radius
    ip, iw = m.bodies["pinion"].inertia, m.bodies["wheel"].inertia
    me = 1.0 / (rp**2 / ip + rw**2 / iw)
    contact = math.pi / math.sqrt(k / me)
    v = 1e-2  # m/s relative approach speed along the line of action
    flight = max(backlash / v, contact)
    dt = min(flight, contact) / 4
    t_end = 12 * (flight + contact)
    sim = gm.simulate(m, t_end, dt=dt, q0={"pinion.theta": -backlash / 2 / rp},
                      v0={"pinion.theta": v / rp, "wheel.theta": v / rp * ip * rw / (iw * rp)})
    assert np.all(np.isfinite(sim.q.to_numpy()))
    assert len(sim.events) >= 10
    assert energy_drift(m, sim) < 1e-10


def test_zero_backlash_is_the_linear_oscillator():
    """With zero backlash exactly one flank is engaged at any time, so the relative motion is
    the linear mesh oscillator: d(t) = (v / omega) sin(omega t), flanks switching at its zeros."""
    m = pair(1.0, 2e8, 0.0)
    rp = m.bodies["pinion"].base_radius
    rw = m.bodies["wheel"].base_radius
    ip, iw = m.bodies["pinion"].inertia, m.bodies["wheel"].inertia
    me = 1.0 / (rp**2 / ip + rw**2 / iw)
    om = math.sqrt(2e8 / me)
    v = 1e-2
    sim = gm.simulate(m, 20 * math.pi / om, dt=0.37 / om, v0={"pinion.theta": v / rp})
    d = rp * sim.q["pinion.theta"] + rw * sim.q["wheel.theta"]
    # the free rotation drifts with the momentum; the mesh deflection is the oscillator
    np.testing.assert_allclose(d, v / om * np.sin(om * sim.t), rtol=0, atol=1e-12 * v / om)
    # at every zero one flank opens and the other closes, at the same instant
    zeros = np.pi / om * np.arange(1, 20)
    times = sim.events.time.drop_duplicates().to_numpy()
    np.testing.assert_allclose(times[1:20], zeros, rtol=1e-12)
    assert (sim.events.groupby("time").size().iloc[1:20] == 2).all()


@pytest.mark.parametrize("clearance", [1e-9, 1e-3])
def test_extreme_clearance(clearance):
    m = gm.Model("block", input="body")
    m.add(gm.RigidBody(name="body", mass=2.0, inertia=1.0, dofs="planar"))
    m.add(gm.Bearing("b", "body", None, stiffness={"x": 1e9, "y": 1e9, "theta": 1e4},
                     clearance={"x": clearance, "y": clearance}))
    sim = gm.simulate(m, 0.5, dt=1e-4, loads={"body.force_x": lambda t: 1e3 * math.sin(60 * t)},
                      v0={"body.y": 0.05})
    assert np.all(np.isfinite(sim.q.to_numpy()))
    assert (sim.events.contact.isin(["y+", "y-"])).sum() > 10  # bouncing in y
    assert np.abs(sim.q["body.y"]).max() < clearance + 0.05 * math.sqrt(2.0 / 1e9) * 1.0001


def test_chatter_cap_raises_naming_the_contact():
    """Many switches inside one step are allowed up to a cap, then a clear error names the
    contact instead of a hang."""
    m = pair(1.0, 2e8, 1e-7)
    rp = m.bodies["pinion"].base_radius
    with pytest.raises(gm.SolveError, match=r"max_events_per_step.*'mesh:(front|back)'"):
        gm.simulate(m, 0.05, dt=0.01, v0={"pinion.theta": 1.0 / rp}, max_events_per_step=20)
    sim = gm.simulate(m, 0.02, dt=0.01, v0={"pinion.theta": 1.0 / rp},
                      max_events_per_step=100_000)
    assert len(sim.events) > 200  # hundreds of switches inside two steps


def test_loads_as_constant_callable_and_series_agree():
    m = pair(1.0, 2e8, 1e-4, damping=50.0)
    t = np.linspace(0, 0.02, 201)
    ramp = pd.Series(100 * t / 0.02, index=t)
    base = dict(dt=1e-4)
    a = gm.simulate(m, 0.02, loads={"pinion.torque": ramp, "wheel.torque": ramp * 2}, **base)
    b = gm.simulate(m, 0.02, loads={"pinion.torque": lambda tt: 100 * tt / 0.02,
                                    "wheel.torque": lambda tt: 200 * tt / 0.02}, **base)
    np.testing.assert_allclose(a.q.to_numpy(), b.q.to_numpy(), rtol=0, atol=1e-15)


def test_bad_inputs():
    m = pair(1.0, 2e8, 1e-4)
    with pytest.raises(gm.ModelError, match=r"dt = -1"):
        gm.simulate(m, 1.0, dt=-1)
    with pytest.raises(gm.ModelError, match=r"loads\.nope: no such load"):
        gm.simulate(m, 1e-3, dt=1e-4, loads={"nope": 1.0})
    with pytest.raises(gm.ModelError, match=r"q0\.pinion\.x: no such DOF"):
        gm.simulate(m, 1e-3, dt=1e-4, q0={"pinion.x": 1.0})
    with pytest.raises(gm.ModelError, match=r"method = 'rk4'"):
        gm.simulate(m, 1e-3, dt=1e-4, method="rk4")


def test_result_outputs(tmp_path):
    m = pair(1.0, 2e8, 1e-4, damping=20.0)
    rp = m.bodies["pinion"].base_radius
    sim = gm.simulate(m, 0.02, dt=1e-4, q0={"pinion.theta": -5e-5 / rp},
                      v0={"pinion.theta": 1.0})
    assert list(sim.events.columns) == ["time", "element", "contact", "state_before",
                                        "state_after", "gap_rate", "force_after",
                                        "peak_force_N", "peak_time"]
    assert {"mesh.front", "mesh.back"} <= set(sim.forces.columns)
    sim.save(tmp_path)
    for f in ("events.parquet", "forces.parquet", "q.parquet", "settings.json"):
        assert (tmp_path / f).exists()
    sim.save(tmp_path / "csv", format="csv")  # CSV when asked for
    for f in ("events.csv", "forces.csv", "q.csv", "settings.json"):
        assert (tmp_path / "csv" / f).exists()
    assert not (tmp_path / "csv" / "forces.parquet").exists()
    assert sim.plot().axes
    # both flanks are never closed together in a free rattle of a pair with backlash
    assert sim.double_contact().empty


def test_scipy_reference_does_not_flip_forever_at_a_tangent_contact():
    """Starting at rest at q = 0 every flank touches with zero gap and rate; solve_ivp restarted
    at the root used to report the same event again and flip the state forever (found by the
    work-precision benchmark). The restart now mutes that contact for a short span."""
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).parent / "validation"))
    from test_exactness import clearance_stage

    loads = {"carrier.force_u": 2e3, "sun.force_u": -2e3, "carrier.force_y": -3e3}
    sim = gm.simulate(clearance_stage(), 0.0004, dt=4e-5, loads=loads, method="scipy",
                      scipy_method="LSODA", rtol=1e-8, atol=1e-16, max_events=2000)
    assert sim.t[-1] == pytest.approx(0.0004)
    assert np.all(np.isfinite(sim.q.to_numpy()))
    ex = gm.simulate(clearance_stage(), 0.0004, dt=4e-5, loads=loads)
    scale = np.abs(ex.q.to_numpy()).max()
    assert np.abs(sim.q.to_numpy() - ex.q.to_numpy()).max() < 1e-6 * scale



def test_driver_reserve_writes_the_history_in_place():
    """Driver.reserve (the turbine run's 600 001-row histories without a concatenated copy)
    gives the same arrays as the appended blocks, and refuses more steps than reserved."""
    from gearmodal.integrate import Driver
    from gearmodal.integrate.system import PiecewiseLinearSystem

    asm = gm.examples.disk_pair(1.0, 1e8, 1e-6, 0.0).assemble()
    runs = []
    for reserve in (False, True):
        # a fresh system each: a system keeps the contact states' bounds it has met, and a
        # second run on it cuts its pieces differently (the same solution to rounding)
        sy = PiecewiseLinearSystem(asm, 0.0)
        x0 = np.zeros(2 * sy.n)
        x0[sy.n:] = 0.01  # both wheels spinning: the pair closes its backlash and rattles
        s0 = sy.penetration(x0) > 0
        F = np.zeros((11, sy.n)) + sy.f_const[None, :]
        run = Driver("exact", 1e-5, x0, s0)
        if reserve:
            run.reserve(20)
        run.advance(sy, 10, F)
        run.advance(sy, 10, F)
        runs.append(run.arrays())
        if reserve:
            with pytest.raises(ValueError, match="reserved"):
                run.advance(sy, 10, F)
    (Xa, Sa, ea), (Xb, Sb, eb) = runs
    assert Xa.shape == Xb.shape == (21, 2 * sy.n)
    assert np.array_equal(Xa, Xb) and np.array_equal(Sa, Sb)
    assert np.array_equal(ea, eb, equal_nan=True)  # (no episode peak on a closing row: NaN)
