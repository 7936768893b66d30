"""The turbine's elastic bodies: a blade's and the tower's assumed modes (issue 56).

As in ElastoDyn, a blade or the tower bends in a few *assumed modes*: shapes along its span,
each with one coordinate. The shapes come from the deck's distributed properties:

* ``shapes="computed"`` (default): the modes ``pybmodes`` computes by finite elements, the
  blade cantilevered at its root and not turning (the centrifugal stiffening of the turning
  blade is added by the whole turbine's linearisation, so that it is counted once), the tower
  cantilevered at its base with the rotor-nacelle assembly lumped on its top (pybmodes'
  ``Tower.from_elastodyn``; the whole turbine then carries the nacelle, hub and blades as
  bodies of their own, so the lumping only shapes the basis). The modal stiffness is
  pybmodes' (``generalized_stiffness``, the finite-element stiffness of the mode); the mass
  is integrated here from the deck's mass per length, so that an isolated body reproduces
  pybmodes' frequency to the quadrature (0.2 % on the 5 MW blade; ``tests``).
* ``shapes="elastodyn"``: ElastoDyn's own shapes, the sixth-order polynomials of the deck
  (``BldFl1Sh``..., ``TwFAM1Sh``...), with the stiffness integrated from the deck's bending
  stiffness, ``K_ij = int EI phi_i'' phi_j'' dx`` (ElastoDyn's generalised stiffness), and the
  deck's stiffness tuners and adjustment factors. This is the basis FAST's published
  linearisation used; it is offered to compare with it, not as the better model (the 5 MW
  deck's tower polynomials are a poor fit of its own properties: pybmodes' validator).

Each mode is normalised to a unit tip displacement in its own direction (flapwise or
fore-aft: component 0; edgewise or side-to-side: component 1).
"""

from __future__ import annotations

import math
import re
import tempfile
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import ModelError
from .elastodyn import StructureDeck, read_blade_file, read_tower_file

SHAPES = ("computed", "elastodyn")
#: Gauss-Legendre points per interval between the shapes' nodes and the property stations:
#: exact for the mass integrals (cubic shapes squared times a linear mass: degree 7), a
#: quadrature for the polynomial shapes' stiffness (degree up to 9 with a linear stiffness)
_GAUSS = 4


@dataclass(frozen=True)
class BeamModes:
    """Assumed modes of one blade or the tower.

    Attributes
    ----------
    kind : ``"blade"`` or ``"tower"``. names : the modes (``flap1``, ``edge1``, ...;
    ``fa1``, ``ss1``, ...). x : quadrature points along the span from the root or base (m),
    weights : their weights (m). mass : mass per length at ``x`` (kg/m).
    disp, slope : (n_modes, 2, n_x): each mode's displacement (flapwise or fore-aft,
    edgewise or side-to-side) and its slope along the span, unit tip displacement.
    stiffness : (n_modes, n_modes) modal stiffness (N/m for a unit tip displacement).
    damping_ratio : (n_modes,) the deck's structural damping of each mode (fraction).
    isolated_hz : (n_modes,) the isolated body's frequencies from pybmodes (``computed``) or
    from the polynomial basis (``elastodyn``). source : ``"computed"`` or ``"elastodyn"``.
    """

    kind: str
    names: tuple[str, ...]
    x: np.ndarray
    weights: np.ndarray
    mass: np.ndarray
    disp: np.ndarray
    slope: np.ndarray
    stiffness: np.ndarray
    damping_ratio: np.ndarray
    isolated_hz: np.ndarray
    source: str

    @property
    def n(self) -> int:
        return len(self.names)

    def mass_matrix(self) -> np.ndarray:
        """``int m phi_i . phi_j dx`` (kg), the body's own modal mass."""
        wm = self.weights * self.mass
        return np.einsum("icx,jcx,x->ij", self.disp, self.disp, wm)

    def slope_matrix(self, tension: np.ndarray) -> np.ndarray:
        """``int N phi_i' . phi_j' dx`` for an axial tension ``N(x)`` (N) at the quadrature
        points: the geometric stiffness of that tension (negative tension: compression)."""
        return np.einsum("icx,jcx,x->ij", self.slope, self.slope, self.weights * tension)

    def tip(self) -> np.ndarray:
        """(n_modes, 2) displacement at the tip (the last quadrature point is the tip)."""
        return self.disp[:, :, -1]

    def tip_slope(self) -> np.ndarray:
        """(n_modes, 2) slope at the tip."""
        return self.slope[:, :, -1]

    def damping_matrix(self) -> np.ndarray:
        """Modal damping ``2 zeta_i sqrt(k_ii m_ii)`` on the diagonal (N s/m), ElastoDyn's
        structural damping of each isolated mode."""
        k = np.diag(self.stiffness)
        m = np.diag(self.mass_matrix())
        return np.diag(2.0 * self.damping_ratio * np.sqrt(np.clip(k * m, 0, None)))


