"""Turning geometry integrated exactly (DESIGN 3.2): closed forms written in the ground frame.

A rigid body turning at 600 rpm (either sense) on a ground support with ``kx != ky`` is, in the
frame turning with it, a time-periodic system; in the ground frame each axis is a fixed
oscillator, with a per-axis clearance a fixed oscillator with a dead band. Both have closed
forms there, from which the turning-frame coordinates follow by ``q = R(psi)^T X``. The exact
method must match them at its defaults: trajectory to 1e-8 of the amplitude, every contact
event (which side, when) to 1e-9 s, no event more or less. The scipy reference integrates the
time-varying equations at each instant's azimuth and is checked against the same closed form.
"""

import math

import numpy as np
import pytest

import gearmodal as gm

MASS, KX, KY, C = 2.0, 4e5, 1e5, 2e-4
X0 = 1e-3
T_END, DT = 0.1, 1e-4


def body(clearance: float = 0.0) -> gm.Model:
    m = gm.Model("turning_body", input="body")
    m.add(gm.Frame("rot", 1.0))
    m.add(gm.RigidBody(name="body", mass=MASS, inertia=1.0, dofs="planar", frame="rot",
                       speed_ratio=1.0))
    m.add(gm.Bearing("support", "body", None, stiffness={"x": KX, "y": KY, "theta": 1e4},
                     clearance={"x": clearance, "y": clearance} if clearance else {}))
    return m


def axis(x0: float, v0: float, k: float, c: float, t: np.ndarray):
    """One ground axis of the body: an undamped oscillator of stiffness ``k`` with a dead band
    ``|x| <= c`` (free flight inside), from ``x0``, ``v0``. Returns positions at ``t`` and the
    events ``(time, side, closing)`` (side +1 / -1), by exact piecewise solution."""
    w = math.sqrt(k / MASS)
    events, knots = [], [(0.0, x0, v0)]  # (start time, x, v) of each free or contact span
    tt, x, v = 0.0, x0, v0
    while tt < t[-1]:
        if abs(x) < c or (abs(x) == c and x * v < 0):  # free flight to the wall ahead
            if v == 0:
                break
            side = 1.0 if v > 0 else -1.0
            tt += (side * c - x) / v
            x = side * c
            events.append((tt, side, True))
        else:  # in contact on side s: y = x - s c is harmonic, leaves when y returns to 0
            side = 1.0 if x > 0 else -1.0
            y = x - side * c
            amp = math.hypot(y, v / w)
            phi = math.atan2(v / w, y)  # y = amp cos(w tau - phi)
            # exit at w tau - phi = side * pi / 2 (y through 0 towards the free side)
            tau = ((side * math.pi / 2 + phi) % (2 * math.pi)) / w
            if tau <= 0:
                tau += 2 * math.pi / w
            v = -amp * w * math.sin(w * tau - phi)
            tt += tau
            x = side * c
            events.append((tt, side, False))
        knots.append((tt, x, v))
    out = np.empty(len(t))
    starts = np.array([kn[0] for kn in knots])
    for i, ti in enumerate(t):
        j = int(np.searchsorted(starts, ti, side="right") - 1)
        t0, xa, va = knots[j]
        tau = ti - t0
        inside = abs(xa) < c or (abs(xa) == c and xa * va < 0) if c else False
        if inside:
            out[i] = xa + va * tau
        else:
            side = math.copysign(1.0, xa) if c else 0.0
            y = xa - side * c
            out[i] = side * c + y * math.cos(w * tau) + va / w * math.sin(w * tau)
    return out, [e for e in events if e[0] <= t[-1]]


