"""The rating report: ``gears.csv``, ``bearings.csv``, ``rating.png`` and a self-contained
``index.html`` from a :class:`gearmodal.rating.Rating`."""

from __future__ import annotations

import base64
import html
import io
import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # reports are written without a screen
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

_CSS = ("body{font-family:sans-serif;max-width:1100px;margin:2em auto;color:#222}"
        "table{border-collapse:collapse;font-size:12px;margin:0.5em 0 1.5em}"
        "td,th{border:1px solid #bbb;padding:2px 6px;text-align:right}th{background:#eee}"
        "tr.low td{background:#ffe1e1;font-weight:bold}img{max-width:100%}")

#: the gears' columns shown first in the report's table
GEAR_COLUMNS = ["mesh", "gear", "member", "teeth", "S_H", "S_F", "sigma_H_MPa",
                "sigma_HG_MPa", "sigma_F_MPa", "sigma_FG_MPa", "cycles", "K_v", "K_Hbeta",
                "K_Halpha", "K_gamma", "K_gamma_model", "Z_NT", "Y_NT"]
BEARING_COLUMNS = ["bearing", "radial_load_N", "speed_rpm", "C_N", "kappa", "a_ISO",
                   "L10_Mrev", "L10m_h", "L10m_over_required"]


def plot_rating(rating):
    """S_H and S_F per gear (bars, with 1 marked) and L10m per bearing against the required
    life; returns the Figure."""
    g = rating.gears
    b = rating.bearings
    fig, axes = plt.subplots(1, 2 if len(b) else 1, figsize=(12, 4.5), squeeze=False)
    ax = axes[0, 0]
    labels = [f"{m.split('.')[-1]}: {n.split('.')[-1]}\n{n.split('.')[0]}"
              for m, n in zip(g["mesh"], g["gear"], strict=True)]
    x = np.arange(len(g))
    ax.bar(x - 0.2, g["S_H"], 0.4, label="S_H (pitting)")
    ax.bar(x + 0.2, g["S_F"], 0.4, label="S_F (tooth root)")
    ax.axhline(1.0, color="k", lw=0.8)
    ax.set_xticks(x, labels, rotation=60, ha="right", fontsize=7)
    ax.set_ylabel("safety factor")
    ax.legend()
    if len(b):
        ax = axes[0, 1]
        y = np.arange(len(b))
        ax.barh(y, b["L10m_h"])
        ax.axvline(rating.settings.get("life_h", np.nan), color="k", lw=0.8,
                   label="required life")
        ax.set_xscale("log")
        ax.set_yticks(y, b["bearing"], fontsize=7)
        ax.set_xlabel("L10m, h (ISO 281)")
        ax.legend()
    fig.tight_layout()
    return fig


