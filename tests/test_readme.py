"""The README's Python examples run as written (from the repository root)."""

import re
from pathlib import Path

import matplotlib
import pytest

matplotlib.use("Agg")

BLOCKS = re.findall(r"```python\n(.*?)```", Path("README.md").read_text(), re.S)


@pytest.mark.parametrize("i", range(len(BLOCKS)))
def test_readme_python_block_runs(i, tmp_path, monkeypatch):
    code = BLOCKS[i]
    root = Path.cwd()
    monkeypatch.chdir(tmp_path)
    # paths in the README are relative to the repository root
    code = code.replace('"studies/', f'"{root}/studies/')
    exec(compile(code, f"README block {i}", "exec"), {})
