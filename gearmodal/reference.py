"""The file-format reference page, ``docs/file-format.md``, generated from the schema.

Regenerate after changing a schema (a test fails while the page is not current)::

    python -m gearmodal.reference            # writes docs/file-format.md
    python -m gearmodal.reference --check    # exit 1 if it is not current
"""

from __future__ import annotations

import sys
from pathlib import Path

from . import scene
from .model import file_schema as fs
from .model import rating_data
from .model.bearing import Bearing
from .model.components import Body, Frame, Gear, RigidBody
from .model.dump import GROUPS_TABLE, MODEL_TABLE
from .model.mesh import Mesh
from .model.schema import Table, reference_markdown
from .turbine.turbine import TURBINE_FILE
from .turbine.wind import Wind

#: the page, relative to the repository root
PAGE = Path("docs") / "file-format.md"

_BUILDER_TEXT = """\
Model files are TOML. `[model] type` picks the builder (`gm.drivetrain`, `gm.gear_pair`,
`gm.planetary_stage`, `gm.parallel_stage`, `gm.lin_parker_stage`) and the other tables hold its
arguments: a single-builder type puts them in one table named after the type
(`[gear_pair]`...), a drivetrain has `[rotor]`, `[main_shaft]`, optional `[shaft_bending]` (a
support of the first stage's input), `[[stages]]` (input first, each a planetary or parallel
stage table with `type`), optional `[generator]` with `[hss_shaft]` and `[housing]` with
`[suspension]` (a support). Units are SI; angles are given in degrees in keys ending in `_deg`.
Every error names the full dotted path of the key (`stages[0].ring.teeth`) and the file.
`studies/models/600kw.toml` is a documented full-size example."""

_COMPONENT_TEXT = """\
`type = "components"` lists the model's frames, bodies and elements one by one, as
`gm.dumps(model)` writes them: any model (built by a builder, loaded, or assembled by hand)
round-trips through it to exactly the same matrices. Angles are radians under their plain key
(exact), or degrees under `<key>_deg`. Bodies are assembled in file order (the DOF order)."""


_SCENE_TEXT = """\
A scene file (`gearmodal simulate SCENE`, `gearmodal.scene.load_scene`) names a model file and
the run: `[scene]`, `[loads]` (by load name: a number in N or N m, a wave table, or
`"balance"`), `[q0]` and `[v0]` (initial displacements and velocities by DOF name), `[options]`
(options of the method, refused by name if it has no such option), `[load_file]`, or a turbine
run: `[turbine]` with `[wind]` (then no `[loads]`, `[q0]`, `[v0]`, `scene.speed_rpm`).
`scene.dumps()` writes a scene back."""

_TURBINE_TEXT = """\
A turbine file (`gearmodal.turbine.load_turbine`) describes the rotor side of a turbine run;
`studies/turbines/600kw_turbine.toml` is the paper's 600 kW turbine. `[airfoil]` is optional."""


def sections() -> list[tuple[str, str, list[Table]]]:
    """The page's sections: (title, text, tables)."""
    groups = Table("groups", (GROUPS_TABLE,), "Named lists of bodies (`[groups]`).")
    return [
        ("Model files: the builder types", _BUILDER_TEXT,
         [fs.MODEL, fs.GEAR, fs.BODY, fs.CARRIER, fs.SHAFT, fs.SUPPORT, fs.PLANETARY,
          fs.PARALLEL, fs.PER_MESH, fs.GEAR_PAIR, fs.LIN_PARKER, fs.PER_MESH_ANGLE,
          fs.LIN_PARKER_BODIES, fs.LIN_PARKER_CENTRAL, rating_data.RATING,
          rating_data.GEAR_RATING, rating_data.BEARING_RATING]),
        ('Model files, component by component (type = "components")', _COMPONENT_TEXT,
         [MODEL_TABLE, Frame.SCHEMA, Gear.SCHEMA, RigidBody.SCHEMA, Body.SCHEMA, Mesh.SCHEMA,
          Bearing.SCHEMA, groups]),
        ("Scene files", _SCENE_TEXT,
         [scene.SCENE, scene.WAVE, scene.LOAD_FILE, scene.TURBINE, Wind.SCHEMA]),
        ("Turbine files", _TURBINE_TEXT, [t for t, _ in TURBINE_FILE.values()]),
    ]


def markdown() -> str:
    """The reference page as Markdown."""
    return reference_markdown(sections())


def main(argv: list[str] | None = None) -> int:
    """Write the page (or, with ``--check``, compare it); returns the exit status."""
    argv = sys.argv[1:] if argv is None else argv
    text = markdown()
    if "--check" in argv:
        current = PAGE.read_text(encoding="utf-8") if PAGE.exists() else ""
        if current != text:
            print(f"{PAGE} is not current: run python -m gearmodal.reference",
                  file=sys.stderr)
            return 1
        return 0
    PAGE.parent.mkdir(parents=True, exist_ok=True)
    PAGE.write_text(text, encoding="utf-8")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