def write_rating(rating, directory) -> Path:
    """Write the rating's tables, figure and ``index.html`` to ``directory``; returns it."""
    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    head = "# " + json.dumps(rating.settings, default=str) + "\n"
    tables = [("gears.csv", rating.gears), ("bearings.csv", rating.bearings)]
    if rating.spectrum is not None:
        tables.append(("spectrum.csv", rating.spectrum))
    for name, df in tables:
        (out / name).write_text(head + df.to_csv(index=False))
    fig = plot_rating(rating)
    fig.savefig(out / "rating.png", dpi=130)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100)
    plt.close(fig)
    png = base64.b64encode(buf.getvalue()).decode()
    s = rating.settings
    g = rating.gears[[c for c in GEAR_COLUMNS if c in rating.gears.columns]]
    body = [f"<h1>Rating: {html.escape(str(s.get('model', '')))}</h1>",
            f"<p>{s.get('input_torque_Nm', float('nan')):.4g} N m at the input, "
            f"{s.get('speed_rpm', float('nan')):.4g} rpm, required life "
            f"{s.get('life_h', float('nan')):.6g} h, K_A {s.get('application_factor')}, "
            f"K_gamma {html.escape(str(s.get('k_gamma')))}; {html.escape(s.get('standards', ''))}."
            " Highlighted: a safety factor below 1 or a life below the required.</p>",
            f"<img alt='rating' src='data:image/png;base64,{png}'>",
            "<h2>Gears (ISO 6336 method B)</h2>",
            _table(g, highlight=(g["S_H"] < 1.0) | (g["S_F"] < 1.0))]
    if len(rating.bearings):
        b = rating.bearings[[c for c in BEARING_COLUMNS if c in rating.bearings.columns]]
        body += ["<h2>Bearings (ISO 281 modified life)</h2>",
                 _table(b, highlight=b["L10m_over_required"] < 1.0)]
    if rating.spectrum is not None and len(rating.spectrum):
        sp = rating.spectrum
        body += ["<h2>Under the run's load spectrum (ISO 6336-6, Palmgren-Miner)</h2>",
                 f"<p>{html.escape(str(s.get('run', '')))}</p>",
                 _table(sp, highlight=(sp.get("S_H_spectrum", 2.0) < 1.0)
                        | (sp.get("S_F_spectrum", 2.0) < 1.0))]
    body.append("<p>Every factor of every gear: gears.csv; bearings.csv"
                + ("; spectrum.csv" if rating.spectrum is not None else "") + ".</p>")
    title = html.escape(f"rating {s.get('model', '')}")
    (out / "index.html").write_text(
        f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{title}</title>"
        f"<style>{_CSS}</style></head><body>" + "\n".join(body) + "</body></html>")
    return out


def _table(df, highlight) -> str:
    """An HTML table of ``df``, the rows where ``highlight`` is true marked."""
    text = df.to_html(index=False, float_format=lambda v: f"{v:.4g}", border=0)
    head, *rows = text.split("<tr>\n")  # the body's rows (the header's <tr> has a style)
    marks = list(highlight)
    return head + "".join(("<tr class='low'>\n" if marks[k] else "<tr>\n") + r
                          for k, r in enumerate(rows))


def write_study_rating(table, settings: dict, directory) -> Path:
    """A fatigue study's ratings (:func:`gearmodal.rating.study.rate_study`): ``ratings.csv``,
    ``rating.png`` (S_H and S_F per gear and variant) and ``index.html``."""
    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    (out / "ratings.csv").write_text("# " + json.dumps(settings, default=str) + "\n"
                                     + table.to_csv(index=False))
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.5))
    variants = list(dict.fromkeys(table.variant))
    first = table[table.variant == variants[0]]
    labels = [f"{m.split('.')[-1]}: {g.split('.')[-1]}"
              for m, g in zip(first["mesh"], first["gear"], strict=True)]
    x = np.arange(len(first))
    w = 0.8 / max(len(variants), 1)
    for ax, col, name in ((axes[0], "S_H_spectrum", "S_H (pitting)"),
                          (axes[1], "S_F_spectrum", "S_F (tooth root)")):
        for k, v in enumerate(variants):
            ax.bar(x + (k - (len(variants) - 1) / 2) * w, table[table.variant == v][col], w,
                   label=v)
        ax.axhline(1.0, color="k", lw=0.8)
        ax.set_xticks(x, labels, rotation=30, ha="right", fontsize=8)
        ax.set_ylabel(name + ", lifetime spectrum")
        ax.legend()
    fig.tight_layout()
    fig.savefig(out / "rating.png", dpi=130)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100)
    plt.close(fig)
    png = base64.b64encode(buf.getvalue()).decode()
    title = html.escape(f"rating of {settings.get('study', '')}")
    body = [f"<h1>Ratings under the lifetime spectra: {html.escape(settings.get('study', ''))}"
            "</h1>",
            f"<p>Scene {html.escape(str(settings.get('scene')))}; hours "
            f"{html.escape(str(settings.get('hours')))}; {html.escape(settings['standards'])}."
            "</p>",
            f"<img alt='rating' src='data:image/png;base64,{png}'>",
            _table(table, highlight=(table.S_H_spectrum < 1.0) | (table.S_F_spectrum < 1.0))]
    (out / "index.html").write_text(
        f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{title}</title>"
        f"<style>{_CSS}</style></head><body>" + "\n".join(body) + "</body></html>")
    return out