def _grid(breaks: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Gauss points and weights on every interval of ``breaks``, plus both ends (weight 0) so
    that the first and last points are the root and the tip."""
    g, w = np.polynomial.legendre.leggauss(_GAUSS)
    a, b = breaks[:-1, None], breaks[1:, None]
    x = ((b - a) / 2 * g + (a + b) / 2).ravel()
    wx = ((b - a) / 2 * w).ravel()
    return (np.concatenate([[breaks[0]], x, [breaks[-1]]]),
            np.concatenate([[0.0], wx, [0.0]]))


def _damping(deck: list[float], n: int) -> list[float]:
    """The deck's damping ratios of a family's first ``n`` modes; modes beyond those the deck
    gives (it has two flapwise, one edgewise, two per tower direction) take its last one."""
    if n == 0:
        return []
    if not deck:
        return [0.0] * n
    return (deck + [deck[-1]] * n)[:n]


def tail_integral(modes: BeamModes, values: np.ndarray) -> np.ndarray:
    """``int_x^L g ds`` at every quadrature point ``x`` of ``modes`` for ``g`` given there as
    ``values``, exact when ``g`` is a polynomial of degree <= 3 on each interval of the grid
    (the mass per length times a linear function: the centrifugal tension, the weight above a
    section): on each interval the cubic through its four Gauss points, integrated (Lagrange
    weights on the reference interval)."""
    g = np.asarray(values, dtype=float)
    vals = g[1:-1].reshape(-1, _GAUSS)
    half = 0.5 * modes.weights[1:-1].reshape(-1, _GAUSS).sum(axis=1)  # (b - a) / 2
    nodes, weights = np.polynomial.legendre.leggauss(_GAUSS)
    coef = np.linalg.inv(np.vander(nodes, _GAUSS, increasing=True))  # Lagrange basis
    k = np.arange(1, _GAUSS + 1)
    # W[i, j] = int_{xi_i}^{1} l_j(xi) d xi
    W = ((1.0 - nodes[:, None] ** k[None, :]) / k[None, :]) @ coef
    full = half * (vals @ weights)
    after = np.concatenate([np.cumsum(full[::-1])[::-1][1:], [0.0]])  # the intervals beyond
    out = np.empty_like(g)
    out[1:-1] = ((vals @ W.T) * half[:, None] + after[:, None]).ravel()
    out[0], out[-1] = float(full.sum()), 0.0
    return out


def _counts(what: str, first: tuple[str, int], second: tuple[str, int],
            shapes: str) -> tuple[int, int]:
    """The two mode counts, each an integer from 0 to 6 and not both 0, and ``shapes``."""
    out = []
    for name, n in (first, second):
        if not isinstance(n, (int, np.integer)) or isinstance(n, bool) or not 0 <= n <= 6:
            raise ModelError(f"{what}.{name}", f"= {n!r}: must be an integer from 0 to 6")
        out.append(int(n))
    if sum(out) == 0:
        raise ModelError(what, f"at least one {first[0]} or {second[0]} mode")
    if shapes not in SHAPES:
        raise ModelError("shapes", f"= {shapes!r}: one of {', '.join(SHAPES)}")
    return out[0], out[1]


def _pybmodes_models():
    try:
        from pybmodes.models import RotatingBlade, Tower
    except ImportError:
        raise ModelError("deck", "the elastic turbine's bodies need pybmodes: pip install "
                         "-e '.[elastic]'") from None
    return RotatingBlade, Tower


def _parked_copy(deck: StructureDeck, folder: Path) -> Path:
    """A copy of the main file with ``RotSpeed = 0`` and absolute paths to the blade and tower
    files: pybmodes stiffens the blade at the main file's speed, and the whole turbine adds the
    stiffening itself (counted once)."""
    text = deck.path.read_text(errors="replace").splitlines()
    out = []
    for line in text:
        tok = line.split()
        if len(tok) >= 2 and tok[1] == "RotSpeed":
            line = re.sub(r"^\s*\S+", "0.0", line, count=1)
        elif len(tok) >= 2 and re.fullmatch(r"BldFile\(?\d\)?", tok[1]):
            line = re.sub(r"^\s*\S+", f'"{deck.blade_file.resolve()}"', line, count=1)
        elif len(tok) >= 2 and tok[1] == "TwrFile":
            line = re.sub(r"^\s*\S+", f'"{deck.tower_file.resolve()}"', line, count=1)
        out.append(line)
    p = folder / deck.path.name
    p.write_text("\n".join(out) + "\n")
    return p


def _select(result, n_first: int, n_second: int, what: str):
    """The first ``n_first`` modes dominated by the first direction (flap or fore-aft) and
    ``n_second`` by the second (edge or side-to-side), each by its larger displacement."""
    first, second = [], []
    for i, s in enumerate(result.shapes):
        a = float(np.max(np.abs(s.flap_disp)))
        b = float(np.max(np.abs(s.lag_disp)))
        if a >= b and len(first) < n_first:
            first.append(i)
        elif b > a and len(second) < n_second:
            second.append(i)
    if len(first) < n_first or len(second) < n_second:
        raise ModelError(what, f"pybmodes gave {len(first)} and {len(second)} modes of the two "
                         f"directions among its {len(result.shapes)}: ask for fewer")
    return first, second


def _hermite(result, idx: list[int], comp: int, span: float, slope_scale: float,
             x: np.ndarray, what: str):
    """Displacement and slope of pybmodes' modes ``idx`` at ``x`` (m), both directions, unit
    tip displacement in direction ``comp`` (a cubic Hermite interpolant of the nodal values)."""
    from scipy.interpolate import CubicHermiteSpline

    disp = np.zeros((len(idx), 2, x.size))
    slope = np.zeros_like(disp)
    for k, i in enumerate(idx):
        s = result.shapes[i]
        z = np.asarray(s.span_loc, dtype=float) * span
        d = np.stack([np.asarray(s.flap_disp, float), np.asarray(s.lag_disp, float)])
        sl = np.stack([np.asarray(s.flap_slope, float), np.asarray(s.lag_slope, float)])
        sl = sl / slope_scale
        tip = d[comp, -1]
        if not math.isfinite(tip) or abs(tip) < 1e-12 * max(np.max(np.abs(d)), 1e-300):
            raise ModelError(what, f"mode {i + 1} from pybmodes has no tip displacement")
        # pybmodes' slopes are per its beam's radius; check the convention on the shape
        fd = np.gradient(d[comp], z)
        inner = slice(1, -1)
        scale = np.max(np.abs(fd[inner]))
        if scale > 0 and np.max(np.abs(fd[inner] - sl[comp][inner])) > 0.2 * scale:
            raise ModelError(what, "pybmodes' mode slopes do not match its displacements "
                             "(its slope convention changed?): pin pybmodes>=1.19,<2")
        for c in range(2):
            sp = CubicHermiteSpline(z, d[c] / tip, sl[c] / tip)
            disp[k, c] = sp(x)
            slope[k, c] = sp.derivative()(x)
    return disp, slope


def _quiet_run(model, n_modes: int, **kw):
    with warnings.catch_warnings():  # pybmodes' notes on the deck's stiffness jumps
        warnings.simplefilter("ignore", UserWarning)
        return model.run(n_modes=n_modes, check_model=False, **kw)


def blade_modes(deck: StructureDeck, flap: int = 2, edge: int = 1,
                shapes: str = "computed") -> BeamModes:
    """The blade's assumed modes: ``flap`` flapwise and ``edge`` edgewise (ElastoDyn's are two
    and one), from the deck's blade file (module docstring for ``shapes``)."""
    flap, edge = _counts("blade_modes", ("flap", flap), ("edge", edge), shapes)
    bf = read_blade_file(deck)
    L = deck.blade_length
    frac = np.asarray(bf.bl_fract, dtype=float)
    mass_tab = np.asarray(bf.b_mass_den, dtype=float) * float(bf.adj_bl_ms)
    zeta = _damping([float(v) / 100 for v in bf.bld_fl_dmp], flap) + \
        _damping([float(v) / 100 for v in bf.bld_ed_dmp], edge)
    if shapes == "elastodyn":
        if flap > 2 or edge > 1:
            raise ModelError("blade_modes", "the deck's polynomials give two flapwise and one "
                             "edgewise mode; use shapes='computed' for more")
        x, w = _grid(frac * L)
        polys = [bf.bld_fl1_sh, bf.bld_fl2_sh][:flap] + [bf.bld_edg_sh][:edge]
        ei = [np.asarray(bf.flp_stff, float) * float(bf.adj_fl_st)] * flap + \
             [np.asarray(bf.edg_stff, float) * float(bf.adj_ed_st)] * edge
        comps = [0] * flap + [1] * edge
        tuners = [float(v) for v in bf.fl_st_tunr][:flap] + [1.0] * edge
        names = tuple([f"flap{i + 1}" for i in range(flap)] + [f"edge{i + 1}"
                                                               for i in range(edge)])
        return _polynomial_modes("blade", names, x, w, frac * L, L, mass_tab, polys, ei,
                                 comps, tuners, np.array(zeta))
    RotatingBlade, _ = _pybmodes_models()
    with tempfile.TemporaryDirectory(prefix="gearmodal-") as tmp:
        main = _parked_copy(deck, Path(tmp))
        model = RotatingBlade.from_elastodyn(main)
    res = _quiet_run(model, 3 * (flap + edge) + 4)
    names = tuple([f"flap{i + 1}" for i in range(flap)] + [f"edge{i + 1}"
                                                           for i in range(edge)])
    return _from_pybmodes("blade", names, res, (flap, edge), L, deck.tip_radius, frac * L,
                          mass_tab, zeta)


