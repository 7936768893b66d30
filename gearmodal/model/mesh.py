"""The gear mesh element: two compression-only flanks with backlash (DESIGN 2.2)."""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from ..errors import ModelError
from ..frames import rz
from ..kernels.mesh import mesh_gap_curvature, mesh_gap_jacobian
from . import validate as v
from .components import Gear, check_structure
from .element import Element
from .mesh_stiffness import variation_of
from .schema import NAME, REQUIRED, STRUCTURE, Field, Table

__all__ = ["Mesh"]


@dataclass(eq=False)
class Mesh(Element):
    """A gear mesh with two compression-only flanks and backlash (DESIGN 2.2).

    The front flank carries ``stiffness * d_f + damping * d_f'`` while ``d_f > 0``; the back
    flank ``stiffness * (d_b - backlash) + damping * d_b'`` while ``d_b > backlash``. ``q = 0`` is
    front flanks touching with zero force. ``side`` (+1 or -1) picks which line of action is the
    front flank: with ``side = +1`` a positive rotation of ``gear_a`` closes the front flank.
    For an internal pair ``gear_a`` is the ring.

    ``pressure_angle`` (transverse, rad), ``base_radii`` (m, m), ``helix_angle`` (base helix,
    rad) and ``internal`` override the values derived from the gears (used by
    :func:`gearmodal.lin_parker_stage`, whose bodies carry no tooth data).

    Mesh stiffness (a fidelity rung, :mod:`gearmodal.model.mesh_stiffness`): ``alternation =
    False`` (default) keeps ``stiffness`` constant. ``alternation = True`` alternates it at the
    mesh frequency between single and double tooth-pair contact, a rectangular wave (M1) whose
    mean is ``stiffness`` (ISO 6336's mean mesh stiffness c_gamma), with the double-pair
    stiffness ``stiffness_ratio`` times the single-pair one (default 1.75, which makes the mean
    ISO 6336-1's c_gamma = c' (0.75 eps + 0.25) for any contact ratio). ``contact_ratio`` is
    the transverse contact ratio eps in (1, 2): the fraction eps - 1 of each mesh period has two
    pairs in contact; by default it is computed from the gears (standard addendum of one
    module, no profile shift). ``phase`` is the fraction of a mesh period elapsed at input
    azimuth 0 (0 = the start of a double-pair zone). The wave runs on the nominal rotation of
    the gears, so it switches at known times: the exact method switches at them exactly.

    Manufacturing errors (exact: offsets of the flanks' gaps): the gears' ``position_error``
    and ``thickness_error`` (constant), their ``runout`` (turning with a gear's spin against
    the frame the mesh's centres turn in, at that relative rotation order), and
    ``transmission_error``: ``[(amplitude_m, phase_rad), ...]``, harmonics k = 1, 2, ... of the
    mesh frequency (``gear_a``'s teeth passing the mesh, per input revolution), a displacement
    ``sum_k A_k cos(k (M psi + 2 pi phase) + phi_k)`` along the line of action that closes the
    front flank and opens the back one (``M`` the mesh order, ``phase`` as above).
    """

    name: str
    gear_a: str
    gear_b: str
    stiffness: float
    backlash: float = 0.0
    damping: float = 0.0
    side: int = 1
    pressure_angle: float | None = None
    base_radii: tuple | None = None
    helix_angle: float | None = None
    internal: bool | None = None
    alternation: bool = False
    contact_ratio: float | None = None
    stiffness_ratio: float = 1.75
    phase: float = 0.0
    stage: str = ""
    role: str = ""
    planet: str | None = None
    transmission_error: tuple = ()

    TABLE: ClassVar[str] = "meshes"
    SCHEMA: ClassVar[Table]

    def __post_init__(self):
        f = self.name
        v.name("Mesh.name", self.name)
        check_structure(self)
        # types and ranges: the schema's (one statement for the file and the API)
        Mesh.SCHEMA.check(self, ("gear_a", "gear_b", "stiffness", "backlash", "damping",
                                 "pressure_angle", "base_radii", "helix_angle", "internal",
                                 "alternation", "contact_ratio", "stiffness_ratio", "phase"))
        if self.side not in (1, -1):
            raise ModelError(f"{f}.side", f"= {self.side!r}: must be +1 or -1")
        te = self.transmission_error  # (amplitude >= 0, phase): a range per column
        if not isinstance(te, (list, tuple)) or not all(
                isinstance(x, (list, tuple)) and len(x) == 2 for x in te):
            raise ModelError(f"{f}.transmission_error", f"= {te!r}: expected [[amplitude_m, "
                             "phase_rad], ...], one pair per harmonic of the mesh frequency")
        self.transmission_error = tuple(
            (v.plausible(f"{f}.transmission_error[{i}]", v.nonnegative(
                f"{f}.transmission_error[{i}]", a, "m"), "gap"),
             v.number(f"{f}.transmission_error[{i}]", p, "rad")) for i, (a, p) in enumerate(te))

    # -- in a model ---------------------------------------------------------------------
    def references(self) -> list[tuple[str, str, str]]:
        return [("gear_a", self.gear_a, "bodies"), ("gear_b", self.gear_b, "bodies")]

    def renamed(self, p, prefix: str, ground: str | None = None) -> Mesh:
        new = copy.copy(self)
        new.name, new.gear_a, new.gear_b = p(self.name), p(self.gear_a), p(self.gear_b)
        new.stage = p(self.stage) if self.stage else prefix
        new.planet = p(self.planet) if self.planet else self.planet
        return new

    def check_in(self, model) -> None:
        """Its gears carry tooth data (or the mesh gives ``base_radii``), turn in frames at one
        speed, and an internal gear is ``gear_a``."""
        a, b = model.bodies[self.gear_a], model.bodies[self.gear_b]
        for side, g in (("gear_a", a), ("gear_b", b)):
            if self.base_radii is None and not isinstance(g, Gear):
                raise ModelError(f"{self.name}.{side}", f"= {g.name!r} is not a Gear; give "
                                 "base_radii and pressure_angle on the mesh")
        if model.frames[a.frame].speed_ratio != model.frames[b.frame].speed_ratio:
            raise ModelError(f"{self.name}", f"gears {a.name!r} and {b.name!r} sit in frames "
                             "turning at different speeds; put both in one frame")
        if isinstance(b, Gear) and b.internal:
            raise ModelError(f"{self.name}.gear_b", f"= {b.name!r} is internal; the internal "
                             "gear (ring) must be gear_a")

    # -- its contribution to the assembly (DESIGN 2.2) --------------------------------------
    def contribute(self, ctx) -> None:
        """Add the two flanks to ``ctx`` (:class:`gearmodal.assembly.Contributions`): each a
        unilateral contact on its line of action, the back flank mirrored and offset by the
        backlash; an alternating stiffness (M1) as the flanks' variation."""
        model = ctx.model
        a, b = model.bodies[self.gear_a], model.bodies[self.gear_b]
        if self.internal is not None:
            internal = 1.0 if self.internal else 0.0
        else:
            internal = 1.0 if isinstance(a, Gear) and a.internal else 0.0
        if self.base_radii is not None:
            rba, rbb = (float(r) for r in self.base_radii)
        else:
            rba, rbb = a.base_radius, b.base_radius
        if self.pressure_angle is not None:
            alpha = self.pressure_angle
        else:
            g = b if isinstance(b, Gear) else a
            alpha = g.transverse_pressure_angle
        if self.helix_angle is not None:
            beta_b = self.helix_angle
        else:
            beta_b = a.base_helix_angle if isinstance(a, Gear) else 0.0
        ca, cb = ctx.centre(a), ctx.centre(b)
        if np.hypot(*(cb - ca)[:2]) == 0.0:
            raise ModelError(self.name, f"gears {a.name!r} and {b.name!r} have the same centre")
        # manufacturing errors (Gear.position_error, Gear.thickness_error): with q measured
        # from the nominal positions, a flank's compression is J (q + e) + t/2, so its offset
        # (p = W q - offset) drops by J e + t/2; the backlash drops by the thickness errors
        ea, eb = _centre_error(ctx, a), _centre_error(ctx, b)
        thick = 0.5 * (getattr(a, "thickness_error", 0.0) + getattr(b, "thickness_error", 0.0))
        if self.backlash - 2.0 * thick < 0.0:
            raise ModelError(f"{self.name}.backlash", f"= {self.backlash!r} m: the tooth "
                             f"thickness errors of {a.name!r} and {b.name!r} take "
                             f"{2.0 * thick!r} m of it; the backlash must stay >= 0")
        order, ratio_j = self._mesh_order(ctx, a, b, ca, cb)
        for flank, side, off in (("front", self.side, 0.0), ("back", -self.side,
                                                             self.backlash)):
            def jac(psi, side=side):
                pa, pb = ctx.centre(a, psi), ctx.centre(b, psi)
                return mesh_gap_jacobian(pa[0], pa[1], pb[0], pb[1], rba, rbb, alpha, beta_b,
                                         float(side), internal)

            J = mesh_gap_jacobian(ca[0], ca[1], cb[0], cb[1], rba, rbb, alpha, beta_b,
                                  float(side), internal)
            off = off - thick - float(J[:3] @ ea + J[6:9] @ eb)
            waves = []
            for body, sl in ((a, slice(0, 3)), (b, slice(6, 9))):  # run-out: J . e(psi)
                h, z = _runout_wave(ctx, body, jac, sl, ratio_j)
                if z:
                    waves.append((h, -z))
            sign = 1.0 if flank == "front" else -1.0  # TE closes the front, opens the back
            for k, (amp, phi) in enumerate(self.transmission_error, start=1):
                if amp:
                    z = amp * np.exp(1j * (phi + 2 * np.pi * k * self.phase))
                    waves.append((k * order, -sign * z))
            off = off + sum(z.real for h, z in waves if h == 0)  # turning with the mesh
            waves = [(h, z) if h > 0 else (-h, np.conj(z)) for h, z in waves if h != 0]
            off = off + sum((z * np.exp(1j * h * ctx.azimuth)).real for h, z in waves)
            w = ctx.row([(a, J[:6]), (b, J[6:])])
            H = mesh_gap_curvature(ca[0], ca[1], cb[0], cb[1], rba, rbb, alpha, beta_b,
                                   float(side), internal)
            if np.any(w):
                variation = variation_of(model, self, a, b, bool(internal)) \
                    if self.alternation else None
                ctx.contact(w, off, self.stiffness, self.damping, flank == "front", self,
                            flank, "mesh", columns=[(f"{self.name}.{flank}", 1.0)],
                            variation=variation, waves=waves,
                            curvature=([(a, slice(0, 6)), (b, slice(0, 6))], H))


    def _mesh_order(self, ctx, a, b, ca, cb) -> tuple[float, float]:
        """``(M, r_J)``: the mesh order (``gear_a``'s teeth passing the mesh per input
        revolution; 0 when not needed or not a gear) and the speed ratio of the frame the
        mesh's centres turn in (the frame of the gear off the axis)."""
        off_a, off_b = np.hypot(*ca[:2]) > 0.0, np.hypot(*cb[:2]) > 0.0
        fa, fb = ctx.model.frames[a.frame], ctx.model.frames[b.frame]
        if off_a and off_b and fa.speed_ratio != fb.speed_ratio:
            ratio_j = math.nan  # centres turning against each other: no fixed mesh frame
        else:
            ratio_j = (fa if off_a else fb).speed_ratio
        needs = any(amp for amp, _ in self.transmission_error)
        if not needs:
            return 0.0, ratio_j
        teeth = getattr(a, "teeth", 0)
        if not teeth or math.isnan(ratio_j):
            raise ModelError(f"{self.name}.transmission_error", "needs gear_a with teeth "
                             "(a gm.Gear) on a mesh whose centres turn in one frame")
        return teeth * abs(a.speed_ratio - ratio_j), ratio_j