def closed_form(rpm: float, clearance: float, t: np.ndarray):
    """The body's turning-frame coordinates and its contact events from the ground frame."""
    om = rpm * math.pi / 30
    # q(0) = (X0, 0) at psi = 0, v(0) = 0 in the turning frame: ground velocity Omega J q0
    X, ex = axis(X0, 0.0, KX, clearance, t)
    Y, ey = axis(0.0, om * X0, KY, clearance, t)
    c, s = np.cos(om * t), np.sin(om * t)
    q = np.column_stack([c * X + s * Y, -s * X + c * Y])  # R(psi)^T [X, Y]
    names = {(1.0, "x"): "x+", (-1.0, "x"): "x-", (1.0, "y"): "y+", (-1.0, "y"): "y-"}
    events = sorted([(tt, names[(sd, "x")], cl) for tt, sd, cl in ex]
                    + [(tt, names[(sd, "y")], cl) for tt, sd, cl in ey])
    return q, events


@pytest.mark.parametrize("rpm", [600.0, -600.0])
def test_turning_body_on_anisotropic_support_matches_the_ground_frame(rpm):
    t = np.arange(round(T_END / DT) + 1) * DT
    ref, _ = closed_form(rpm, 0.0, t)
    sim = gm.simulate(body(), T_END, dt=DT, q0={"body.x": X0}, speed_rpm=rpm)
    got = sim.q[["body.x", "body.y"]].to_numpy()
    assert np.abs(got - ref).max() < 1e-8 * X0


@pytest.mark.parametrize("rpm", [600.0, -600.0])
def test_turning_body_in_a_ground_clearance_switches_at_the_true_crossings(rpm):
    """Per-axis clearance in the ground axes: every event of the closed form, in order, at its
    time to 1e-9 s, and none more."""
    t = np.arange(round(T_END / DT) + 1) * DT
    ref, ev_ref = closed_form(rpm, C, t)
    sim = gm.simulate(body(C), T_END, dt=DT, q0={"body.x": X0}, speed_rpm=rpm)
    ev = sim.events
    # the run starts with x+ closed (q0 penetrates), which the closed form does not log
    got = [(float(r.time), r.contact, r.state_after == "closed") for r in ev.itertuples()]
    assert len(got) == len(ev_ref) > 20
    assert [g[1:] for g in got] == [e[1:] for e in ev_ref]
    assert max(abs(g[0] - e[0]) for g, e in zip(got, ev_ref, strict=True)) < 1e-9
    assert np.abs(sim.q[["body.x", "body.y"]].to_numpy() - ref).max() < 1e-8 * X0


def test_scipy_integrates_the_time_varying_equations():
    """The reference method evaluates the turning rows at each instant: it reaches the same
    closed form to its tolerance (not to a refreeze error)."""
    t_end = 0.03
    t = np.arange(round(t_end / DT) + 1) * DT
    ref, ev_ref = closed_form(600.0, C, t)
    sim = gm.simulate(body(C), t_end, dt=DT, q0={"body.x": X0}, speed_rpm=600.0,
                      method="scipy", scipy_method="DOP853", rtol=1e-11, atol=1e-16)
    assert len(sim.events) == len(ev_ref)
    times = sim.events["time"].to_numpy()
    assert np.abs(times - [e[0] for e in ev_ref]).max() < 1e-7
    assert np.abs(sim.q[["body.x", "body.y"]].to_numpy() - ref).max() < 1e-6 * X0


def test_newmark_follows_the_turning_geometry():
    """Newmark with the matrices at each step's azimuth converges to the closed form at second
    order (no frozen-azimuth error that would not shrink with the step)."""
    t = np.arange(round(0.02 / 1e-5) + 1) * 1e-5
    ref, _ = closed_form(600.0, 0.0, t)
    errs = []
    for dt in (4e-5, 2e-5, 1e-5):
        sim = gm.simulate(body(), 0.02, dt=dt, q0={"body.x": X0}, speed_rpm=600.0,
                          method="newmark")
        k = round(dt / 1e-5)
        errs.append(np.abs(sim.q[["body.x", "body.y"]].to_numpy() - ref[::k]).max())
    assert errs[0] / errs[1] > 3.5 and errs[1] / errs[2] > 3.5
    assert errs[2] < 1e-3 * X0


