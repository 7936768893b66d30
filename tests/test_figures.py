"""Every figure of the documentation is written by ``gearmodal docs-figures`` (issue 23): each
image the README and docs/ show is one the command writes, and docs/ holds no other. (CI runs
the command itself, --quick, from the installed wheel: .ci/wheel-check.)"""

import re
from pathlib import Path

import pytest

import gearmodal as gm
from gearmodal.figures import FIGURES, INTERACTIVE, MODE_SHAPES

ROOT = Path(__file__).resolve().parents[1]
WRITTEN = ({f.name for f in FIGURES} | {f"{n}.png" for n, *_ in MODE_SHAPES}
           | {f"{n}.gif" for n, _, _, animated in MODE_SHAPES if animated} | {INTERACTIVE})


def _shown() -> set[str]:
    pages = [ROOT / "README.md", *(ROOT / "docs").rglob("*.md")]
    names = set()
    for page in pages:
        for link in re.findall(r"!\[[^\]]*\]\(([^)]+)\)", page.read_text()):
            names.add(Path(link).name)
    return names


def test_every_shown_figure_is_written_by_docs_figures():
    shown = _shown()
    assert shown, "no figures found in the pages: the pattern is wrong"
    assert shown <= WRITTEN, f"shown but written by no command: {sorted(shown - WRITTEN)}"


def test_docs_holds_only_written_figures():
    present = {p.name for p in (ROOT / "docs").glob("*")
               if p.suffix in (".png", ".gif", ".html")}
    assert present == WRITTEN, (f"not written by docs-figures: {sorted(present - WRITTEN)}; "
                                f"missing (run gearmodal docs-figures --out docs): "
                                f"{sorted(WRITTEN - present)}")


def test_commands_run_jobs_at_a_time_and_a_failure_is_raised(tmp_path, monkeypatch):
    """``docs_figures(jobs=2)`` runs two commands at once (each waits at a two-party barrier,
    which only concurrent runs pass), keeps every command's own folder and time, and a
    failing command's error reaches the caller; ``jobs`` outside [1, 64] is refused by name."""
    import threading

    from gearmodal import figures

    barrier = threading.Barrier(2, timeout=60)
    seen = []

    def fake(argv, log):
        barrier.wait()
        seen.append(argv[0])
        Path(argv[argv.index("--out") + 1]).mkdir()

    monkeypatch.setattr(figures, "_run", fake)
    runs = {("a",): tmp_path / "a", ("b",): tmp_path / "b"}
    seconds = figures._run_all(runs, tmp_path, jobs=2)
    assert sorted(seen) == ["a", "b"] and set(seconds) == set(runs)
    assert all((tmp_path / n).is_dir() for n in "ab")

    def failing(argv, log):
        if argv[0] == "b":
            raise RuntimeError("gearmodal b failed (exit 3): boom")

    monkeypatch.setattr(figures, "_run", failing)
    with pytest.raises(RuntimeError, match="gearmodal b failed"):
        figures._run_all(runs, tmp_path, jobs=2)
    with pytest.raises(gm.ModelError, match=r"^jobs = 0: an integer in \[1, 64\]"):
        figures.docs_figures(tmp_path / "out", jobs=0)
