"""The Taylor propagator of the exact method (gearmodal/integrate/taylor.py): its root
isolation, its spectral bound, its safety net for stiff states and its agreement with the
exponential propagator."""

import math
import sys
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

import gearmodal as gm
from gearmodal.errors import ModelError, SolveError
from gearmodal.integrate.kernels import GRAZE_MARGIN, candidate, hermite_max
from gearmodal.integrate.system import PiecewiseLinearSystem
from gearmodal.integrate.taylor import (
    DEPTH,
    N_TERMS,
    REACH,
    TABLE_DEGREE,
    StateBound,
    TaylorIntegrator,
    _bernstein,
    _state_rho,
    first_root,
    spectral_bound_all,
    terms_for,
)

sys.path.insert(0, str(Path(__file__).parent / "validation"))
from test_exactness import clearance_stage  # noqa: E402

STAGE_LOADS = {"carrier.force_u": 2e3, "sun.force_u": -2e3, "carrier.force_y": -3e3}


def root(coef):
    coef = np.asarray(coef, dtype=float)
    return first_root(coef, np.empty((DEPTH + 5, len(coef))), np.empty((2, DEPTH + 1)))


def first_crossing_numpy(coef):
    """Reference: the smallest real root in [0, 1] where the polynomial goes from <= 0 to
    > 0 (numpy's companion-matrix roots, checked by the sign just after)."""
    r = np.roots(coef[::-1])
    r = np.sort(r[(np.abs(r.imag) < 1e-9) & (r.real >= 0) & (r.real <= 1)].real)
    for x in r:
        if np.polyval(coef[::-1], min(x + 1e-7, 1.0)) > 0:
            return x
    return math.inf


def test_first_root_matches_numpy_on_random_polynomials():
    """Degree 12 polynomials with decaying coefficients (as the scaled Taylor rows are):
    the first upward crossing agrees with numpy's roots to 1e-9 (numpy's companion matrix is
    the less accurate of the two), and "no crossing" agrees."""
    rng = np.random.default_rng(3)
    found = 0
    for _ in range(300):
        k = np.arange(13)
        c = rng.standard_normal(13) * 4.0**k / np.array([math.factorial(j) for j in k])
        c[0] = -abs(c[0])
        ours, ref = root(c), first_crossing_numpy(c)
        if math.isinf(ref):
            assert math.isinf(ours)
        else:
            found += 1
            assert ours == pytest.approx(ref, abs=1e-9)
            assert np.polyval(c[::-1], ours) > 0  # the returned point is past the crossing
    assert found > 50


def test_first_root_finds_a_graze_and_rejects_a_near_miss():
    """g = -(tau - 0.3)^2 + eps: positive only on 0.3 -+ sqrt(eps). With eps = 1e-12 the bump
    is 2e-6 wide (no sampling would see it); with eps = -1e-12 it stays below zero. The root
    is ill-conditioned: g is evaluated to ~1e-17 against a slope of 2e-6, so 1e-11."""
    for eps, expect in ((1e-12, 0.3 - 1e-6), (-1e-12, math.inf)):
        c = [-0.09 + eps, 0.6, -1.0]
        r = root(c)
        if math.isinf(expect):
            assert math.isinf(r)
        else:
            assert r == pytest.approx(expect, abs=1e-11)