def tower_modes(deck: StructureDeck, fore_aft: int = 2, side_to_side: int = 2,
                shapes: str = "computed") -> BeamModes:
    """The tower's assumed modes: ``fore_aft`` and ``side_to_side`` (ElastoDyn's are two
    each), from the deck's tower file (module docstring for ``shapes``)."""
    fore_aft, side_to_side = _counts("tower_modes", ("fore_aft", fore_aft),
                                     ("side_to_side", side_to_side), shapes)
    tf = read_tower_file(deck)
    H = deck.tower_length
    frac = np.asarray(tf.ht_fract, dtype=float)
    mass_tab = np.asarray(tf.t_mass_den, dtype=float) * float(tf.adj_tw_ma)
    zeta = _damping([float(v) / 100 for v in tf.twr_fa_dmp], fore_aft) + \
        _damping([float(v) / 100 for v in tf.twr_ss_dmp], side_to_side)
    names = tuple([f"fa{i + 1}" for i in range(fore_aft)] + [f"ss{i + 1}"
                                                             for i in range(side_to_side)])
    if shapes == "elastodyn":
        if fore_aft > 2 or side_to_side > 2:
            raise ModelError("tower_modes", "the deck's polynomials give two modes each way; "
                             "use shapes='computed' for more")
        x, w = _grid(frac * H)
        polys = [tf.tw_fa_m1_sh, tf.tw_fa_m2_sh][:fore_aft] + \
                [tf.tw_ss_m1_sh, tf.tw_ss_m2_sh][:side_to_side]
        ei = [np.asarray(tf.tw_fa_stif, float) * float(tf.adj_fa_st)] * fore_aft + \
             [np.asarray(tf.tw_ss_stif, float) * float(tf.adj_ss_st)] * side_to_side
        tuners = [float(v) for v in tf.fa_st_tunr][:fore_aft] + \
                 [float(v) for v in tf.ss_st_tunr][:side_to_side]
        comps = [0] * fore_aft + [1] * side_to_side
        return _polynomial_modes("tower", names, x, w, frac * H, H, mass_tab, polys, ei,
                                 comps, tuners, np.array(zeta))
    _, Tower = _pybmodes_models()
    model = Tower.from_elastodyn(deck.path)
    res = _quiet_run(model, max(8, 2 * (fore_aft + side_to_side) + 4))
    return _from_pybmodes("tower", names, res, (fore_aft, side_to_side), H, H, frac * H,
                          mass_tab, zeta)


