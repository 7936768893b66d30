"""Modal analysis of a model at one input speed (DESIGN 3.1).

Undamped and non-rotating: the generalised symmetric eigenproblem ``K phi = w^2 M phi``.
Otherwise the first-order (state-space) form of
``M q'' + (C + Omega G) q' + (K + Omega K_speed + Omega^2 K_cent) q = 0``. The contact
state is the nominal one (front flanks engaged, bearing clearances taken up) unless a state is
given.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd
import scipy.linalg as sla

from .assembly import Assembly, as_assembly, reduction
from .errors import ModelError
from .frames import centre
from .model.validate import plausible
from .result_io import read_csv, read_header, refuses_damage, write_header
from .whirl import damping_ratios, log_decrement, rigid_undamped, translation_pairs, whirl

RPM = 2.0 * math.pi / 60.0  # rad/s per rpm
#: layout version of :meth:`ModalResult.save` (``result.json``)
SAVE_VERSION = 1


@dataclass
class ModalResult:
    """Natural frequencies and mode shapes at one speed.

    Attributes
    ----------
    speed_rpm : input speed, rpm.
    frequencies_hz : undamped natural frequencies ``|lambda| / 2 pi``, ascending, Hz
        (rigid-body modes near 0 included).
    damping_ratios : ``-Re(lambda) / |lambda|`` (0 for undamped modes and rigid-body modes).
    shapes : (n_dofs, n_modes) mode shapes, complex when rotating or damped, each scaled to a
        largest component of 1.
    dof_names : names of the rows of ``shapes``.
    kinetic_energy, strain_energy : DataFrames (modes x bodies / elements) with each mode's
        share of kinetic energy per body and of strain energy per spring element (rows sum to 1).
    mode_types : label per mode (see :func:`gearmodal.modetypes.classify`); ``labels``
        overrides by mode index.
    equilibrium : the static equilibrium (:class:`gearmodal.static.Equilibrium`) when loads
        were given, else None. contact_state : the contact states the modes belong to.
    geometry : the bodies where they sit at azimuth 0 (index ``body``: ``x``, ``y`` (m),
        ``radius`` (pitch radius of a gear, m; NaN otherwise), ``orientation`` (rad), ``role``
        and the DOF names of the centre's local ``x``/``y`` and of the rotation, with the
        rotation's scale), for drawing the modes (:meth:`body_motion`, :meth:`plot_shape`);
        None for an assembly or coupled system given without its model.
    """

    speed_rpm: float
    frequencies_hz: np.ndarray
    damping_ratios: np.ndarray
    shapes: np.ndarray
    dof_names: list
    kinetic_energy: pd.DataFrame
    strain_energy: pd.DataFrame
    mode_types: list = field(default_factory=list)
    model_name: str = ""
    equilibrium: object = None
    contact_state: np.ndarray | None = None
    geometry: pd.DataFrame | None = None

    @property
    def n_modes(self) -> int:
        return len(self.frequencies_hz)

    def to_frame(self) -> pd.DataFrame:
        """One row per mode: ``mode``, ``frequency_hz``, ``damping_ratio``, ``mode_type``,
        ``dominant_body`` (largest kinetic energy share) and that share, ``log_dec`` (the
        logarithmic decrement) and ``whirl`` (``forward``/``backward``/``linear``, ``""`` for
        modes without translation or without the model's geometry; :mod:`gearmodal.whirl`)."""
        ke = self.kinetic_energy
        return pd.DataFrame({
            "mode": np.arange(self.n_modes),
            "speed_rpm": self.speed_rpm,
            "frequency_hz": self.frequencies_hz,
            "damping_ratio": self.damping_ratios,
            "mode_type": self.mode_types,
            "dominant_body": ke.idxmax(axis=1).to_numpy() if ke.shape[1] else "",
            "dominant_share": ke.max(axis=1).to_numpy() if ke.shape[1] else np.nan,
            "log_dec": log_decrement(self.damping_ratios),
            "whirl": self.whirl(),
        })

    def whirl(self) -> np.ndarray:
        """Whirl direction of each mode (:func:`gearmodal.whirl.whirl`): from the orbits of
        the body centres of :attr:`geometry`; ``""`` for every mode without it."""
        if self.geometry is None:
            return np.full(self.n_modes, "", dtype=object)
        return whirl(self.shapes, translation_pairs(self.geometry, list(self.dof_names)))

    def shape(self, i: int) -> pd.Series:
        """Mode ``i``'s shape as a Series indexed by DOF name (real part after phase
        alignment)."""
        return pd.Series(_real_shape(self.shapes[:, i]), index=self.dof_names, name=f"mode {i}")

    def body_motion(self, i: int, scale: float | None = None,
                    phase_deg: float = 0.0) -> pd.DataFrame:
        """Mode ``i`` as the motion of each body in the gearbox plane (global axes), from
        :attr:`geometry` and the phase-aligned shape at ``phase_deg`` of the cycle (the real
        part of ``phi e^{i phase}``; 0: :meth:`shape`): ``x``, ``y``, ``radius``, the centre's
        displacement ``dx``, ``dy`` (m) and the ``rotation`` (rad), all scaled by one factor
        so that the largest motion over the cycle (a centre's displacement, or a rotation
        times its radius) is ``scale`` (m; default 15 % of the largest pitch radius, or of
        the bodies' spread). Displacements: the local ``x``/``y`` turned by the body's
        orientation."""
        g = self._geometry()
        dx, dy, rot = self._motion(i, np.exp(1j * math.radians(phase_deg)))
        k = (0.15 * self._size() if scale is None else scale) / self._largest_motion(i)
        return pd.DataFrame({"x": g.x, "y": g.y, "radius": g.radius, "dx": k * dx,
                             "dy": k * dy, "rotation": k * rot}, index=g.index)

    def _geometry(self) -> pd.DataFrame:
        if self.geometry is None:
            raise ModelError("geometry", "this result has no model geometry (modal of an "
                             "assembly or coupled system): use plot_shape(kind='bars')")
        return self.geometry

    def _size(self) -> float:
        """The drawing's reference length: the largest pitch radius, or the bodies' spread."""
        g = self._geometry()
        size = np.nanmax(g.radius.to_numpy()) if np.isfinite(g.radius).any() else 0.0
        spread = float(np.ptp(np.r_[g.x, g.y])) if len(g) else 0.0
        return size if size > 0 else (spread if spread > 0 else 1.0)

    def _motion(self, i: int, turn: complex = 1.0):
        """Unscaled global ``dx``, ``dy`` and ``rotation`` of each body for the phase-aligned
        complex shape times ``turn`` (real part)."""
        g = self._geometry()
        v = self.shapes[:, i]
        j = int(np.argmax(np.abs(v)))
        aligned = v * np.conj(v[j]) / np.abs(v[j]) if np.abs(v[j]) > 0 else v
        s = dict(zip(self.dof_names, np.real(aligned * turn), strict=True))

        def val(name):
            return float(s[name]) if isinstance(name, str) and name in s else 0.0

        lx = np.array([val(n) for n in g.x_dof])
        ly = np.array([val(n) for n in g.y_dof])
        rot = np.array([val(n) / sc for n, sc in zip(g.rot_dof, g.rot_scale, strict=True)])
        c, sn = np.cos(g.orientation.to_numpy()), np.sin(g.orientation.to_numpy())
        return c * lx - sn * ly, sn * lx + c * ly, rot

    def _largest_motion(self, i: int) -> float:
        """The largest motion of mode ``i`` over its cycle (centre displacement, or rotation
        times the rim radius, so a torsional mode is drawn at the scale of a translational
        one), sampled at 36 phases."""
        g = self._geometry()
        r = g.radius.to_numpy()
        rim = np.where(np.isfinite(r), r, self._size())
        big = 1e-300
        for ph in np.linspace(0.0, np.pi, 36, endpoint=False):
            dx, dy, rot = self._motion(i, np.exp(1j * ph))
            big = max(big, float(np.hypot(dx, dy).max(initial=0.0)),
                      float(np.abs(rim * rot).max(initial=0.0)))
        return big

    def plot_shape(self, i: int, ax=None, kind: str = "auto", phase_deg: float = 0.0):
        """Mode ``i``: the gearbox drawn (``kind="geometry"``, the default when the model's
        geometry is known; one panel per stage: each gear as its pitch circle, the carrier's
        arms to its planets, the housing as a square, other bodies as a dot, at rest in grey
        and displaced by the mode in colour at ``phase_deg`` of its cycle, each rotation as a
        turned radius) or a bar chart of the shape per DOF (``kind="bars"``). Returns the
        matplotlib Figure (:meth:`animate_shape` writes the cycle as a GIF)."""
        import matplotlib.pyplot as plt

        if kind not in ("auto", "geometry", "bars"):
            raise ModelError("kind", f"= {kind!r}: must be 'auto', 'geometry' or 'bars'")
        if kind == "geometry" or (kind == "auto" and self.geometry is not None):
            return self._plot_geometry(i, ax, phase_deg)
        if ax is None:
            fig, ax = plt.subplots(figsize=(max(6.0, 0.18 * len(self.dof_names)), 3.2))
        else:
            fig = ax.figure
        s = self.shape(i)
        ax.bar(range(len(s)), s.to_numpy(), color="C0")
        ax.set_xticks(range(len(s)))
        ax.set_xticklabels(s.index, rotation=90, fontsize=6)
        ax.set_ylabel("normalised amplitude")
        ax.set_title(self._title(i))
        fig.tight_layout()
        return fig

    def animate_shape(self, i: int, path, frames: int = 24, fps: int = 12,
                      dpi: int = 80) -> Path:
        """Write mode ``i`` moving through one cycle (``frames`` phases, drawn as
        :meth:`plot_shape`) as an animated GIF at ``path`` (Pillow, matplotlib's own
        dependency; ``dpi`` sets its size). Returns the path."""
        import matplotlib.pyplot as plt
        from matplotlib.animation import FuncAnimation, PillowWriter

        if not (isinstance(frames, int) and 2 <= frames <= 360):
            raise ModelError("frames", f"= {frames!r}: must be an integer from 2 to 360")
        if not (isinstance(fps, int) and 1 <= fps <= 60):
            raise ModelError("fps", f"= {fps!r}: must be an integer from 1 to 60")
        path = Path(path)
        fig = self._plot_geometry(i, None, 0.0)

        def draw(k):
            for ax in fig.axes:
                ax.clear()
            self._draw(i, fig.axes, 360.0 * k / frames)
            return []

        anim = FuncAnimation(fig, draw, frames=frames, blit=False)
        anim.save(path, writer=PillowWriter(fps=fps), dpi=dpi)
        plt.close(fig)
        return path

    def _title(self, i: int) -> str:
        typ = self.mode_types[i] if self.mode_types else ""
        return f"mode {i}: {self.frequencies_hz[i]:.3f} Hz {typ} ({self.speed_rpm:g} rpm)"

    def _panels(self) -> list[list[str]]:
        """The bodies drawn together: one panel per stage (the name's prefix before the
        first '.'); the housing in every panel, the other bodies of no stage (rotor,
        generator) in the first."""
        g = self._geometry()
        names = list(g.index)
        stages = list(dict.fromkeys(n.split(".", 1)[0] for n in names if "." in n))
        if not stages:
            return [names]
        house = [n for n in names if "." not in n and g.role[n] == "housing"]
        free = [n for n in names if "." not in n and n not in house]
        return [(house + free if k == 0 else house)
                + [n for n in names if n.startswith(st + ".")] for k, st in enumerate(stages)]

    def _plot_geometry(self, i: int, ax=None, phase_deg: float = 0.0):
        import matplotlib.pyplot as plt

        panels = self._panels()
        if ax is None:
            n = len(panels)
            fig, axs = plt.subplots(1, n, figsize=(min(5.0 * n, 15.0), 5.4), squeeze=False)
            axes = list(axs[0])
        else:
            fig, axes = ax.figure, [ax]
        self._draw(i, axes, phase_deg)
        fig.tight_layout()
        return fig

    def _draw(self, i: int, axes, phase_deg: float) -> None:
        from matplotlib.patches import Circle, Rectangle

        m = self.body_motion(i, phase_deg=phase_deg)
        roles = self._geometry().role
        panels = self._panels() if len(axes) > 1 else [list(m.index)]
        for ax, names in zip(axes, panels, strict=False):
            sub = m.loc[names]
            size = np.nanmax(sub.radius) if np.isfinite(sub.radius).any() else self._size()
            dot = 0.06 * size
            for name, r in sub.iterrows():
                cx, cy = r.x + r.dx, r.y + r.dy
                if roles[name] == "housing":  # the housing: a square around the panel
                    h = 1.15 * size
                    ax.add_patch(Rectangle((r.x - h, r.y - h), 2 * h, 2 * h, fill=False,
                                           color="0.8", lw=0.8))
                    ax.add_patch(Rectangle((cx - h, cy - h), 2 * h, 2 * h, fill=False,
                                           color="C0", lw=1.0, ls="--"))
                    continue
                rad = r.radius if np.isfinite(r.radius) else dot
                ax.add_patch(Circle((r.x, r.y), rad, fill=False, color="0.75", lw=0.8))
                ax.add_patch(Circle((cx, cy), rad, fill=False, color="C3", lw=1.2))
                a = r.rotation
                ax.plot([cx, cx + rad * math.cos(a)], [cy, cy + rad * math.sin(a)],
                        color="C3", lw=1.0)
                ax.annotate(str(name).rsplit(".", 1)[-1], (r.x, r.y), fontsize=6,
                            color="0.4", ha="center", va="center")
            carriers = [n for n in names if roles[n] == "carrier"]
            for c in carriers:  # the carrier's arms to its planets' centres
                prefix = c.rsplit(".", 1)[0] + "." if "." in c else ""
                cr = m.loc[c]
                for p in names:
                    if roles[p] == "planet" and p.startswith(prefix):
                        pr = m.loc[p]
                        ax.plot([cr.x, pr.x], [cr.y, pr.y], color="0.8", lw=2.5, zorder=0)
                        ax.plot([cr.x + cr.dx, pr.x + pr.dx], [cr.y + cr.dy, pr.y + pr.dy],
                                color="C1", lw=2.0, alpha=0.7, zorder=0)
            ax.set_aspect("equal")
            ax.relim()
            ax.autoscale_view()
            # the panel holds every body at rest and displaced, with its radius (a displaced
            # gear at the panel's edge was clipped)
            rad = np.where(np.isfinite(sub.radius), sub.radius, dot).astype(float)
            xs = np.concatenate([sub.x - rad, sub.x + sub.dx - rad, sub.x + rad,
                                 sub.x + sub.dx + rad])
            ys = np.concatenate([sub.y - rad, sub.y + sub.dy - rad, sub.y + rad,
                                 sub.y + sub.dy + rad])
            pad = 0.15 * size
            if any(roles[n] == "housing" for n in names):
                pad = max(pad, 1.2 * size)  # the housing's square
            ax.set_xlim(np.nanmin(xs) - pad, np.nanmax(xs) + pad)
            ax.set_ylim(np.nanmin(ys) - pad, np.nanmax(ys) + pad)
            ax.set_xlabel("x [m]")
            ax.set_ylabel("y [m]")
            stage = next((n.split(".", 1)[0] for n in names if "." in n), "")
            ax.set_title(stage, fontsize=9)
        axes[0].figure.suptitle(self._title(i) + "\ngrey: at rest; colour: displaced (scaled), "
                                "rotation as a turned radius, carrier arms in orange",
                                fontsize=9)

    def save(self, directory) -> Path:
        """Write ``modes.csv``, ``shapes.csv`` (real, phase-aligned), ``kinetic_energy.csv``,
        ``strain_energy.csv``, ``modal.json``, ``modal.npz`` (the complex shapes, frequencies
        and damping ratios, exact) and ``result.json`` into ``directory``: what :meth:`load`
        reads back. Returns the directory."""
        d = Path(directory)
        d.mkdir(parents=True, exist_ok=True)
        self.to_frame().to_csv(d / "modes.csv", index=False)
        pd.DataFrame(np.array([_real_shape(s) for s in self.shapes.T]).T,
                     index=self.dof_names).to_csv(d / "shapes.csv", index_label="dof")
        self.kinetic_energy.to_csv(d / "kinetic_energy.csv", index_label="mode")
        self.strain_energy.to_csv(d / "strain_energy.csv", index_label="mode")
        (d / "modal.json").write_text(json.dumps(
            {"model": self.model_name, "speed_rpm": self.speed_rpm,
             "n_modes": self.n_modes}, indent=2))
        arrays = {"shapes": self.shapes, "frequencies_hz": self.frequencies_hz,
                  "damping_ratios": self.damping_ratios}
        if self.contact_state is not None:
            arrays["contact_state"] = np.asarray(self.contact_state, dtype=bool)
        if self.geometry is not None:
            self.geometry.to_csv(d / "geometry.csv", index_label="body")
        np.savez_compressed(d / "modal.npz", **arrays)
        write_header(d, "ModalResult", SAVE_VERSION, dof_names=list(self.dof_names),
                     mode_types=list(self.mode_types), model=self.model_name,
                     speed_rpm=self.speed_rpm)
        return d

    @classmethod
    @refuses_damage
    def load(cls, directory) -> ModalResult:
        """The result :meth:`save` wrote to ``directory``, numbers exact. The static
        ``equilibrium`` is not saved: it is ``None`` (its contact state is kept)."""
        d = Path(directory)
        head = read_header(d, "ModalResult", SAVE_VERSION)
        npz = d / "modal.npz"
        if not npz.is_file():
            raise ModelError("directory", f"= {str(d)!r}: modal.npz is missing")
        with np.load(npz) as z:
            arrays = {k: z[k] for k in z.files}
        ke = read_csv(d / "kinetic_energy.csv", index_col="mode")
        se = read_csv(d / "strain_energy.csv", index_col="mode")
        ke.index.name = se.index.name = None  # as modal() makes them
        geometry = None
        if (d / "geometry.csv").is_file():
            geometry = read_csv(d / "geometry.csv", index_col="body", keep_default_na=False,
                                dtype={c: str for c in ("role", "x_dof", "y_dof", "rot_dof")})
            geometry["radius"] = np.array([float(r) if r != "" else math.nan
                                           for r in geometry["radius"].astype(str)])
        return cls(speed_rpm=head["speed_rpm"], frequencies_hz=arrays["frequencies_hz"],
                   damping_ratios=arrays["damping_ratios"], shapes=arrays["shapes"],
                   dof_names=list(head["dof_names"]), kinetic_energy=ke, strain_energy=se,
                   mode_types=list(head["mode_types"]), model_name=head["model"],
                   contact_state=arrays.get("contact_state"), geometry=geometry)


def _real_shape(v: np.ndarray) -> np.ndarray:
    """Rotate a complex shape so its largest component is real; return the real part."""
    j = int(np.argmax(np.abs(v)))
    if np.abs(v[j]) == 0:
        return np.real(v)
    return np.real(v * np.conj(v[j]) / np.abs(v[j]))


def eigensolve(M, C, K, G=None, speed=0.0, Kc=None, Kv=None):
    """Eigenvalues ``lambda`` (n,) and displacement shapes (n, n) of the quadratic problem
    ``(lambda^2 M + lambda (C + speed G) + K + speed Kv + speed^2 Kc) phi = 0``, one per DOF,
    ordered by ``|lambda|``. Uses the symmetric generalised solver when the damping term
    vanishes."""
    n = M.shape[0]
    D = C + (speed * G if G is not None and speed else 0.0)
    Ks = K + (speed**2 * Kc if Kc is not None and speed else 0.0)
    if Kv is not None and speed and np.any(Kv):
        Ks = Ks + speed * Kv
    if not np.any(D):
        w2, phi = sla.eigh(Ks, M)
        lam = np.sqrt(w2.astype(complex))  # negative w2 (centripetal softening) -> real lambda
        lam = np.where(w2 >= 0, 1j * np.sqrt(np.clip(w2, 0, None)), lam)
        order = np.argsort(np.abs(lam), kind="stable")
        return lam[order], phi[:, order].astype(complex)
    Minv_K = sla.solve(M, Ks, assume_a="pos")
    Minv_D = sla.solve(M, D, assume_a="pos")
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-Minv_K, -Minv_D]])
    lam, vec = sla.eig(A)
    scale = max(1.0, float(np.max(np.abs(lam))))
    osc = np.abs(lam.imag) > 1e-9 * scale
    pos = np.flatnonzero(osc & (lam.imag > 0))
    real = np.flatnonzero(~osc)
    real = real[np.argsort(np.abs(lam[real]), kind="stable")]
    keep = np.concatenate([pos, real[: max(0, n - len(pos))]])
    lam, vec = lam[keep], vec[:n, keep]
    order = np.argsort(np.abs(lam), kind="stable")
    return lam[order], vec[:, order]


