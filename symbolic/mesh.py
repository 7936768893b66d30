"""Flank gap function of a gear mesh (DESIGN 2.2, planar limit: Lin & Parker 1999).

Wheel ``a`` (centre ``c_a``) meshes with wheel ``b`` (centre ``c_b``), both centres in the plane
``z = 0`` (global axes). With ``e = (c_b - c_a) / |c_b - c_a|``, side ``s = +-1`` (front flank:
``s``, back flank: ``-s``) and the internal flag ``i`` (1 when ``a`` is an internal gear with
``b`` inside it, else 0):

    n_t = Rz(s (pi/2 - alpha)) e      (external),   n_t = Rz(s (pi/2 + alpha)) e   (internal)
    P_a = c_a + rba Rz(-s pi/2) n_t
    P_b = c_b - rbb Rz(-s pi/2) n_t   (external),   P_b = c_b + rbb Rz(-s pi/2) n_t (internal)
    n   = cos(beta_b) n_t - s sin(beta_b) z_hat

Both cases are one expression with ``sigma = 1 - 2 i``: for ``s = +-1``,
``Rz(s (pi/2 -+ alpha)) = [[sigma sin(alpha), -s cos(alpha)], [s cos(alpha), sigma sin(alpha)]]``
and ``P_b - c_b = -sigma rbb Rz(-s pi/2) n_t``.

With the body displacements ``q = (ux, uy, uz, rx, ry, rz)`` (translation of the centre and small
rotation vector, global axes, exact rotation ``Rs``), the gap (compression, positive when the
flanks interpenetrate) is

    d(q_a, q_b) = [(u_a + (Rs(r_a) - I)(P_a - c_a)) - (u_b + (Rs(r_b) - I)(P_b - c_b))] . n.

Its Jacobian at ``q = 0`` reproduces Lin & Parker's sun-planet and ring-planet deflections
(``u_j = r_j theta_j``) for the spur front flank; ``s = -1`` flips the rotational and
tangential terms and keeps the radial ones (a radial approach closes both flanks).

The geometric stiffness of a flank that carries a force ``f`` (DESIGN 2.5a) is ``f`` times
the curvature of the gap. ``d`` above holds the line of action fixed, which is exact for the
wheels' rotations but not for their translations: a relative translation across the line of
action turns the common tangent of the base circles. To second order that is the belt (or
string) analogy of involute gearing: the contact's compression is the change of the distance
between the two base-circle tangent points ``P_a``, ``P_b`` of the transverse plane,

    d2 = d + cos(beta_b) (delta . t)^2 / (2 l),
    l = (P_a - P_b) . n_t = -sigma |c_b - c_a| sin(alpha),

with ``delta`` the relative displacement of the two points and ``t = z_hat x n_t``. It matches
the involute's own law (the compression ``-(rba + sigma rbb) (inv alpha_w - inv alpha)``
of a centre distance change has the curvature ``-cos^2(alpha) / (a sin(alpha))`` per unit of
distance squared, which ``d2`` gives), and, unlike ``d``, it is invariant under a rigid
rotation of both wheels about the stage axis to second order: the property that makes a
steadily turning drivetrain's rigid rotation neutral (see ``gearmodal.assembly``).
"""

from __future__ import annotations

import sympy as sp

from .codegen import Kernel, ScalarArg, VectorArg, print_module
from .rotations import Rs

SOURCE = "mesh"
DESCRIPTION = "Gear mesh flank gap (DESIGN 2.2): exact gap function and its Jacobian at q = 0."

cax, cay, cbx, cby = sp.symbols("cax cay cbx cby", real=True)
rba, rbb = sp.symbols("rba rbb", positive=True)
alpha, beta_b = sp.symbols("alpha beta_b", real=True)
side, internal = sp.symbols("side internal", real=True)

QA = sp.symbols("uax uay uaz rax ray raz", real=True)
QB = sp.symbols("ubx uby ubz rbx rby rbz", real=True)

_DOCS = {
    cax: "x of the centre of wheel a (global axes)",
    cay: "y of the centre of wheel a",
    cbx: "x of the centre of wheel b",
    cby: "y of the centre of wheel b",
    rba: "base radius of wheel a",
    rbb: "base radius of wheel b",
    alpha: "transverse pressure angle",
    beta_b: "base helix angle (signed)",
    side: "+1.0 or -1.0: line of action (front flank side s, back flank -s)",
    internal: "0.0 external pair; 1.0 when a is an internal gear (ring) and b inside it",
}


# Auxiliary symbols: unit centre-line direction e = (ex, ey), cos/sin of alpha.
_ex, _ey, _ca, _sa = sp.symbols("ex ey ca sa", real=True)
#: Groebner basis of the side conditions s^2 = 1, i in {0, 1}, |e| = 1, cos^2 + sin^2 = 1
#: (pairwise coprime leading terms in lex order side > internal > ex > ey > sa > ca).
_BASIS = [side**2 - 1, internal**2 - internal, _ex**2 + _ey**2 - 1, _sa**2 + _ca**2 - 1]
_GENS = (side, internal, _ex, _ey, _sa, _ca)


def _reduce(expr: sp.Expr) -> sp.Expr:
    """Reduce a polynomial in the auxiliary symbols modulo the side conditions, then
    substitute ``e = (c_b - c_a) / |c_b - c_a|`` and ``cos/sin(alpha)``."""
    rem = sp.reduced(sp.expand(expr), _BASIS, *_GENS)[1]
    dx, dy = cbx - cax, cby - cay
    L = sp.sqrt(dx**2 + dy**2)
    back = {_ex: dx / L, _ey: dy / L, _ca: sp.cos(alpha), _sa: sp.sin(alpha)}
    return sp.factor_terms(rem.subs(back))


