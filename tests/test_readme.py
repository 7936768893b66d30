"""The Python examples of the README and of the guide (docs/**/*.md) run as written (from the
repository root)."""

import importlib.util
import os
import re
from pathlib import Path

import matplotlib
import pytest

matplotlib.use("Agg")

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
BLOCKS = [(p, i, code) for p in PAGES
          for i, code in enumerate(re.findall(r"```python\n(.*?)```", p.read_text(), re.S))]


def test_the_pages_have_examples():
    pages = {p.name for p, _, _ in BLOCKS}
    assert {"README.md", "models.md", "simulation.md", "studies.md"} <= pages


@pytest.mark.parametrize("page, i, code", BLOCKS,
                         ids=[f"{p.relative_to(ROOT)}:{i}" for p, i, _ in BLOCKS])
def test_python_block_runs(page, i, code, tmp_path, monkeypatch):
    if ("rosco" in code or "nrel5mw" in code) and not os.environ.get("GEARMODAL_CI") and (
            importlib.util.find_spec("rosco") is None
            or importlib.util.find_spec("openfast_io") is None):
        pytest.skip("the nrel5mw extra: pip install -e '.[nrel5mw]' and pip install "
                    "--no-deps 'rosco>=2.10,<2.11' (CI installs them)")
    if "flexible(" in code and not os.environ.get("GEARMODAL_CI") and (
            importlib.util.find_spec("pybmodes") is None):
        pytest.skip("the elastic extra: pip install -e '.[elastic]' (CI installs it)")
    monkeypatch.chdir(tmp_path)
    # paths in the pages are relative to the repository root
    code = code.replace('"studies/', f'"{ROOT}/studies/')
    exec(compile(code, f"{page.name} block {i}", "exec"), {})