#: a band's basis (:func:`band_basis`): this many undamped modes per mode asked for, and at
#: least :data:`BAND_EXTRA` more
BAND_BASIS = 2
BAND_EXTRA = 16


def check_band(n_modes, fmax_hz) -> None:
    """``n_modes`` (an integer >= 1) and ``fmax_hz`` (a frequency > 0), each optional."""
    if n_modes is not None and not (isinstance(n_modes, (int, np.integer))
                                    and not isinstance(n_modes, bool) and n_modes >= 1):
        raise ModelError("n_modes", f"= {n_modes!r}: a number of modes >= 1 (None: all)")
    if fmax_hz is not None and not (isinstance(fmax_hz, (int, float)) and fmax_hz > 0
                                    and math.isfinite(fmax_hz)):
        raise ModelError("fmax_hz", f"= {fmax_hz!r}: a frequency > 0 Hz (None: all)")


def band_basis(M, K, n_modes=None, fmax_hz=None) -> np.ndarray | None:
    """The Ritz basis of a band (``n_modes`` lowest modes, or those below ``fmax_hz``): the
    lowest undamped, non-rotating modes of ``(K, M)`` (``M``-orthonormal columns), twice as
    many as asked for (:data:`BAND_BASIS`) and at least :data:`BAND_EXTRA` more, or those below
    twice ``fmax_hz``; None when that is every mode (the full solve then)."""
    n = M.shape[0]
    if n_modes is not None:
        m = max(BAND_BASIS * int(n_modes), int(n_modes) + BAND_EXTRA)
    else:
        w2 = sla.eigh(K, M, eigvals_only=True)  # (cheap beside the speed's solve)
        below = int(np.sum(w2 <= (2 * math.pi * fmax_hz) ** 2))
        top = int(np.sum(w2 <= (2 * math.pi * BAND_BASIS * fmax_hz) ** 2))
        m = max(top, below + BAND_EXTRA)
    if m >= n:
        return None
    return sla.eigh(K, M, subset_by_index=[0, m - 1])[1]


