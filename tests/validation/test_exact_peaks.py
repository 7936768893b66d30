"""Exact peaks (DESIGN 3.2: load statistics from the exact solution): the true maximum of every
contact force and planet-bearing radial force over each piece, against closed forms and a
dense-output reference; independent of the output step; never below a sampled value."""

import math

import numpy as np
import pytest

import gearmodal as gm
from gearmodal.scene import load_scene

I_P, I_W, K_MESH = 1e-3, 1.6e-2, 2e8
STAGE = "studies/scenes/planetary_double_contact.toml"


def test_rattle_contact_peak_is_the_closed_form():
    """A free torsional pair rattling in its backlash (tests/validation/test_exactness.py): each
    contact is half a period of the mesh oscillator, so its peak force is ``v sqrt(k m_e)`` (v
    the approach speed along the line of action, m_e the effective mass) at the middle of the
    contact. The event log's episode peaks and the run's peak equal it to 1e-12 at an output
    step 18 times longer than a contact."""
    m = gm.examples.gear_pair(pinion_inertia=I_P, wheel_inertia=I_W, mesh_stiffness=K_MESH,
                              backlash=1e-4)
    rp, rw = m.bodies["pinion"].base_radius, m.bodies["wheel"].base_radius
    me = 1.0 / (rp**2 / I_P + rw**2 / I_W)
    v = rp * 1.0
    sim = gm.simulate(m, 0.02, dt=3e-3, q0={"pinion.theta": -0.5e-4 / rp},
                      v0={"pinion.theta": 1.0})
    ev = sim.events
    ends = ev[ev.state_after == "open"]
    starts = ev[ev.state_after == "closed"]
    assert len(ends) >= 5
    np.testing.assert_allclose(ends.peak_force_N, v * math.sqrt(K_MESH * me), rtol=1e-12)
    half = 0.5 * (ends.time.to_numpy() - starts.time.to_numpy()[:len(ends)])
    np.testing.assert_allclose(ends.peak_time - starts.time.to_numpy()[:len(ends)], half,
                               rtol=1e-9)
    assert starts.peak_force_N.isna().all()  # the peak is on the row that ends the episode
    pk = sim.peaks()
    assert pk.loc["mesh.front", "exact"]
    assert pk.loc["mesh.front", "peak_force_N"] == pytest.approx(v * math.sqrt(K_MESH * me),
                                                                 rel=1e-12)
    # the rows (3 ms apart) see almost nothing of 0.17 ms contacts
    assert sim.forces["mesh.front"].max() < 0.5 * pk.loc["mesh.front", "peak_force_N"]


@pytest.fixture(scope="module")
def stage_runs():
    """The double-contact stage over its first 40 ms (the carrier drops into double contact)
    at its output step and with rows every 0.2 us (dense output: the same solution)."""
    run = load_scene(STAGE, {"scene.t_end": 0.04}).simulate()
    dense = load_scene(STAGE, {"scene.t_end": 0.04, "scene.dt": 2e-7}).simulate()
    return run, dense


def dense_channel(f, ch):
    """A channel's values at the dense rows: a flank as is, a radial force from x and y."""
    if ch.endswith(".radial"):
        el = ch[:-len(".radial")]
        return np.hypot(f[f"{el}.x"], f[f"{el}.y"])
    return f[ch] if ch.endswith((".front", ".back")) else f[ch].abs()


def test_peak_bins_against_the_dense_output():
    """Bins of 5 ms (eight in the run: pieces across bin ends, each bin's own search): every
    bin's exact peak against the dense run's largest sample in that bin, as above."""
    sc = load_scene(STAGE, {"scene.t_end": 0.04})
    run = gm.simulate(sc.model, 0.04, dt=1e-4, loads=sc.loads, peak_bin=0.005)
    dense = gm.simulate(sc.model, 0.04, dt=2e-7, loads=sc.loads, peak_bin=None)
    bins = run.peak_bins
    assert bins.bin_start_s.nunique() == 9  # 0 .. 0.04: the last a bin of its own end
    f = dense.forces
    checked = 0
    for ch, g in bins.groupby("channel"):
        x = dense_channel(f, ch).to_numpy()
        t = f.index.to_numpy()
        for b0, peak in zip(g.bin_start_s, g.peak_force_N, strict=True):
            inside = (t >= b0 - 1e-12) & (t <= b0 + 0.005 + 1e-12)  # (its ends included)
            if not inside.any():
                continue
            top = x[inside].max()
            assert top <= peak * (1 + 1e-12) + 1e-9, (ch, b0)
            assert peak - top <= 2e-6 * max(peak, 1.0) + 1e-9, (ch, b0)
            checked += 1
    assert checked >= 100


