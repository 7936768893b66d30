"""method = "auto" (gearmodal.auto): the step ladder's choice meets its tolerance against a
much finer run on the paper's cases, sized for CI: the 600 kW planetary stage of the
double-contact study alone (``studies/scenes/planetary_double_contact.toml``, 0.3 s of rated
torque and the rotor's shaft-end force), with the paper's ``clearance`` carrier bearing (1 mm,
1e8 N/m: double contact) and the ``reference`` one (1e9 N/m, no clearance). The paper's
turbine scene (30 s per rung) is run by ``benchmarks/fidelity.py --auto``."""

import copy
import math
from pathlib import Path

import pytest

import gearmodal as gm
from gearmodal.auto import QUANTITIES, difference
from gearmodal.cli import main
from gearmodal.errors import ModelError
from gearmodal.run import RunResult
from gearmodal.scene import load_scene
from gearmodal.studies import summarize

SCENE = "studies/scenes/planetary_double_contact.toml"
MODELS = str((Path(SCENE).parent.parent / "models").resolve())


def scene_text() -> str:
    """The scene file with its model path absolute (to write variants elsewhere)."""
    return Path(SCENE).read_text(encoding="utf-8").replace('"../models/', f'"{MODELS}/')
CASES = {"clearance": {}, "reference": {"model.planetary_stage.carrier_bearing": 1.0e9}}


@pytest.mark.parametrize("case", sorted(CASES))
def test_auto_choice_meets_its_tolerance_against_a_much_finer_run(case):
    """The truth is the exact method at 1/64 of the scene's step (16x finer than the finest
    rung: its sampled peaks moved < 1e-3 relative between 1/32 and 1/128 when measured). The
    chosen rung must be within the tolerance of it on every quantity, and the rule must have
    chosen the first rung satisfying (A2)."""
    tol = 0.05
    sc = load_scene(SCENE, CASES[case])
    ch = gm.choose_fidelity(sc, tol, keep_all=True)
    assert ch.met and ch.rung is not None and ch.result is ch.results[ch.rung]
    t = ch.table
    assert t.chosen.sum() == 1 and bool(t.chosen.iloc[ch.rung])
    assert t.diff_next.iloc[ch.rung] <= tol and t.diff_next2.iloc[ch.rung] <= tol
    for r in range(ch.rung):  # no cheaper rung satisfies the rule
        assert not (t.diff_next.iloc[r] <= tol and t.diff_next2.iloc[r] <= tol)
    assert ch.settings["dt"] == pytest.approx(t.dt.iloc[ch.rung])
    truth_scene = copy.copy(sc)
    truth_scene.dt = sc.dt / 64
    truth = summarize(truth_scene.simulate())
    chosen = summarize(ch.result)
    assert difference(chosen, truth) <= tol, {q: (chosen[q], truth[q]) for q in QUANTITIES}
    if case == "clearance":  # the case is a real choice: coarser rungs are off by more
        assert ch.rung > 0 and difference(summarize(ch.results[0]), truth) > tol


def test_scene_method_auto_returns_the_chosen_rung_and_the_cli_writes_the_table(tmp_path):
    text = scene_text().replace('method = "exact"', 'method = "auto"\ntolerance = 0.05')
    p = tmp_path / "auto.toml"
    p.write_text(text)
    sc = load_scene(p)
    assert sc.method == "auto" and sc.tolerance == 0.05
    calls = []
    sim = sc.simulate(progress=lambda i, n: calls.append((i, n)))
    assert calls[0] == (1, 6) and len(calls) == len(sim.choice.table)
    assert sim.choice.results == []  # only the chosen rung's run is kept
    assert sim.choice.met
    assert sim.gearbox.settings["dt"] == pytest.approx(sim.choice.settings["dt"])
    assert sim.gearbox.settings["method"] == "exact"
    assert isinstance(sim, RunResult) and isinstance(sim.result, gm.SimulationResult)
    # as it was returned before: the chosen rung's result's own names, the choice as .auto
    assert sim.auto is sim.choice and sim.forces is sim.result.forces
    out = tmp_path / "run"
    assert main(["simulate", str(p), "--out", str(out), "--quiet"]) == 0
    for f in ("auto.csv", "auto.json", "auto.png", "events.parquet", "forces.parquet"):
        assert (out / f).exists(), f


def test_auto_reports_an_unmet_tolerance_by_name(tmp_path):
    sc = load_scene(SCENE)
    sc.t_end = 0.05
    ch = gm.choose_fidelity(sc, 1e-9, levels=3)
    assert not ch.met and ch.result is None and len(ch.table) == 3
    assert math.isnan(ch.table.diff_next2.iloc[-1])
    sc.method, sc.tolerance = "auto", 1e-9
    with pytest.raises(ModelError, match="scene.tolerance"):
        sc.simulate()