def _runout_wave(ctx, body, jac, sl: slice, ratio_j: float) -> tuple[float, complex]:
    """``(h, z)`` of ``body``'s run-out on a flank: ``J(psi) . e(psi) = Re(z e^(i h psi))``
    with ``e`` turning with the body's spin and the flank's gradient ``J`` (``jac(psi)``)
    with the mesh's frame: one harmonic of order ``h`` = the spin against that frame, ``z``
    from two evaluations a quarter period apart; ``(0, 0)`` without run-out."""
    e, phase = getattr(body, "runout", (0.0, 0.0))
    if not e:
        return 0.0, 0j
    if math.isnan(ratio_j):
        raise ModelError(f"{body.name}.runout", "on a mesh whose centres turn against each "
                         "other: not modelled")
    h = body.speed_ratio - ratio_j

    def value(psi):
        d = rz(body.speed_ratio * psi + body.orientation + phase) @ np.array([e, 0.0, 0.0])
        return float(jac(psi)[sl] @ d)

    psi1 = ctx.azimuth
    if h == 0.0:  # turning with the mesh: a constant offset (Re z at h = 0)
        return 0.0, complex(value(psi1))
    v1, v2 = value(psi1), value(psi1 + math.pi / (2.0 * h))
    return h, complex(v1, -v2) * np.exp(-1j * h * psi1)


