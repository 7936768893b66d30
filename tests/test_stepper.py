"""The public stepping API (gm.Stepper): a run chopped into calls is the run of one call."""

import math

import numpy as np
import pandas as pd
import pytest

import gearmodal as gm

RATIO = 1 + 99 / 21  # the clearance stage's sun per carrier speed


@pytest.fixture(scope="module")
def stage():
    return gm.load("studies/models/planetary_clearance.toml")


@pytest.fixture(scope="module")
def pair():
    return gm.load("studies/models/gear_pair.toml")


def _chunks(seed: int, n_steps: int, n_calls: int) -> np.ndarray:
    """Random call ends (output steps), the run's end last."""
    rng = np.random.default_rng(seed)
    ends = np.sort(rng.choice(np.arange(1, n_steps), n_calls - 1, replace=False))
    return np.append(ends, n_steps)


def _stage_loads(t):
    """Carrier torque, its sun reaction and a shaft-end force, varying (so that every call
    end is a kink of the loads: one call has a knot there too)."""
    tc = 2e5 * (1 + 0.5 * np.sin(2 * math.pi * 7 * t))
    return {"carrier.torque": tc, "sun.torque": -tc / RATIO,
            "carrier.force_x": 2e5 * np.cos(30 * t)}


@pytest.mark.parametrize("rpm", [600.0, -600.0])
def test_chunked_run_is_one_call(stage, rpm):
    """The clearance stage at +-600 rpm (turning geometry, double contact) advanced in 16
    random calls with ramped loads: the same pieces, events, states, exact peaks and turning
    points as one gm.simulate call with the loads as Series knotted at the call ends, to the
    bit (the kernel carries its state across calls and keeps times from the run's start)."""
    dt, n = 1e-4, 2000
    ends = _chunks(1, n, 16)
    tk = np.append(0, ends) * dt
    series = {k: pd.Series(v, index=tk) for k, v in _stage_loads(tk).items()}
    one = gm.simulate(stage, n * dt, dt=dt, loads=series, speed_rpm=rpm)
    st = gm.Stepper(stage, dt=dt, speed_rpm=rpm,
                    loads={k: float(v.iloc[0]) for k, v in series.items()})
    for j, k in enumerate(ends):
        st.advance(k * dt, {name: float(v.iloc[j + 1]) for name, v in series.items()})
    chunked = st.result()
    assert len(one.events) > 1000  # a contact-rich run: the test has something to show
    assert chunked.stats["pieces"] == one.stats["pieces"]
    pd.testing.assert_frame_equal(chunked.events, one.events, check_exact=True)
    np.testing.assert_array_equal(chunked.q.to_numpy(), one.q.to_numpy())
    np.testing.assert_array_equal(chunked.v.to_numpy(), one.v.to_numpy())
    pd.testing.assert_frame_equal(chunked.peak_bins, one.peak_bins, check_exact=True)
    pd.testing.assert_frame_equal(chunked.turning_points, one.turning_points,
                                  check_exact=True)


def test_outputs_and_state_at_call_end(stage):
    """advance returns the named outputs at the call's end: the result's own rows there (the
    force of one row formed alone rounds apart from the table's: 1e-13)."""
    st = gm.Stepper(stage, dt=1e-4, speed_rpm=300.0,
                    loads={"carrier.torque": 1e5, "sun.torque": -1e5 / RATIO},
                    outputs=["sun_planet1.front", "carrier.theta.velocity", "sun.theta"])
    out = st.advance(0.01)
    assert list(out) == ["sun_planet1.front", "carrier.theta.velocity", "sun.theta"]
    res = st.result()
    assert out["sun_planet1.front"] == pytest.approx(res.forces["sun_planet1.front"].iloc[-1],
                                                     rel=1e-13)
    # speeds and angles out are absolute: the reference rotation (300 rpm on the carrier,
    # 300 x 5.714 on the sun) added to the state
    om = 300.0 * math.pi / 30
    assert out["carrier.theta.velocity"] == res.v["carrier.theta"].iloc[-1] + om
    q, v = st.state
    assert q["sun.theta"] == res.q["sun.theta"].iloc[-1]
    assert out["sun.theta"] == pytest.approx(q["sun.theta"] + RATIO * om * 0.01, rel=1e-15)
    assert st.time == pytest.approx(0.01, abs=0)
    assert st.contact_state.dtype == bool


