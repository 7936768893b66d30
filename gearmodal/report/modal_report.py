"""The Campbell/modal report: CSV tables, figures and one self-contained ``report.html``."""

from __future__ import annotations

import base64
import html
import io
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # reports are written without a screen
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from ..campbell import CampbellResult  # noqa: E402
from ..modal import ModalResult  # noqa: E402

#: number of (non-rigid) lowest modes that get a mode-shape figure
N_SHAPES = 6
#: upper frequency of the low-frequency Campbell zoom (raised to 3x the lowest housing mode)
LOW_FMAX_HZ = 40.0


def _png(fig, path: Path) -> str:
    fig.savefig(path, dpi=130)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100)
    plt.close(fig)
    return base64.b64encode(buf.getvalue()).decode()


def _table(df: pd.DataFrame, highlight=None, floatfmt="{:.4g}") -> str:
    rows = []
    head = "".join(f"<th>{html.escape(str(c))}</th>" for c in df.columns)
    for i, r in df.iterrows():
        cls = ' class="hl"' if highlight is not None and bool(highlight.loc[i]) else ""
        cells = "".join(
            f"<td>{floatfmt.format(v) if isinstance(v, float) else html.escape(str(v))}</td>"
            for v in r)
        rows.append(f"<tr{cls}>{cells}</tr>")
    return f"<table><tr>{head}</tr>{''.join(rows)}</table>"


_CSS = """body{font-family:sans-serif;max-width:1100px;margin:2em auto;color:#222}
table{border-collapse:collapse;font-size:12px;margin:0.5em 0 1.5em}
td,th{border:1px solid #bbb;padding:2px 6px;text-align:right}th{background:#eee}
tr.hl td{background:#ffe1e1;font-weight:bold}img{max-width:100%}
.figs img{max-width:48%;margin:0.5%}"""


def _shape_figures(res: ModalResult, out: Path) -> list[tuple[str, str]]:
    figs = []
    idx = [i for i, t in enumerate(res.mode_types) if t != "rigid"][:N_SHAPES]
    for i in idx:
        fig = res.plot_shape(i)
        figs.append((f"mode_{i:02d}.png", _png(fig, out / f"mode_{i:02d}.png")))
    return figs


def _all_shapes(res: ModalResult, skip=()) -> str:
    """Every other non-rigid mode's drawn shape (not in ``skip``), each under an anchor
    ``mode-XX`` (the interactive Campbell diagram's points link there), in a ``<details>``."""
    parts = []
    for i, t in enumerate(res.mode_types):
        if t == "rigid" or i in skip:
            continue
        fig = res.plot_shape(i)
        buf = io.BytesIO()
        fig.savefig(buf, format="png", dpi=85)  # readable at the page's width (55 was not)
        plt.close(fig)
        b64 = base64.b64encode(buf.getvalue()).decode()
        parts.append(f"<div id='mode-{i:02d}' class='shape'><h3>Mode {i}: "
                     f"{res.frequencies_hz[i]:.4g} Hz, {html.escape(t)}</h3>"
                     f"<img alt='mode {i}' src='data:image/png;base64,{b64}'></div>")
    return ("<details id='all-shapes'><summary>The other modes drawn (a click on a point of "
            "the interactive diagram opens its mode here)</summary>" + "".join(parts)
            + "</details>")