def _centre_error(ctx, body) -> np.ndarray:
    """The global (x, y, z) offset of ``body``'s true centre at the assembly's azimuth, m:
    its ``position_error`` turned by its local axes (a body that is not a gear has none)."""
    e = getattr(body, "position_error", (0.0, 0.0))
    if not any(e):
        return np.zeros(3)
    frame = ctx.model.frames[body.frame]
    return rz(frame.speed_ratio * ctx.azimuth + body.orientation) @ np.array([*e, 0.0])


Mesh.SCHEMA = Table("meshes", (
    NAME,
    Field("gear_a", "name", default=REQUIRED, doc="first gear (the ring of an internal pair)"),
    Field("gear_b", "name", default=REQUIRED, doc="second gear"),
    Field("stiffness", "number", "N/m", low=0.0, default=REQUIRED,
          doc="mesh stiffness along the line of action (the mean if alternating)",
          limits="stiffness"),
    Field("backlash", "number", "m", low=0.0, default=0.0, doc="backlash on the line of action",
          limits="gap"),
    Field("damping", "number", "N s/m", low=0.0, default=0.0, doc="mesh damping",
          limits="damping"),
    Field("side", "integer", low=-1, high=1, default=1,
          doc="+1 or -1: which line of action is the front flank"),
    Field("pressure_angle", "angle", "rad", low=1e-6, high=math.pi / 2, high_open=True,
          doc="transverse pressure angle (default: from the gears)"),
    Field("base_radii", "vector", "m", lengths=(2,), low=0.0,
          doc="[a, b] base radii (default: from the gears)"),
    Field("helix_angle", "angle", "rad", doc="base helix angle (default: from the gears)"),
    Field("internal", "boolean", doc="internal pair (default: gear_a is an internal gear)"),
    Field("alternation", "boolean", default=False,
          doc="stiffness alternates between single and double tooth-pair contact"),
    Field("contact_ratio", "number", low=1.0, high=2.0, low_open=True, high_open=True,
          doc="transverse contact ratio (default: from the gears)",
          note="single/double tooth-pair alternation"),
    Field("stiffness_ratio", "number", low=1.0, high=10.0, default=1.75,
          doc="double-pair over single-pair stiffness",
          note="double-pair over single-pair stiffness"),
    Field("phase", "number", default=0.0,
          doc="fraction of a mesh period elapsed at input azimuth 0"),
    *STRUCTURE, Field("planet", "name", doc="the planet this mesh belongs to"),
    Field("transmission_error", "pairs", default=(),
          doc="[[amplitude_m, phase_rad], ...]: harmonics 1, 2, ... of the mesh frequency")),
    "A gear mesh with two compression-only flanks and backlash (`[[meshes]]`).")