@pytest.mark.parametrize("kwargs, field", [({"tol": 0.0}, "tol"), ({"tol": "5%"}, "tol"),
                                           ({"coarsest": 0.5}, "coarsest"),
                                           ({"levels": 2}, "levels")])
def test_auto_bad_arguments_name_the_field(kwargs, field):
    with pytest.raises(ModelError, match=f"^{field}"):
        gm.choose_fidelity(load_scene(SCENE), **kwargs)


def test_scene_tolerance_needs_method_auto_and_a_range(tmp_path):
    base = scene_text()
    p = tmp_path / "s.toml"
    p.write_text(base.replace('method = "exact"', 'method = "exact"\ntolerance = 0.05'))
    with pytest.raises(ModelError, match="scene.tolerance.*auto"):
        load_scene(p)
    p.write_text(base.replace('method = "exact"', 'method = "auto"\ntolerance = 0'))
    with pytest.raises(ModelError, match=r"scene.tolerance.*\(0, 10\)"):
        load_scene(p)


def test_turbine_rungs_keep_dt_a_whole_fraction_of_the_aerodynamic_step():
    """A turbine scene's dt must divide aero_dt (0.02 s): the ladder snaps each rung's step."""
    from gearmodal.auto import _rung_settings, _settings

    sc = load_scene("studies/scenes/600kw_turbine_10ms.toml", {"scene.dt": 2e-3})
    base = _settings(sc)
    assert base == {"dt": 2e-3}  # the turning geometry is exact: no refreeze angle to refine
    for f in (4.0, 2.0, 1.0, 0.5, 0.25, 3.0):
        st = _rung_settings(sc, base, f)
        m = 0.02 / st["dt"]
        assert abs(m - round(m)) < 1e-9
        assert st["dt"] / (2e-3 * f) == pytest.approx(1.0, rel=0.34)


def test_difference_is_symmetric_about_zero():
    a, b = dict.fromkeys(QUANTITIES, 1.0), dict.fromkeys(QUANTITIES, 1.0)
    assert difference(a, b) == 0.0
    a["double_contact_time_s"] = 0.0
    assert difference(a, b) == math.inf and difference(b, a) == math.inf
    b["double_contact_time_s"] = 0.0
    b["max_front_force_N"] = 1.1
    assert difference(a, b) == pytest.approx(0.1 / 1.1)


def test_auto_store_resumes_an_interrupted_ladder(tmp_path):
    """A ladder stopped after two rungs resumes from its store: the finished rungs are loaded
    (``cached``), the rest run, and the table and the chosen result equal an uninterrupted
    ladder's to the last bit (the runs are deterministic). A rerun loads every rung and runs
    only the chosen one again; another scene is refused."""
    sc = load_scene(SCENE)
    sc.t_end = 0.1
    plain = gm.choose_fidelity(sc, 0.05)
    store = tmp_path / "rungs"

    def stop_after_two(level, st, row):
        if level == 1:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        gm.choose_fidelity(sc, 0.05, store=store, progress=stop_after_two)
    assert sorted(p.name for p in store.glob("rung*.json")) == ["rung0.json", "rung1.json"]
    ran = []
    resumed = gm.choose_fidelity(sc, 0.05, store=store,
                                 progress=lambda lv, st, row: ran.append(lv))
    assert list(resumed.table.cached) == [lv < 2 for lv in range(len(resumed.table))]
    assert ran == list(range(len(resumed.table)))  # progress reports loaded rungs too
    cols = ["rung", "dt", *QUANTITIES, "diff_next", "diff_next2", "chosen"]
    assert resumed.table[cols].equals(plain.table[cols])
    assert resumed.result.forces.equals(plain.result.forces)
    again = gm.choose_fidelity(sc, 0.05, store=store)
    assert again.table.cached.all() and again.rung == plain.rung
    assert again.result.forces.equals(plain.result.forces)  # the chosen rung, run again
    other = load_scene(SCENE, CASES["reference"])
    with pytest.raises(gm.StoreError, match="^store.*different scene sha256"):
        gm.choose_fidelity(other, 0.05, store=store)


def test_fingerprint_ignores_the_path_the_method_and_a_finished_run():
    """The store's key is the scene's content: a relative and an absolute path, ``method`` and
    ``tolerance`` do not change it, nor do the caches a turbine run fills (the turbulence box,
    the rotor's induction warm start); the model does."""
    from gearmodal.auto import fingerprint

    turbine = "studies/scenes/600kw_turbine_10ms.toml"
    sc = load_scene(turbine, {"scene.t_end": 0.04})
    before = fingerprint(sc)
    assert fingerprint(load_scene(str(Path(turbine).resolve()), {"scene.t_end": 0.04})) \
        == before
    sc.simulate()
    assert fingerprint(sc) == before
    sc.method, sc.tolerance = "auto", 0.01
    assert fingerprint(sc) == before
    assert fingerprint(load_scene(turbine, {"scene.t_end": 0.04,
                                            "model.stages.0.backlash": 2e-4})) != before
