"""Systems coupled through Lagrange multipliers (paper section 3): every case the paper lists,
coupled = monolithic, constraint forces and drift."""

import math

import numpy as np
import pytest

import gearmodal as gm

RB1 = 20 * 0.004 / 2 * math.cos(math.radians(20))  # pinion base radius of the pair below, m


def pair():
    return gm.examples.gear_pair()


class Flywheel(gm.System):
    """A user-written system in plain Python: a flywheel driven by a torque, J a = T."""

    def __init__(self, name, inertia):
        self.name = name
        self.inertia = inertia
        self.dof_names = ["theta"]
        self.load_names = ["torque"]

    def residual(self, t, q, v, a, u=None):
        u = np.zeros(1) if u is None else np.asarray(u)
        return np.array([self.inertia * a[0] - u[0]])


def test_internal_and_external_system_closed_form():
    """A plain-Python flywheel splined to the pinion adds its inertia: the mesh mode is
    sqrt(k (rb1^2 / (J1 + Jf) + rb2^2 / J2)) exactly (tangents by differences: 1e-9)."""
    both = gm.Coupled([gm.ModelSystem(pair(), "pair"), Flywheel("fly", 1e-3)],
                      [gm.LinearConstraint("spline", {"fly.theta": 1.0,
                                                      "pair.pinion.theta": -1.0})])
    f = gm.modal(both).frequencies_hz
    expect = math.sqrt(2e8 * (RB1**2 / 2e-3 + (2 * RB1) ** 2 / 1.6e-2)) / (2 * math.pi)
    assert f[0] < 1e-6 * expect  # the free rotation
    assert f[1] == pytest.approx(expect, rel=1e-9)
    assert both.dof_names == ["pair.pinion.theta", "pair.wheel.theta", "fly.theta"]


def test_constraint_inside_one_system_and_to_the_ground():
    """A joint locking the wheel to the ground (constraint inside one system): the pinion
    then rings on the mesh alone, sqrt(k rb1^2 / J1)."""
    lock = gm.Joint("lock", "pair.wheel", None, directions=("theta",))
    f = gm.modal(gm.Coupled([gm.ModelSystem(pair(), "pair")], [lock])).frequencies_hz
    assert len(f) == 1
    assert f[0] == pytest.approx(math.sqrt(2e8 * RB1**2 / 1e-3) / (2 * math.pi), rel=1e-9)
    # a joint between two bodies of one system: pinion and wheel turn together -> rigid only
    same = gm.Joint("same", "pair.pinion", "pair.wheel", directions=("theta",))
    f2 = gm.modal(gm.Coupled([gm.ModelSystem(pair(), "pair")], [same])).frequencies_hz
    assert len(f2) == 1


def test_two_external_systems_and_a_system_alone():
    """Two linear systems (spring-mass chains) joined end to end equal the joined chain; a
    system alone equals itself."""
    k, m = 1e4, 2.0
    a = gm.LinearSystem("a", ["x1", "x2"], M=np.diag([m, m / 2]),
                        K=[[k, -k], [-k, k]])
    b = gm.LinearSystem("b", ["x3"], M=[[m / 2]], K=[[0.0]])
    glue = gm.LinearConstraint("glue", {"a.x2": 1.0, "b.x3": -1.0})
    f = gm.modal(gm.Coupled([a, b], [glue])).frequencies_hz
    assert f[1] == pytest.approx(math.sqrt(2 * k / m) / (2 * math.pi), rel=1e-12)
    alone = gm.modal(gm.Coupled([pair()])).frequencies_hz
    np.testing.assert_allclose(alone, gm.modal(pair()).frequencies_hz, rtol=1e-12)


