"""Planet load sharing as the standards define it: the mesh load factor K_gamma (issue 21).

``K_gamma = N max_i F_i / sum_i F_i``: the largest planet's mesh load over the mean, per stage
and per mesh kind (sun-planet, ring-planet), with ``F_i`` the planet's net flank force (front
minus back) averaged over the window considered (AGMA 6123, IEC 61400-4: the load of the most
loaded branch over the nominal one; ISO 6336's K_gamma). 1 is equal sharing.

:func:`static_load_sharing` gives it from the static equilibrium against input torque (at
given carrier azimuths); :meth:`gearmodal.SimulationResult.k_gamma` over a run or per window
(a carrier revolution) of a simulation; both tabulate through :func:`k_gamma_table`.

Published references for the trends (tests/validation/test_load_sharing.py): K_gamma falls
with torque towards 1 for a given error (Ligata, Kahraman and Singh 2008; the closed form of
a four-planet stage: ``K_gamma - 1`` proportional to ``error / deflection``, i.e. to 1/torque);
three planets with a floating sun share equally whatever the errors; ABS's tabulated design
values (as quoted by FVA-Workbench, attribute 6051): 1.0 up to 3 planets, 1.2 for 4, 1.3 for 5,
1.4 for 6 and more.
"""

from __future__ import annotations

import math
from collections.abc import Iterable

import numpy as np
import pandas as pd

from .errors import ModelError
from .static import balance, equilibrium

#: the mesh kinds K_gamma is given for
MESH_ROLES = ("sun_planet", "ring_planet")

#: ABS's design values of K_gamma by planet count (quoted by FVA-Workbench, attribute 6051)
ABS_K_GAMMA = {3: 1.0, 4: 1.2, 5: 1.3, 6: 1.4}


def k_gamma(loads: np.ndarray) -> float:
    """``N max(F) / sum(F)`` of one stage's planet loads ``F`` (N, one per planet); NaN when
    the planets carry no load in total."""
    f = np.asarray(loads, dtype=float)
    total = float(f.sum())
    if not total > 0.0:
        return math.nan
    return len(f) * float(f.max()) / total


def k_gamma_table(net: pd.DataFrame, meshes: dict[str, tuple[str, str, str]]) -> pd.DataFrame:
    """K_gamma per stage and mesh kind of the net flank forces ``net`` (one row per window
    or case, one column per mesh), with ``meshes[name] = (stage, role, planet)``. Returns one
    row per row of ``net`` and stage and mesh kind: the index of ``net`` (as columns), ``stage``,
    ``mesh`` (the role), ``n_planets``, ``k_gamma``, ``max_planet`` and ``mean_load_N``."""
    groups: dict[tuple[str, str], list[str]] = {}
    for name, (stage, role, _) in meshes.items():
        if role in MESH_ROLES and name in net.columns:
            groups.setdefault((stage, role), []).append(name)
    rows = []
    keys = list(net.index.names) if net.index.names != [None] else ["window"]
    for idx, r in net.iterrows():
        head = dict(zip(keys, idx if isinstance(idx, tuple) else (idx,), strict=True))
        for (stage, role), names in groups.items():
            f = r[names].to_numpy(dtype=float)
            kg = k_gamma(f)
            top = meshes[names[int(np.argmax(f))]][2] if np.isfinite(kg) else ""
            rows.append({**head, "stage": stage, "mesh": role, "n_planets": len(names),
                         "k_gamma": kg, "max_planet": top, "mean_load_N": float(f.mean())})
    return pd.DataFrame(rows)


def static_load_sharing(model, torques: Iterable[float], *, load: str = "carrier.torque",
                        balance_on: str = "sun.torque", loads: dict | None = None,
                        azimuths_deg: Iterable[float] = (0.0,)) -> pd.DataFrame:
    """K_gamma of every planetary stage of ``model`` from its static equilibrium, for each
    input torque in ``torques`` (N m on the load ``load``, balanced on ``balance_on``), with
    the other ``loads`` (e.g. ``{"gravity": 9.81}``) and at each carrier azimuth in
    ``azimuths_deg`` (the geometry turning against the ground: gravity, supports). Returns
    :func:`k_gamma_table`'s columns with ``torque_Nm`` and ``azimuth_deg`` first, and one
    column ``<mesh>`` per mesh with its net flank force (N)."""
    meshes = {name: (m.stage, m.role, _planet_name(m.planet, m.stage))
              for name, m in model.meshes.items()}
    if not any(role in MESH_ROLES for _, role, _ in meshes.values()):
        raise ModelError("model", f"{model.name!r} has no planetary stage (no sun-planet or "
                         "ring-planet meshes)")
    rows = []
    for torque in torques:
        base = {**(loads or {}), load: float(torque)}
        for az in azimuths_deg:
            asm = model.assemble(math.radians(float(az)))
            eq = equilibrium(asm, balance(model, base, on=balance_on))
            c = eq.contacts.set_index(["element", "contact"]).force_N
            net = {n: float(c.get((n, "front"), 0.0)) - float(c.get((n, "back"), 0.0))
                   for n in meshes}
            rows.append({"torque_Nm": float(torque), "azimuth_deg": float(az), **net})
    table = pd.DataFrame(rows).set_index(["torque_Nm", "azimuth_deg"])
    out = k_gamma_table(table, meshes)
    return out.merge(table.reset_index(), on=["torque_Nm", "azimuth_deg"])


def _planet_name(planet: str | None, stage: str) -> str:
    planet = planet or ""
    return planet[len(stage) + 1:] if stage and planet.startswith(stage + ".") else planet
