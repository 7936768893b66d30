"""Modal analysis: closed forms and the Lin & Parker (1999) mode structure."""

import math

import numpy as np
import pandas as pd
import pytest

import gearmodal as gm
from gearmodal.modal import modal

LP = dict(mass={"carrier": 5.43, "ring": 2.35, "sun": 0.4, "planet": 0.66},
          inertia_over_r2={"carrier": 6.29, "ring": 3.0, "sun": 0.39, "planet": 0.61},
          bearing={"carrier": 1e8, "ring": 1e8, "sun": 1e8, "planet": 1e8},
          torsional={"carrier": 0.0, "ring": 1e9, "sun": 0.0},
          mesh={"sun_planet": 5e8, "ring_planet": 5e8})
ALPHA = math.radians(24.6)


def test_gear_pair_torsional_frequency_closed_form():
    """omega^2 = k (r_p^2 / I_p + r_w^2 / I_w) for the torsional pair; plus one rigid mode."""
    pair = gm.examples.gear_pair()
    p, w = pair.bodies["pinion"], pair.bodies["wheel"]
    res = modal(pair)
    f = math.sqrt(2e8 * (p.base_radius**2 / 1e-3 + w.base_radius**2 / 1.6e-2)) / 2 / math.pi
    assert res.frequencies_hz[1] == pytest.approx(f, rel=1e-12)
    assert res.frequencies_hz[0] < 1e-6 * f
    assert res.mode_types == ["rigid", "torsional"]


def groups(freqs, rtol=1e-8):
    """Cluster sorted frequencies into (value, multiplicity)."""
    out = []
    for f in freqs:
        if out and abs(f - out[-1][0]) <= rtol * max(f, 1.0):
            out[-1][1] += 1
        else:
            out.append([f, 1])
    return out


@pytest.mark.parametrize("n", [3, 4, 5, 6])
@pytest.mark.parametrize("speed_rpm, geometric", [(0.0, True), (600.0, True), (600.0, False)])
def test_lin_parker_mode_structure(n, speed_rpm, geometric):
    """Equally spaced planets, isotropic supports: rotational modes are simple, translational
    modes double, planet modes have multiplicity N - 3 (Lin & Parker 1999)."""
    res = modal(gm.lin_parker_stage(n, **LP, pressure_angle=ALPHA), speed_rpm=speed_rpm,
                geometric_stiffness=geometric)
    types = np.array(res.mode_types)
    f = res.frequencies_hz
    assert len(f) == 3 * (n + 3)
    # free sun and carrier rotation (k_su = k_cu = 0) give a rigid mode at rest; with the
    # planet bearings' centrifugal preload (geometric stiffness) it stays rigid at speed, as a
    # free rotation must; Lin & Parker's centripetal-only form lifts it off zero (a real
    # eigenvalue) and it reads rotational
    assert (types == "rigid").sum() == (1 if geometric else 0)
    assert (types == "rotational").sum() + (types == "rigid").sum() == 6
    assert (types == "translational").sum() == 12
    assert (types == "planet").sum() == 3 * (n - 3)
    # multiplicities, with a tolerance far below the smallest frequency gap (~1e-2 relative);
    # under rotation the translational pairs split into forward and backward whirl
    mults = (("rotational", 1), ("translational", 2 if speed_rpm == 0 else 1),
             ("planet", n - 3))
    for typ, mult in mults:
        sel = np.sort(f[types == typ])
        if len(sel):
            assert all(m == mult for _, m in groups(sel)), (typ, groups(sel))


def test_a_rigid_mode_at_speed_reads_undamped_not_unstable():
    """The example planetary stage turns freely (the ring's and sun's rotations rigid): at
    speed the gyroscopic and centripetal terms split the zero eigenvalue pair into two real
    roundings (|lambda| about 1e-4 rad/s), whose ratio read as damping -1 and +1 (an unstable
    mode) before; rigid modes now read 0, in the modal table and the Campbell diagram, and no
    mode of this passive gearbox reads negative."""
    m = gm.examples.planetary_stage()
    for rpm in (0.0, 20.0, 100.0):
        res = modal(m, speed_rpm=rpm)
        rigid = np.array(res.mode_types) == "rigid"
        assert rigid.sum() == 2
        assert np.all(res.frequencies_hz[rigid] < 1e-3)
        assert np.all(res.damping_ratios[rigid] == 0.0)
        assert np.all(res.damping_ratios >= 0.0)
        assert np.all(res.to_frame().log_dec[rigid] == 0.0)
    camp = gm.campbell(m, np.array([0.0, 20.0, 100.0]))
    rigid = camp.mode_types == "rigid"
    assert rigid.sum() == 6
    assert np.all(camp.damping_ratios[rigid] == 0.0)
    assert np.all(camp.damping_ratios >= 0.0)
    # an undamped mode reads the same 0 in both tables (Campbell read its rounding, 1e-16)
    for i, rpm in enumerate((0.0, 20.0, 100.0)):
        zm = np.sort(modal(m, speed_rpm=rpm).damping_ratios)
        zc = np.sort(camp.damping_ratios[i])
        assert (zc == 0.0).sum() == (zm == 0.0).sum() > 0
        np.testing.assert_allclose(zc, zm, rtol=1e-9, atol=1e-14)