def test_hold_is_a_constant_load(pair):
    """hold="hold": the values given act over the whole call: one call is gm.simulate with
    those constant loads, to the bit."""
    loads = {"pinion.torque": 5.0, "wheel.torque": -8.0}
    one = gm.simulate(pair, 0.02, dt=1e-4, loads={k: pd.Series([v, v], index=[0.0, 0.02])
                                                   for k, v in loads.items()})
    st = gm.Stepper(pair, dt=1e-4, loads=dict.fromkeys(loads, 0.0))
    st.advance(0.02, loads, hold="hold")
    res = st.result()
    pd.testing.assert_frame_equal(res.events, one.events, check_exact=True)
    np.testing.assert_array_equal(res.q.to_numpy(), one.q.to_numpy())


def test_drive_ten_thousand_revolutions(pair):
    """A host's shaft turning 10 027 revolutions drives the pinion through a spring: the
    stepper moves the rigid rotation out of its state (no caller-side re-basing), angles stay
    absolute, and the forces are those of the same run with the shaft at rest (rotation
    changes no force; to 1e-8, the host's own rounding of 63 000 rad at the spring's
    stiffness); the drive torque balances the wheel's load torque at the speed ratio."""
    w, t_end, n_calls = 6000.0, 10.5, 1050  # rad/s, s
    k_d, c_d, load = 2e3, 0.5, -20.0
    runs = {}
    for speed in (0.0, w):
        st = gm.Stepper(pair, dt=1e-3, loads={"wheel.torque": load},
                        v0={"pinion.theta": speed, "wheel.theta": -0.5 * speed},
                        drive=gm.Drive("pinion.theta", k_d, c_d, angle0=0.0, speed0=speed))
        for k in range(1, n_calls + 1):
            t = k * t_end / n_calls
            out = st.advance(t, drive_angle=speed * t, drive_speed=speed)
        runs[speed] = (st.result(), out)
    (rest, o0), (turning, o1) = runs[0.0], runs[w]
    assert turning.stats["n_rebases"] > 1000 and rest.stats["n_rebases"] == 0
    # absolute angles: the shaft's 63 000 rad less the spring's twist
    twist = o1["drive.torque"] / k_d
    assert o1["pinion.theta"] == pytest.approx(w * t_end - twist, abs=1e-9)
    # the last row holds the state before this call's re-basing, the output the state after
    # it (the rigid rotation moved into the offset): the same angle to rounding (1 ulp of
    # 63 000 rad is 7e-12)
    assert turning.q["pinion.theta"].iloc[-1] == pytest.approx(o1["pinion.theta"], abs=1e-10)
    fa, fb = rest.forces.to_numpy(), turning.forces.to_numpy()
    assert np.abs(fa - fb).max() <= 1e-8 * np.abs(fa).max()
    # the wheel's -20 N m acts on the pinion as -20 x (-0.5) = 10 N m (the wheel turns at
    # -0.5 times the pinion): the drive holds it with -10 N m
    assert o0["drive.torque"] == pytest.approx(load * 0.5, rel=1e-9)
    assert o1["drive.torque"] == pytest.approx(load * 0.5, rel=1e-8)


def test_streamed_equals_held(stage, tmp_path):
    """out=DIR streams the rows as the calls go: the same tables as a run held in memory."""
    kw = dict(dt=1e-4, speed_rpm=600.0, loads={"carrier.torque": 1e5, "sun.torque": -1.7e4})
    a, b = gm.Stepper(stage, **kw), gm.Stepper(stage, out=tmp_path / "run", **kw)
    for t in (0.004, 0.01, 0.013):
        a.advance(t, {"carrier.torque": 1e5 + 1e7 * t})
        b.advance(t, {"carrier.torque": 1e5 + 1e7 * t})
    ra, rb = a.result(), b.result()
    np.testing.assert_array_equal(ra.forces.to_numpy(), rb.forces.to_numpy())
    pd.testing.assert_frame_equal(ra.events, rb.events, check_exact=True)
    back = gm.SimulationResult.load(tmp_path / "run")
    np.testing.assert_array_equal(back.q.to_numpy(), ra.q.to_numpy())