@pytest.mark.parametrize("d", [0, 1, 5, 23, TABLE_DEGREE, TABLE_DEGREE + 1, 50])
def test_bernstein_basis_change_matches_exact_rationals(d):
    """The tabulated basis change (degree <= TABLE_DEGREE) and the repeated summation beyond
    it against ``b_i = sum_(k <= i) C(i, k) / C(d, k) c_k`` in exact rational arithmetic:
    within a rounding bound of 4 (d + 1) eps sum |c_k| (each b_i is a sum of at most d + 1
    terms, each of magnitude <= |c_k|, since C(i, k) <= C(d, k))."""
    rng = np.random.default_rng(d)
    k = np.arange(d + 1)
    for _ in range(20):
        c = rng.standard_normal(d + 1) * 3.0**k / np.array([float(math.factorial(j))
                                                              for j in k])
        b = np.empty(d + 1)
        _bernstein(c, b)
        exact = [sum(Fraction(math.comb(i, j), math.comb(d, j)) * Fraction(float(c[j]))
                     for j in range(i + 1)) for i in range(d + 1)]
        err = max(abs(Fraction(float(b[i])) - exact[i]) for i in range(d + 1))
        assert float(err) <= 4 * (d + 1) * np.finfo(float).eps * np.abs(c).sum()


def test_candidate_control_point_bound_changes_no_decision():
    """``candidate`` clears most gaps on the control points of the Hermite cubic before
    computing its maximum; being an upper bound, it must give the decision of the maximum
    itself on every input (200,000 random gaps, receding, rising and mixed)."""
    rng = np.random.default_rng(7)
    n = 200_000
    ga = -np.abs(rng.standard_normal(n)) * 10.0 ** rng.uniform(-3, 1, n)
    gb = -np.abs(rng.standard_normal(n)) * 10.0 ** rng.uniform(-3, 1, n)
    ra = rng.standard_normal(n) * 10.0 ** rng.uniform(-3, 1, n)
    rb = rng.standard_normal(n) * 10.0 ** rng.uniform(-3, 1, n)
    L = 10.0 ** rng.uniform(-2, 0, n)
    flagged = 0
    for i in range(n):
        scale = abs(ra[i] * L[i]) + abs(rb[i] * L[i])
        expect = hermite_max(ga[i], ra[i], gb[i], rb[i], L[i]) > -GRAZE_MARGIN * scale
        got = candidate(ga[i], ra[i], gb[i], rb[i], L[i], GRAZE_MARGIN)
        assert got == expect, (ga[i], ra[i], gb[i], rb[i], L[i])
        flagged += got
    assert 0.05 * n < flagged < 0.95 * n  # both outcomes are exercised


def test_spectral_bound_holds_for_every_contact_state():
    system = PiecewiseLinearSystem(gm.assemble(clearance_stage()), speed_rpm=0.0)
    bound = spectral_bound_all(system)
    rng = np.random.default_rng(0)
    worst = 0.0
    for _ in range(40):
        s = rng.random(system.n_contacts) < 0.5
        A, _ = system.first_order(s)
        worst = max(worst, np.abs(np.linalg.eigvals(A)).max())
    A, _ = system.first_order(np.ones(system.n_contacts, dtype=bool))
    assert np.abs(np.linalg.eigvals(A)).max() <= bound
    assert worst <= bound
    assert bound < 1.5 * np.abs(np.linalg.eigvals(A)).max()  # and it is not loose


def test_per_state_bound_holds_for_its_state_and_never_exceeds_the_global_one():
    """Each contact state's own bound (StateBound, kappa = 1 on a frozen system) bounds that
    state's spectral radius, is below the all-states bound, and is tighter for states with
    few contacts closed (the open stage: its supports only)."""
    system = PiecewiseLinearSystem(gm.assemble(clearance_stage()), speed_rpm=0.0)
    rho_all = spectral_bound_all(system)
    sb = StateBound(system, rho_all)
    assert sb.enabled and sb.kappa == pytest.approx(1.0)
    args = sb.args()[1:]
    rng = np.random.default_rng(1)
    for _ in range(30):
        s = rng.random(system.n_contacts) < 0.5
        A, _ = system.first_order(s)
        rho_s = _state_rho(s, *args[:-2], rho_all, *args[-2:])
        assert np.abs(np.linalg.eigvals(A)).max() <= rho_s <= rho_all
    none = np.zeros(system.n_contacts, dtype=bool)
    assert _state_rho(none, *args[:-2], rho_all, *args[-2:]) < 0.5 * rho_all
    assert len(sb.cache) == 31  # one eigenproblem per state met