def _interactive(camp: CampbellResult, res: ModalResult) -> str:
    """The interactive Campbell diagram (plotly, inline) with each tracked mode linked to the
    drawn shape of the mode nearest in frequency at the report's speed; a note when plotly
    is not installed (the ``interactive`` extra)."""
    try:
        import plotly  # noqa: F401
    except ImportError:
        return ("<p>(The interactive diagram needs the <code>interactive</code> extra: "
                "<code>pip install gearmodal[interactive]</code>.)</p>")
    k = int(abs(camp.speeds_rpm - res.speed_rpm).argmin())
    links = {}
    for j in range(camp.n_modes):
        i = int(abs(res.frequencies_hz - camp.frequencies_hz[k, j]).argmin())
        if res.mode_types[i] != "rigid":
            links[j] = f"mode-{i:02d}"
    fig = camp.plot_interactive(links=links)
    div = fig.to_html(full_html=False, include_plotlyjs=True, div_id="campbell-interactive")
    click = """<script>
document.getElementById('campbell-interactive').on('plotly_click', function (ev) {
  var p = ev.points[0], a = p.customdata && p.customdata[5];
  if (!a) { return; }
  var el = document.getElementById(a);
  if (el && el.closest('details')) { el.closest('details').open = true; }
  location.hash = a;
});
</script>"""
    return ("<h2>Interactive Campbell diagram</h2><p>Hover a point: mode, type, frequency, "
            "damping ratio, logarithmic decrement and whirl; colour: logarithmic decrement "
            "(red unstable, yellow lightly damped, green well damped). Click a point for the "
            "mode's drawn shape.</p>" + div + click)


def write_modal_report(res: ModalResult, out, summary: str = "") -> Path:
    """Write ``modes.csv``, shape tables, mode-shape figures and ``report.html`` to ``out``."""
    out = Path(out)
    res.save(out)
    figs = _shape_figures(res, out)
    modes = res.to_frame()
    body = [f"<h1>Modal report: {html.escape(res.model_name)}</h1>",
            f"<p>{html.escape(summary)}</p>",
            f"<p>Input speed {res.speed_rpm:g} rpm; nominal contact state (front flanks "
            "engaged, bearing clearances taken up).</p>",
            "<h2>Modes</h2>", _table(modes),
            "<h2>Lowest mode shapes</h2><div class='figs'>",
            *[f"<img alt='{n}' src='data:image/png;base64,{b}'>" for n, b in figs], "</div>"]
    (out / "report.html").write_text(_page(res.model_name, body))
    return out