@pytest.mark.parametrize("method, options, dt", [("newmark", {}, 1e-5),
                                                 ("exact", {"propagator": "expm"}, 1e-4)])
def test_unchained_chunks_keep_run_times(pair, method, options, dt):
    """A method that does not chain (Newmark, the exact method's expm propagator) is given
    times from the call's start: its events are logged at the run's times and its loads
    follow the ramp. (Newmark at 1e-4 s, omega dt = 3.9 on the mesh, is stopped: its first
    impact, switched a step late, penetrates with 15x the energy there is.)"""
    kw = dict(dt=dt, loads={"pinion.torque": 0.0}, method=method,
              v0={"pinion.theta": 1.0}, **options)
    one, two = gm.Stepper(pair, **kw), gm.Stepper(pair, **kw)
    one.advance(0.02, {"pinion.torque": 2.0})
    two.advance(0.01, {"pinion.torque": 1.0})
    two.advance(0.02, {"pinion.torque": 2.0})
    ea, eb = one.result().events, two.result().events
    assert len(ea) == len(eb) > 2
    # the call's restart retakes the acceleration from the equations (rounding), which the
    # 40 impacts after it amplify: 1.4e-11 s at most (1e-6 of Newmark's step), measured
    np.testing.assert_allclose(eb["time"], ea["time"], rtol=0, atol=1e-10)


def test_record_false_keeps_nothing(pair):
    st = gm.Stepper(pair, dt=1e-4, loads={"pinion.torque": 1.0}, record=False)
    out = st.advance(0.01)
    assert math.isfinite(out["mesh.front"])
    with pytest.raises(gm.ModelError, match="record"):
        st.result()


@pytest.mark.parametrize("call, match", [
    (lambda st: st.advance(0.00015), "whole number of output steps"),
    (lambda st: st.advance(-1.0), "after the time reached"),
    (lambda st: st.advance(0.001, {"wheel.torque": 1.0}), "wheel.torque"),
    (lambda st: st.advance(0.001, hold="zoh"), "hold"),
    (lambda st: st.result(), "nothing was run"),
])
def test_bad_calls(pair, call, match):
    st = gm.Stepper(pair, dt=1e-4, loads={"pinion.torque": 1.0})
    with pytest.raises(gm.ModelError, match=match):
        call(st)


def test_bad_construction(pair):
    with pytest.raises(gm.ModelError, match="outputs.nope"):
        gm.Stepper(pair, dt=1e-4, outputs=["nope"])
    with pytest.raises(gm.ModelError, match="drive.dof"):
        gm.Stepper(pair, dt=1e-4, drive=gm.Drive("pinion.x", 1e3))
    with pytest.raises(gm.ModelError, match="drive.stiffness"):
        gm.Stepper(pair, dt=1e-4, drive=gm.Drive("pinion.theta", -1.0))
    with pytest.raises(gm.ModelError, match="loads.nope"):
        gm.Stepper(pair, dt=1e-4, loads={"nope": 1.0})
    with pytest.raises(TypeError, match="gm.Drive"):
        gm.Stepper(pair, dt=1e-4, drive=("pinion.theta", 1e3, 0.0))
    with pytest.raises(gm.ModelError, match="speed_torque.law"):
        gm.Stepper(pair, dt=1e-4, speed_torque=gm.SpeedTorque("wheel.theta", lambda w: 1.0))
    with pytest.raises(gm.ModelError, match="q0"):
        gm.Stepper(pair, dt=1e-4, q0="rest")
    st = gm.Stepper(pair, dt=1e-4, loads={"pinion.torque": 1.0})
    with pytest.raises(gm.ModelError, match="speed_torque"):
        st.set_speed_torque(gm.SpeedTorque("wheel.theta", lambda w: (0.0, 0.0)))
    st.reserve(0.001)
    with pytest.raises(gm.ModelError, match="reserve"):
        st.reserve(0.002)
    with pytest.raises(gm.ModelError, match="beyond the rows reserved"):
        st.advance(0.002)  # refused before integrating: the run is still at 0
    st.advance(0.001)
    st.result()
    with pytest.raises(gm.ModelError, match="finished"):
        st.advance(0.002)


