"""Study reports: the paper-style tooth-force figure and a self-contained ``report.html`` built
from paragraphs, tables and figures."""

from __future__ import annotations

import html
from pathlib import Path

import pandas as pd

from .modal_report import _page, _png, _table

__all__ = ["tooth_force_figure", "write_study_report"]


def tooth_force_figure(forces: pd.DataFrame, title: str = "", planet: str = "planet1",
                       ymax_N: float | None = None, cut_in_s: float | None = None):
    """Front and back flank forces of ``planet`` on its sun-planet and ring-planet meshes
    against time, four panels as in the paper's Figures 6-8; returns the Figure.

    ``forces`` has the columns ``<stage>.sun_<planet>.front`` ... (a
    :class:`~gearmodal.SimulationResult`'s ``forces`` or the table :func:`gearmodal.sweep`
    stores with :func:`gearmodal.studies.summarize`); ``ymax_N`` fixes a common scale so that
    cases can be compared.
    """
    import matplotlib.pyplot as plt

    fig, axs = plt.subplots(4, 1, sharex=True, figsize=(8, 7.5))
    panels = [(kind, side) for kind in ("sun", "ring") for side in ("front", "back")]
    for ax, (kind, side) in zip(axs, panels, strict=True):
        cols = [c for c in forces.columns if c.endswith(f"{kind}_{planet}.{side}")]
        if cols:
            ax.plot(forces.index, forces[cols[0]] / 1e3, lw=0.6, color="C0" if side == "front"
                    else "C3")
        ax.set_ylabel(f"{kind}-planet\n{side} [kN]", fontsize=9)
        if ymax_N:
            ax.set_ylim(0, 1.05 * ymax_N / 1e3)
        if cut_in_s is not None:
            ax.axvline(cut_in_s, color="0.6", ls="--", lw=0.8)
        ax.grid(alpha=0.3)
    axs[-1].set_xlabel("time [s]")
    if title:
        axs[0].set_title(title)
    fig.tight_layout()
    return fig


def write_study_report(out, title: str, blocks: list) -> Path:
    """Write ``out/report.html``. ``blocks`` are, in order: ``("h2", text)`` headings,
    strings (paragraphs; HTML when they start with ``<``), DataFrames (tables) and
    ``(name, Figure)`` pairs (saved as ``out/name`` and embedded). Returns the path."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    body = [f"<h1>{html.escape(title)}</h1>"]
    for b in blocks:
        if isinstance(b, pd.DataFrame):
            body.append(_table(b.reset_index() if b.index.name else b))
        elif isinstance(b, tuple) and b and b[0] in ("h2", "h3"):
            body.append(f"<{b[0]}>{html.escape(b[1])}</{b[0]}>")
        elif isinstance(b, tuple):
            name, fig = b
            body.append(f"<img alt='{html.escape(name)}' "
                        f"src='data:image/png;base64,{_png(fig, out / name)}'>")
        else:
            text = str(b)
            body.append(text if text.startswith("<") else f"<p>{html.escape(text)}</p>")
    path = out / "report.html"
    path.write_text(_page(title, body), encoding="utf-8")
    return path
