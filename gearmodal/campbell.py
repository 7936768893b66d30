"""Campbell diagrams: natural frequencies against input speed, tracked by MAC (DESIGN 3.1).

Modes are followed from speed to speed by a one-to-one assignment (Hungarian algorithm,
``scipy.optimize.linear_sum_assignment``) that maximises the mass-weighted modal assurance
criterion between consecutive speeds, never by sorting. Excitation orders (multiples of the
input speed) are chosen from the model by default: 1P and 3P of the rotor, each mesh's tooth
order and its 2nd harmonic, and the planet-pass order of each planetary stage.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd
import scipy.linalg as sla
from scipy.linalg import blas

from .assembly import reduction
from .errors import ModelError
from .modal import RPM, band_basis, check_band, eigensolve, geometry_table
from .model.components import Gear
from .model.model import Model
from .model.validate import plausible
from .modetypes import LOOSE, QUIET, classify, turbine_groups
from .result_io import read_header, refuses_damage, write_header
from .whirl import damping_ratios, log_decrement, rigid_undamped, translation_pairs, whirl

#: layout version of :meth:`CampbellResult.save` (``result.json``)
SAVE_VERSION = 1
#: a tracked mode whose shape keeps less MAC than this across a near-approach has veered
VEERING_MAC = 0.5
#: half-width (in speed steps) of the window over which a veering's shape exchange is judged
VEERING_WINDOW = 3
#: mode-shape entries (speeds x DOF x modes) whose types are worked out in one vectorised pass
_LABEL_ENTRIES = 1 << 20


def mac(phi: np.ndarray, psi: np.ndarray, M: np.ndarray | None = None) -> np.ndarray:
    """Mass-weighted modal assurance criterion between columns of ``phi`` and ``psi``:
    ``|phi_i^H M psi_j|^2 / ((phi_i^H M phi_i) (psi_j^H M psi_j))``."""
    Mp = psi if M is None else M @ psi
    Mf = phi if M is None else M @ phi
    num = np.abs(phi.conj().T @ Mp) ** 2
    a = np.real(np.einsum("im,im->m", phi.conj(), Mf))
    b = np.real(np.einsum("im,im->m", psi.conj(), Mp))
    return num / np.outer(a, b)


def default_orders(model: Model) -> dict[str, float]:
    """Excitation orders (per revolution of the input) from the model's content."""
    orders: dict[str, float] = {"1P": 1.0}
    if any(b == "rotor" or b.endswith(".rotor") for b in model.bodies):
        orders["3P"] = 3.0
    for m in model.meshes.values():
        a = model.bodies[m.gear_a]
        if not isinstance(a, Gear):
            continue
        fr = model.frames[a.frame].speed_ratio
        o = a.teeth * abs(a.speed_ratio - fr)
        if o == 0:
            b = model.bodies[m.gear_b]
            o = b.teeth * abs(b.speed_ratio - fr) if isinstance(b, Gear) else 0.0
        stage = m.name.rsplit(".", 1)[0] if "." in m.name else ""
        key = f"{stage} mesh".strip() if stage else "mesh"
        if o > 0 and not any(math.isclose(o, v) for v in orders.values()):
            orders[key if key not in orders else f"{m.name} mesh"] = o
            orders[f"2x {key}"] = 2 * o
    for g, members in model.groups.items():
        if g.endswith("planets") and members:
            b = model.bodies[members[0]]
            fr = model.frames[b.frame].speed_ratio
            stage = g.rsplit(".", 1)[0] if "." in g else ""
            orders[f"{stage} planet pass".strip()] = len(members) * abs(fr)
    return orders


#: the logarithmic decrements the colour scales span: from -1/5 of the top (unstable, red)
#: through 0 (yellow) to the top (green)
LOG_DEC_SCALE = (-0.1, 0.5)
#: the interactive diagram's colours over [-top/5, top]: red below 0, yellow at 0 (1/6 of the
#: way), green at the top (matplotlib's RdYlGn stops)
LOG_DEC_COLOURS = [[0.0, "#a50026"], [1 / 12, "#f46d43"], [1 / 6, "#ffffbf"],
                    [0.45, "#a6d96a"], [1.0, "#006837"]]


def order_labels(orders: dict, names: list, x_max: float, f_max: float,
                  avoid: tuple = ()) -> dict:
    """Where each order line's label goes (right-aligned, above the point): lines of the same
    order share one label (``3P = stage1 planet pass``); a label starts where its line leaves
    the plot (its right end or the top) and moves down along its own line until it covers no
    label placed before it (from the right, at 7-point text: about 1 % of the axis per
    character, 4 % high) nor a box of ``avoid`` (``(x0, x1, y0, y1)``: the legend); a label
    that would reach past the left edge is set to the right of its point. Returns
    ``{label: (x, y, horizontal alignment)}``."""
    same: dict[float, list[str]] = {}
    for o in names:
        same.setdefault(float(orders[o]), []).append(o)
    placed: list[tuple] = list(avoid)  # (x0, x1, y0, y1)
    out = {}
    h = 0.04 * f_max
    for order in sorted(same, key=lambda r: min(x_max, f_max * 60.0 / r) if r > 0 else x_max,
                        reverse=True):
        text = " = ".join(same[order])
        w = 0.0105 * x_max * len(text)
        edge = order <= 0 or order * x_max / 60.0 <= f_max  # leaves at the right edge
        x0 = x_max if edge else f_max * 60.0 / order
        y0 = order * x0 / 60.0 if edge else f_max
        # candidates: where the line leaves, then down (along the line from the top, along
        # the edge from the right), then up the right edge
        steps = [y0 - k * h for k in range(40) if y0 - k * h >= 0.0]
        if edge:
            steps += [y0 + k * h for k in range(1, 40) if y0 + k * h <= f_max - h]
        x, y, box = x0, y0, (x0 - w, x0, y0, y0 + h)
        for y in steps:
            x = x0 if edge else y * 60.0 / order
            box = (x - w, x, y, y + h) if x - w >= 0.0 else (x, x + w, y, y + h)
            if not any(box[0] < p[1] and p[0] < box[1] and box[2] < p[3] and p[2] < box[3]
                       for p in placed):
                break
        placed.append(box)
        out[text] = (x, y, "right" if box[1] == x else "left")
    return out


