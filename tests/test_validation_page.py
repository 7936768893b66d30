"""The validation page (docs/validation.md) names tests that exist: every ``file::function`` in
its tables is a test function defined in that file, so a renamed or removed test breaks this
test instead of leaving the page pointing at nothing. The benchmarks page's build-time include
(docs_hooks.py) is checked here too."""

import ast
import importlib.util
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "validation.md"
#: a test reference in a table cell: `tests/....py::test_name`
REFERENCE = re.compile(r"`(?P<file>tests/[\w/]+\.py)::(?P<name>\w+)`")


def table_references(text: str) -> list[tuple[str, str, int]]:
    """``(file, function, line number)`` of every test named in a table row of ``text``."""
    out = []
    for number, line in enumerate(text.splitlines(), 1):
        if line.lstrip().startswith("|"):
            out += [(m["file"], m["name"], number) for m in REFERENCE.finditer(line)]
    return out


def test_functions(path: Path) -> set[str]:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    return {node.name for node in ast.walk(tree)
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef)
            and node.name.startswith("test_")}


test_functions.__test__ = False  # a helper, not a test


def test_every_named_test_exists():
    refs = table_references(PAGE.read_text(encoding="utf-8"))
    assert len(refs) >= 50, "the validation tables lost their test column"
    missing = []
    for file, name, line in refs:
        path = ROOT / file
        if not path.is_file():
            missing.append(f"docs/validation.md:{line}: {file} does not exist")
        elif name not in test_functions(path):
            missing.append(f"docs/validation.md:{line}: {file} has no test {name}")
    assert not missing, "\n".join(missing)


def test_every_table_row_names_a_test():
    """Each data row of the validation tables ends in a test reference."""
    bad = []
    for number, line in enumerate(PAGE.read_text(encoding="utf-8").splitlines(), 1):
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        header = set(cells[0]) <= {"-"} or cells[0] == "what is compared"
        if not line.lstrip().startswith("|") or header:
            continue
        if len(cells) != 5 or not REFERENCE.search(cells[-1]):
            bad.append(f"docs/validation.md:{number}: {line[:80]}")
    assert not bad, "\n".join(bad)


def test_benchmarks_page_includes_the_results():
    spec = importlib.util.spec_from_file_location("docs_hooks", ROOT / "docs_hooks.py")
    hooks = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(hooks)
    page = (ROOT / "docs" / "benchmarks.md").read_text(encoding="utf-8")
    assert hooks.MARKER.search(page)

    class Config:
        config_file_path = str(ROOT / "mkdocs.yml")

    class Page:
        class file:
            src_path = "benchmarks.md"

    out = hooks.on_page_markdown(page, Page, Config, None)
    assert not hooks.MARKER.search(out)
    results = (ROOT / "benchmarks" / "RESULTS.md").read_text(encoding="utf-8")
    first = next(line for line in results.splitlines() if line.startswith("## "))
    assert "#" + first in out  # the sections, one level down under the page's own
