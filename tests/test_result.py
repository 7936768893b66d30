"""SimulationResult analyses: double-contact episodes and load sharing."""

import numpy as np
import pytest

import gearmodal as gm
from gearmodal.scene import load_scene


@pytest.fixture(scope="module")
def clearance_run():
    sc = load_scene("studies/scenes/planetary_double_contact.toml")
    sc.t_end = 0.06
    return sc.simulate()


def test_double_contact_episodes_match_the_contact_states(clearance_run):
    sim = clearance_run
    dc = sim.double_contact()
    single = dc[dc.n_planets == 1]
    assert len(single) > 0
    t = sim.t
    st = sim.contact_state
    for mesh in single.mesh.unique():
        both = (st[f"{mesh}:front"] & st[f"{mesh}:back"]).to_numpy()
        inside = np.zeros(len(t), dtype=bool)
        for r in single[single.mesh == mesh].itertuples():
            inside |= (t > r.start) & (t < r.end)
        edge = np.zeros(len(t), dtype=bool)
        for r in single[single.mesh == mesh].itertuples():
            edge |= np.isclose(t, r.start, rtol=0, atol=1e-12) | np.isclose(t, r.end, rtol=0,
                                                                            atol=1e-12)
        # at every output time strictly inside an episode both flanks are closed, and
        # outside all episodes they are not both closed
        assert np.all(both[inside])
        assert not np.any(both[~inside & ~edge])
    assert (single.planet.str.match(r"planet\d")).all()
    np.testing.assert_allclose(single.duration, single.end - single.start, rtol=1e-15)


def test_several_planet_episodes_are_intersections(clearance_run):
    dc = clearance_run.double_contact()
    single, multi = dc[dc.n_planets == 1], dc[dc.n_planets >= 2]
    assert len(multi) > 0
    for r in multi.itertuples():
        mid = 0.5 * (r.start + r.end)
        on = single[(single.start <= mid) & (single.end > mid)]
        assert set(r.planet.split(",")) == set(on.planet)


def test_load_sharing_shares_sum_to_one_and_factor(clearance_run):
    ls = clearance_run.load_sharing().iloc[1:]
    shares = ls[["planet1", "planet2", "planet3"]].to_numpy()
    np.testing.assert_allclose(shares.sum(axis=1), 1.0, rtol=1e-9)
    np.testing.assert_allclose(ls.factor, 3 * shares.max(axis=1), rtol=1e-12)
    assert ls.attrs["peak_factor"]["stage"] == pytest.approx(ls.factor.max())
    assert ls.factor.max() > 1.2  # double contact unloads a planet


def test_symmetric_stage_shares_load_equally():
    """Without clearance or radial load the three planets share exactly (symmetry)."""
    m = gm.load("studies/models/planetary_clearance.toml")
    m.bearings["carrier_bearing"].clearance = {}
    loads = gm.balance(m, {"carrier.torque": 2.6e5}, on="sun.torque")
    sim = gm.simulate(m, 0.02, dt=1e-4, loads=loads)
    ls = sim.load_sharing().iloc[1:]
    np.testing.assert_allclose(ls.factor, 1.0, rtol=1e-7)
    assert sim.double_contact().empty


def test_tables_are_built_when_read_and_survive_pickling(clearance_run):
    """The five tables are built from the run's arrays on first read (a study reading only
    the event log does not pay for the force table), agree with the contact states and the
    event rows of the kernel, and a pickled result carries them all."""
    import pickle

    sc = load_scene("studies/scenes/planetary_double_contact.toml")
    sc.t_end = 0.02
    sim = sc.simulate()
    assert "_forces" not in sim.__dict__ or sim.__dict__["_forces"] is None
    ev = sim.events
    assert list(ev.columns) == gm.integrate.result.EVENT_COLUMNS
    assert set(ev.state_after) <= {"open", "closed"} and len(ev) > 10
    assert (ev.state_before != ev.state_after).all()
    # every logged change is seen in the contact states at the output times around it
    st = sim.contact_state
    for r in ev.head(20).itertuples():
        # the first output time after the event (row 0 is the state before any change)
        k = int(np.searchsorted(sim.t, r.time, side="right"))
        name = f"{r.element}:{r.contact}"
        later = ev[(ev.element == r.element) & (ev.contact == r.contact) & (ev.time > r.time)
                   & (ev.time <= sim.t[k])]
        if len(later) == 0:  # no further change of this contact before that output time
            assert bool(st[name].iloc[k]) == (r.state_after == "closed")
    back = pickle.loads(pickle.dumps(sim))
    for name in sim.TABLES:
        a, b = getattr(sim, name), getattr(back, name)
        assert a.equals(b), name
    assert sim.tables is None  # all five built: the run's arrays are released
    with pytest.raises(ValueError, match="forces"):
        sim.forces = None  # a rebuild would lose what simulate corrects after the run