def write_campbell_report(camp: CampbellResult, res: ModalResult, out,
                          summary: str = "") -> Path:
    """Write the Campbell report into ``out``: the Campbell result (``campbell.csv``,
    ``crossings.csv``...: :meth:`CampbellResult.load` reads ``out`` back), the modal result at
    the report's speed in ``out/modal`` (and its ``modes.csv`` in ``out``), ``campbell.png``,
    ``mode_XX.png`` and a self-contained ``report.html`` (model summary, every mode drawn, the
    static and, with plotly installed, the
    interactive diagram whose points link to the drawn modes, modes at rated speed with their
    whirl and logarithmic decrement, crossings with those inside the operating range
    highlighted)."""
    out = Path(out)
    res.save(out / "modal")  # loads back: ModalResult.load(out / "modal")
    camp.save(out)  # loads back: CampbellResult.load(out)
    res.to_frame().to_csv(out / "modes.csv", index=False)
    fig = camp.plot()
    cpng = _png(fig, out / "campbell.png")
    low_orders = [o for o in camp.orders if o in ("1P", "3P") or "planet pass" in o
                  or (o.endswith("mesh") and not o.startswith("2x"))]
    housing = res.frequencies_hz[[t == "housing" for t in res.mode_types]]
    f_low = LOW_FMAX_HZ if not len(housing) else max(LOW_FMAX_HZ, 3.0 * float(housing.min()))
    fig = camp.plot(fmax_hz=f_low, orders=low_orders)
    lpng = _png(fig, out / "campbell_low.png")
    turbine = _turbine_zoom(camp, out)
    figs = _shape_figures(res, out)
    cr = camp.crossings()
    hmodes = sorted({int(j) for j in range(camp.n_modes)
                     if (camp.mode_types[:, j] == "housing").any()})
    hcr = cr[cr["mode"].isin(hmodes)]
    htab = pd.DataFrame({"mode": hmodes,
                         "frequency_hz_at_rated": [camp.frequencies_hz[
                             int(abs(camp.speeds_rpm - res.speed_rpm).argmin()), j]
                             for j in hmodes]})
    modes = res.to_frame()
    rng = camp.speed_range_rpm
    rng_txt = f"{rng[0]:g}-{rng[1]:g} rpm" if rng else "the whole sweep"
    body = [f"<h1>Campbell report: {html.escape(camp.model_name)}</h1>",
            f"<p>{html.escape(summary)}</p>",
            f"<p>Speed sweep {camp.speeds_rpm[0]:g}-{camp.speeds_rpm[-1]:g} rpm of the input "
            f"({len(camp.speeds_rpm)} speeds); operating range {rng_txt}. Modes tracked by "
            "mass-weighted MAC with one-to-one assignment.</p>",
            f"<img alt='campbell' src='data:image/png;base64,{cpng}'>",
            _interactive(camp, res),
            "<h2>Low-frequency zoom: rotor orders and the gearbox housing modes</h2>",
            f"<img alt='campbell_low' src='data:image/png;base64,{lpng}'>",
            *turbine,
            "<h3>Gearbox housing modes (housing on its suspension)</h3>",
            _table(htab) if len(htab) else "<p>no housing modes in this model</p>",
            "<p>Crossings of the housing modes with every order over the sweep "
            "(highlighted: inside the operating range):</p>",
            _table(hcr, highlight=hcr.in_operating_range) if len(hcr) else
            "<p>no order crosses a housing mode within the sweep</p>",
            "<h2>Excitation orders</h2>",
            _table(pd.DataFrame({"order": list(camp.orders),
                                 "per_revolution": list(camp.orders.values())})),
            f"<h2>Crossings ({int(cr.in_operating_range.sum())} inside the operating "
            "range, highlighted)</h2>",
            _table(cr, highlight=cr.in_operating_range) if len(cr) else "<p>none</p>",
            f"<h2>Modes at {res.speed_rpm:g} rpm</h2>", _table(modes),
            "<h2>Lowest mode shapes</h2><div class='figs'>",
            *[f"<img id='mode-{n[5:7]}' alt='{n}' src='data:image/png;base64,{b}'>"
              for n, b in figs], "</div>",
            _all_shapes(res, skip={int(n[5:7]) for n, _ in figs})]
    (out / "report.html").write_text(_page(camp.model_name, body))
    return out


#: an elastic turbine's mode families (:func:`gearmodal.modetypes.turbine_family`)
_TURBINE = ("tower ", "flap", "edge", "drivetrain", "nacelle")


def _turbine_zoom(camp, out: Path) -> list[str]:
    """The elastic turbine's own modes (tower, blades in multi-blade coordinates,
    drivetrain) against the rotor orders (1P and the blade passing): figure
    ``campbell_turbine.png`` and its crossings; nothing for a model without them."""
    types = camp.mode_types
    cols = [j for j in range(camp.n_modes)
            if any(str(t).startswith(_TURBINE) for t in types[:, j])]
    if not cols:
        return []
    top = 1.25 * float(np.max(camp.frequencies_hz[:, cols]))
    rotor = [o for o in camp.orders if o.endswith("P")]
    fig = camp.plot(fmax_hz=top, orders=rotor)
    png = _png(fig, out / "campbell_turbine.png")
    cr = camp.crossings()
    cr = cr[cr["mode"].isin(cols) & cr.order.isin(rotor)]
    return ["<h2>The turbine's modes: tower, blades (multi-blade coordinates: collective, "
            "backward and forward whirl), drivetrain, and the rotor orders</h2>",
            f"<img alt='campbell_turbine' src='data:image/png;base64,{png}'>",
            "<p>Their crossings with the rotor orders (highlighted: inside the operating "
            "range):</p>",
            _table(cr, highlight=cr.in_operating_range) if len(cr) else "<p>none</p>"]


def _page(title: str, body: list[str]) -> str:
    return (f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>"
            f"{html.escape(title)}</title><style>{_CSS}</style></head><body>"
            + "\n".join(body) + "</body></html>")