def test_unequal_spacing_breaks_degeneracy():
    res = modal(gm.lin_parker_stage(4, **LP, pressure_angle=ALPHA,
                                    planet_angles=[0.0, 1.4, 3.3, 4.6]))
    g = groups(np.sort(res.frequencies_hz[1:]), rtol=1e-6)
    assert all(m == 1 for _, m in g)
    eq = modal(gm.lin_parker_stage(4, **LP, pressure_angle=ALPHA))
    assert any(m == 2 for _, m in groups(np.sort(eq.frequencies_hz[1:])))


def test_gyroscopic_split_of_isotropic_support():
    """A mass on an isotropic support in a frame turning at Omega: in the rotating frame the
    translational frequencies are omega_0 +- Omega (exact for this linear model)."""
    m = gm.Model("disk", input="body")
    m.add(gm.Frame("rot", 1.0))
    m.add(gm.RigidBody(name="body", mass=2.0, inertia=1.0, dofs="planar", frame="rot",
                       speed_ratio=1.0))
    m.add(gm.Bearing("support", "body", None, stiffness={"x": 8e4, "y": 8e4, "theta": 1e3}))
    w0 = math.sqrt(8e4 / 2.0)
    om = 60.0 * 2 * math.pi / 60  # 60 rpm
    res = modal(m, speed_rpm=60.0)
    f = np.sort(res.frequencies_hz) * 2 * math.pi
    expect = np.sort([w0 - om, w0 + om, math.sqrt(1e3)])
    np.testing.assert_allclose(f, expect, rtol=1e-10)


def test_modal_result_outputs(tmp_path):
    res = modal(gm.lin_parker_stage(3, **LP, pressure_angle=ALPHA))
    df = res.to_frame()
    assert list(df.columns[:5]) == ["mode", "speed_rpm", "frequency_hz", "damping_ratio",
                                    "mode_type"]
    np.testing.assert_allclose(res.kinetic_energy.sum(axis=1), 1.0, rtol=1e-12)
    res.save(tmp_path)
    assert (tmp_path / "modes.csv").exists() and (tmp_path / "shapes.csv").exists()
    fig = res.plot_shape(3)
    assert fig.axes


def test_mode_shapes_are_drawn_as_the_gearbox(tmp_path):
    """plot_shape draws the bodies where they sit, displaced by the mode: a planet's centre
    moves along its local zeta/eta turned by its orientation, every motion by one factor."""
    import matplotlib

    matplotlib.use("Agg")
    stage = gm.examples.planetary_stage()
    res = modal(stage)
    i = 6
    m = res.body_motion(i, scale=1.0)
    s = res.shape(i)
    planet = stage.bodies["planet2"]
    c, sn = math.cos(planet.orientation), math.sin(planet.orientation)
    zeta, eta = s["planet2.zeta"], s["planet2.eta"]
    ratio = m.at["planet2", "dx"] / (c * zeta - sn * eta)
    assert m.at["planet2", "dy"] == pytest.approx(ratio * (sn * zeta + c * eta), rel=1e-9)
    assert m.at["sun", "rotation"] == pytest.approx(ratio * s["sun.theta"], rel=1e-9)
    rim = np.where(np.isfinite(m.radius), m.radius, np.nanmax(m.radius))
    motion = np.r_[np.hypot(m.dx, m.dy), np.abs(rim * m.rotation)]
    assert motion.max() == pytest.approx(1.0, rel=1e-12)  # the largest motion is the scale
    fig = res.plot_shape(i)
    assert len(fig.axes[0].patches) == 2 * len(stage.bodies)  # at rest and displaced
    res.save(tmp_path)
    back = gm.ModalResult.load(tmp_path)
    pd.testing.assert_frame_equal(back.body_motion(i), res.body_motion(i), check_exact=True)
    with pytest.raises(gm.ModelError, match="no model geometry"):
        modal(stage.assemble()).body_motion(0)