def band_solve(V, M, C, K, G=None, speed=0.0, Kc=None, Kv=None):
    """:func:`eigensolve` of the problem projected on the basis ``V`` (:func:`band_basis`):
    eigenvalues and shapes ``V y`` of its ``V.shape[1]`` lowest modes, ordered by
    ``|lambda|``. The projection is the band's approximation: its error against the full
    solve is measured in ``tests/test_modal.py`` and ``benchmarks/modal_size.py``."""
    def pr(X):
        return None if X is None else V.T @ X @ V

    lam, y = eigensolve(pr(M), pr(C), pr(K), pr(G), speed, pr(Kc), pr(Kv))
    return lam, V @ y


def modal(model, speed_rpm: float = 0.0, loads: dict | None = None, *, state=None,
          labels: dict | None = None, n_modes: int | None = None,
          fmax_hz: float | None = None, geometric_stiffness: bool = True) -> ModalResult:
    """Natural frequencies, damping ratios and mode shapes of ``model`` at ``speed_rpm``.

    Parameters
    ----------
    model : a :class:`gearmodal.Model`, a :class:`gearmodal.Coupled` system (modes of the
        constrained motion, shapes in the original coordinates) or an :class:`Assembly`.
    speed_rpm : input speed in rpm (gyroscopic and centripetal terms scale with it).
    loads : ``{load name: value}`` (N, N m). When given, the static equilibrium under these
        loads (and the centrifugal forces at ``speed_rpm``) is solved first and the modes are
        those of its contact state (see :func:`gearmodal.static.equilibrium`); it is kept in
        ``result.equilibrium``. The loads must be balanced (:func:`gearmodal.static.balance`).
    state : contact-state booleans (default: nominal state, or the loaded one).
    labels : ``{mode index: label}`` overriding the automatic mode types.
    n_modes, fmax_hz : a band: only the ``n_modes`` lowest modes, or those below ``fmax_hz``
        (both: the fewer), from the problem projected on twice as many undamped modes
        (:func:`band_solve`: an approximation, its error measured against the full solve:
        at most 2e-6 relative on the 600 kW drivetrain's lowest 5 to 15 modes at 22.1 rpm);
        default: every mode, solved in full.
    geometric_stiffness : include the stiffness of the steady rotation's internal forces (the
        planets' centrifugal preload on their bearings and meshes, :mod:`gearmodal.assembly`),
        which keeps a free drivetrain's rigid rotation neutral at every speed (default);
        ``False``: Lin & Parker's (1999) centripetal-only linearisation, as published (its
        rigid rotation has a real positive eigenvalue at speed).

    Examples
    --------
    >>> import math, gearmodal as gm
    >>> p = gm.Gear(20, 0.004, math.radians(20), mass=1.0, inertia=1e-3)
    >>> w = gm.Gear(40, 0.004, math.radians(20), mass=4.0, inertia=1.6e-2)
    >>> res = gm.modal(gm.gear_pair(p, w, mesh_stiffness=2e8, backlash=1e-4))
    >>> [round(float(f), 1) for f in res.frequencies_hz]
    [0.0, 2991.1]
    """
    speed_rpm = float(speed_rpm)
    if not math.isfinite(speed_rpm) or speed_rpm < 0:
        raise ModelError("speed_rpm", f"= {speed_rpm!r}: must be a finite number >= 0 rpm")
    plausible("speed_rpm", speed_rpm, "speed_rpm")
    # the model's assembly is reused while the model is unchanged (read-only, shared)
    asm, name = as_assembly(model, cached=True)
    asm.require_piecewise_linear("gm.modal")
    red, N = reduction(asm)  # a coupled system is solved in its constrained coordinates
    om = speed_rpm * RPM
    eq = None
    if loads:
        from .static import equilibrium

        eq = equilibrium(asm, loads, speed_rpm, state=state)
        state = eq.state
    s = asm.state(state)
    check_band(n_modes, fmax_hz)
    V = None
    if n_modes is not None or fmax_hz is not None:
        V = band_basis(red.M, red.stiffness(s), n_modes, fmax_hz)
    Kc = red.speed_stiffness(bool(geometric_stiffness))
    if V is None:
        lam, shapes = eigensolve(red.M, red.damping(s), red.stiffness(s), red.G, om, Kc,
                                 red.K_speed)
    else:
        lam, shapes = band_solve(V, red.M, red.damping(s), red.stiffness(s), red.G, om, Kc,
                                 red.K_speed)
    keep = np.ones(lam.size, dtype=bool)
    if fmax_hz is not None:
        keep &= np.abs(lam) <= 2 * math.pi * fmax_hz
    if n_modes is not None:
        keep &= np.arange(lam.size) < n_modes
    lam, shapes = lam[keep], shapes[:, keep]
    if N is not None:
        shapes = N @ shapes
    absl = np.abs(lam)
    freq = absl / (2 * math.pi)
    zeta = damping_ratios(lam)
    big = np.argmax(np.abs(shapes), axis=0)
    shapes = shapes / shapes[big, np.arange(shapes.shape[1])]
    ke, se = energies(asm, shapes, freq, s)
    from .modetypes import classify
    types = classify(asm, shapes, freq, K=asm.stiffness(s))
    for i, lab in (labels or {}).items():
        types[int(i)] = str(lab)
    zeta = rigid_undamped(zeta, types)
    return ModalResult(speed_rpm=speed_rpm, frequencies_hz=freq, damping_ratios=zeta,
                       shapes=shapes, dof_names=list(asm.dof_names), kinetic_energy=ke,
                       strain_energy=se, mode_types=types, model_name=name,
                       equilibrium=eq, contact_state=s, geometry=geometry_table(model))


