"""Mode type labels from the kinetic energy of each DOF group.

For planetary stages the Lin & Parker (1999) types: ``rotational`` (central members rotate
only, planets move alike), ``translational`` (central members translate only), ``planet``
(central members at rest). For drivetrains also ``housing`` (the housing on its suspension
carries most of the kinetic energy), ``torsional`` (rotational coordinates carry nearly all of
it) and ``mixed``; ``rigid`` for modes at (near) zero frequency.
"""

from __future__ import annotations

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
    num = np.real(np.einsum("im,ij,jm->m", shapes.conj(), K, shapes))
    den = np.real(np.einsum("im,ij,jm->m", shapes.conj(), asm.M, shapes))
    static_hz = np.sqrt(np.clip(num / den, 0, None)) / (2 * np.pi)
    names = asm.dof_names
    e = dof_energy(asm, shapes)
    rot = np.array([n.rsplit(".", 1)[1] in ("theta", "u") for n in names])
    body = [n.rsplit(".", 1)[0] for n in names]
    planet = np.array([b.rsplit(".", 1)[-1].startswith("planet") for b in body])
    stage_of = [b.rsplit(".", 1)[0] if "." in b else "" for b in body]
    central = np.zeros(len(names), dtype=bool)
    for i, b in enumerate(body):
        leaf = b.rsplit(".", 1)[-1]
        central[i] = leaf in ("carrier", "sun", "ring")
    housing = np.array([b == "housing" or b.endswith(".housing") for b in body])
    has_planets = planet.any()
    # the stages in sorted order (as a groupby would list them) and each DOF's stage index
    stages, stage_idx = np.unique(np.array(stage_of, dtype=object).astype(str),
                                  return_inverse=True)
    in_stages = [stage_idx == k for k in range(len(stages))]
    types = []
    for m in range(shapes.shape[1]):
        em = e[:, m]
        if static_hz[m] < rigid_rel * fmax:
            types.append("rigid")
            continue
        if housing.any() and em[housing].sum() > 0.5:
            types.append("housing")
            continue
        if has_planets:
            # Lin & Parker types, judged on the stage holding most of the energy
            # the stage with the most energy (the first of equals, in sorted order)
            in_stage = in_stages[int(np.argmax(np.bincount(stage_idx, weights=em,
                                                           minlength=len(stages))))]
            c, p = central & in_stage, planet & in_stage
            if (c | p).any() and em[c | p].sum() > 0.5:
                if em[c].sum() < QUIET:
                    types.append("planet")
                    continue
                if em[c & ~rot].sum() < QUIET * em[c].sum() + QUIET:
                    types.append("rotational")
                    continue
                if em[c & rot].sum() < QUIET * em[c].sum() + QUIET:
                    types.append("translational")
                    continue
                stage_e = em[c | p].sum()
                if em[c].sum() < LOOSE * stage_e:
                    types.append("planet")
                    continue
                if em[c & ~rot].sum() < LOOSE * em[c].sum():
                    types.append("rotational")
                    continue
                if em[c & rot].sum() < LOOSE * em[c].sum():
                    types.append("translational")
                    continue
        if em[rot].sum() > 0.9:
            types.append("torsional")
        else:
            types.append("mixed")
    return types