def test_exact_peaks_against_a_dense_output_reference(stage_runs):
    """Every exact channel's peak is at least the dense run's largest sample and above it by
    less than 2e-6 of the peak: between samples 0.2 us apart a force can exceed them by at
    most ``f'' dt^2 / 8``, about ``(omega dt)^2 / 8 = 1e-6`` of its amplitude for the 3 kHz
    contact modes. The 0.1 ms rows of the normal run stay below the exact peaks."""
    run, dense = stage_runs
    pk = run.peaks()
    assert pk.exact.sum() >= 15  # 12 flanks, the carrier bearing's sides, 3 planet bearings
    dp = dense.peaks()
    np.testing.assert_array_equal(pk.loc[pk.exact, "peak_force_N"],
                                  dp.loc[pk.index[pk.exact], "peak_force_N"])
    f = dense.forces
    for ch in pk.index[pk.exact]:
        x = dense_channel(f, ch)
        exact = pk.loc[ch, "peak_force_N"]
        assert x.max() <= exact * (1 + 1e-12) + 1e-9, ch
        assert exact - x.max() <= 2e-6 * max(exact, 1.0), ch
        assert run.forces[ch].max() <= exact * (1 + 1e-12) + 1e-9 if ch in run.forces else True


def test_episode_peaks_against_the_dense_output(stage_runs):
    """Each contact episode's peak in the event log (the row that ends it) is the largest
    dense sample of that contact between its closing and opening, to 2e-6."""
    run, dense = stage_runs
    ev = run.events
    f = dense.forces
    closing = {}
    checked = 0
    for row in ev.itertuples():
        key = f"{row.element}.{row.contact}"
        if row.state_after == "closed":
            closing[key] = row.time
        elif key in f.columns and key in closing:
            seg = f[key][(f.index >= closing[key]) & (f.index <= row.time)]
            if len(seg) > 20:
                assert seg.max() <= row.peak_force_N * (1 + 1e-12) + 1e-9
                assert row.peak_force_N - seg.max() <= 2e-6 * row.peak_force_N
                assert closing[key] <= row.peak_time <= row.time
                checked += 1
    assert checked > 50


def test_peaks_do_not_depend_on_the_output_step():
    """The same exact peaks, to the bit, at the scene's step, half and twice it."""
    sims = [load_scene(STAGE, {"scene.t_end": 0.05, "scene.dt": dt}).simulate()
            for dt in (1e-4, 5e-5, 2e-4)]
    ref = sims[0].peak_bins
    for s in sims[1:]:
        np.testing.assert_array_equal(s.peak_bins.peak_force_N, ref.peak_force_N)
        np.testing.assert_array_equal(s.peak_bins.time_s, ref.time_s)
        np.testing.assert_array_equal(s.events.peak_force_N.fillna(-1.0),
                                      sims[0].events.peak_force_N.fillna(-1.0))


def test_peaks_over_later_bins_and_sampled_elsewhere():
    """``peaks(t_from)`` on the bins' grid reads the bins from there; off the grid, and for
    methods without the series, the peaks are the sampled ones and say so."""
    sc = load_scene(STAGE, {"scene.t_end": 0.06})
    sim = gm.simulate(sc.model, 0.06, dt=1e-4, loads=sc.loads, peak_bin=0.02)
    late = sim.peaks(0.02)
    assert late.exact.any()
    assert (late.time_s[late.exact] >= 0.02).all()
    f = sim.forces[sim.forces.index >= 0.02]
    for ch in late.index[late.exact & late.index.str.endswith((".front", ".back"))]:
        assert late.loc[ch, "peak_force_N"] >= f[ch].max()
    full = sim.peaks()  # the run's peaks: some before 0.02 s, above the window's
    assert (late.peak_force_N[late.exact] < full.peak_force_N[late.exact]).any()
    assert not sim.peaks(0.015).exact.any()  # off the grid: sampled
    nm = gm.simulate(sc.model, 0.01, dt=1e-5, loads=sc.loads, method="newmark")
    assert nm.peak_bins is None and not nm.peaks().exact.any()


def test_turbine_peaks_against_a_dense_output():
    """The clearance gearbox in the turbine (the studies' rung), 2 s from start-up: its peaks
    are found across 100 kernel calls (one per aerodynamic step) and the re-basings of the
    reference rotation. Against the same run with rows every 10 us: never below a dense
    sample, above the largest by less than 2e-4 (the rung's fastest modes at 500 Hz:
    ``(2 pi 500 10 us)^2 / 8 = 1.2e-4``)."""
    import sys
    from pathlib import Path

    from gearmodal.turbine import simulate_drivetrain

    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "studies"))
    from double_contact import CLEARANCE

    sc = load_scene("studies/scenes/600kw_turbine_10ms.toml",
                    overrides={"scene.t_end": 2.0, "model.stages.0.carrier_bearing": CLEARANCE})
    kw = {**sc.drivetrain, "top_frequency_hz": 500.0}
    run = simulate_drivetrain(sc.turbine, sc.wind, sc.model, 2.0, dt=1e-3, **kw).gearbox
    dense = simulate_drivetrain(sc.turbine, sc.wind, sc.model, 2.0, dt=1e-5, peak_bin=None,
                                **kw).gearbox
    assert len(run.events) > 50 and run.stats["n_events"] == dense.stats["n_events"]
    pk = run.peaks()
    checked = 0
    for ch in pk.index[pk.exact]:
        x = dense_channel(dense.forces, ch)
        exact = pk.loc[ch, "peak_force_N"]
        assert x.max() <= exact * (1 + 1e-12) + 1e-9, ch
        assert exact - x.max() <= 2e-4 * max(exact, 1.0), ch
        checked += 1
    assert checked >= 15
