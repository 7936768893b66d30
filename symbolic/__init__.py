"""Symbolic derivation and code generation (DESIGN 4).

Run at development time: ``python -m symbolic`` derives, with SymPy, the floating-frame wheel
inertia terms (DESIGN 2.1), the mesh flank gap (2.2) and the joint/bearing constraint (2.3, 2.5)
and prints them as numba kernels into ``gearmodal/kernels``. The runtime never imports SymPy.
:func:`generate` writes the same files into any directory, so a test can regenerate them and
compare the text with the committed files.
"""

from __future__ import annotations

from pathlib import Path

from . import joint, mesh, wheel

__all__ = ["MODULES", "KERNEL_DIR", "generate", "sources"]

#: Generated file name -> deriving module (each has ``generate_source() -> str``).
MODULES = {"wheel.py": wheel, "mesh.py": mesh, "joint.py": joint}

#: Where ``python -m symbolic`` writes by default.
KERNEL_DIR = Path(__file__).resolve().parent.parent / "gearmodal" / "kernels"


def sources() -> dict[str, str]:
    """Text of every generated file, keyed by file name."""
    return {name: module.generate_source() for name, module in MODULES.items()}


def generate(outdir: str | Path = KERNEL_DIR) -> list[Path]:
    """Write the generated kernel modules into ``outdir``; return the written paths."""
    out = Path(outdir)
    out.mkdir(parents=True, exist_ok=True)
    written = []
    for name, text in sources().items():
        path = out / name
        path.write_text(text, encoding="utf-8", newline="\n")
        written.append(path)
    return written
