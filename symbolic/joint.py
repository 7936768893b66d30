"""Generic joint constraint ``g(q_a, q_b)``, ``G_a``, ``G_b`` (DESIGN 2.5; bearing deflection, 2.3).

Material point ``P_a`` of body ``a`` (offset ``pa`` from its centre) and ``P_b`` of body ``b``
(offset ``pb``) are nominally coincident. With joint axes ``E = Rz(gamma) = [e1 e2 e3]`` and the
body displacements ``q = (ux, uy, uz, rx, ry, rz)`` (global axes, exact rotation ``Rs``):

    g = [ E^T ((u_a + (Rs(r_a) - I) pa) - (u_b + (Rs(r_b) - I) pb)) ;
          E^T (r_a - r_b) ]

the relative translation of the two points in joint axes (exact) and the relative small
rotation. ``G_a = dg/dq_a``, ``G_b = dg/dq_b`` at ``q = 0`` are the constraint gradients of the
Lagrange-multiplier coupling ``B + G^T lambda = 0, g = 0`` (DESIGN 2.5).

A bearing is the same joint made compliant, with a dead band per direction (DESIGN 2.3): with
clearance ``c_i`` (free play on each side) direction ``i`` has the two gap functions (positive =
penetration, the side is in contact)

    p_i+ = g_i - c_i,    p_i- = -g_i - c_i,

ordered ``x+, x-, y+, y-, z+, z-, rx+, rx-, ry+, ry-, theta+, theta-``, with Jacobians
``d p / d q_a``, ``d p / d q_b`` at ``q = 0``.

The geometric stiffness of a joint that carries a force (DESIGN 2.5a) needs the curvature of
its deflection: with ``f`` the force in each direction (joint axes; N and N m), the force adds
``sum_i f_i d2 g^x_i / dq dq`` (``q = [q_a; q_b; r_x]``) to the stiffness, where the
deflection is measured in axes that turn with a body ``x`` by its small rotation ``r_x``
(the body the load turns with: ``gearmodal.model.bearing``):

    g^x = [ E^T Rs(r_x)^T ((u_a + (Rs(r_a) - I) pa) - (u_b + (Rs(r_b) - I) pb)) ;
            E^T (r_a - r_b) ].

Its first derivatives at 0 are those of ``g`` (the relative displacement vanishes there); its
curvature holds the offsets' rotations and the turning of the axes against the relative
displacement. ``g^x`` is invariant under a rigid rotation of ``a``, ``b`` and ``x`` at any
nearby configuration, a loaded and deflected one too (see ``gearmodal.assembly``, geometric
stiffness).
"""

from __future__ import annotations

import sympy as sp

from .codegen import Kernel, ScalarArg, VectorArg, print_module
from .rotations import Rs, Rz

SOURCE = "joint"
DESCRIPTION = "Joint/bearing constraint (DESIGN 2.3, 2.5): exact residual g and gradients G_a, G_b."

pax, pay, paz, pbx, pby, pbz = sp.symbols("pax pay paz pbx pby pbz", real=True)
gamma = sp.Symbol("gamma", real=True)
CLEAR = sp.symbols("cx cy cz crx cry ctheta", real=True)

QA = sp.symbols("uax uay uaz rax ray raz", real=True)
QB = sp.symbols("ubx uby ubz rbx rby rbz", real=True)
RX = sp.symbols("rxx rxy rxz", real=True)

_DOCS = {
    pax: "x of the offset from a's centre to the joint point (global axes)",
    pay: "y of the offset from a's centre",
    paz: "z of the offset from a's centre",
    pbx: "x of the offset from b's centre to the joint point",
    pby: "y of the offset from b's centre",
    pbz: "z of the offset from b's centre",
    gamma: "joint axes angle: e1 = Rz(gamma) x_hat, e2 = Rz(gamma) y_hat, e3 = z_hat",
}


