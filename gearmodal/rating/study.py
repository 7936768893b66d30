"""Ratings of a fatigue study's output: its gearboxes' first stage under their lifetime load
spectra (ISO 6336-6, :func:`gearmodal.rating.rate_spectrum`).

A fatigue study (``gearmodal study fatigue --out DIR``) writes ``spectra.csv``: per variant
(the gearboxes) the lifetime load revolution distribution of the largest tooth force of the
first planetary stage's flanks (:func:`gearmodal.fatigue.drivetrain_fatigue`) and the hours
they stand for, and ``study.json`` (or its store's ``sweep.json``), which names the scene the
runs were made of (a path as given, else relative to the working folder or to the study).
Each variant's spectrum rates the first stage's mesh groups (every flank of the stage in it:
conservative for each); the variants differ in bearings only, so they are rated on the scene's
gears.
"""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd

from ..errors import ModelError
from .gearbox import rate_spectrum


def is_study(path) -> bool:
    """Whether ``path`` is a fatigue study's output folder."""
    p = Path(path)
    return p.is_dir() and (p / "spectra.csv").exists() and (
        (p / "study.json").exists() or (p / "store" / "sweep.json").exists())


def _scene(d: Path) -> Path:
    if (d / "study.json").exists():
        source, scene = d / "study.json", json.loads((d / "study.json").read_text()).get("scene")
    else:
        source = d / "store" / "sweep.json"
        scene = json.loads(source.read_text()).get("identity", {}).get("scene")
    for p in ((Path(scene), d / scene) if scene else ()):
        if p.exists():
            return p
    raise ModelError(str(source), f"names the scene {scene!r}, which is not there: the "
                     "study's model is needed to rate it")


def rate_study(directory) -> tuple[pd.DataFrame, dict]:
    """The first stage's gears rated under each variant's lifetime spectrum of the study in
    ``directory``: a table (``variant``, ``mesh``, ``gear``, ``member``, ``S_H_spectrum``,
    ``S_F_spectrum``, damages, cycles) and the settings (scene, hours per variant)."""
    from ..scene import load_scene

    d = Path(directory)
    if not is_study(d):
        raise ModelError(str(directory), "is not a fatigue study's output (spectra.csv and "
                         "study.json or store/sweep.json)")
    scene = _scene(d)
    model = load_scene(scene).model
    spec = pd.read_csv(d / "spectra.csv", comment="#")
    first = next(iter(model.meshes.values())).stage
    groups = sorted({f"{m.stage}.{m.role}" for m in model.meshes.values()
                     if m.stage == first and m.role})
    rows, hours = [], {}
    for variant, g in spec.groupby("variant", sort=False):
        teeth = g[g.quantity == "tooth_force_N"]
        hours[variant] = float(g[g.quantity == "rotor_torque_Nm"].hours.sum())
        if teeth.empty or not (teeth.revolutions > 0).any():
            continue
        r = rate_spectrum(model, teeth, meshes=groups, hours=hours[variant])
        rows.append(r.assign(variant=variant, flank="largest of the stage's"))
    if not rows:
        raise ModelError(f"{directory}/spectra.csv", "has no tooth-force spectrum to rate")
    table = pd.concat(rows, ignore_index=True)
    table = table[["variant", *[c for c in table.columns if c != "variant"]]]
    return table, {"study": str(d), "scene": str(scene), "hours": hours, "meshes": groups,
                   "standards": "ISO 6336-6 (Palmgren-Miner), ISO 6336-1/-2/-3 method B; "
                                "K_A = K_gamma = K_v = 1 (the runs' own dynamics)"}