def test_mode_shape_cycle_and_animation(tmp_path):
    """body_motion over the cycle is Re(phi e^{i phase}) at one scale: half a cycle later every
    motion is reversed, and a real (undamped, non-rotating) mode passes through rest at a
    quarter; animate_shape writes a GIF of that cycle with one frame per phase."""
    import matplotlib

    matplotlib.use("Agg")
    from PIL import Image

    stage = gm.examples.planetary_stage()
    res = modal(stage)
    i = 6
    m0, m180 = res.body_motion(i), res.body_motion(i, phase_deg=180.0)
    for col in ("dx", "dy", "rotation"):
        np.testing.assert_allclose(m180[col], -m0[col], atol=1e-15 * np.abs(m0[col]).max())
        assert np.abs(res.body_motion(i, phase_deg=90.0)[col]).max() < 1e-12 * np.abs(
            m0[col]).max()
    fig = res.plot_shape(i)
    arms = [ln for ln in fig.axes[0].lines if ln.get_color() == "C1"]
    assert len(arms) == 3  # the carrier's arms to its three planets, displaced
    path = res.animate_shape(i, tmp_path / "mode.gif", frames=8, fps=4)
    with Image.open(path) as gif:
        assert gif.format == "GIF" and gif.n_frames == 8
    with pytest.raises(gm.ModelError, match="frames"):
        res.animate_shape(i, tmp_path / "x.gif", frames=1)


def test_a_model_changed_in_place_gives_fresh_modes():
    """gm.modal reuses a model's assembly (assembly.cached_assembly) only while the model is
    unchanged: a bearing stiffness changed inside its table, a body's inertia, a removed
    bearing each give exactly the modes of a fresh copy, and the cached arrays are
    read-only."""
    from gearmodal.assembly import cached_assembly

    m = gm.load("studies/models/600kw.toml")
    first = modal(m, speed_rpm=22.1).frequencies_hz.copy()
    assert not cached_assembly(m).M.flags.writeable
    bearing = next(b for b in m.bearings.values() if b.role == "carrier_bearing")
    bearing.stiffness["x"] *= 0.5
    changed = modal(m, speed_rpm=22.1).frequencies_hz
    assert not np.allclose(changed, first)
    np.testing.assert_array_equal(changed, modal(m.copy(), speed_rpm=22.1).frequencies_hz)
    m.bodies["generator"].inertia *= 2.0
    np.testing.assert_array_equal(modal(m, speed_rpm=22.1).frequencies_hz,
                                  modal(m.copy(), speed_rpm=22.1).frequencies_hz)
    del m.bearings[bearing.name]
    np.testing.assert_array_equal(modal(m, speed_rpm=22.1).frequencies_hz,
                                  modal(m.copy(), speed_rpm=22.1).frequencies_hz)


def test_a_band_is_the_full_solves_lowest_modes():
    """``n_modes`` / ``fmax_hz`` solve the problem projected on twice as many undamped modes:
    on the 600 kW drivetrain at speed (damped, gyroscopic) its lowest modes match the full
    solve's to 1e-5 relative (measured: 2e-6), with the same mode types; a band of every mode
    is the full solve; bad band arguments are named."""
    m = gm.load("studies/models/600kw.toml")
    full = gm.modal(m, 22.1)
    for k in (5, 12):
        b = gm.modal(m, 22.1, n_modes=k)
        f = full.frequencies_hz[:k]
        assert b.n_modes == k and b.shapes.shape == (len(full.dof_names), k)
        np.testing.assert_allclose(b.frequencies_hz, f, rtol=1e-5, atol=1e-6)
        assert list(b.mode_types) == list(full.mode_types[:k])
    b = gm.modal(m, 22.1, fmax_hz=50.0)
    assert b.n_modes == int((full.frequencies_hz <= 50.0).sum())
    whole = gm.modal(m, 22.1, n_modes=200)
    np.testing.assert_array_equal(whole.frequencies_hz, full.frequencies_hz)
    for kw, match in (({"n_modes": 0}, "n_modes = 0"), ({"n_modes": 2.5}, "n_modes = 2.5"),
                      ({"fmax_hz": -1.0}, "fmax_hz = -1.0")):
        with pytest.raises(gm.ModelError, match=match):
            gm.modal(m, 22.1, **kw)


def test_a_campbell_band_tracks_the_full_diagrams_lowest_modes():
    m = gm.load("studies/models/600kw.toml")
    speeds = np.linspace(0.0, 30.0, 16)
    full = gm.campbell(m, speeds)
    b = gm.campbell(m, speeds, n_modes=12)
    assert b.frequencies_hz.shape == (16, 12)
    # atol: the rigid rotation's frequency is the rounding of a zero eigenvalue (~1e-6 Hz,
    # different in the two solves), every other mode is above 1.9 Hz
    np.testing.assert_allclose(b.frequencies_hz, full.frequencies_hz[:, :12], rtol=1e-5,
                               atol=1e-5)
    assert (b.mode_types == full.mode_types[:, :12]).all()
    c = gm.campbell(m, speeds, fmax_hz=100.0)
    assert c.frequencies_hz.shape[1] == int((full.frequencies_hz[0] <= 100.0).sum())