def split_600kw(j_flange=10.0):
    """The 600 kW drivetrain as the paper couples it: the turbine (rotor, main shaft and the
    shaft flange, an internal system) and the gearbox without them (external system), the
    flange splined to the carrier, which gives up the flange's inertia."""
    mono = gm.load("studies/models/600kw.toml")
    gear = mono.copy()
    gear.name = "gearbox"
    del gear.bodies["rotor"]
    del gear.bearings["main_shaft"]
    gear.input = "stage1.carrier"
    gear.bodies["stage1.carrier"].inertia -= j_flange
    turbine = gm.Model("turbine", input="rotor")
    rotor = mono.bodies["rotor"]
    turbine.add(gm.RigidBody(name="rotor", mass=rotor.mass, inertia=rotor.inertia,
                             dofs="torsional"))
    turbine.add(gm.RigidBody(name="flange", mass=1.0, inertia=j_flange, dofs="torsional"))
    turbine.add(gm.Shaft("main_shaft", "rotor", "flange",
                         mono.bearings["main_shaft"].stiffness["theta"]))
    spline = gm.Joint("spline", "turbine.flange", "gearbox.stage1.carrier",
                      directions=("theta",))
    return mono, gm.Coupled([turbine, gear], [spline], name="600kW coupled")


@pytest.mark.parametrize("rpm", [0.0, 22.1])
def test_coupled_equals_monolithic_frequencies(rpm):
    mono, coupled = split_600kw()
    a = gm.modal(mono, rpm).frequencies_hz
    b = gm.modal(coupled, rpm).frequencies_hz
    assert len(a) == len(b)
    fmax = a.max()
    keep = a > 1e-6 * fmax  # the free rotation is zero to the solver's resolution in both
    np.testing.assert_allclose(b[keep], a[keep], rtol=1e-9)
    assert np.all(b[~keep] < 1e-6 * fmax)


def test_coupled_equals_monolithic_campbell():
    mono, coupled = split_600kw()
    ca = gm.campbell(mono, [0.0, 11.0, 22.1])
    cb = gm.campbell(coupled, [0.0, 11.0, 22.1])
    keep = ca.frequencies_hz > 1e-6 * ca.frequencies_hz.max()
    np.testing.assert_allclose(cb.frequencies_hz[keep], ca.frequencies_hz[keep], rtol=1e-9)
    assert list(cb.orders.values()) == list(ca.orders.values())  # names gain "gearbox."


def test_coupled_equals_monolithic_time_response_and_constraint_drift():
    """Rotor torque step with a generator counter-torque: the same trajectory (exact
    method) and the same events; the linearised spline holds to rounding (|g| <= 1e-12
    max|q|: the stated drift bound) over 20000 steps; its multiplier is the torque the flange
    passes to the carrier: main-shaft torque minus the flange's inertia torque."""
    mono, coupled = split_600kw()
    ratio = mono.gear_ratio
    loads = {"rotor.torque": 1e5, "generator.torque": -1e5 / ratio}
    kw = dict(t_end=2.0, dt=1e-4)
    a = gm.simulate(mono, loads=loads, **kw)
    b = gm.simulate(coupled, loads={"turbine.rotor.torque": 1e5,
                                    "gearbox.generator.torque": -1e5 / ratio}, **kw)
    qa = a.q.to_numpy()
    names = ["turbine." + n if n == "rotor.theta" else "gearbox." + n for n in a.q.columns]
    qb = b.q[names].to_numpy()
    scale = np.abs(qa).max()
    assert np.abs(qb - qa).max() < 1e-9 * scale
    assert len(a.events) == len(b.events)
    drift = np.abs(b.constraint_residual.to_numpy()).max()
    assert drift <= 1e-12 * np.abs(b.q.to_numpy()).max()
    # multiplier = force on body b (the carrier) = k_ms (rotor - flange) - J_f flange''
    k_ms = mono.bearings["main_shaft"].stiffness["theta"]
    tw = b.q["turbine.rotor.theta"] - b.q["turbine.flange.theta"]
    acc = np.gradient(b.v["turbine.flange.theta"].to_numpy(), b.t)
    lam = b.constraint_forces["spline.theta"].to_numpy()
    expect = k_ms * tw.to_numpy() - 10.0 * acc
    inner = slice(10, -10)
    assert np.abs(lam - expect)[inner].max() < 1e-3 * np.abs(expect).max()


