"""Where the shipped study scripts and example files are: ``gearmodal.library`` (the source
tree's ``studies/``, mapped there by pyproject.toml), and a file found by its name.

>>> find("600kw", "models").name
'600kw.toml'
"""

from __future__ import annotations

from pathlib import Path

#: the kinds of shipped files, each a folder of the library
KINDS = ("models", "scenes", "turbines")


def folder() -> Path:
    """The folder of the shipped studies and example files: the installed
    ``gearmodal.library``, or the source tree's ``studies/`` when it was never installed."""
    try:
        import gearmodal.library as lib
    except ImportError:  # run from a source tree that was never installed
        return Path(__file__).resolve().parents[1] / "studies"
    return Path(lib.__file__).resolve().parent


def find(name: str, kind: str) -> Path | None:
    """The shipped file ``<kind>/<name>.toml`` (``kind`` one of :data:`KINDS`), or None."""
    p = folder() / kind / f"{name}.toml"
    return p if p.is_file() else None