@pytest.mark.parametrize("reference", ["fixed", "follow"])
def test_speed_torque_settles_where_the_torques_balance(pair, reference):
    """A torque falling linearly with the wheel's speed, ``tau(w) = -c (w - w_s)`` (an
    induction generator's tangent), against a constant pinion torque ``T``: the pair settles
    where the work balances, ``T + r tau(w) = 0`` (``r`` the wheel's speed per pinion speed),
    ``w = w_s + T / (r c)``. The slope acts as a damper in the equations (implicit: calls of
    10 ms against the pair's 1.4 s time constant). The following reference takes the law's
    tangent anew at each re-basing; the fixed one at the start (exact for a linear law)."""
    c, w_s, torque = 2.0, -50.0, 10.0
    r = pair.bodies["wheel"].speed_ratio
    law = gm.SpeedTorque("wheel.theta", lambda w: (-c * (w - w_s), -c))
    st = gm.Stepper(pair, dt=1e-3, loads={"pinion.torque": torque}, speed_rpm=600.0,
                    speed_torque=law, reference=reference, q0="equilibrium",
                    outputs=["wheel.theta.velocity"])
    for k in range(1, 801):
        out = st.advance(k * 1e-2)
    assert out["wheel.theta.velocity"] == pytest.approx(w_s + torque / (r * c), abs=1e-4)


def test_speed_torque_set_before_the_first_call(pair):
    """A law set before the first call acts from the start: the run of a stepper made with
    it, to rounding."""
    off = gm.SpeedTorque("wheel.theta", lambda w: (0.0, 0.0))
    on = gm.SpeedTorque("wheel.theta", lambda w: (-2.0 * (w + 50.0), -2.0))
    kw = dict(dt=1e-3, loads={"pinion.torque": 10.0}, speed_rpm=600.0,
              outputs=["wheel.theta.velocity"])
    a = gm.Stepper(pair, speed_torque=on, **kw)
    b = gm.Stepper(pair, speed_torque=off, **kw)
    b.set_speed_torque(on)
    ya, yb = a.advance(0.5), b.advance(0.5)
    assert yb["wheel.theta.velocity"] == pytest.approx(ya["wheel.theta.velocity"], rel=1e-12)
    assert abs(ya["wheel.theta.velocity"] - 600 * math.pi / 30 * pair.bodies["wheel"]
               .speed_ratio) > 1.0  # the law acted


def _cubic_law(w, w_s=-50.0):
    """A curved speed torque on the wheel: linear plus cubic in the slip from ``w_s``, with its
    derivative."""
    return -0.02 * (w - w_s) - 2e-4 * (w - w_s) ** 3, -0.02 - 6e-4 * (w - w_s) ** 2


def _curved_law_error(pair, reference: str, h: float, t_end: float = 1.0) -> float:
    """Largest error of the wheel's speed under a curved speed torque (a cubic in the slip)
    against the pair's rigid equation ``J w_p' = T + r tau(r w_p)`` solved by ``solve_ivp``,
    relative to the speed's swing over the run (calls of ``h``). The rigid equation stands
    for the compliant pair to 3e-8 of the swing (the same comparison with a linear law,
    which the tangent takes exactly)."""
    from scipy.integrate import solve_ivp

    r = pair.bodies["wheel"].speed_ratio
    j = pair.bodies["pinion"].inertia + r * r * pair.bodies["wheel"].inertia
    torque, w0, law = 0.5, 600 * math.pi / 30, _cubic_law
    ref = solve_ivp(lambda t, y: [(torque + r * law(r * y[0])[0]) / j], (0.0, t_end), [w0],
                    rtol=1e-12, atol=1e-12, dense_output=True)
    st = gm.Stepper(pair, dt=1.25e-4, loads={"pinion.torque": torque}, speed_rpm=600.0,
                    speed_torque=gm.SpeedTorque("wheel.theta", law), q0="equilibrium",
                    reference=reference, outputs=["wheel.theta.velocity"])
    err = max(abs(st.advance(k * h)["wheel.theta.velocity"] - r * ref.sol(k * h)[0])
              for k in range(1, round(t_end / h) + 1))
    return err / abs(r * (ref.y[0, -1] - w0))