@pytest.mark.parametrize("rpm", [600.0, -600.0])
def test_planetary_stage_with_clearance_carrier_bearing_matches_time_varying_scipy(rpm):
    """The paper's configuration: a carrier floating in a 1 mm per-axis clearance in the
    housing (ground axes), rated torque and a shaft-end force that drops it through the
    clearance into double contact, turning at 600 rpm either way (a third of a turn). The
    exact method against solve_ivp (DOP853, rtol 1e-10) of the time-varying equations: the
    same events in the same order (carrier bearing and back flanks among them), at the same
    times to 1e-9 s, forces to 1e-6 of their peak (measured 5e-12 s and 1e-8 over 0.02 s)."""
    m = gm.load("studies/models/planetary_clearance.toml")
    loads = {"carrier.torque": 2.6e5, "sun.torque": -2.6e5 / 5.714285714285714,
             "carrier.force_y": -1.5e5}
    a, b = _exact_against_scipy(m, 0.008, rpm, loads, min_events=20)
    assert {"carrier_bearing", "ring_planet1"} <= set(a["element"])
    assert (a["contact"] == "back").any()
    # the gap rate is the gap's time derivative in both (the turning rows' own rate included)
    rate = np.abs(b["gap_rate"].to_numpy()).max()
    assert np.abs(a["gap_rate"].to_numpy() - b["gap_rate"].to_numpy()).max() < 1e-6 * rate


def _exact_against_scipy(m, t_end, rpm, loads, min_events):
    """The exact method and solve_ivp (DOP853, rtol 1e-10) on ``m``: more than ``min_events``
    events, the same in the same order, at the same times to 1e-9 s, forces to 1e-6 of their
    peak; returns both event tables."""
    kw = dict(dt=1e-4, speed_rpm=rpm, loads=loads)
    ex = gm.simulate(m, t_end, **kw)
    sp = gm.simulate(m, t_end, method="scipy", scipy_method="DOP853", rtol=1e-10, atol=1e-15,
                     **kw)
    a, b = ex.events, sp.events
    assert len(a) == len(b) > min_events
    assert (a[["element", "contact", "state_after"]].to_numpy()
            == b[["element", "contact", "state_after"]].to_numpy()).all()
    assert np.abs(a["time"].to_numpy() - b["time"].to_numpy()).max() < 1e-9
    fa, fb = ex.forces.to_numpy(), sp.forces.to_numpy()
    assert np.abs(fa - fb).max() < 1e-6 * np.abs(fb).max()
    return a, b


def test_two_planetary_stages_turning_at_unrelated_speeds_match_time_varying_scipy():
    """The 5 MW reference gearbox: stage 2's carrier turns at 75/19 of the input, so its
    geometry is not periodic in one input revolution (orders 1, 2, 75/19 and 150/19, fitted
    by least squares, gearmodal/integrate/azimuth.py). At 120 rpm input from rest under rated
    torque and a shaft-end force, stage 2's carrier in a 20 um clearance: the exact method
    against solve_ivp (DOP853, rtol 1e-10) of the time-varying equations, 10 ms (stage 2's
    carrier turns 0.5 rad): the same events in the same order, at the same times to 1e-9 s,
    forces to 1e-6 of their peak (measured 1e-10 s and 2e-10)."""
    from gearmodal.shipped import find

    text = find("nrel5mw", "models").read_text().replace(
        "carrier_bearing = { stiffness = { x = 1.2e8, y = 2.4e9 } }",
        "carrier_bearing = { stiffness = { x = 1.2e8, y = 2.4e9 }, "
        "clearance = { x = 2.0e-5, y = 2.0e-5 } }")
    m = gm.loads(text)
    loads = gm.balance(m, {"rotor.torque": 4.0e6, "stage1.carrier.force_y": -5e5},
                       on="generator.torque")
    a, _ = _exact_against_scipy(m, 0.01, 120.0, loads, min_events=40)
    assert {"stage2.carrier_bearing", "stage2.ring_planet1"} <= set(a["element"])