def test_multiplier_closed_form_in_free_flight():
    """A flywheel splined to the pinion, driven by a torque T inside the backlash: the
    spline carries T J_p / (J_p + J_f) exactly (both accelerate at T / (J_p + J_f))."""
    both = gm.Coupled([gm.ModelSystem(pair(), "pair"), Flywheel("fly", 3e-3)],
                      [gm.LinearConstraint("spline", {"fly.theta": 1.0,
                                                      "pair.pinion.theta": -1.0})])
    T = 0.2
    sim = gm.simulate(both, 0.002, dt=1e-4, loads={"fly.torque": T},
                      q0={"pair.pinion.theta": -1e-3, "fly.theta": -1e-3})
    free = sim.t < sim.events.time.iloc[0] if len(sim.events) else sim.t <= sim.t[-1]
    lam = sim.constraint_forces["spline.g"].to_numpy()[free]
    np.testing.assert_allclose(lam, T * 1e-3 / 4e-3, rtol=1e-10)
    acc = T / 4e-3
    th = sim.q["fly.theta"].to_numpy()[free]
    np.testing.assert_allclose(th, -1e-3 + 0.5 * acc * sim.t[free] ** 2, rtol=0, atol=1e-15)


def test_nonlinear_joint_residual_is_second_order():
    """A pin joint at a point 5 cm off the pinion centre (x, y held), linearised at q = 0:
    the pinion swings about that point. Along the trajectory the exact residual (finite
    rotation) is g_x = |at| (cos theta - 1), g_y = |at| (sin theta - theta): second order,
    |g| = |at| theta^2 / 2 to within theta^2 / 12."""
    m = pair()
    m.bodies["wheel"].dofs = "planar"
    m.bodies["pinion"].dofs = "planar"
    m.add(gm.Bearing("wheel_bearing", "wheel", None, stiffness={"x": 1e8, "y": 1e8}))
    pin = gm.Joint("pin", "pair.pinion", None, directions=("x", "y"), at=(0.05, 0.0, 0.0))
    cs = gm.Coupled([gm.ModelSystem(m.check(), "pair")], [pin])
    sim = gm.simulate(cs, 0.01, dt=1e-4, v0={"pair.pinion.theta": 2.0,
                                              "pair.pinion.y": -0.1})
    th = sim.q["pair.pinion.theta"].to_numpy()
    assert np.abs(th).max() > 1e-3
    g = sim.constraint_residual.to_numpy()
    np.testing.assert_allclose(g[:, 0], 0.05 * (np.cos(th) - 1.0), rtol=1e-6, atol=1e-18)
    np.testing.assert_allclose(g[:, 1], 0.05 * (np.sin(th) - th), rtol=1e-6, atol=1e-18)
    bound = 0.5 * 0.05 * th**2
    assert np.all(np.abs(g[:, 0]) <= bound * (1 + 1e-9) + 1e-18)
    assert np.abs(g[:, 0]).max() >= 0.99 * bound.max()


def test_bad_coupled_input():
    with pytest.raises(gm.ModelError, match="no DOF|no such DOF"):
        gm.Coupled([gm.ModelSystem(pair(), "pair")], [gm.LinearConstraint("c", {"pair.nope": 1.0})])
    with pytest.raises(gm.ModelError, match="refers to system"):
        gm.Coupled([pair()], [gm.LinearConstraint("c", {"other.x": 1.0})])
    with pytest.raises(gm.ModelError, match="used twice"):
        gm.Coupled([pair(), pair()])
    with pytest.raises(gm.ModelError, match="no body"):
        gm.Coupled([gm.ModelSystem(pair(), "p")], [gm.Joint("j", "p.nope")])
    with pytest.raises(gm.ModelError, match="directions"):
        gm.Joint("j", "p.pinion", directions=("w",))
    fly = Flywheel("fly", 1e-3)
    cs = gm.Coupled([gm.ModelSystem(pair(), "pair"), fly],
                    [gm.LinearConstraint("s", {"fly.theta": 1.0, "pair.pinion.theta": -1.0})])
    with pytest.raises(gm.ModelError, match="violates the constraints"):
        gm.simulate(cs, 0.001, dt=1e-4, q0={"fly.theta": 1e-3})


def test_coupled_system_with_turning_frames_is_refused_at_speed():
    """The 600 kW coupled drivetrain at speed turns its carrier against the housing: its
    constraint forces would need the turning geometry, which the coupled path does not follow
    yet, so the run is refused with an error naming the setting (at 0 rpm it runs)."""
    _, coupled = split_600kw()
    with pytest.raises(gm.ModelError, match="speed_rpm"):
        gm.simulate(coupled, 0.01, dt=1e-3, speed_rpm=22.1)
    assert len(gm.simulate(coupled, 0.01, dt=1e-3).t) == 11
