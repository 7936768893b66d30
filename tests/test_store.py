"""The one store of the sweep and the fidelity ladder (gearmodal.store): its layout tag and
identity refuse what they do not hold, its entries are written whole, leftovers of a killed
writer are removed."""

import json
import os
import time

import pytest

import gearmodal as gm
from gearmodal.store import STALE_S, Store


def _store(path, **identity):
    return Store(path, meta="meta.json", format="test/1", identity=identity or {"scene": "a"})


def test_a_store_reopens_with_its_identity_and_refuses_another(tmp_path):
    s = _store(tmp_path, scene="a", metrics="m")
    assert s.previous == {}
    s.write_meta(cases=[1, 2])
    assert json.loads((tmp_path / "meta.json").read_text()) == {
        "format": "test/1", "identity": {"scene": "a", "metrics": "m"}, "cases": [1, 2]}
    again = _store(tmp_path, scene="a", metrics="m")
    assert again.previous["cases"] == [1, 2]
    with pytest.raises(gm.StoreError, match=r"^store = .*different metrics \(metrics: 'm', "
                                            r"not 'n'\).*new store"):
        _store(tmp_path, scene="a", metrics="n")
    # only the entries compared; one the stored identity lacks is not (recorded later)
    Store(tmp_path, meta="meta.json", format="test/1", identity={"scene": "a", "metrics": "n",
                                                                   "new": 1},
          compare=("scene", "new"))
    with pytest.raises(gm.StoreError, match="different scene file"):
        Store(tmp_path, meta="meta.json", format="test/1", identity={"scene": "b"},
              labels={"scene": "scene file"})


def test_other_layouts_and_damaged_meta_are_refused(tmp_path):
    (tmp_path / "meta.json").write_text(json.dumps({"format": "test/0"}))
    with pytest.raises(gm.StoreError, match="older gearmodal.*test/0.*test/1"):
        _store(tmp_path)
    (tmp_path / "meta.json").write_text('{"format": "te')
    with pytest.raises(gm.StoreError, match="meta.json is unreadable"):
        _store(tmp_path)
    (tmp_path / "meta.json").write_text("[1, 2]")
    with pytest.raises(gm.StoreError, match="not a table"):
        _store(tmp_path)
    # the identity at the top level (the ladder's earlier layout) is still read
    (tmp_path / "meta.json").write_text(json.dumps({"format": "test/1", "scene": "a"}))
    _store(tmp_path, scene="a")
    with pytest.raises(gm.StoreError, match="different scene"):
        _store(tmp_path, scene="b")
    # an earlier tag named as read: read, and rewritten with this one's
    (tmp_path / "meta.json").write_text(json.dumps({"format": "test/0", "scene": "a"}))
    s = Store(tmp_path, meta="meta.json", format="test/1", identity={"scene": "a"},
              older=("test/0",))
    s.write_meta()
    assert json.loads((tmp_path / "meta.json").read_text())["format"] == "test/1"


def test_entries_are_written_whole(tmp_path):
    s = _store(tmp_path)

    def fill(text):
        def f(tmp):
            tmp.mkdir()
            (tmp / "x.txt").write_text(text)
        return f

    def broken(tmp):
        tmp.mkdir()
        (tmp / "x.txt").write_text("half")
        raise OSError("disk full")

    with pytest.raises(OSError, match="disk full"):
        s.put("cases/c1", broken)
    assert not (tmp_path / "cases" / "c1").exists()
    assert list((tmp_path / "cases").iterdir()) == []  # no temporary folder left
    s.put("cases/c1", fill("first"))
    s.put("cases/c1", fill("second"), replace=False)  # another run finished it first
    assert (tmp_path / "cases" / "c1" / "x.txt").read_text() == "first"
    s.put("cases/c1", fill("third"))
    assert (tmp_path / "cases" / "c1" / "x.txt").read_text() == "third"
    assert sorted(p.name for p in (tmp_path / "cases").iterdir()) == ["c1"]  # nothing aside
    s.write_json("rung0.json", {"a": 1})
    assert s.read_json("rung0.json") == {"a": 1} and s.read_json("rung1.json") is None
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cases", "rung0.json"]
    s.drop("cases/c1")
    s.drop("rung0.json")
    s.drop("nothing")
    assert list((tmp_path / "cases").iterdir()) == []


def test_a_killed_writers_leftovers_are_removed(tmp_path):
    s = _store(tmp_path)
    old, fresh = tmp_path / "cases" / ".tmp-c1-dead", tmp_path / "cases" / ".tmp-c2-live"
    old.mkdir(parents=True)
    fresh.mkdir()
    then = time.time() - 2 * STALE_S
    os.utime(old, (then, then))
    s.clean("cases")
    assert not old.exists() and fresh.exists()  # a running writer's folder is young