@pytest.mark.parametrize("reference", ["fixed", "follow"])
def test_a_curved_speed_torque_converges_with_the_call(pair, reference):
    """The speed torque is taken anew at each call's start at the DOF's own speed (its slope
    too once the speed has left the tangent's by ``rebase_speed``), so a curved law
    converges with the call, to second order: measured 3.8 % of the swing at 20 ms, 0.19 % at
    5 ms, with either reference. Taken at the reference speed and kept, the fixed
    reference's torque stayed the start's tangent: 65 % at any call."""
    err = [_curved_law_error(pair, reference, h) for h in (0.02, 0.005)]
    assert err[1] < 3e-3 and err[1] < 0.1 * err[0]  # second order: 1/16


def test_a_speed_torque_without_slope_settles_at_its_root(pair):
    """A law flat at the reference speed, ``tau(w) = -k (w - w_r)^3`` on the wheel, against a
    constant pinion torque ``T``: the pair settles where ``T + r tau(w) = 0``, ``w - w_r =
    -(T / (-r k))^(1/3)`` (``r`` < 0 the wheel's speed per pinion speed). The tangent taken at
    the reference speed has no slope, so the correction of its constant is explicit over a
    call: its slope is taken anew as the speed leaves the tangent's, and calls of 20 ms,
    longer than the settling's time scale, settle at the root (without: the run diverged)."""
    r = pair.bodies["wheel"].speed_ratio
    w_r, k, torque = r * 600 * math.pi / 30, 0.1, 0.5
    law = gm.SpeedTorque("wheel.theta", lambda w: (-k * (w - w_r) ** 3, -3 * k * (w - w_r) ** 2))
    st = gm.Stepper(pair, dt=1.25e-4, loads={"pinion.torque": torque}, speed_rpm=600.0,
                    speed_torque=law, q0="equilibrium", outputs=["wheel.theta.velocity"])
    for j in range(1, 31):
        out = st.advance(j * 0.02)
    root = -((torque / (-r * k)) ** (1 / 3))
    assert out["wheel.theta.velocity"] - w_r == pytest.approx(root, rel=1e-6)
    assert st.result().stats["speed_torque_tangents"] > 3


@pytest.mark.parametrize("reference", ["fixed", "follow"])
def test_outputs_after_a_speed_torque_tangent_are_the_results_forces(stage, reference):
    """The forces a call returns are the result's at the call's end, also after the speed
    torque's tangent was taken anew between re-basings (a new system made mid-stretch of the
    reference): the turning carrier's bearing rows are evaluated at the new system's own
    time (counted from the reference's re-basing instead, they were off by several times
    the force)."""
    w_r = RATIO * 600 * math.pi / 30

    def law(w):
        s = w - w_r
        return -2e3 * s - 2e3 * s**3, -2e3 - 6e3 * s**2

    st = gm.Stepper(stage, dt=1e-4, speed_rpm=600.0, q0="equilibrium", reference=reference,
                    loads={"carrier.torque": 2e5, "sun.torque": -0.8 * 2e5 / RATIO,
                           "carrier.force_x": 3e5},
                    speed_torque=gm.SpeedTorque("sun.theta", law), rebase_speed=1e-3)
    assert st.system.turning
    got = {j * 50: st.advance(j * 5e-3) for j in range(1, 25)}
    res = st.result()
    assert res.stats["speed_torque_tangents"] >= 2
    for k, out in got.items():
        for name in ("carrier_bearing.x", "carrier_bearing.y", "ring_planet1.front"):
            row = float(res.forces[name].iloc[k])
            assert out[name] == pytest.approx(row, rel=1e-9, abs=1e-6), (k, name)


