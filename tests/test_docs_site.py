"""The documentation site builds with warnings as errors (mkdocs.yml: the guide, the generated
file-format page and the API reference from the docstrings)."""

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.slow
def test_the_site_builds_strict(tmp_path):
    pytest.importorskip("mkdocstrings", reason="the docs extra: pip install -e '.[docs]'")
    r = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir",
                        str(tmp_path / "site")], cwd=ROOT, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr[-2000:]
    assert (tmp_path / "site" / "guide" / "models" / "index.html").exists()
    api = (tmp_path / "site" / "api" / "index.html").read_text()
    assert "simulate" in api and "SimulationResult" in api
    shutil.rmtree(tmp_path / "site")


def test_every_public_name_is_in_the_api_reference():
    """Issue 58: each name of ``gearmodal.__all__`` (but the two constants the page states) is
    a ``:::`` entry of docs/api.md, by the module and name it is defined under."""
    import gearmodal as gm

    text = (ROOT / "docs" / "api.md").read_text()
    entries = {line[4:].strip() for line in text.splitlines() if line.startswith("::: ")}
    missing = []
    for name in gm.__all__:
        obj = getattr(gm, name)
        if name in ("DOF_LEVELS", "G_STANDARD"):
            assert f"`gm.{name}`" in text
            continue
        if f"{obj.__module__}.{obj.__qualname__}" not in entries:
            missing.append(f"{name} ({obj.__module__}.{obj.__qualname__})")
    assert not missing, missing