@dataclass
class CampbellResult:
    """Tracked natural frequencies over a speed sweep.

    Attributes
    ----------
    speeds_rpm : (n_speeds,) input speeds, rpm.
    frequencies_hz, damping_ratios : (n_speeds, n_modes), column j follows tracked mode j
        (the damping ratio of a rigid-body mode: 0).
    mode_types : (n_speeds, n_modes) labels.
    macs : list of (n_modes, n_modes) MAC matrices between consecutive speeds (tracked order
        on both axes; the diagonal is the tracking MAC).
    veering : (n_speeds, n_modes) True at the speed where a mode veers (see :meth:`veerings`).
    orders : excitation orders ``{name: multiple of input speed}``.
    speed_range_rpm : operating range used to mark crossings.
    whirl : (n_speeds, n_modes) ``forward``/``backward``/``linear``/``""`` of each tracked mode
        (:mod:`gearmodal.whirl`; ``""`` everywhere without the model's geometry).
    """

    speeds_rpm: np.ndarray
    frequencies_hz: np.ndarray
    damping_ratios: np.ndarray
    mode_types: np.ndarray
    macs: list
    veering: np.ndarray
    orders: dict
    speed_range_rpm: tuple | None = None
    model_name: str = ""
    extra: dict = field(default_factory=dict)
    whirl: np.ndarray | None = None

    def __post_init__(self):
        if self.whirl is None:
            self.whirl = np.full(self.frequencies_hz.shape, "", dtype=object)

    @property
    def n_modes(self) -> int:
        return self.frequencies_hz.shape[1]

    @property
    def log_decrements(self) -> np.ndarray:
        """(n_speeds, n_modes) logarithmic decrements of the tracked modes
        (:func:`gearmodal.whirl.log_decrement`)."""
        return log_decrement(self.damping_ratios)

    def to_frame(self) -> pd.DataFrame:
        """Long table: ``speed_rpm``, ``mode``, ``frequency_hz``, ``damping_ratio``,
        ``mode_type``, ``veering``, ``log_dec``, ``whirl``."""
        ns, nm = self.frequencies_hz.shape
        return pd.DataFrame({
            "speed_rpm": np.repeat(self.speeds_rpm, nm),
            "mode": np.tile(np.arange(nm), ns),
            "frequency_hz": self.frequencies_hz.ravel(),
            "damping_ratio": self.damping_ratios.ravel(),
            "mode_type": self.mode_types.ravel(),
            "veering": self.veering.ravel(),
            "log_dec": self.log_decrements.ravel(),
            "whirl": np.asarray(self.whirl, dtype=object).ravel(),
        })

    def veerings(self) -> pd.DataFrame:
        """Veerings: two tracked modes approach in frequency without crossing and exchange
        their shapes. Columns ``speed_rpm``, ``mode_a``, ``mode_b``, ``frequency_hz``,
        ``min_gap_hz``, ``mac_across`` (MAC of mode_a's shape across the approach)."""
        return pd.DataFrame(self.extra.get("veerings", []),
                            columns=["speed_rpm", "mode_a", "mode_b", "frequency_hz",
                                     "min_gap_hz", "mac_across"])

    def crossings(self, orders=None, fmin_hz: float = 1e-3) -> pd.DataFrame:
        """Every crossing of a tracked mode with an order line, by linear interpolation.

        Columns ``speed_rpm``, ``frequency_hz``, ``mode``, ``mode_type``, ``order``,
        ``order_value``, ``in_operating_range``. ``orders`` restricts to the named orders.
        """
        names = list(self.orders) if orders is None else [orders] if isinstance(orders, str) \
            else list(orders)
        for o in names:
            if o not in self.orders:
                raise ModelError("orders", f"unknown order {o!r}; known: "
                                 + ", ".join(self.orders))
        s = self.speeds_rpm
        rows = []
        lo, hi = self.speed_range_rpm or (s.min(), s.max())
        for o in names:
            line = self.orders[o] * s / 60.0
            for j in range(self.n_modes):
                f = self.frequencies_hz[:, j]
                if np.all(f < fmin_hz):
                    continue
                d = f - line
                for k in np.flatnonzero(np.sign(d[:-1]) * np.sign(d[1:]) < 0):
                    t = d[k] / (d[k] - d[k + 1])
                    sp = s[k] + t * (s[k + 1] - s[k])
                    fr = f[k] + t * (f[k + 1] - f[k])
                    if fr < fmin_hz:
                        continue  # a rigid-body mode leaving zero, not a resonance
                    rows.append((sp, fr, j, self.mode_types[k, j], o, self.orders[o],
                                 bool(lo <= sp <= hi)))
        cols = ["speed_rpm", "frequency_hz", "mode", "mode_type", "order", "order_value",
                "in_operating_range"]
        return pd.DataFrame(rows, columns=cols).sort_values(["speed_rpm", "frequency_hz"],
                                                            ignore_index=True)

    def _fmax(self, fmax_hz, names) -> float:
        if fmax_hz is not None:
            return fmax_hz
        top = max(self.orders[o] for o in names) * self.speeds_rpm.max() / 60.0
        return min(max(1.2 * top, 1.0), 1.05 * np.nanmax(self.frequencies_hz))

    def plot(self, fmax_hz: float | None = None, ax=None, orders=None,
             color_by: str = "type"):
        """The Campbell diagram (tracked modes coloured by type, or by their logarithmic
        decrement with ``color_by="log_dec"``: red below zero (unstable), yellow near zero
        (lightly damped), green well damped; order lines dashed, crossings marked, operating
        range shaded); returns the matplotlib Figure."""
        import matplotlib.pyplot as plt

        if color_by not in ("type", "log_dec"):
            raise ModelError("color_by", f"= {color_by!r}: must be 'type' or 'log_dec'")
        if ax is None:
            fig, ax = plt.subplots(figsize=(8, 5.5))
        else:
            fig = ax.figure
        s = self.speeds_rpm
        names = list(self.orders) if orders is None else list(orders)
        fmax_hz = self._fmax(fmax_hz, names)
        types = sorted(set(self.mode_types.ravel()))
        colours = {t: f"C{i % 10}" for i, t in enumerate(types)}
        seen = set()
        if color_by == "log_dec":
            from matplotlib.collections import LineCollection
            from matplotlib.colors import TwoSlopeNorm

            norm = TwoSlopeNorm(vmin=-LOG_DEC_SCALE[1] / 5, vcenter=0.0, vmax=LOG_DEC_SCALE[1])
            dec = np.clip(self.log_decrements, -LOG_DEC_SCALE[1] / 5, LOG_DEC_SCALE[1])
            lc = None
            for j in range(self.n_modes):
                f = self.frequencies_hz[:, j]
                if np.all(f > fmax_hz):
                    continue
                if self.mode_types[len(s) // 2, j] == "rigid":  # no decay to read
                    ax.plot(s, f, color="0.7", lw=0.8)
                    continue
                seg = np.stack([np.column_stack([s[:-1], f[:-1]]),
                                np.column_stack([s[1:], f[1:]])], axis=1)
                lc = LineCollection(seg, cmap="RdYlGn", norm=norm, lw=1.6)
                lc.set_array(0.5 * (dec[:-1, j] + dec[1:, j]))
                ax.add_collection(lc)
            if lc is not None:
                fig.colorbar(lc, ax=ax, label="logarithmic decrement", extend="both")
        for j in range(self.n_modes) if color_by == "type" else ():
            f = self.frequencies_hz[:, j]
            if np.all(f > fmax_hz):
                continue
            t = self.mode_types[len(s) // 2, j]
            ax.plot(s, f, color=colours[t], lw=1.3, label=t if t not in seen else None)
            seen.add(t)
        for o in names:
            ax.plot(s, self.orders[o] * s / 60.0, ls="--", lw=0.9, color="0.35")
        legend = (0.0, 0.3 * float(s.max()), 0.75 * fmax_hz, fmax_hz)  # upper left
        for o, (x, y, ha) in order_labels(self.orders, names, float(s.max()), fmax_hz,
                                           (legend,)).items():
            ax.annotate(o, (x, y), fontsize=7, color="0.25", ha=ha, va="bottom")
        cr = self.crossings(names)
        cr = cr[cr.frequency_hz <= fmax_hz]
        if len(cr):
            inside = cr[cr.in_operating_range]
            ax.plot(cr.speed_rpm, cr.frequency_hz, "o", ms=4, mfc="none", mec="k")
            ax.plot(inside.speed_rpm, inside.frequency_hz, "o", ms=5, color="crimson",
                    label="crossing in operating range")
        if self.speed_range_rpm:
            ax.axvspan(*self.speed_range_rpm, color="0.92", zorder=0)
        ax.set_xlim(s.min(), s.max())
        ax.set_ylim(0, fmax_hz)
        ax.set_xlabel("input speed [rpm]")
        ax.set_ylabel("natural frequency [Hz]")
        ax.set_title(f"Campbell diagram {self.model_name}".strip())
        ax.legend(fontsize=7, loc="upper left")
        fig.tight_layout()
        return fig

    def plot_interactive(self, fmax_hz: float | None = None, orders=None,
                         links: dict | None = None):
        """The Campbell diagram as a plotly Figure (the ``interactive`` extra): each tracked
        mode a line whose points are coloured by their logarithmic decrement (red: unstable,
        yellow: lightly damped, green: well damped); hovering a point shows the mode, its type,
        frequency, damping ratio, logarithmic decrement and whirl; order lines dashed,
        crossings in the operating range marked. ``links``: ``{mode: anchor}`` put in each
        point's ``customdata`` (the report jumps to the mode's drawn shape on a click)."""
        try:
            import plotly.graph_objects as go
        except ImportError:
            raise ModelError("plotly", "is not installed: the interactive Campbell diagram "
                             "needs the 'interactive' extra (pip install gearmodal"
                             "[interactive])") from None
        s = self.speeds_rpm
        names = list(self.orders) if orders is None else list(orders)
        fmax_hz = self._fmax(fmax_hz, names)
        dec = self.log_decrements
        shown = np.clip(dec, -LOG_DEC_SCALE[1] / 5, LOG_DEC_SCALE[1])
        fig = go.Figure()
        for j in range(self.n_modes):
            f = self.frequencies_hz[:, j]
            if np.all(f > fmax_hz):
                continue
            link = (links or {}).get(j, "")
            custom = np.column_stack([np.full(len(s), j), self.mode_types[:, j],
                                      self.damping_ratios[:, j], dec[:, j],
                                      np.asarray(self.whirl, dtype=object)[:, j],
                                      np.full(len(s), link)])
            fig.add_trace(go.Scatter(
                x=s, y=f, mode="lines+markers", name=f"mode {j}", customdata=custom,
                line={"color": "rgba(120,120,120,0.5)", "width": 1},
                marker={"size": 5, "color": shown[:, j], "coloraxis": "coloraxis"},
                hovertemplate=("mode %{customdata[0]} (%{customdata[1]})<br>"
                               "%{y:.4g} Hz at %{x:.4g} rpm<br>damping ratio "
                               "%{customdata[2]:.3g}, log dec %{customdata[3]:.3g}<br>whirl "
                               "%{customdata[4]}<extra></extra>")))
        for o in names:
            fig.add_trace(go.Scatter(x=s, y=self.orders[o] * s / 60.0, mode="lines", name=o,
                                     line={"dash": "dash", "color": "#555", "width": 1},
                                     hoverinfo="name"))
        for o, (x, y, ha) in order_labels(self.orders, names, float(s.max()),
                                           fmax_hz).items():
            fig.add_annotation(x=x, y=y, text=o, showarrow=False, xanchor=ha,
                               yanchor="bottom", font={"size": 10, "color": "#444"})
        cr = self.crossings(names)
        cr = cr[cr.in_operating_range & (cr.frequency_hz <= fmax_hz)]
        if len(cr):
            fig.add_trace(go.Scatter(x=cr.speed_rpm, y=cr.frequency_hz, mode="markers",
                                     name="crossing in operating range",
                                     marker={"color": "crimson", "size": 8,
                                             "symbol": "circle-open"}))
        fig.update_layout(
            title=f"Campbell diagram {self.model_name}".strip(),
            xaxis_title="input speed [rpm]", yaxis_title="natural frequency [Hz]",
            yaxis_range=[0, fmax_hz], showlegend=False, template="plotly_white",
            # plotly ignores cmid beside cmin and cmax: the scale's own stops put yellow at 0
            # (a lightly damped mode is yellow-green, only a negative decrement red)
            coloraxis={"colorscale": LOG_DEC_COLOURS, "cmin": -LOG_DEC_SCALE[1] / 5,
                       "cmax": LOG_DEC_SCALE[1],
                       "colorbar": {"title": {"text": "log dec"}}})
        if self.speed_range_rpm:
            fig.add_vrect(x0=self.speed_range_rpm[0], x1=self.speed_range_rpm[1],
                          fillcolor="#eee", opacity=0.5, line_width=0, layer="below")
        return fig

    def save(self, directory) -> Path:
        """Write ``campbell.csv``, ``crossings.csv``, ``mac.npz``, ``campbell.json``,
        ``campbell.npz`` (the tracked arrays, exact) and ``result.json``: what :meth:`load`
        reads back."""
        d = Path(directory)
        d.mkdir(parents=True, exist_ok=True)
        self.to_frame().to_csv(d / "campbell.csv", index=False)
        self.crossings().to_csv(d / "crossings.csv", index=False)
        np.savez_compressed(d / "mac.npz", macs=np.array(self.macs))
        (d / "campbell.json").write_text(json.dumps(
            {"model": self.model_name, "orders": self.orders,
             "speed_range_rpm": self.speed_range_rpm,
             "speeds_rpm": [float(x) for x in self.speeds_rpm]}, indent=2))
        arrays = {"speeds_rpm": self.speeds_rpm, "frequencies_hz": self.frequencies_hz,
                  "damping_ratios": self.damping_ratios, "veering": self.veering,
                  "mode_types": np.asarray(self.mode_types, dtype=str),
                  "whirl": np.asarray(self.whirl, dtype=str)}
        extra = {}
        for key, val in self.extra.items():
            if isinstance(val, np.ndarray):
                arrays[f"extra.{key}"] = val
            else:
                extra[key] = val
        np.savez_compressed(d / "campbell.npz", **arrays)
        write_header(d, "CampbellResult", SAVE_VERSION, model=self.model_name,
                     orders=self.orders, speed_range_rpm=self.speed_range_rpm,
                     extra=_plain(extra))
        return d

    @classmethod
    @refuses_damage
    def load(cls, directory) -> CampbellResult:
        """The result :meth:`save` wrote to ``directory``, numbers exact (veerings as lists)."""
        d = Path(directory)
        head = read_header(d, "CampbellResult", SAVE_VERSION)
        z = {}
        for name in ("campbell.npz", "mac.npz"):
            if not (d / name).is_file():
                raise ModelError("directory", f"= {str(d)!r}: {name} is missing")
            with np.load(d / name) as f:
                z.update({k: f[k] for k in f.files})
        extra = {k: (v if k != "veerings" else [tuple(r) for r in v])
                 for k, v in head.get("extra", {}).items()}
        extra.update({k[len("extra."):]: v for k, v in z.items() if k.startswith("extra.")})
        rng = head.get("speed_range_rpm")
        return cls(speeds_rpm=z["speeds_rpm"], frequencies_hz=z["frequencies_hz"],
                   damping_ratios=z["damping_ratios"],
                   mode_types=z["mode_types"].astype(object), macs=list(z["macs"]),
                   veering=z["veering"], orders=dict(head["orders"]),
                   speed_range_rpm=tuple(rng) if rng is not None else None,
                   model_name=head["model"], extra=extra,
                   whirl=z["whirl"].astype(object) if "whirl" in z else None)


def _plain(x):
    """JSON-able copy: numpy scalars and tuples as Python numbers and lists."""
    if isinstance(x, dict):
        return {k: _plain(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_plain(v) for v in x]
    if isinstance(x, np.generic):
        return x.item()
    return x


def campbell(model, speeds_rpm, orders: dict | None = None, loads=None, *, state=None,
             progress=None, n_modes: int | None = None,
             fmax_hz: float | None = None, geometric_stiffness: bool = True) -> CampbellResult:
    """Natural frequencies of ``model`` over input speeds ``speeds_rpm`` (rpm), MAC-tracked.

    Parameters
    ----------
    model : :class:`gearmodal.Model` (the input is the carrier of a stage, the rotor of a
        drivetrain).
    speeds_rpm : increasing speeds, rpm (>= 0).
    orders : ``{name: order}`` excitation orders (default :func:`default_orders`).
    loads : ``{load name: value}`` (N, N m). When given, the static equilibrium under these
        loads and the centrifugal forces is solved at every speed
        (:func:`gearmodal.static.equilibrium`) and the modes are those of its contact state;
        ``result.extra["states"]`` keeps the state per speed.
    state : contact state (default nominal; with loads, the equilibrium's starting guess).
    progress : optional callable ``progress(i, n)`` called after each speed (the CLI passes a
        progress bar; the solver never prints).
    n_modes, fmax_hz : a band: only the ``n_modes`` lowest modes at every speed, or as many as
        the non-rotating undamped problem has below ``fmax_hz`` (both: the fewer), from the
        problem projected on twice as many undamped modes of each contact state
        (:func:`gearmodal.modal.band_solve`: an approximation, its error against the full
        solve measured); default: every mode, solved in full.
    geometric_stiffness : the stiffness of the steady rotation's internal forces (the planet
        bearings' and meshes' centrifugal preload, :mod:`gearmodal.assembly`), which keeps a
        free drivetrain's rigid rotation neutral at every speed (default). ``False`` solves
        Lin & Parker's (1999) centripetal-only linearisation, whose rigid rotation turns into
        a real positive eigenvalue at speed (as published; reproduce their diagrams with it).
    """
    from .coupling import Coupled

    if not isinstance(model, (Model, Coupled)):
        raise TypeError(f"expected a gm.Model or gm.Coupled, got {type(model).__name__}")
    try:
        s = np.asarray(speeds_rpm, dtype=float).ravel()
    except (TypeError, ValueError):
        raise ModelError("speeds_rpm", f"= {speeds_rpm!r}: expected an array of speeds in rpm "
                         "(e.g. np.linspace(0, 30, 31); the command line's '0:30:31' is "
                         "text)") from None
    if s.size < 2 or not np.all(np.isfinite(s)) or np.any(s < 0) or np.any(np.diff(s) <= 0):
        raise ModelError("speeds_rpm", "must be at least two finite, increasing speeds >= 0 rpm")
    plausible("speeds_rpm", float(s[-1]), "speed_rpm")
    asm = model.assemble()
    asm.require_piecewise_linear("gm.campbell")
    red, N = reduction(asm)  # a coupled system is solved in its constrained coordinates
    if loads:
        from .static import equilibrium

        states = [equilibrium(asm, loads, rpm, state=state).state for rpm in s]
    else:
        states = [asm.state(state)] * s.size
    n = red.n
    M = red.M
    Kc = red.speed_stiffness(bool(geometric_stiffness))
    Kv = red.K_speed if np.any(red.K_speed) else None
    solvers: dict[bytes, object] = {}
    check_band(n_modes, fmax_hz)
    band = n_modes is not None or fmax_hz is not None
    if fmax_hz is not None:  # the band's width: the modes below fmax_hz at rest, undamped
        w2 = sla.eigh(red.stiffness(states[0]), M, eigvals_only=True)
        below = max(1, int(np.sum(w2 <= (2 * math.pi * fmax_hz) ** 2)))
        n_modes = below if n_modes is None else min(n_modes, below)

    def solve_at(i, om):
        st = states[i]
        key = st.tobytes()
        if key not in solvers:  # one precomputed solver per contact state met in the sweep
            V = band_basis(M, red.stiffness(st), n_modes) if band else None
            if V is None:
                solvers[key] = (None, _sweep_solver(M, red.damping(st), red.stiffness(st),
                                                    red.G, Kc, Kv))
            else:  # the band: the problem projected on the state's basis, solved per speed

                def pr(X):
                    return None if X is None else V.T @ X @ V

                solvers[key] = (V, _sweep_solver(pr(M), pr(red.damping(st)),
                                                 pr(red.stiffness(st)), pr(red.G),
                                                 pr(Kc), pr(Kv)))
        V, solve = solvers[key]
        lam, phi = solve(om)
        if V is not None:
            phi = V @ phi
        if band:
            lam, phi = lam[:n_modes], phi[:, :n_modes]
        return lam, phi

    label = _labeller(asm)
    chunk = max(1, _LABEL_ENTRIES // max(n * n, 1))  # speeds labelled together
    pending = []  # (speed index, shape, M shape) not yet labelled
    if band:
        n = min(n, n_modes)  # the modes reported at every speed
    freqs = np.zeros((s.size, n))
    zetas = np.zeros((s.size, n))
    types = np.empty((s.size, n), dtype=object)
    macs = []
    shapes = []
    prev = prev_M = prev_norm = None
    for i, rpm in enumerate(s):
        lam, phi = solve_at(i, rpm * RPM)
        absl = np.abs(lam)
        f = absl / (2 * math.pi)
        z = damping_ratios(lam)
        Mphi = _matmul(M, phi)
        norm = _re_dot(phi, Mphi)
        if prev is not None:
            # mac(prev, phi, M) with M prev and the norms kept from the previous speed
            mm = np.abs(blas.zgemm(1.0, prev_M, phi, trans_a=2)) ** 2 / np.outer(prev_norm, norm)
            # one-to-one assignment: maximise total MAC, tie-broken by frequency closeness
            cost = -mm + 1e-6 * np.abs(freqs[i - 1][:, None] - f[None, :]) / (1.0 + f.max())
            from scipy.optimize import linear_sum_assignment  # loaded when needed

            _, col = linear_sum_assignment(cost)
            f, z, phi, Mphi, norm = f[col], z[col], phi[:, col], Mphi[:, col], norm[col]
            mm = mm[:, col]
            macs.append(mm)
        freqs[i], zetas[i] = f, z
        shapes.append(phi)
        if N is None:
            pending.append((i, phi, Mphi))
        else:  # labels from the shapes in the original coordinates
            full = N @ phi
            pending.append((i, full, _matmul(asm.M, full)))
        if len(pending) == chunk or i == s.size - 1:
            _label_speeds(label, pending, freqs, types)
            pending = []
        prev, prev_M, prev_norm = phi, Mphi, norm
        if progress is not None:
            progress(i + 1, s.size)
    zetas = rigid_undamped(zetas, types)
    base = model.merged if isinstance(model, Coupled) else model
    own = getattr(model, "excitation_orders", None)  # a system that knows its own orders
    if orders is not None:
        order_map = _orders(orders)
    else:
        order_map = own() if callable(own) else default_orders(base)
    geometry = geometry_table(base)
    whirls = np.full((s.size, n), "", dtype=object)
    if geometry is not None:  # the orbits of the body centres, in the original coordinates
        pairs = translation_pairs(geometry, list(asm.dof_names))
        for i, phi in enumerate(shapes):
            whirls[i] = whirl(phi if N is None else N @ phi, pairs)
    found = _find_veerings(s, freqs, shapes, M)
    veer = np.zeros((s.size, n), dtype=bool)
    for i, a, b, *_ in found:
        veer[i, a] = veer[i, b] = True
    return CampbellResult(speeds_rpm=s, frequencies_hz=freqs, damping_ratios=zetas,
                          mode_types=types, macs=macs, veering=veer, orders=order_map,
                          speed_range_rpm=model.speed_range_rpm, model_name=model.name,
                          whirl=whirls,
                          extra={"veerings": [(s[i], a, b, fr, gap, m)
                                              for i, a, b, fr, gap, m in found],
                                 "states": np.array(states)})


def _orders(orders) -> dict[str, float]:
    """``orders`` as ``{name: order per revolution}``, each a finite number > 0."""
    try:
        items = dict(orders).items()
    except (TypeError, ValueError):
        raise ModelError("orders", f"= {orders!r}: a mapping {{name: order per revolution}}, "
                         "e.g. {'3P': 3.0}") from None
    out = {}
    for k, v in items:
        try:
            x = float(v)
        except (TypeError, ValueError):
            raise ModelError(f"orders.{k}", f"= {v!r}: an order per revolution (a number)") \
                from None
        if not math.isfinite(x) or x <= 0:
            raise ModelError(f"orders.{k}", f"= {v!r}: must be a finite number > 0")
        out[str(k)] = x
    return out


def _sweep_solver(M, C, K, G, Kc, Kv=None):
    """``solve(speed)``: :func:`gearmodal.modal.eigensolve` of ``(M, C, K, G, speed, Kc)`` for a
    sweep in which only the speed changes.

    ``M^-1 K``, ``M^-1 K_cent``, ``M^-1 K_speed``, ``M^-1 C`` and ``M^-1 G`` are computed once, so
    that each speed costs one non-symmetric eigen-solve of the state matrix
    ``[[0, I], [-(M^-1 (K + speed K_speed + speed^2 K_cent)), -(M^-1 (C + speed G))]]``;
    eigenvalues and shapes are selected and ordered exactly as ``eigensolve`` does. Speeds
    without a damping term (undamped at rest) go to ``eigensolve`` itself (the symmetric
    solver).

    The state matrix goes straight to LAPACK ``dgeev`` (right eigenvectors, workspace size
    queried once), which is what ``scipy.linalg.eig`` calls; of its real-format eigenvectors only
    the displacement rows of the kept roots are made complex, as ``scipy.linalg.eig`` does for
    all of them.
    """
    n = M.shape[0]

    def minv(X):
        return sla.solve(M, X, assume_a="pos")

    MiK, MiC = minv(K), minv(C)
    MiG = minv(G) if G is not None else None
    MiKc = minv(Kc) if Kc is not None else None
    MiKv = minv(Kv) if Kv is not None else None
    A0 = np.zeros((2 * n, 2 * n), order="F")  # Fortran order: LAPACK works on it in place
    A0[:n, n:] = np.eye(n)
    geev, geev_lwork = sla.get_lapack_funcs(("geev", "geev_lwork"), (A0,))
    work, info = geev_lwork(2 * n, compute_vl=0, compute_vr=1)
    lwork = int(np.real(work)) if info == 0 else max(8 * n, 1)

    def solve(speed):
        D = C + (speed * G if G is not None and speed else 0.0)
        if not np.any(D):
            return eigensolve(M, C, K, G, speed, Kc, Kv)
        A = A0.copy(order="F")
        lower_k, lower_d = A[n:, :n], A[n:, n:]
        np.negative(MiK, out=lower_k)
        if MiKc is not None and speed:
            lower_k -= speed**2 * MiKc
        if MiKv is not None and speed:
            lower_k -= speed * MiKv
        np.negative(MiC, out=lower_d)
        if MiG is not None and speed:
            lower_d -= speed * MiG
        wr, wi, _, vr, info = geev(A, compute_vl=0, compute_vr=1, lwork=lwork, overwrite_a=1)
        if info != 0:
            return eigensolve(M, C, K, G, speed, Kc, Kv)  # scipy.linalg.eig reports the failure
        lam = np.empty(2 * n, dtype=complex)
        lam.real, lam.imag = wr, wi
        # selection and order as in eigensolve: oscillatory roots with Im > 0, then the real
        # roots of smallest magnitude, one per DOF, ordered by |lambda|
        scale = max(1.0, float(np.max(np.abs(lam))))
        osc = np.abs(lam.imag) > 1e-9 * scale
        pos = np.flatnonzero(osc & (lam.imag > 0))
        real = np.flatnonzero(~osc)
        real = real[np.argsort(np.abs(lam[real]), kind="stable")]
        keep = np.concatenate([pos, real[: max(0, n - len(pos))]])
        keep = keep[np.argsort(np.abs(lam[keep]), kind="stable")]
        return lam[keep], _eigvecs(wi, vr, keep, n)

    return solve


def _eigvecs(wi, vr, cols, rows):
    """Columns ``cols`` (first ``rows`` rows) of the complex eigenvectors that
    ``scipy.linalg.eig`` makes from LAPACK ``geev``'s real output: a complex pair ``j, j + 1``
    (``wi[j] > 0``, scipy's marking) stored as ``vr[:, j] +- i vr[:, j + 1]``; real when every
    root is real, as scipy returns them."""
    if np.all(wi == 0.0):
        return vr[:rows, cols]
    first = wi > 0
    first[:-1] |= wi[1:] < 0  # scipy's workaround for LAPACK (its ticket #709)
    lead = np.flatnonzero(first)
    if lead.size and (np.any(np.diff(lead) < 2) or lead[-1] == wi.size - 1):
        # not clean pairs: scipy's own conversion, column by column
        v = np.array(vr, dtype=complex)
        for i in lead:
            v.imag[:, i] = vr[:, i + 1]
            np.conj(v[:, i], v[:, i + 1])
        return v[:rows, cols]
    second = np.zeros_like(first)
    second[lead + 1] = True
    out = np.empty((rows, len(cols)), dtype=complex)
    re_cols = np.where(second[cols], cols - 1, cols)
    out.real = vr[:rows, re_cols]
    out.imag = 0.0
    a, b = first[cols], second[cols]
    out.imag[:, a] = vr[:rows, cols[a] + 1]
    out.imag[:, b] = -vr[:rows, cols[b]]
    return out


def _matmul(R, X):
    """``R @ X`` for a real matrix ``R`` and a real or complex ``X``, through scipy's BLAS.

    numpy and scipy wheels each bundle an OpenBLAS with its own thread pool; calling numpy's
    ``@`` between scipy's eigen-solves kept both pools' threads competing for the cores (a
    68-DOF sweep on 2 cores ran 3x slower than with either pool on one thread), so the sweep
    does all its matrix products in scipy's. A complex ``X`` is multiplied as its interleaved
    real view, one ``dgemm`` with no copies: ``(R X)^T = X^T R^T``, both transposes Fortran-
    ordered views of C-ordered arrays.
    """
    X = np.ascontiguousarray(X)
    cplx = np.iscomplexobj(X)
    Xr = X.view(np.float64) if cplx else X
    out = blas.dgemm(1.0, Xr.T, np.ascontiguousarray(R).T).T
    return out.view(np.complex128) if cplx else out


def _re_dot(a, b):
    """``Re(sum_i conj(a_im) b_im)`` per column ``m``."""
    if not np.iscomplexobj(a):
        return np.einsum("im,im->m", a, np.real(b))
    return np.einsum("im,im->m", a.real, b.real) + np.einsum("im,im->m", a.imag, b.imag)


def _label_speeds(label, pending, freqs, types):
    """Mode types of the speeds in ``pending`` (``(index, shape, M shape)``), all modes of all
    of them in one vectorised pass; a speed with a mode too close to a threshold to be sure is
    labelled by ``classify`` itself."""
    idx = [i for i, _, _ in pending]
    f = freqs[idx]
    n = f.shape[1]  # modes per speed
    nd = pending[0][1].shape[0]  # coordinates (more than modes for a coupled system)
    phi = np.empty((nd, len(idx) * n), dtype=complex)  # C order: see _matmul
    Mphi = np.empty_like(phi)
    for k, (_, p, mp) in enumerate(pending):
        phi[:, k * n:(k + 1) * n] = p
        Mphi[:, k * n:(k + 1) * n] = mp
    fmax = np.repeat(np.max(f, axis=1), n)
    out, unsure = label(phi, Mphi, f.ravel(), fmax)
    types[idx] = out.reshape(len(idx), n)
    for k in np.flatnonzero(unsure.reshape(len(idx), n).any(axis=1)):
        i = idx[k]
        types[i] = label.exact(pending[k][1], freqs[i])


def _labeller(asm, rigid_rel: float = 1e-6):
    """``label(phi, M phi, freq_hz, fmax_hz) -> (labels, unsure)``: the mode types of
    :func:`gearmodal.modetypes.classify` (default arguments: nominal-state ``K``), vectorised
    over the columns of ``phi``, which may hold the modes of several speeds (``fmax_hz``: the
    highest frequency of each column's speed). ``label.exact(phi, freq_hz)`` is ``classify``.

    Mirrors ``classify`` rule by rule (rigid, housing, the Lin & Parker tests on the stage with
    the most energy, torsional, mixed): keep the two in step. The energy sums are formed with one
    matrix product instead of one masked sum per mode and group, so they can differ from
    ``classify``'s in the last bits; a mode whose deciding quantity lies within a rounding bound
    of its threshold (or whose top two stages are that close) is flagged ``unsure``, and its
    speed goes to ``classify`` itself (:func:`_label_speeds`), so the labels are always
    ``classify``'s.
    """
    K = asm.stiffness()
    M = asm.M
    absK, absM = np.abs(K), np.abs(M)
    names = asm.dof_names
    n = len(names)
    rot = np.array([nm.rsplit(".", 1)[1] in ("theta", "u") for nm in names], dtype=bool)
    body = [nm.rsplit(".", 1)[0] for nm in names]
    planet = np.array([b.rsplit(".", 1)[-1].startswith("planet") for b in body], dtype=bool)
    stage_of = [b.rsplit(".", 1)[0] if "." in b else "" for b in body]
    central = np.array([b.rsplit(".", 1)[-1] in ("carrier", "sun", "ring") for b in body],
                       dtype=bool)
    housing = np.array([b == "housing" or b.endswith(".housing") for b in body], dtype=bool)
    has_planets, has_housing = bool(planet.any()), bool(housing.any())
    stages = sorted(set(stage_of))  # pandas groupby order; idxmax takes the first maximum
    rows = [rot, housing]
    for stg in stages:
        in_stage = np.array([x == stg for x in stage_of], dtype=bool)
        c, p = central & in_stage, planet & in_stage
        rows += [in_stage, c | p, c, c & ~rot, c & rot]
    S = np.array(rows, dtype=float)
    ns = len(stages)
    st_rows = 2 + 5 * np.arange(ns)
    cp_any = np.array([bool(S[r + 1].any()) for r in st_rows], dtype=bool)
    eps = np.finfo(float).eps
    gamma = 16.0 * (n + 2) * eps

    turbine = turbine_groups(tuple(names))

    def label(phi, Mphi, freq_hz, fmax):
        nm = phi.shape[1]
        if turbine is not None:  # an elastic turbine's families: classify itself, speed by speed
            return np.full(nm, "mixed", dtype=object), np.ones(nm, dtype=bool)
        # rigid: stiffness Rayleigh quotient num / den (as a frequency) below rigid_rel * fmax
        num = _re_dot(phi, _matmul(K, phi))
        den = _re_dot(phi, Mphi)
        thr = rigid_rel * fmax
        # classify: static_hz < thr, never true for thr <= 0 (static_hz >= 0)
        aphi = np.abs(phi)
        q = (2 * np.pi * thr) ** 2
        d = num - q * den
        bound = (gamma * (np.einsum("im,im->m", aphi, _matmul(absK, aphi))
                          + q * np.einsum("im,im->m", aphi, _matmul(absM, aphi)))
                 + 16 * eps * q * np.abs(den))
        rigid = (d < 0) & (thr > 0)
        unsure = (thr > 0) & ~(np.abs(d) > bound)  # also catches NaN
        # kinetic energy share per DOF, as modetypes.dof_energy
        e = phi.real * Mphi.real + phi.imag * Mphi.imag  # Re(conj(phi) M phi)
        tot = e.sum(axis=0, keepdims=True)
        e = np.divide(e, tot, out=np.zeros_like(e), where=tot > 0)
        tol = gamma * np.abs(e).sum(axis=0)
        g = _matmul(S, e)
        out = np.full(nm, "mixed", dtype=object)
        open_ = np.ones(nm, dtype=bool)

        def rule(cond, margin, tag, where=None):
            nonlocal unsure, open_
            m = open_ if where is None else open_ & where
            unsure |= m & ~(np.abs(margin) > tol * 4)
            hit = m & cond
            out[hit] = tag
            open_ = open_ & ~hit

        out[rigid] = "rigid"
        open_ &= ~rigid
        if has_housing:
            rule(g[1] > 0.5, g[1] - 0.5, "housing")
        if has_planets:
            sums = g[st_rows]
            best = np.argmax(sums, axis=0)
            if ns > 1:
                top2 = np.sort(sums, axis=0)[-2:]
                unsure |= open_ & ~(top2[1] - top2[0] > tol * 4)
            cols = np.arange(nm)
            r = st_rows[best]
            cp, c, cnr, cr = g[r + 1, cols], g[r + 2, cols], g[r + 3, cols], g[r + 4, cols]
            inner = cp_any[best] & (cp > 0.5)
            unsure |= open_ & cp_any[best] & ~(np.abs(cp - 0.5) > tol * 4)
            rule(c < QUIET, c - QUIET, "planet", inner)
            rule(cnr < QUIET * c + QUIET, cnr - QUIET * c - QUIET, "rotational", inner)
            rule(cr < QUIET * c + QUIET, cr - QUIET * c - QUIET, "translational", inner)
            rule(c < LOOSE * cp, c - LOOSE * cp, "planet", inner)
            rule(cnr < LOOSE * c, cnr - LOOSE * c, "rotational", inner)
            rule(cr < LOOSE * c, cr - LOOSE * c, "translational", inner)
        rule(g[0] > 0.9, g[0] - 0.9, "torsional")
        return out, unsure

    def exact(phi, freq_hz):
        return classify(asm, phi, freq_hz, rigid_rel=rigid_rel, K=K)

    label.exact = exact
    return label


def _find_veerings(s, freqs, shapes, M, w=VEERING_WINDOW):
    """Local minima of the gap between frequency-adjacent tracked modes (no sign change)
    across which the tracked shape changes character (MAC < VEERING_MAC)."""
    ns, n = freqs.shape
    out = []
    if ns < 2 * w + 1 or n < 2:
        return out
    order = np.argsort(freqs, axis=1)
    # frequency-adjacent pairs at any speed, in sorted order
    pairs = np.unique(np.stack([order[:, :-1].ravel(), order[:, 1:].ravel()], axis=1), axis=0)
    gap = freqs[:, pairs[:, 1]] - freqs[:, pairs[:, 0]]  # (ns, n_pairs)
    keep = ~(np.any(gap > 0, axis=0) & np.any(gap < 0, axis=0))  # crossing pairs never veer
    pairs, g = pairs[keep], np.abs(gap[:, keep]).T  # (n_pairs, ns)
    scale = np.maximum(np.abs(freqs[:, pairs[:, 0]]), 1e-12).T
    mid = g[:, w:ns - w]
    hit = ((mid < g[:, w - 1:ns - w - 1]) & (mid <= g[:, w + 1:ns - w + 1])
           & (mid < 0.1 * scale[:, w:ns - w]))
    for k, j in zip(*np.nonzero(hit), strict=True):  # pair by pair, speeds increasing
        a, b, i = int(pairs[k, 0]), int(pairs[k, 1]), int(j) + w
        m = float(mac(shapes[i - w][:, [a]], shapes[i + w][:, [a]], M)[0, 0])
        if m < VEERING_MAC:
            out.append((i, a, b, float(freqs[i, a]), float(g[k, i]), m))
    return out