def _stage_run(**options):
    return gm.simulate(clearance_stage(), 0.004, dt=4e-5, loads=STAGE_LOADS, **options)


def test_taylor_and_expm_propagators_agree_on_the_double_contact_stage():
    """Two exact propagations of the same trajectory (310 events, double contact): the same
    events to 1e-13 s and the same states to rounding amplified by the problem (~1e-13)."""
    a = _stage_run(propagator="taylor")
    b = _stage_run(propagator="expm")
    assert len(a.events) == len(b.events) > 300
    assert (a.events.contact == b.events.contact).all()
    np.testing.assert_allclose(a.events.time, b.events.time, rtol=0, atol=1e-13)
    scale = np.abs(b.q.to_numpy()).max()
    assert np.abs(a.q.to_numpy() - b.q.to_numpy()).max() < 1e-10 * scale
    assert a.stats["pieces"] >= len(a.events)
    assert b.stats["exponentials"] > 0


@pytest.mark.parametrize("speed_rpm, t_end", [(0.0, 0.004), (-600.0, 0.004), (0.0, 0.012)])
def test_the_solution_does_not_depend_on_the_output_step(speed_rpm, t_end):
    """The output step only places the output rows: at half the step the double-contact
    stage (at rest, and turning in its clearance carrier bearing) takes the same pieces and
    switches the same contacts at the same times, and the shared rows hold the same state to
    the bit. A tie window in units of dt made them differ at rounding (2e-15 s in the event
    times); over 12 ms (1 089 events) the event buffer runs full, and ending the stretch at an
    output time to grow it parted the runs from the 437th event."""
    a = gm.simulate(clearance_stage(), t_end, dt=4e-5, loads=STAGE_LOADS, speed_rpm=speed_rpm)
    b = gm.simulate(clearance_stage(), t_end, dt=2e-5, loads=STAGE_LOADS, speed_rpm=speed_rpm)
    assert len(a.events) > 200 and a.stats["pieces"] == b.stats["pieces"]
    np.testing.assert_array_equal(a.events.time, b.events.time)
    np.testing.assert_array_equal(a.q.to_numpy(), b.q.to_numpy()[::2])
    np.testing.assert_array_equal(a.v.to_numpy(), b.v.to_numpy()[::2])


def test_a_body_without_stiffness_moves_under_its_load():
    """A free rigid body under a constant torque: theta = T t^2 / (2 J), omega = T t / J (its
    spectral bound is zero, so the system's time scale is unbounded; a tie window on that scale
    alone swallowed the whole run and left the body at rest)."""
    m = gm.Model("free")
    m.add(gm.RigidBody(name="b", mass=1.0, inertia=2.0, dofs="torsional"))
    r = gm.simulate(m, 0.01, dt=1e-3, loads={"b.torque": 3.0})
    t = r.q.index.to_numpy()
    np.testing.assert_allclose(r.q["b.theta"], 3.0 * t**2 / 4.0, rtol=1e-12, atol=1e-18)
    np.testing.assert_allclose(r.v["b.theta"], 3.0 * t / 2.0, rtol=1e-12, atol=1e-18)


def test_the_event_dense_stage_does_bounded_work():
    """A guard on the kernel's work, not its time (deterministic counts): the double-contact
    stage (310 events, 219 contact states in 4 ms; the work-precision benchmark's problem).
    Recorded at 8300b1f: 391 pieces, 1 298 root searches, 10 790 gap series, 3 state
    eigenproblems, no halving. A bound per contact state for every state met (219
    eigenproblems) made this run 3x slower unnoticed for ten commits (CHANGELOG, 2026-11-25);
    the bounds below are the recorded counts plus 10 %: a change that needs more must say why
    here."""
    st = _stage_run().stats
    assert st["n_events"] == 310
    assert st["n_events"] <= st["pieces"] <= 430
    assert st["root_searches"] <= 1430 and st["taylor_rows"] <= 11_900
    # the start state's bound, then only states that outlive two pieces (LAZY)
    assert st["state_bounds"] <= 10
    assert st["halved"] == 0  # the bound holds on every piece: no tail check fails