def geometry() -> dict[str, sp.Matrix]:
    """Nominal contact geometry: offsets ``P_a - c_a``, ``P_b - c_b`` and the normal ``n``."""
    e = sp.Matrix([_ex, _ey])
    sigma = 1 - 2 * internal
    rot_n = sp.Matrix([[sigma * _sa, -side * _ca], [side * _ca, sigma * _sa]])
    n_t = rot_n @ e
    rot_m90 = sp.Matrix([[0, side], [-side, 0]])  # Rz(-s pi/2) for s = +-1
    radial = rot_m90 @ n_t
    pa = sp.Matrix([rba * radial[0], rba * radial[1], 0])
    pb = sp.Matrix([-sigma * rbb * radial[0], -sigma * rbb * radial[1], 0])
    n = sp.Matrix([sp.cos(beta_b) * n_t[0], sp.cos(beta_b) * n_t[1], -side * sp.sin(beta_b)])
    return {"pa": pa, "pb": pb, "n": n}


def derive() -> dict[str, sp.Expr | sp.Matrix]:
    """Return the exact ``gap`` and its ``jacobian`` (12,) at ``q = 0``."""
    g = {k: v.applyfunc(_reduce) for k, v in geometry().items()}
    ua, ra = sp.Matrix(QA[:3]), QA[3:]
    ub, rb = sp.Matrix(QB[:3]), QB[3:]
    da = ua + (Rs(ra) - sp.eye(3)) @ g["pa"]
    db = ub + (Rs(rb) - sp.eye(3)) @ g["pb"]
    gap = (da - db).dot(g["n"])
    # Jacobian in the auxiliary symbols (so that it can be reduced), then substituted.
    raw = geometry()
    da = ua + (Rs(ra) - sp.eye(3)) @ raw["pa"]
    db = ub + (Rs(rb) - sp.eye(3)) @ raw["pb"]
    raw_gap = (da - db).dot(raw["n"])
    zero = dict.fromkeys(QA + QB, 0)
    jac = sp.Matrix([_reduce(sp.diff(raw_gap, x).subs(zero)) for x in QA + QB])
    return {"gap": gap, "jacobian": jac, "curvature": _curvature(raw, raw_gap, zero)}


def _curvature(raw: dict, raw_gap: sp.Expr, zero: dict) -> sp.Matrix:
    """Hessian (12, 12) at ``q = 0`` of the belt gap ``d2`` (module docstring)."""
    e = sp.Matrix([_ex, _ey, 0])
    n_t = sp.Matrix([raw["n"][0], raw["n"][1], 0]) / sp.cos(beta_b)
    t = sp.Matrix([-n_t[1], n_t[0], 0])
    ua, ra = sp.Matrix(QA[:3]), QA[3:]
    ub, rb = sp.Matrix(QB[:3]), QB[3:]
    delta = (ua + (Rs(ra) - sp.eye(3)) @ raw["pa"]) - (ub + (Rs(rb) - sp.eye(3)) @ raw["pb"])
    across = sp.Matrix([_reduce(sp.diff(delta.dot(t), x).subs(zero)) for x in QA + QB])
    # l = (P_a - P_b) . n_t with P_a - P_b = -D e + pa - pb (D the centre distance)
    dist = sp.sqrt((cbx - cax) ** 2 + (cby - cay) ** 2)
    length = _reduce((-e * sp.Symbol("D") + raw["pa"] - raw["pb"]).dot(n_t)).subs(
        sp.Symbol("D"), dist)
    own = sp.hessian(raw_gap, QA + QB).subs(zero).applyfunc(_reduce)
    return own + (sp.cos(beta_b) / length) * (across @ across.T)


def kernels() -> list[Kernel]:
    """The generated kernels of ``gearmodal/kernels/mesh.py``."""
    d = derive()
    geo = [ScalarArg(s, _DOCS[s]) for s in (cax, cay, cbx, cby, rba, rbb, alpha, beta_b)]
    geo += [ScalarArg(side, _DOCS[side]), ScalarArg(internal, _DOCS[internal])]
    qa = VectorArg("qa", QA, "displacements of a (ux, uy, uz, rx, ry, rz), global axes")
    qb = VectorArg("qb", QB, "displacements of b (ux, uy, uz, rx, ry, rz), global axes")
    return [
        Kernel(
            "mesh_gap",
            [qa, qb, *geo],
            [d["gap"]],
            "Exact flank gap d(q_a, q_b) (float), positive = interpenetration (DESIGN 2.2).",
        ),
        Kernel(
            "mesh_gap_jacobian",
            geo,
            [d["jacobian"]],
            "Jacobian dd/d[q_a; q_b] (12,) of the flank gap at q = 0 (DESIGN 2.2).\n\n"
            "Spur front flank: Lin & Parker 1999 d_sn, d_rn (u_j = r_j theta_j).",
        ),
        Kernel(
            "mesh_gap_curvature",
            geo,
            [d["curvature"]],
            "Curvature (12, 12) at q = 0 of the flank's belt gap d2 (module docstring): a flank\n"
            "carrying the force f adds f times it to the stiffness (DESIGN 2.5a).",
        ),
    ]


def generate_source() -> str:
    """Text of ``gearmodal/kernels/mesh.py``."""
    return print_module(SOURCE, DESCRIPTION, kernels())
