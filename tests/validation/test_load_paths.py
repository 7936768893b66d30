"""Loads keep their own time structure (DESIGN 2.4): the exact method's solution does not depend
on the output step for any load, against closed forms.

A harmonic load is carried exactly (its series in every piece), a pandas Series is linear
between its own knots wherever they fall, a callable is sampled on ``load_dt``; the output
step ``dt`` only places the rows.
"""

import math

import numpy as np
import pandas as pd
import pytest
from scipy.optimize import brentq

import gearmodal as gm

MASS, K, C = 3.0, 2e6, 1e-4
OM = math.sqrt(K / MASS)  # contact oscillator, rad/s


def block() -> gm.Model:
    """A planar body in a per-axis dead band ``C`` on a spring ``K`` (x)."""
    model = gm.Model("block", input="body")
    model.add(gm.RigidBody(name="body", mass=MASS, inertia=1.0, dofs="planar"))
    model.add(gm.Bearing("b", "body", None, stiffness={"x": K, "y": K, "theta": 1e4},
                         clearance={"x": C}))
    return model


def harmonic_closed_form(A: float, nu: float):
    """x'' = A/m sin(nu t) from rest at 0: free flight
    x = A/(m nu) (t - sin(nu t)/nu) until x = C at t_c; then m y'' + K y = A sin(nu t) with
    y = x - C, y(t_c) = 0, y'(t_c) = v_c: y = a cos w(t - t_c) + b sin w(t - t_c)
    + A sin(nu t) / (K - m nu^2), until y = 0 again (the contact opens)."""
    x = lambda t: A / (MASS * nu) * (t - math.sin(nu * t) / nu)  # noqa: E731
    xd = lambda t: A / (MASS * nu) * (1 - math.cos(nu * t))  # noqa: E731
    t_c = brentq(lambda t: x(t) - C, 1e-6, 1.0, xtol=1e-18, rtol=1e-15)
    P = A / (K - MASS * nu**2)
    a = -P * math.sin(nu * t_c)
    b = (xd(t_c) - P * nu * math.cos(nu * t_c)) / OM

    def y(t):
        return a * math.cos(OM * (t - t_c)) + b * math.sin(OM * (t - t_c)) + P * math.sin(nu * t)

    # the first return of y to 0 after t_c (y > 0 in between: sample, then bracket)
    ts = t_c + np.linspace(1e-9, 2 * math.pi / OM, 4001)
    ys = np.array([y(t) for t in ts])
    i = int(np.flatnonzero(ys < 0)[0])
    t_s = brentq(y, ts[i - 1], ts[i], xtol=1e-18, rtol=1e-15)
    return t_c, t_s, x, y


@pytest.mark.parametrize("dt", [1e-3, 2.7e-4])
def test_harmonic_load_is_integrated_exactly(dt):
    """A 40 Hz harmonic force: contact and separation at the closed form's times to 1e-12
    (relative), whatever the output step; the old sampled load (linear between rows) missed the
    contact time by 1e-4 relative at dt = 1 ms. The output rows lie on the closed form to
    1e-9 of the clearance."""
    A, f = 50.0, 40.0
    nu = 2 * math.pi * f
    t_c, t_s, x, y = harmonic_closed_form(A, nu)
    sim = gm.simulate(block(), 0.012, dt=dt, loads={"body.force_x": gm.Harmonic(0.0, A, f)})
    ev = sim.events[sim.events.contact == "x+"]
    np.testing.assert_allclose(ev.time.iloc[:2], [t_c, t_s], rtol=1e-12)
    assert list(ev.state_after.iloc[:2]) == ["closed", "open"]
    t = sim.t[sim.t < t_s]
    q = sim.q["body.x"].to_numpy()[: len(t)]
    ref = np.array([x(tt) if tt <= t_c else C + y(tt) for tt in t])
    assert np.abs(q - ref).max() < 1e-9 * C


def test_harmonic_mean_and_phase_against_a_finely_sampled_callable():
    """``mean + amplitude sin(2 pi f t + phase)`` as the scene files give it, against the same
    function as a plain callable sampled every microsecond (interpolation error below
    (2 pi f dt)^2 / 8 = 6e-9 of the amplitude): the same events to 1e-8 s."""
    wave = gm.Harmonic(20.0, 30.0, 35.0, 2.0)
    a = gm.simulate(block(), 0.02, dt=1e-4, loads={"body.force_x": wave})
    b = gm.simulate(block(), 0.02, dt=1e-4, load_dt=1e-6,
                    loads={"body.force_x": lambda t: float(wave(t))})
    assert len(a.events) == len(b.events) > 2
    np.testing.assert_allclose(a.events.time, b.events.time, rtol=0, atol=1e-8)


