"""Mode type labels from the kinetic energy of each DOF group.

For planetary stages the Lin & Parker (1999) types: ``rotational`` (central members rotate
only, planets move alike), ``translational`` (central members translate only), ``planet``
(central members at rest). For drivetrains also ``housing`` (the housing on its suspension
carries most of the kinetic energy), ``torsional`` (rotational coordinates carry nearly all of
it) and ``mixed``; ``rigid`` for modes at (near) zero frequency.

For an elastic turbine (:mod:`gearmodal.turbine.structure`) the families OpenFAST's Campbell
diagrams use: ``tower FA<i>`` and ``tower SS<i>`` (fore-aft, side-to-side), ``drivetrain``
(the shaft's torsion holds a quarter of the energy or more, or a coupled gearbox's torsion
moves the rotor with a tenth of it) and the blade modes in multi-blade
coordinates (Coleman): ``flap<i> collective``, ``flap<i> pitch`` (the cosine component: the
rotor plane tilts about the horizontal), ``flap<i> yaw`` (the sine component), at speed
``flap<i> FW`` and ``flap<i> BW`` (the asymmetric pattern whirling forward or backward), and the
same for ``edge<i>``.
"""

from __future__ import annotations

import re
from functools import lru_cache
from typing import NamedTuple

import numpy as np

#: share of kinetic energy below which a DOF group counts as at rest (exact structure)
QUIET = 1e-6
#: share below which a group counts as at rest in a coupled drivetrain (approximate structure)
LOOSE = 0.1


def dof_energy(asm, shapes: np.ndarray) -> np.ndarray:
    """Kinetic energy share of every DOF in every mode, (n_dofs, n_modes), columns sum to 1."""
    e = np.real(shapes.conj() * (asm.M @ shapes))
    tot = e.sum(axis=0, keepdims=True)
    return np.divide(e, tot, out=np.zeros_like(e), where=tot > 0)


#: an elastic turbine's coordinates (the last part of a coupled name)
_TOWER = re.compile(r"tower_(fa|ss)(\d+)$")
_BLADE = re.compile(r"blade(\d+)_((?:flap|edge)\d+)$")
#: multi-blade coordinates: the families they read as
_MBC = re.compile(r"((?:flap|edge)\d+)_(collective|cos|sin)$")
_SHAFT = ("shaft_twist", "generator_azimuth", "rotor_azimuth")
_YAW = "nacelle_yaw"


@lru_cache(maxsize=32)
def turbine_groups(names: tuple):
    """``(turbine DOF indices, {tower label: indices}, shaft indices, {blade mode: (blade
    numbers, indices)}, {blade mode: {collective/cos/sin: index}})`` or None when ``names``
    has no elastic turbine."""
    tower: dict[str, list[int]] = {}
    blades: dict[str, tuple[list[int], list[int]]] = {}
    mbc: dict[str, dict[str, int]] = {}
    shaft: list[int] = []
    for i, n in enumerate(names):
        last = n.rsplit(".", 1)[-1]
        if (m := _TOWER.match(last)) is not None:
            tower.setdefault(f"tower {m.group(1).upper()}{m.group(2)}", []).append(i)
        elif last == _YAW:
            tower.setdefault("nacelle yaw", []).append(i)
        elif (m := _MBC.match(last)) is not None:
            mbc.setdefault(m.group(1), {})[m.group(2)] = i
        elif (m := _BLADE.match(last)) is not None:
            nums, idx = blades.setdefault(m.group(2), ([], []))
            nums.append(int(m.group(1)))
            idx.append(i)
        elif last in _SHAFT or n.endswith(".rotor.theta"):  # a coupled gearbox's rotor too
            shaft.append(i)
    if not blades and not tower and not mbc:
        return None
    every = sorted([i for v in tower.values() for i in v] + shaft
                   + [i for _, v in blades.values() for i in v]
                   + [i for v in mbc.values() for i in v.values()])
    return np.array(every), tower, np.array(shaft, dtype=int), blades, mbc


#: ``|2 Im(conj(q_cos) q_sin)| / (|q_cos|^2 + |q_sin|^2)`` above which an asymmetric blade
#: mode whirls (1: circular whirl; 0: a standing pitch or yaw pattern)
WHIRL = 0.5