@pytest.mark.parametrize("reference", ["fixed", "follow"])
def test_a_curved_speed_torque_does_not_depend_on_the_calls(pair, reference):
    """With ``rebase_dt`` the speed torque is taken anew on that grid only, so a run with
    calls ending between its points is the run of one call per point, to rounding (taken at
    every call's start instead, the two ran up to 16 % of the speed's swing apart)."""
    grid = np.arange(1, 26) * 0.02
    cuts = np.unique(np.concatenate([grid, np.arange(1, 4000, 67) * 1.25e-4]))

    def run(ends):
        st = gm.Stepper(pair, dt=1.25e-4, loads={"pinion.torque": 0.5}, speed_rpm=600.0,
                        speed_torque=gm.SpeedTorque("wheel.theta", _cubic_law),
                        q0="equilibrium", reference=reference, rebase_dt=0.02,
                        outputs=["wheel.theta.velocity"])
        got = {round(t / 1.25e-4): st.advance(t)["wheel.theta.velocity"] for t in ends}
        return np.array([got[round(t / 1.25e-4)] for t in grid])

    a, b = run(grid), run(cuts)
    assert len(cuts) > 2 * len(grid)
    assert np.abs(a - b).max() < 1e-9 * np.ptp(a)
    assert np.ptp(a) > 10.0  # the law acted: the wheel slowed by 10 rad/s and more


def _spin_inputs(t_end, h):
    """A host's shaft spun up from rest to 600 rpm in 0.3 s (angle, speed on a grid of
    ``h``), the sun's load torque rising with the speed: knots every ``h``."""
    w_top = 600 * math.pi / 30
    tk = np.arange(round(t_end / h) + 1) * h
    wk = np.minimum(tk / 0.3, 1.0) * w_top
    ak = np.where(tk <= 0.3, w_top / 0.3 * tk**2 / 2, w_top * 0.15 + w_top * (tk - 0.3))
    return tk, wk, ak, w_top


def _spin(stage, t_end, h_call, h_knots, **kw):
    tk, wk, ak, w_top = _spin_inputs(t_end, h_knots)
    st = gm.Stepper(stage, dt=1e-4, loads={"sun.torque": 0.0},
                    drive=gm.Drive("carrier.theta", 5e7, 2e4), reference="follow", **kw)
    for k in range(1, round(t_end / h_call) + 1):
        t = k * h_call
        w, a = np.interp(t, tk, wk), np.interp(t, tk, ak)
        out = st.advance(t, {"sun.torque": -1e5 / RATIO * w / w_top}, drive_angle=a,
                         drive_speed=w)
    return st, out, (a, w)


def test_follow_spins_a_stage_up_with_its_shaft(stage):
    """reference="follow": the clearance stage driven from rest to 600 rpm through a shaft
    spring (the host's angle and speed), its geometry turning with the carrier: the carrier
    follows the shaft (absolute speed out), the shaft's twist is its torque over its
    stiffness, the torque is the sun's load at the stage's ratio, and the tables hold the
    elastic deflections (the rigid rotation taken out, as the turbine's)."""
    st, out, (a, w) = _spin(stage, 0.4, 2e-3, 2e-3)
    res = st.result()
    assert res.stats["n_rebases"] > 50
    assert out["carrier.theta.velocity"] == pytest.approx(w, rel=1e-3)
    assert out["drive.torque"] == pytest.approx(1e5, rel=0.02)
    assert a - out["carrier.theta"] == pytest.approx(out["drive.torque"] / 5e7, rel=0.01)
    r = st.rigid
    rigid = res.q.to_numpy() @ (stage.assemble().M @ r)
    assert np.abs(rigid).max() <= 1e-11 * np.abs(res.q.to_numpy()).max()  # rounding