def test_series_knots_between_output_rows_are_followed_exactly():
    """A ramp to F at t1 = 0.37 ms (between rows of 1 and 0.5 ms), then held: free flight
    x = F t^3 / (6 m t1) until t1, then x(t1) + v(t1)(t - t1) + F (t - t1)^2 / (2 m); the
    contact time to 1e-12 at both output steps (the old load, resampled on the rows, moved it
    with dt)."""
    F, t1 = 40.0, 3.7e-4
    load = pd.Series([0.0, F], index=[0.0, t1])
    x1, v1 = F * t1**2 / (6 * MASS), F * t1 / (2 * MASS)

    def x(t):
        return x1 + v1 * (t - t1) + F * (t - t1) ** 2 / (2 * MASS)

    t_c = brentq(lambda t: x(t) - C, t1, 1.0, xtol=1e-18, rtol=1e-15)
    times = []
    for dt in (1e-3, 5e-4):
        sim = gm.simulate(block(), 0.01, dt=dt, loads={"body.force_x": load})
        times.append(sim.events.time.iloc[0])
    np.testing.assert_allclose(times, [t_c, t_c], rtol=1e-12)


def test_callable_is_sampled_on_its_load_step_not_the_output_step():
    """A callable load: the same events (count and times, to the bit) at output steps 0.1,
    0.05 and 0.2 ms; a different ``load_dt`` is a different (approximate) load, and its
    effect shrinks as the square of the load step (linear interpolation of a smooth load)."""
    f = 35.0

    def force(t):
        return 30.0 * math.sin(2 * math.pi * f * t) + 20.0

    runs = [gm.simulate(block(), 0.02, dt=dt, loads={"body.force_x": force})
            for dt in (1e-4, 5e-5, 2e-4)]
    t0 = runs[0].events.time.to_numpy()
    assert len(t0) > 2
    for r in runs[1:]:
        assert np.array_equal(r.events.time.to_numpy(), t0)
    exact = gm.simulate(block(), 0.02, dt=1e-4,
                        loads={"body.force_x": gm.Harmonic(20.0, 30.0, f)}).events.time.iloc[0]
    errs = [abs(gm.simulate(block(), 0.02, dt=1e-4, load_dt=ld, loads={"body.force_x": force})
                .events.time.iloc[0] - exact) for ld in (4e-4, 2e-4)]
    assert errs[0] / errs[1] > 3.0  # second order in the load step
    assert abs(t0[0] - exact) < errs[1]  # the default load step (0.1 ms) closer still


def test_load_dt_is_checked():
    with pytest.raises(gm.ModelError, match="load_dt"):
        gm.simulate(block(), 0.01, dt=1e-4, load_dt=0.0, loads={"body.force_x": math.sin})


@pytest.mark.slow
@pytest.mark.parametrize("rpm", [600.0, -600.0])
def test_harmonic_load_on_turning_geometry_matches_time_varying_scipy(rpm):
    """The double-contact stage turning at +-600 rpm with its shaft-end force as a harmonic
    (a load fixed in the carrier's axes: its turning map times the wave, at h omega +- nu):
    the exact method against solve_ivp (DOP853, rtol 1e-10, the load evaluated at each instant,
    steps of at most 2 us: at -600 rpm a back flank opens for 5 us, which solve_ivp steps over
    with longer steps), the same events at the same times to 1e-9 s, forces to 1e-6 of their
    peak."""
    m = gm.load("studies/models/planetary_clearance.toml")
    loads = {"carrier.torque": 2.6e5, "sun.torque": -2.6e5 / 5.714285714285714,
             "carrier.force_y": gm.Harmonic(-1.5e5, 6.0e4, 60.0, 0.3)}
    kw = dict(dt=1e-4, speed_rpm=rpm, loads=loads)
    ex = gm.simulate(m, 0.008, **kw)
    sp = gm.simulate(m, 0.008, method="scipy", scipy_method="DOP853", rtol=1e-10, atol=1e-15,
                     max_step=2e-6, **kw)
    a, b = ex.events, sp.events
    assert len(a) == len(b) > 10
    assert (a[["element", "contact", "state_after"]].to_numpy()
            == b[["element", "contact", "state_after"]].to_numpy()).all()
    assert np.abs(a["time"].to_numpy() - b["time"].to_numpy()).max() < 1e-9
    fa, fb = ex.forces.to_numpy(), sp.forces.to_numpy()
    assert np.abs(fa - fb).max() < 1e-6 * np.abs(fb).max()