def turbine_family(groups, shape: np.ndarray, share: np.ndarray) -> str:
    """The family of one mode of an elastic turbine (module docstring) from its ``shape``
    and its DOFs' kinetic-energy ``share``: the group holding the most energy (a tower mode,
    a blade mode). A blade mode in multi-blade coordinates is ``collective``, or asymmetric:
    whirling forward (``FW``: the pattern turns with the rotor, ``Im(conj(q_cos) q_sin) <
    0``) or backward (``BW``), else standing, ``pitch`` (cosine) or ``yaw`` (sine). In blade
    coordinates, blade ``k`` of ``n`` sits at azimuth ``2 pi (k - 1) / n`` (the assembly's
    azimuth 0) and its Coleman components decide."""
    _, tower, shaft, blades, mbc = groups
    if shaft.size and share[shaft].sum() >= 0.25:
        return "drivetrain"
    parts = {lab: share[idx].sum() for lab, idx in tower.items()}
    parts.update({mode: share[idx].sum() for mode, (_, idx) in blades.items()})
    parts.update({mode: share[list(ix.values())].sum() for mode, ix in mbc.items()})
    best = max(parts, key=parts.get)
    if best in tower:
        return best
    if best in mbc:
        ix = mbc[best]
        a0, a1, b1 = (shape[ix[c]] if c in ix else 0.0 for c in ("collective", "cos", "sin"))
        nb = 3
    else:
        nums, idx = blades[best]
        nb = max(nums)
        psi = 2 * np.pi * (np.array(nums) - 1) / nb
        q = shape[idx]
        a0 = q.mean()
        a1 = 2 / nb * (q * np.cos(psi)).sum()
        b1 = 2 / nb * (q * np.sin(psi)).sum()
        rest = max(float(np.sum(np.abs(q) ** 2)) - nb * abs(a0) ** 2
                   - nb / 2 * (abs(a1) ** 2 + abs(b1) ** 2), 0.0)
        if nb > 3 and rest > max(nb * abs(a0) ** 2, nb / 2 * (abs(a1) ** 2 + abs(b1) ** 2)):
            return f"{best} differential"
    asym = abs(a1) ** 2 + abs(b1) ** 2
    if 2 * abs(a0) ** 2 >= asym:  # the energies nb |a0|^2 against nb / 2 (|a1|^2 + |b1|^2)
        return f"{best} collective"
    whirl = 2 * float(np.imag(np.conj(a1) * b1)) / asym
    if abs(whirl) > WHIRL:
        return f"{best} {'FW' if whirl < 0 else 'BW'}"
    return f"{best} {'pitch' if abs(a1) >= abs(b1) else 'yaw'}"


class _Groups(NamedTuple):
    """The DOF groups :func:`classify` sums the kinetic energy over, from the DOF names."""

    rot: np.ndarray  # indices of the rotational coordinates (theta, u)
    housing: np.ndarray  # indices of the housing's coordinates
    has_housing: bool
    has_planets: bool
    stage_idx: np.ndarray  # each DOF's stage, as an index into the sorted stage names
    n_stages: int
    #: per stage: whether it has central members or planets, and the DOF indices of those,
    #: of its central members, of their translations and of their rotations
    stage_masks: list


@lru_cache(maxsize=64)
def _groups(names: tuple) -> _Groups:
    rot = np.array([n.rsplit(".", 1)[1] in ("theta", "u") for n in names], dtype=bool)
    body = [n.rsplit(".", 1)[0] for n in names]
    planet = np.array([b.rsplit(".", 1)[-1].startswith("planet") for b in body], dtype=bool)
    stage_of = [b.rsplit(".", 1)[0] if "." in b else "" for b in body]
    central = np.array([b.rsplit(".", 1)[-1] in ("carrier", "sun", "ring") for b in body],
                       dtype=bool)
    housing = np.array([b == "housing" or b.endswith(".housing") for b in body], dtype=bool)
    # the stages in sorted order (as a groupby would list them) and each DOF's stage index
    stages, stage_idx = np.unique(np.array(stage_of, dtype=object).astype(str),
                                  return_inverse=True)
    stage_idx = stage_idx.reshape(-1)
    masks = []
    for k in range(len(stages)):
        in_stage = stage_idx == k
        c, p = central & in_stage, planet & in_stage
        masks.append((bool((c | p).any()), *(np.flatnonzero(x) for x in
                                             (c | p, c, c & ~rot, c & rot))))
    rot, housing = np.flatnonzero(rot), np.flatnonzero(housing)
    for a in (rot, housing, stage_idx, *(x for st in masks for x in st[1:])):
        a.flags.writeable = False  # shared between calls
    return _Groups(rot, housing, bool(len(housing)), bool(planet.any()), stage_idx,
                   len(stages), masks)