def test_an_underestimated_bound_is_rescued_by_halving():
    """Pieces 20 times too long for the series' terms (as if a state were stiffer than the
    bound): the tail check halves them until the series converges; the result is unchanged."""
    system = PiecewiseLinearSystem(gm.assemble(clearance_stage()))
    n = system.n
    F = np.tile(np.zeros(n), (101, 1))
    asm = system.asm
    F += np.array([sum(asm.B[:, asm.load_names.index(k)] * v for k, v in STAGE_LOADS.items())])
    x0, s0 = np.zeros(2 * n), np.zeros(system.n_contacts, dtype=bool)
    good = TaylorIntegrator(system, 4e-5)
    X1, _, ev1 = good.run(100, F, x0, s0)
    assert good.n_terms == N_TERMS == terms_for(REACH)
    # the terms of a reach 20 times shorter than the pieces'
    bad = TaylorIntegrator(system, 4e-5, n_terms=terms_for(REACH / 20))
    X2, _, ev2 = bad.run(100, F, x0, s0)
    assert bad.counts["halved"] > 20
    assert len(ev1) == len(ev2)
    assert np.abs(X1 - X2).max() < 1e-10 * np.abs(X1).max()


def test_event_buffer_grows_and_the_event_cap_names_the_contact():
    """max_events_per_step sizes the event buffer; a run with more events than the initial
    buffer grows it and loses nothing. Exceeding the cap inside one step raises."""
    a = _stage_run()
    b = _stage_run(max_events_per_step=12)  # buffer 4 * (12 + 17) rows < 310 events
    assert len(b.events) == len(a.events)
    assert (a.events.contact == b.events.contact).all()
    np.testing.assert_allclose(a.events.time, b.events.time, rtol=0, atol=1e-13)
    with pytest.raises(SolveError, match="max_events_per_step.*contact"):
        _stage_run(max_events_per_step=1)


def test_bad_propagator_is_named():
    with pytest.raises(ModelError, match="propagator.*'taylor', 'expm'"):
        _stage_run(propagator="rk4")


def test_first_root_ends_on_a_tangent_and_on_non_finite_input():
    """A double root (tangent graze exactly at zero) and non-finite coefficients: the search
    ends (found in review: subdivision ran to 1e-60 widths, and forever on NaN)."""
    r = root([-0.09, 0.6, -1.0])  # -(tau - 0.3)^2: touches zero, never positive
    assert math.isinf(r) or abs(r - 0.3) < 1e-7
    assert math.isinf(root([-1.0, 0.0, 0.0, math.inf, 0.0, -math.inf]))


def test_first_root_near_overflow_and_scratch_width():
    """Coefficients near the largest double: the Bernstein sums (up to (d + 1) max |c_k|)
    would overflow to inf - inf and the subdivision run to its smallest width; scaled by a
    power of two the search gives the unscaled polynomial's roots (review finding). Scratch of
    another width than the polynomial is refused rather than read past it."""
    for c in ([-1.0, 0.5, 1.0, -0.25], [-1.0, 3.0, -3.0], [-0.2, 1.7, -2.9, 1.6, 0.1]):
        c = np.array(c)
        big = c * (1.7e308 / np.abs(c).max())  # largest |c_k| 1.7e308: finite, the sums not
        assert root(big) == pytest.approx(root(c), rel=1e-12)
    with pytest.raises(ValueError, match="one column per coefficient"):
        first_root(np.array([-1.0, 3.0, -3.0]), np.empty((DEPTH + 5, 8)),
                   np.empty((2, DEPTH + 1)))
