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
from scipy.optimize import linear_sum_assignment

from .errors import ModelError
from .modal import RPM, eigensolve
from .model.components import Gear
from .model.model import Model
from .modetypes import classify

#: a tracked mode whose shape keeps less MAC than this across a near-approach has veered
VEERING_MAC = 0.5
#: half-width (in speed steps) of the window over which a veering's shape exchange is judged
VEERING_WINDOW = 3


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
    if "rotor" in model.bodies:
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


@dataclass
class CampbellResult:
    """Tracked natural frequencies over a speed sweep.

    Attributes
    ----------
    speeds_rpm : (n_speeds,) input speeds, rpm.
    frequencies_hz, damping_ratios : (n_speeds, n_modes), column j follows tracked mode j.
    mode_types : (n_speeds, n_modes) labels.
    macs : list of (n_modes, n_modes) MAC matrices between consecutive speeds (tracked order
        on both axes; the diagonal is the tracking MAC).
    veering : (n_speeds, n_modes) True at the speed where a mode veers (see :meth:`veerings`).
    orders : excitation orders ``{name: multiple of input speed}``.
    speed_range_rpm : operating range used to mark crossings.
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

    @property
    def n_modes(self) -> int:
        return self.frequencies_hz.shape[1]

    def to_frame(self) -> pd.DataFrame:
        """Long table: ``speed_rpm``, ``mode``, ``frequency_hz``, ``damping_ratio``,
        ``mode_type``, ``veering``."""
        ns, nm = self.frequencies_hz.shape
        return pd.DataFrame({
            "speed_rpm": np.repeat(self.speeds_rpm, nm),
            "mode": np.tile(np.arange(nm), ns),
            "frequency_hz": self.frequencies_hz.ravel(),
            "damping_ratio": self.damping_ratios.ravel(),
            "mode_type": self.mode_types.ravel(),
            "veering": self.veering.ravel(),
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

    def plot(self, fmax_hz: float | None = None, ax=None, orders=None):
        """The Campbell diagram (tracked modes coloured by type, order lines dashed, crossings
        marked, operating range shaded); returns the matplotlib Figure."""
        import matplotlib.pyplot as plt

        if ax is None:
            fig, ax = plt.subplots(figsize=(8, 5.5))
        else:
            fig = ax.figure
        s = self.speeds_rpm
        names = list(self.orders) if orders is None else list(orders)
        if fmax_hz is None:
            top = max(self.orders[o] for o in names) * s.max() / 60.0
            fmax_hz = min(max(1.2 * top, 1.0), 1.05 * np.nanmax(self.frequencies_hz))
        types = sorted(set(self.mode_types.ravel()))
        colours = {t: f"C{i % 10}" for i, t in enumerate(types)}
        seen = set()
        for j in range(self.n_modes):
            f = self.frequencies_hz[:, j]
            if np.all(f > fmax_hz):
                continue
            t = self.mode_types[len(s) // 2, j]
            ax.plot(s, f, color=colours[t], lw=1.3, label=t if t not in seen else None)
            seen.add(t)
        for _i, o in enumerate(names):
            ax.plot(s, self.orders[o] * s / 60.0, ls="--", lw=0.9, color="0.35")
            x = s.max()
            y = self.orders[o] * x / 60.0
            if y > fmax_hz:
                x, y = fmax_hz * 60.0 / self.orders[o], fmax_hz
            ax.annotate(o, (x, y), fontsize=7, color="0.25", ha="right", va="bottom")
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

    def save(self, directory) -> Path:
        """Write ``campbell.csv``, ``crossings.csv``, ``mac.npz`` and ``campbell.json``."""
        d = Path(directory)
        d.mkdir(parents=True, exist_ok=True)
        self.to_frame().to_csv(d / "campbell.csv", index=False)
        self.crossings().to_csv(d / "crossings.csv", index=False)
        np.savez_compressed(d / "mac.npz", macs=np.array(self.macs))
        (d / "campbell.json").write_text(json.dumps(
            {"model": self.model_name, "orders": self.orders,
             "speed_range_rpm": self.speed_range_rpm,
             "speeds_rpm": [float(x) for x in self.speeds_rpm]}, indent=2))
        return d


def campbell(model, speeds_rpm, orders: dict | None = None, loads=None, *, state=None,
             progress=None) -> CampbellResult:
    """Natural frequencies of ``model`` over input speeds ``speeds_rpm`` (rpm), MAC-tracked.

    Parameters
    ----------
    model : :class:`gearmodal.Model` (the input is the carrier of a stage, the rotor of a
        drivetrain).
    speeds_rpm : increasing speeds, rpm (>= 0).
    orders : ``{name: order}`` excitation orders (default :func:`default_orders`).
    loads : reserved for the loaded contact state (not yet supported).
    state : contact state (default nominal).
    progress : optional callable ``progress(i, n)`` called after each speed (the CLI passes a
        progress bar; the solver never prints).
    """
    if not isinstance(model, Model):
        raise TypeError(f"expected a gm.Model, got {type(model).__name__}")
    s = np.asarray(speeds_rpm, dtype=float).ravel()
    if s.size < 2 or not np.all(np.isfinite(s)) or np.any(s < 0) or np.any(np.diff(s) <= 0):
        raise ModelError("speeds_rpm", "must be at least two finite, increasing speeds >= 0 rpm")
    if loads:
        raise ModelError("loads", "loaded Campbell diagrams are not implemented yet")
    asm = model.assemble()
    st = asm.state(state)
    K, C = asm.stiffness(st), asm.damping(st)
    n = asm.n
    freqs = np.zeros((s.size, n))
    zetas = np.zeros((s.size, n))
    types = np.empty((s.size, n), dtype=object)
    macs = []
    shapes = []
    prev = None
    for i, rpm in enumerate(s):
        lam, phi = eigensolve(asm.M, C, K, asm.G, rpm * RPM, asm.K_cent)
        absl = np.abs(lam)
        f = absl / (2 * math.pi)
        with np.errstate(invalid="ignore", divide="ignore"):
            z = np.where(absl > 0, -lam.real / np.where(absl > 0, absl, 1.0), 0.0)
        if prev is not None:
            mm = mac(prev, phi, asm.M)
            # one-to-one assignment: maximise total MAC, tie-broken by frequency closeness
            cost = -mm + 1e-6 * np.abs(freqs[i - 1][:, None] - f[None, :]) / (1.0 + f.max())
            _, col = linear_sum_assignment(cost)
            f, z, phi = f[col], z[col], phi[:, col]
            mm = mm[:, col]
            macs.append(mm)
        freqs[i], zetas[i] = f, z
        types[i] = classify(asm, phi, f)
        shapes.append(phi)
        prev = phi
        if progress is not None:
            progress(i + 1, s.size)
    order_map = default_orders(model) if orders is None else dict(orders)
    found = _find_veerings(s, freqs, shapes, asm.M)
    veer = np.zeros((s.size, n), dtype=bool)
    for i, a, b, *_ in found:
        veer[i, a] = veer[i, b] = True
    return CampbellResult(speeds_rpm=s, frequencies_hz=freqs, damping_ratios=zetas,
                          mode_types=types, macs=macs, veering=veer, orders=order_map,
                          speed_range_rpm=model.speed_range_rpm, model_name=model.name,
                          extra={"veerings": [(s[i], a, b, fr, gap, m)
                                              for i, a, b, fr, gap, m in found]})


def _find_veerings(s, freqs, shapes, M, w=VEERING_WINDOW):
    """Local minima of the gap between frequency-adjacent tracked modes (no sign change)
    across which the tracked shape changes character (MAC < VEERING_MAC)."""
    ns, n = freqs.shape
    out = []
    if ns < 2 * w + 1:
        return out
    order = np.argsort(freqs, axis=1)
    pairs = set()
    for i in range(ns):
        for k in range(n - 1):
            pairs.add((int(order[i, k]), int(order[i, k + 1])))
    for a, b in sorted(pairs):
        gap = freqs[:, b] - freqs[:, a]
        if np.any(gap > 0) and np.any(gap < 0):
            continue  # they cross: not a veering
        g = np.abs(gap)
        scale = np.maximum(np.abs(freqs[:, a]), 1e-12)
        for i in range(w, ns - w):
            if g[i] < g[i - 1] and g[i] <= g[i + 1] and g[i] < 0.1 * scale[i]:
                m = float(mac(shapes[i - w][:, [a]], shapes[i + w][:, [a]], M)[0, 0])
                if m < VEERING_MAC:
                    out.append((i, a, b, float(freqs[i, a]), float(g[i]), m))
    return out
