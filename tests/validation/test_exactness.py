"""Proof of exactness of ``method="exact"`` against closed forms and a tight solve_ivp."""

import math

import numpy as np
import pytest

import gearmodal as gm
from gearmodal.integrate.system import PiecewiseLinearSystem

I_P, I_W, K_MESH = 1e-3, 1.6e-2, 2e8


@pytest.fixture(params=["taylor", "expm"])
def propagator(request):
    """Both propagators of the exact method must pass every closed form."""
    return request.param


def pair(backlash):
    m = gm.examples.gear_pair(pinion_inertia=I_P, wheel_inertia=I_W, mesh_stiffness=K_MESH,
                              backlash=backlash)
    return m, m.bodies["pinion"].base_radius, m.bodies["wheel"].base_radius


def rattle_times(b, rp, rw, approach, n):
    """Closed form of a free torsional pair rattling in its backlash, starting mid-backlash:
    flight b/2 at the relative speed, half a period of the mesh oscillator in contact, flight
    b, ... Effective mass 1/m_e = r_p^2/I_p + r_w^2/I_w."""
    me = 1.0 / (rp**2 / I_P + rw**2 / I_W)
    half = math.pi / math.sqrt(K_MESH / me)
    t, out = (b / 2) / approach, []
    for _ in range(n // 2):
        out += [t, t + half]
        t += half + b / approach
    return np.array(out)


@pytest.mark.parametrize("dt", [1e-4, 3e-3])
def test_rattle_contact_and_separation_times(dt, propagator):
    """Free flight inside the backlash, contact, separation, flight to the back flank...:
    every event time equals the closed form to machine precision, also with dt 18 times longer
    than the contact (brief contacts inside one step are found)."""
    b = 1e-4
    model, rp, rw = pair(b)
    om = 1.0  # pinion speed, rad/s; the wheel at rest
    sim = gm.simulate(model, 0.02, dt=dt, q0={"pinion.theta": -b / 2 / rp},
                      v0={"pinion.theta": om}, propagator=propagator)
    ev = sim.events
    expect = rattle_times(b, rp, rw, rp * om, len(ev))
    assert len(ev) >= 12
    # times are sums of a few closed-form terms: agreement to a few ulp of the time
    # (a few ulp per term; the bisection path may differ by rounding: allow 1e-13)
    np.testing.assert_allclose(ev.time.to_numpy(), expect, rtol=1e-13, atol=1e-18)
    assert list(ev.contact[:4]) == ["front", "front", "back", "back"]
    assert list(ev.state_after[:2]) == ["closed", "open"]
    # contact begins and ends with the approach speed reversed (elastic, undamped)
    np.testing.assert_allclose(np.abs(ev.gap_rate), rp * om, rtol=1e-12)


def test_brief_contact_much_shorter_than_dt_is_found(propagator):
    b = 1e-4
    model, rp, rw = pair(b)
    me = 1.0 / (rp**2 / I_P + rw**2 / I_W)
    contact = math.pi / math.sqrt(K_MESH / me)
    dt = 50 * contact
    sim = gm.simulate(model, 4 * dt, dt=dt, q0={"pinion.theta": -b / 2 / rp},
                      v0={"pinion.theta": 1.0}, propagator=propagator)
    first = sim.events.iloc[:2]
    t1 = (b / 2) / (rp * 1.0)
    np.testing.assert_allclose(first.time, [t1, t1 + contact], rtol=1e-13)
    assert first.time.iloc[1] - first.time.iloc[0] < dt / 40


def test_bearing_clearance_closes_under_step_load(propagator):
    """A mass in a dead band c under a step force F from rest: free flight to x = c at
    t_c = sqrt(2 m c / F), then the spring; it leaves the contact when
    theta = omega (t - t_c) = 2 pi - 2 atan(v_c k / (omega F))."""
    m_, k, c, F = 3.0, 2e6, 1e-4, 50.0
    model = gm.Model("block", input="body")
    model.add(gm.RigidBody(name="body", mass=m_, inertia=1.0, dofs="planar"))
    model.add(gm.Bearing("b", "body", None, stiffness={"x": k, "y": k, "theta": 1e4},
                         clearance={"x": c}))
    sim = gm.simulate(model, 0.05, dt=1e-3, loads={"body.force_x": F}, propagator=propagator)
    tc = math.sqrt(2 * m_ * c / F)
    om = math.sqrt(k / m_)
    vc = F / m_ * tc
    ts = tc + (2 * math.pi - 2 * math.atan(vc * k / (om * F))) / om
    ev = sim.events[sim.events.contact == "x+"]
    np.testing.assert_allclose(ev.time.iloc[:2], [tc, ts], rtol=1e-12)
    assert list(ev.state_after.iloc[:2]) == ["closed", "open"]


@pytest.mark.slow
def test_undamped_energy_is_conserved_over_many_switches(propagator):
    """No loads, no damping: the mechanical energy stays constant through 1e5
    contact switches. The rigid-body mode is started at rest so that the angles stay small
    (gaps are differences of angles; a drifting rotation would cost digits)."""
    b = 1e-6
    model, rp, rw = pair(b)
    wd = I_P * rw / (I_W * rp)  # zero momentum of the free rotation
    sim = gm.simulate(model, 9.8, dt=1e-4, q0={"pinion.theta": -b / 2 / rp},
                      v0={"pinion.theta": 1.0, "wheel.theta": wd}, propagator=propagator)
    n_switch = len(sim.events)
    assert n_switch >= 100_000
    S = PiecewiseLinearSystem(model.assemble())
    x = np.concatenate([sim.q.to_numpy(), sim.v.to_numpy()], axis=1)
    E = np.array([S.energy(xx) for xx in x])
    # rounding accumulates about linearly with the number of operations: a few eps per step
    # and per switch, i.e. ~1e-16 * (n_steps + n_switch) ~ 1e-12; allow 10x that
    assert (E.max() - E.min()) / E.max() < 1e-16 * (len(x) + n_switch) * 10


def clearance_stage():
    lp = dict(mass={"carrier": 5.43, "ring": 2.35, "sun": 0.4, "planet": 0.66},
              inertia_over_r2={"carrier": 6.29, "ring": 3.0, "sun": 0.39, "planet": 0.61},
              bearing={"carrier": 1e8, "ring": 1e8, "sun": 1e8, "planet": 1e8},
              torsional={"carrier": 1e6, "ring": 1e9, "sun": 1e6},
              mesh={"sun_planet": 5e8, "ring_planet": 5e8})
    m = gm.lin_parker_stage(3, **lp, pressure_angle=math.radians(24.6), backlash=2e-6,
                            mesh_damping=50.0)
    br = m.bearings["carrier_support"]
    br.clearance = {"x": 2e-5, "y": 2e-5}
    return m


def test_exact_agrees_with_tight_solve_ivp_on_planetary_stage_with_clearance(propagator):
    """A Lin & Parker stage whose carrier has a bearing clearance larger than the backlash,
    driven by a torque and a radial force into double contact: the exact method and DOP853 at
    rtol 1e-12 give the same trajectory and the same events."""
    m = clearance_stage()
    loads = {"carrier.force_u": 2e3, "sun.force_u": -2e3, "carrier.force_y": -3e3}
    kw = dict(dt=2e-5, loads=loads)
    ex = gm.simulate(m, 0.004, propagator=propagator, **kw)
    ref = gm.simulate(m, 0.004, method="scipy", scipy_method="DOP853", rtol=1e-12,
                      atol=1e-18, **kw)
    assert len(ex.events) > 10
    dc = ex.double_contact()
    assert len(dc) > 0  # the clearance lets the planets wedge: both flanks in contact
    scale = np.abs(ref.q.to_numpy()).max()
    assert np.abs(ex.q.to_numpy() - ref.q.to_numpy()).max() < 1e-7 * scale
    assert len(ex.events) == len(ref.events)
    np.testing.assert_allclose(ex.events.time, ref.events.time, rtol=0, atol=1e-9)


def test_contact_hidden_by_same_sign_end_rates_is_found(propagator):
    """Free flight under a load varying linearly over the step: the gap is an exact cubic whose
    rate is positive at both step ends but which rises above zero and comes back inside the
    step (found in review). Closed form of the free-flight gap (normalised):
    g(tau) = -0.01 + 0.16 tau - tau^2/2 + tau^3/3, tau = t/dt, first root on [0, 0.2]."""
    import pandas as pd
    from scipy.optimize import brentq

    m = gm.load("studies/models/gear_pair.toml")
    asm = m.assemble()
    Wp, Jp = asm.contacts.W[0, 0], asm.M[0, 0]
    dt, G = 1e-4, 1e-5
    T0 = -G * Jp / (Wp * dt**2)
    load = pd.Series([T0, -T0, -T0], index=[0, dt, 2 * dt])
    sim = gm.simulate(m, dt, dt=dt, loads={"pinion.torque": load},
                      q0={"pinion.theta": -0.01 * G / Wp},
                      v0={"pinion.theta": 0.16 * G / dt / Wp}, propagator=propagator)
    tau = brentq(lambda s: -0.01 + 0.16 * s - s**2 / 2 + s**3 / 3, 0, 0.2, xtol=1e-16)
    first = sim.events.iloc[0]
    assert (first.contact, first.state_after) == ("front", "closed")
    assert first.time == pytest.approx(tau * dt, rel=1e-12)


def test_graze_narrower_than_the_taylor_samples_is_found(propagator):
    """A constant force decelerating the gap: a parabola positive only on [0.505, 0.515] dt,
    between two of the samples of a Taylor piece (found in review)."""
    from scipy.optimize import brentq

    m = gm.load("studies/models/gear_pair.toml")
    asm = m.assemble()
    Wp, Jp = asm.contacts.W[0, 0], asm.M[0, 0]
    dt, acc = 1e-4, 1e4
    tc, w = 0.51 * dt, 0.01 * dt
    v0 = acc * tc
    g0 = acc * (w / 2) ** 2 / 2 - acc * tc**2 / 2
    sim = gm.simulate(m, dt, dt=dt, loads={"pinion.torque": -acc * Jp / Wp},
                      q0={"pinion.theta": g0 / Wp}, v0={"pinion.theta": v0 / Wp},
                      propagator=propagator)
    t_in = brentq(lambda t: g0 + v0 * t - acc * t**2 / 2, 0, tc, xtol=1e-20)
    assert len(sim.events) == 2
    assert sim.events.time.iloc[0] == pytest.approx(t_in, rel=1e-10)
    assert list(sim.events.state_after) == ["closed", "open"]


def test_doubled_propagators_equal_the_direct_exponential():
    """Coarse dyadic levels are derived from the finest by exact doubling (FOH composition);
    they must equal Van Loan's exponential computed directly at each level. Tolerance: the
    squaring amplifies rounding by ~2 per level, a few levels here -> 1e-13 relative
    (measured 1e-15)."""
    from gearmodal.integrate.system import Propagators

    system = PiecewiseLinearSystem(gm.assemble(clearance_stage()), speed_rpm=600.0)
    prop = Propagators(system, 4e-5)
    s = np.zeros(system.n_contacts, dtype=bool)
    s[::3] = True
    assert prop.taylor_level(s) >= 3  # stiff enough that several levels are doubled
    doubled = prop.level(s, 0)
    assert prop.n_exponentials == 1
    direct = prop._exponential(prop.state(s)["A"], prop.dt)
    for a, b in zip(doubled, direct, strict=True):
        assert np.abs(a - b).max() <= 1e-13 * np.abs(b).max()