def derive() -> dict[str, sp.Matrix]:
    """Return the exact residual ``g`` (6,), its gradients ``Ga``, ``Gb`` (6, 6) at 0 and
    ``Ga_q``, ``Gb_q`` at any ``q``."""
    E = Rz(gamma)
    pa = sp.Matrix([pax, pay, paz])
    pb = sp.Matrix([pbx, pby, pbz])
    ua, ra = sp.Matrix(QA[:3]), QA[3:]
    ub, rb = sp.Matrix(QB[:3]), QB[3:]
    dpa = ua + (Rs(ra) - sp.eye(3)) @ pa
    dpb = ub + (Rs(rb) - sp.eye(3)) @ pb
    g = sp.Matrix.vstack(E.T @ (dpa - dpb), E.T @ (sp.Matrix(ra) - sp.Matrix(rb)))
    zero = dict.fromkeys(QA + QB, 0)
    Ga_q = g.jacobian(QA)
    Gb_q = g.jacobian(QB)
    Ga = Ga_q.subs(zero)
    Gb = Gb_q.subs(zero)
    gaps = sp.Matrix([sign * g[i] - CLEAR[i] for i in range(6) for sign in (1, -1)])
    Ja = gaps.jacobian(QA).subs(zero)
    Jb = gaps.jacobian(QB).subs(zero)
    # curvature at 0 of the deflection in axes that turn with x (module docstring), stacked:
    # rows 15 i .. 15 i + 14 are d2 g^x_i / dq dq, q = [q_a; q_b; r_x]
    gx = sp.Matrix.vstack(E.T @ Rs(RX).T @ (dpa - dpb), E.T @ (sp.Matrix(ra) - sp.Matrix(rb)))
    zero_x = dict.fromkeys(QA + QB + RX, 0)
    H = sp.Matrix.vstack(*(sp.hessian(gx[i], QA + QB + RX).subs(zero_x) for i in range(6)))
    return {"g": g, "Ga": Ga, "Gb": Gb, "Ga_q": Ga_q, "Gb_q": Gb_q, "gaps": gaps, "Ja": Ja,
            "Jb": Jb, "H": H.applyfunc(sp.expand)}


def kernels() -> list[Kernel]:
    """The generated kernels of ``gearmodal/kernels/joint.py``."""
    d = derive()
    geo = [ScalarArg(s, _DOCS[s]) for s in (pax, pay, paz, pbx, pby, pbz, gamma)]
    qa = VectorArg("qa", QA, "displacements of a (ux, uy, uz, rx, ry, rz), global axes")
    qb = VectorArg("qb", QB, "displacements of b (ux, uy, uz, rx, ry, rz), global axes")
    return [
        Kernel(
            "joint_residual",
            [qa, qb, *geo],
            [d["g"]],
            "Exact joint residual g (6,): relative translation and rotation in joint axes "
            "(DESIGN 2.5).",
        ),
        Kernel(
            "joint_gradients",
            geo,
            [d["Ga"], d["Gb"]],
            "Constraint gradients (Ga, Gb), each (6, 6): dg/dq_a and dg/dq_b at q = 0 "
            "(DESIGN 2.5).",
            output_names=["Ga", "Gb"],
        ),
        Kernel(
            "joint_gradients_at",
            [qa, qb, *geo],
            [d["Ga_q"], d["Gb_q"]],
            "Constraint gradients (Ga, Gb), each (6, 6), of the exact residual at (qa, qb): "
            "the tangent of a nonlinear joint away from q = 0 (DESIGN 2.5).",
            output_names=["Ga", "Gb"],
        ),
        Kernel(
            "joint_curvatures",
            geo,
            [d["H"]],
            "Curvatures (90, 15) at q = 0 of the joint deflection in axes turning with a body x\n"
            "(module docstring): rows 15 i .. 15 i + 14 are d2 g^x_i / d[q_a; q_b; r_x]^2 of\n"
            "direction i (x, y, z, rx, ry, theta); a force f_i carried in direction i adds f_i\n"
            "times it to the stiffness (DESIGN 2.5a).",
        ),
        Kernel(
            "bearing_gaps",
            [qa, qb, *geo, *(ScalarArg(c, f"clearance of direction {c.name[1:]} (m or rad)")
                             for c in CLEAR)],
            [d["gaps"]],
            "Dead-band gap functions (12,) of a bearing, positive = that side in contact: "
            "x+, x-, y+, y-, z+, z-, rx+, rx-, ry+, ry-, theta+, theta- (DESIGN 2.3).",
        ),
        Kernel(
            "bearing_gap_jacobians",
            geo,
            [d["Ja"], d["Jb"]],
            "Jacobians (Ja, Jb), each (12, 6), of the bearing gap functions at q = 0 "
            "(DESIGN 2.3).",
            output_names=["Ja", "Jb"],
        ),
    ]


def generate_source() -> str:
    """Text of ``gearmodal/kernels/joint.py``."""
    return print_module(SOURCE, DESCRIPTION, kernels())
