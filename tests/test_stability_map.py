"""The stability-map benchmark's classification (benchmarks/stability_map.py) on two corners
whose outcome is known: the exact method conserves the energy of an undamped rattle, Newmark
with a step longer than the contact does not, and the event count tells missed contacts."""

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "benchmarks"))

import stability_map as sm  # noqa: E402


def test_exact_holds_where_newmark_fails():
    name = "rattle k=1e+08 m=1 b=0.001"
    exact = sm.run_one(name, dict(method="exact", propagator="taylor"), budget_s=60)
    status, drift, _ = sm.classify(exact, None)
    # undamped: conserved to rounding, ~1e-16 per piece over ~1e4 pieces of rho h <= 6
    assert status == "ok" and drift < 1e-10
    newmark = sm.run_one(name, dict(method="newmark"), budget_s=60)
    status, drift, traj = sm.classify(newmark, exact)
    # dt = 1/40 of a 0.1 s flight is 2.5 ms, 5x the 0.5 ms contact: the step-end switch
    # penetrates deep and the energy jumps at every impact, growing without bound (the map's
    # "blowup" before the energy audit): now a SolveError naming the method and the setting
    assert status == "stopped", (status, newmark.get("note"))
    assert "newmark" in newmark["note"] and "diverging" in newmark["note"]
    assert "reduce dt" in newmark["note"]
    fn, args, _ = sm.cases(False)[name]
    dt = fn(*args)["dt"]
    # at dt / 16 (omega dt = 1.6 on the contact) the first impact, switched a step late,
    # penetrates with 2.6x the energy there is: stopped too (the map's "energy" before)
    assert sm.classify(sm.run_one(name, dict(method="newmark", dt=dt / 16), budget_s=60),
                       exact)[0] == "stopped"
    fine = sm.run_one(name, dict(method="newmark", dt=dt / 64), budget_s=60)
    status, drift, traj = sm.classify(fine, exact)
    # at dt / 64 it finishes, its energy off by the switches' lag (80 %: the map's "energy")
    assert status == "energy" and drift > 1e-3


def test_chatter_counts_events_against_exact():
    name = "chatter k=1e8 m=1 b=1e-06"
    exact = sm.run_one(name, dict(method="exact"), budget_s=60)
    fine = sm.run_one(name, dict(method="scipy", scipy_method="RK45", rtol=1e-6), budget_s=60)
    assert sm.classify(fine, exact)[0] == "ok"
    coarse = sm.run_one(name, dict(method="newmark"), budget_s=60)
    assert sm.classify(coarse, exact)[0] == "missed_events"


@pytest.mark.parametrize("name", ["rattle k=1e+08 m=1 b=0", "rattle k=1e+11 m=0.1 b=0"])
def test_scipy_switches_the_back_flank_with_the_front_at_zero_backlash(name):
    # zero backlash: the back flank's crossing is at the instant the front one opens, the
    # restart point of solve_ivp, where its event is missed once rounding has put the located
    # state past it; without the switch the teeth pass through each other and the energy
    # grows tenfold (the map's 'blowup'). The stiff light pair's contact (2 us) puts the tie
    # window at the event location's own tolerance, not at 1e-9 dt
    exact = sm.run_one(name, dict(method="exact"), budget_s=60)
    ref = sm.run_one(name, dict(method="scipy", scipy_method="RK45", rtol=1e-9), budget_s=60)
    status, drift, traj = sm.classify(ref, exact)
    assert status == "ok" and drift < 1e-6 and traj < 1e-6  # RK45 at rtol 1e-9: ~8e-8
    assert len(ref["events"]) == len(exact["events"]) == 49
    # event times to the solver's tolerance: 1e-7 of the contact (4e-13 s of 0.2 ms measured)
    assert abs(ref["events"] - exact["events"]).max() < 1e-7 * ref["contact_s"]