def test_follow_with_rebase_dt_does_not_depend_on_the_calls(stage):
    """With rebase_dt the reference re-bases at the same times whatever the calls: inputs on
    the same lines advanced in calls of 4, 2 and 1 ms give the same run to rounding (the
    extra call ends are piece ends: 1e-11). A re-basing happens where the next stretch
    starts: at each of the 49 grid points inside the 200 ms (the spin-up leaves the reference
    speed by more than 1 % every 4 ms), none at the run's end."""
    runs = [_spin(stage, 0.2, h, 4e-3, rebase_dt=4e-3)[0].result() for h in (4e-3, 2e-3, 1e-3)]
    ref = runs[0]
    for r in runs[1:]:
        assert r.stats["n_rebases"] == ref.stats["n_rebases"] == 49
        pd.testing.assert_frame_equal(r.events[["element", "contact", "state_after"]],
                                      ref.events[["element", "contact", "state_after"]])
        fa, fb = ref.forces.to_numpy(), r.forces.to_numpy()
        assert np.abs(fa - fb).max() <= 1e-10 * np.abs(fa).max()


def test_follow_without_a_rebase_is_fixed(stage):
    """A "follow" reference that never re-bases is the fixed one, to the bit."""
    kw = dict(dt=1e-4, speed_rpm=600.0, loads={"carrier.torque": 1e5, "sun.torque": -1e5 / RATIO})
    a = gm.Stepper(stage, **kw)
    b = gm.Stepper(stage, reference="follow", rebase_speed=1e9, rebase_angle=1e9, **kw)
    for t in (0.005, 0.012):
        assert a.advance(t) == b.advance(t)
    assert b.result().stats["n_rebases"] == 0


def test_from_scene():
    """A gearbox scene's model, step, method and initial state make the stepper; its loads'
    values at 0 are the inputs; a turbine scene is refused."""
    from gearmodal.scene import load_scene

    scene = load_scene("studies/scenes/planetary_double_contact.toml")
    st = gm.Stepper.from_scene(scene, outputs=["ring_planet1.front"])
    assert st.dt == scene.dt and st.settings["method"] == scene.method
    assert set(st.settings["loads"]) == set(scene.loads)
    out = st.advance(10 * scene.dt)
    assert list(out) == ["ring_planet1.front"] and math.isfinite(out["ring_planet1.front"])
    with pytest.raises(gm.ModelError, match="scene.turbine"):
        gm.Stepper.from_scene(load_scene("studies/scenes/600kw_turbine_10ms.toml"))


def test_stepper_misuse_is_named(pair):
    """Issue 62's Stepper cases: loads that are not a mapping, a reservation for a time
    already passed, and a user's law that raises (its own error chained, not hidden)."""
    st = gm.Stepper(pair, dt=1e-4, loads={"pinion.torque": 1.0})
    with pytest.raises(gm.ModelError, match=r"^loads: expected \{load name: value\}.*list"):
        st.advance(0.001, [1.0, 2.0])
    st.advance(0.002)
    with pytest.raises(gm.ModelError, match=r"t_end = 0.001: must be after the time reached"):
        st.reserve(0.001)
    # a call whose arrays cannot fit is refused before they are made, naming the size
    with pytest.raises(gm.ModelError, match=r"^t: advancing to t = 1000000000.0 s "
                       r"\(9,999,999,999,980 output steps in one call\).*GB"):
        st.advance(1e9)
    kept = gm.Stepper(pair, dt=1e-4, loads={"pinion.torque": 1.0}, record=True)
    with pytest.raises(gm.ModelError, match=r"^t: advancing to t = 1000000.0 s"):
        kept.advance(1e6)
    assert st.time == 0.002 and kept.time == 0.0  # nothing advanced
    st.advance(0.003)  # and the run goes on

    def law(w):
        raise ValueError("slip out of the table")

    with pytest.raises(gm.ModelError, match="raised ValueError.*slip out of the table") as e:
        gm.Stepper(pair, dt=1e-4, speed_torque=gm.SpeedTorque("wheel.theta", law))
    assert isinstance(e.value.__cause__, ValueError)