def _from_pybmodes(kind, names, res, counts, span, slope_scale, stations, mass_tab,
                   zeta) -> BeamModes:
    """pybmodes' modes of both directions (``counts``) on the quadrature of their nodes and
    the property stations: shapes, pybmodes' modal stiffness, the deck's mass per length."""
    what = f"{kind}_modes"
    first, second = _select(res, *counts, what)
    nodes = np.asarray(res.shapes[0].span_loc, dtype=float) * span
    x, w = _grid(np.unique(np.concatenate([nodes, stations])))
    d1, s1 = _hermite(res, first, 0, span, slope_scale, x, what)
    d2, s2 = _hermite(res, second, 1, span, slope_scale, x, what)
    idx = first + second
    k = np.asarray(res.generalized_stiffness, dtype=float)[idx]
    return BeamModes(kind, names, x, w, np.interp(x, stations, mass_tab),
                     np.concatenate([d1, d2]), np.concatenate([s1, s2]), np.diag(k),
                     np.array(zeta), np.asarray(res.frequencies, dtype=float)[idx], "computed")


def _polynomial_modes(kind, names, x, w, stations, length, mass_tab, polys, ei, comps, tuners,
                      zeta) -> BeamModes:
    """ElastoDyn's polynomial shapes ``sum_k c_k (x/L)^k`` (k = 2..6) and their stiffness
    ``int EI phi_i'' phi_j'' dx`` (same direction only, times the stiffness tuners)."""
    n = len(polys)
    u = x / length
    disp = np.zeros((n, 2, x.size))
    slope = np.zeros_like(disp)
    curv = np.zeros((n, x.size))
    for i, (c, comp) in enumerate(zip(polys, comps, strict=True)):
        c = np.asarray(c, dtype=float)
        if c.size != 5 or not np.all(np.isfinite(c)):
            raise ModelError(f"{kind}_modes", f"mode {names[i]}: the deck's polynomial needs "
                             "five finite coefficients (x^2 .. x^6)")
        k = np.arange(2, 7)
        disp[i, comp] = (c[None, :] * u[:, None] ** k).sum(axis=1)
        slope[i, comp] = (c * k * u[:, None] ** (k - 1)).sum(axis=1) / length
        curv[i] = (c * k * (k - 1) * u[:, None] ** (k - 2)).sum(axis=1) / length ** 2
    K = np.zeros((n, n))
    for i in range(n):
        for j in range(n):
            if comps[i] == comps[j]:
                e = np.interp(x, stations, ei[i])
                K[i, j] = np.sum(w * e * curv[i] * curv[j])
    K = K * np.sqrt(np.outer(tuners, tuners))
    mass = np.interp(x, stations, mass_tab)
    modes = BeamModes(kind, tuple(names), x, w, mass, disp, slope, K, zeta, np.zeros(n),
                      "elastodyn")
    from scipy.linalg import eigh

    lam = eigh(K, modes.mass_matrix(), eigvals_only=True)
    hz = np.sqrt(np.clip(lam, 0, None)) / (2 * math.pi)
    return BeamModes(kind, tuple(names), x, w, mass, disp, slope, K, zeta, hz, "elastodyn")