def geometry_table(model) -> pd.DataFrame | None:
    """Where each body of a :class:`~gearmodal.Model` sits at azimuth 0 and which DOFs move
    it (:attr:`ModalResult.geometry`); None for anything else."""
    bodies = getattr(model, "bodies", None)
    frames = getattr(model, "frames", None)
    if not isinstance(bodies, dict) or not isinstance(frames, dict):
        return None
    rows = {}
    for b in bodies.values():
        c = centre(model, b, 0.0)
        names = dict(zip(b.local_indices, b.coordinates, strict=True))
        pre = f"{b.name}."
        radius = getattr(b, "pitch_radius", None)
        rows[b.name] = (float(c[0]), float(c[1]),
                        float(radius) if radius is not None else math.nan,
                        float(b.orientation), b.role,
                        pre + names[0] if 0 in names else "", pre + names[1] if 1 in names
                        else "", pre + names[5], float(b.rotation_scale or 1.0))
    return pd.DataFrame(list(rows.values()), index=pd.Index(list(rows), name="body"),
                        columns=["x", "y", "radius", "orientation", "role", "x_dof", "y_dof",
                                 "rot_dof", "rot_scale"])


def energies(asm: Assembly, shapes: np.ndarray, freq_hz: np.ndarray, state=None):
    """Modal kinetic energy share per body and strain energy share per spring element.

    Kinetic: ``phi_b^H M_bb phi_b`` per body (M is block-diagonal by body); strain:
    ``k |w . phi|^2`` per spring, summed per element (mesh flanks, bearing directions).
    """
    n_modes = shapes.shape[1]
    bodies = list(asm.body_slices)
    ke = np.zeros((n_modes, len(bodies)))
    for j, b in enumerate(bodies):
        sl = asm.body_slices[b]
        phi = shapes[sl]
        ke[:, j] = np.real((phi.conj() * (asm.M[sl, sl] @ phi)).sum(axis=0))
    tot = ke.sum(axis=1, keepdims=True)
    ke = np.divide(ke, tot, out=np.zeros_like(ke), where=tot > 0)
    c = asm.contacts
    s = asm.state(state)
    column = {name: j for j, name in enumerate(dict.fromkeys(c.element))}
    elems = list(column)
    se = np.zeros((n_modes, len(elems)))
    # row by row (a polygon clearance has hundreds, few of them active): each active row's
    # k |w . phi|^2 added to its element's column in row order
    for e in np.flatnonzero(s[:len(c.element)]).tolist():
        d = c.W[e] @ shapes
        se[:, column[c.element[e]]] += c.stiffness[e] * np.abs(d) ** 2
    # always-active springs of K (bearings without clearance, shafts): per body pair is not
    # recoverable from K alone, so they are reported together as "linear springs".
    # (a product, then the column sums: an einsum over i, j, m without a contraction path
    # is a triple loop, 39 ms against 3.4 ms at 204 DOF)
    lin = np.real((shapes.conj() * (asm.K @ shapes)).sum(axis=0))
    se = np.column_stack([se, lin]) if len(elems) else lin[:, None]
    cols = [*elems, "linear springs"]
    tot = se.sum(axis=1, keepdims=True)
    se = np.divide(se, tot, out=np.zeros_like(se), where=tot > 0)
    return (pd.DataFrame(ke, columns=bodies), pd.DataFrame(se, columns=cols))
