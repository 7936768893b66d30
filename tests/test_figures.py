"""Every figure of the documentation is written by ``gearmodal docs-figures`` (issue 23): each
image the README and docs/ show is one the command writes, and docs/ holds no other. (CI runs
the command itself, --quick, from the installed wheel: .ci/wheel-check.)"""

import re
from pathlib import Path

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