def classify(asm, shapes: np.ndarray, freq_hz: np.ndarray, rigid_rel: float = 1e-6,
             K: np.ndarray | None = None) -> list[str]:
    """Label each mode (column of ``shapes``) by where its kinetic energy sits.

    Rules, in order: ``rigid`` when the shape is (numerically) in the null space of the static
    stiffness ``K`` (default: nominal contact state, no speed terms): its stiffness Rayleigh
    quotient, as a frequency, is below ``rigid_rel`` times the highest frequency (the
    eigen-solver resolves a zero frequency only to about sqrt(eps) of the spectrum's width; a
    rigid rotation stays rigid when Lin & Parker's centripetal term lifts it off zero).
    ``housing`` when the housing holds over half the kinetic energy. For a planetary stage
    holding over half of it: Lin & Parker's exact tests (central members at rest: ``planet``;
    central members not translating: ``rotational``; not rotating: ``translational``), then
    the same tests with a loose tolerance (``LOOSE`` of the stage's energy) for coupled
    drivetrains. Else ``torsional`` when rotational coordinates hold over 90 %, else ``mixed``.
    """
    fmax = float(np.max(freq_hz)) if len(freq_hz) else 0.0
    if K is None:
        K = asm.stiffness()
    num = np.real((shapes.conj() * (K @ shapes)).sum(axis=0))
    den = np.real((shapes.conj() * (asm.M @ shapes)).sum(axis=0))
    static_hz = np.sqrt(np.clip(num / den, 0, None)) / (2 * np.pi)
    g = _groups(tuple(asm.dof_names))
    e = dof_energy(asm, shapes)
    # row m of E is mode m's DOF shares; each group's share is the 1-D sum over its DOFs of
    # that row, as before (the same numbers added in the same order: the same labels)
    E = np.ascontiguousarray(e.T)
    rigid = (static_hz < rigid_rel * fmax).tolist()
    if g.has_planets:
        # the stage with the most energy (the first of equals, in sorted order): per stage
        # the sum down its DOF rows, in DOF order, as np.bincount(stage_idx, weights=e[:, m])
        best = np.argmax(np.stack([e[g.stage_idx == k].sum(axis=0)
                                   for k in range(g.n_stages)]), axis=0).tolist()
    turbine = turbine_groups(tuple(asm.dof_names))
    types = []
    for m in range(shapes.shape[1]):
        if rigid[m]:
            types.append("rigid")
            continue
        em = E[m]
        if turbine is not None and em[turbine[0]].sum() > 0.5:
            types.append(turbine_family(turbine, shapes[:, m], em))
            continue
        if g.has_housing and em[g.housing].sum() > 0.5:
            types.append("housing")
            continue
        if g.has_planets:
            # Lin & Parker types, judged on the stage holding most of the energy
            any_cp, cp, c, c_tr, c_rot = g.stage_masks[best[m]]
            if any_cp and em[cp].sum() > 0.5:
                e_c = em[c].sum()
                e_tr = em[c_tr].sum()
                if e_c < QUIET:
                    types.append("planet")
                    continue
                if e_tr < QUIET * e_c + QUIET:
                    types.append("rotational")
                    continue
                e_rot = em[c_rot].sum()
                if e_rot < QUIET * e_c + QUIET:
                    types.append("translational")
                    continue
                if e_c < LOOSE * em[cp].sum():
                    types.append("planet")
                    continue
                if e_tr < LOOSE * e_c:
                    types.append("rotational")
                    continue
                if e_rot < LOOSE * e_c:
                    types.append("translational")
                    continue
        if em[g.rot].sum() > 0.9:
            # the gearbox's torsion moving the turbine's rotor (a tenth of the energy or more):
            # the turbine's drivetrain torsion
            near = turbine is not None and em[turbine[0]].sum() >= 0.1
            types.append("drivetrain" if near else "torsional")
        else:
            types.append("mixed")
    return types
