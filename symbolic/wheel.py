"""Floating-frame gear wheel: linearised inertia terms (DESIGN 2.1).

A wheel's material point ``x`` is placed by (DESIGN 2.1)

    r(t) = R(t) + A(t) (R0 + A1 u(t) + A2(t) x)

with the 12 coordinates ``q = (X, Y, Z, RX, RY, RZ, ux, uy, uz, rx, ry, rz)``:

- frame orientation ``A = Rz(Omega_f t) Rs(RX, RY, RZ)``: steady spin about the global z axis
  at ``Omega_f`` and small rotations about the (spinning) frame axes;
- frame position ``R = Rz(Omega_f t) (X, Y, Z)``: the frame translations are measured along the
  spinning frame axes as well (see the note below);
- wheel offset ``R0`` in frame axes, ``A1 = Rz(a1)``, local translation ``u = (ux, uy, uz)`` in
  ``A1`` axes and ``A2 = A1 Rs(rx, ry, rz) Rz(s t)`` with the nominal spin relative to the frame
  ``s = omega_s - Omega_f``;
- body of mass ``m``, centre of mass at ``x = 0``, inertia ``diag(Id, Id, Ip)`` in body axes.

With ``T(q, q')`` the kinetic energy, Lagrange's equations linearised about ``q = q' = 0`` are

    M q'' + G q' + K q = F0 + Q,
    M = d2T/dq'dq',  N = d2T/dq'dq,  G = N - N^T,  K = -d2T/dqdq,  F0 = dT/dq    (at 0).

(the momentum ``dT/dq'`` at 0 is constant and drops out.)  ``G`` holds the Coriolis and
gyroscopic coupling, ``K`` the centripetal softening (Lin & Parker 1999: ``2 m Omega [[0,-1],
[1,0]]`` and ``-m Omega^2 I`` for a translating body in the carrier frame) and ``F0`` the
centrifugal force of the nominal motion.

Note on the frame translations: if ``R = (X, Y, Z)`` were measured along the *fixed* global axes
while the frame spins, the term ``R' . Rz(Omega_f t)(...)`` of ``T`` would depend on ``t`` and the
linearised equations would have periodic coefficients. Measuring them along the spinning frame
axes (as Lin & Parker do for the carrier) makes ``T`` independent of ``t``. The derivation
*proves* this before dropping the spins: it factors ``Rz(Omega_f t)`` and ``Rz(s t)`` out of ``T``
with identities checked symbolically modulo ``cos^2 + sin^2 = 1`` (:func:`_spin_identities`;
the wheel spin drops out because the inertia is axisymmetric). For ``Omega_f = 0`` both choices
of axes coincide.

Method: the coordinates are scaled by ``eps``, every small rotation is expanded to ``eps**2``
and ``T`` is truncated at ``eps**2``; its ``eps**1`` and ``eps**2`` coefficients are the linear
and quadratic forms whose coefficients are ``F0`` and ``M, N, -K``. The algebra runs in a sparse
polynomial ring (well under a second).
"""

from __future__ import annotations

import sympy as sp

from .codegen import Kernel, ScalarArg, print_module
from .rotations import rot_z

SOURCE = "wheel"
DESCRIPTION = (
    "Floating-frame gear wheel (DESIGN 2.1): linearised mass, gyroscopic, centripetal matrices "
    "and centrifugal force."
)

#: Names of the 12 coordinates, in order.
COORDINATES = ("X", "Y", "Z", "RX", "RY", "RZ", "ux", "uy", "uz", "rx", "ry", "rz")

m, Id, Ip = sp.symbols("m Id Ip", positive=True)
R0x, R0y, R0z, a1 = sp.symbols("R0x R0y R0z a1", real=True)
Omega_f, omega_s = sp.symbols("Omega_f omega_s", real=True)

_DOCS = {
    m: "wheel mass",
    Id: "diametral moment of inertia (about body x and y)",
    Ip: "polar moment of inertia (about body z)",
    R0x: "wheel offset in the frame, frame x",
    R0y: "wheel offset in the frame, frame y",
    R0z: "wheel offset in the frame, frame z",
    a1: "orientation angle of the wheel's local axes about frame z (A1 = Rz(a1))",
    Omega_f: "steady spin rate of the frame about global z",
    omega_s: "absolute nominal spin rate of the wheel about its z axis",
}


def _args(*symbols: sp.Symbol) -> list[ScalarArg]:
    return [ScalarArg(s, _DOCS[s]) for s in symbols]


def _spin_identities(c: sp.Symbol, s: sp.Symbol, w: sp.Expr, J: sp.Matrix) -> None:
    """Prove the identities that remove a steady spin ``S = Rz(w t)`` from ``T``.

    With ``S' = w (d/dc S (-s) + d/ds S c)``: ``S^T S = I``, ``S^T S' = w Z`` (``Z`` the skew
    matrix of the z axis) and ``S J S^T = J`` for the axisymmetric inertia ``J``; all modulo
    ``c^2 + s^2 = 1``.
    """
    S = rot_z(c, s)
    Sd = sp.diff(S, c) * (-w * s) + sp.diff(S, s) * (w * c)
    Z = sp.Matrix([[0, -1, 0], [1, 0, 0], [0, 0, 0]])
    basis = [s**2 + c**2 - 1]
    checks = {
        "S^T S - I": S.T @ S - sp.eye(3),
        "S^T S' - w Z": S.T @ Sd - w * Z,
        "S J S^T - J": S @ J @ S.T - J,
    }
    for name, mat in checks.items():
        for e in mat:
            if sp.reduced(sp.expand(e), basis, s, c)[1] != 0:
                raise AssertionError(f"spin identity {name} = 0 does not hold")


def derive() -> dict[str, sp.Matrix]:
    """Return ``{"M", "G", "K", "F0"}`` as SymPy matrices in the kernel parameters.

    The frame spin ``Sf = Rz(Omega_f t)`` and the wheel spin ``Sw = Rz(s t)`` are factored out
    with identities proved by :func:`_spin_identities`:

        r_c = Sf rho,  |r_c'|^2 = |rho' + Omega_f Z rho|^2,
        A_tot = Sf B Sw,  w_b = Sw^T w',  w' = axial(B^T B' + Omega_f B^T Z B) + s z_hat,
        w_b^T J w_b = w'^T (Sw J Sw^T) w' = w'^T J w',

    with ``rho = X + Rs(RX, RY, RZ) (R0 + A1 u)`` and ``B = Rs(RX, RY, RZ) A1 Rs(rx, ry, rz)``,
    so ``T`` depends on ``q, q'`` only (no explicit time). The algebra runs in a sparse
    polynomial ring (``eps``, coordinates, rates, sin/cos of ``a1``, parameters) for speed.
    """
    c1, s1, cf, sf, cw, sw = sp.symbols("c1 s1 cf sf cw sw", real=True)
    _spin_identities(cf, sf, Omega_f, sp.diag(Id, Id, Ip))
    _spin_identities(cw, sw, omega_s - Omega_f, sp.diag(Id, Id, Ip))

    n = len(COORDINATES)
    eps = sp.Symbol("eps")
    q_sym = sp.symbols(" ".join(COORDINATES), real=True)
    qd_sym = sp.symbols(" ".join(c + "_d" for c in COORDINATES), real=True)
    params = (m, Id, Ip, R0x, R0y, R0z, Omega_f, omega_s)
    # lex order with s1 before c1: division by s1^2 + c1^2 - 1 turns sin^2 into 1 - cos^2.
    ring, *gens = sp.ring((eps, *q_sym, *qd_sym, s1, c1, *params), sp.QQ)
    e, q, qd = gens[0], gens[1 : 1 + n], gens[1 + n : 1 + 2 * n]
    s1_, c1_, m_, Id_, Ip_, R0x_, R0y_, R0z_, Om_, om_ = gens[1 + 2 * n :]
    zero, one = ring.zero, ring.one

    def trunc(p):  # drop the terms above eps**2
        return ring({mon: c for mon, c in p.terms() if mon[0] <= 2})

    def mul(a, b):  # 3x3 @ 3x3 or 3x3 @ 3-vector, truncated
        if not isinstance(b[0], list):
            return [trunc(sum((a[i][k] * b[k] for k in range(3)), zero)) for i in range(3)]
        return [
            [trunc(sum((a[i][k] * b[k][j] for k in range(3)), zero)) for j in range(3)]
            for i in range(3)
        ]

    def ddt(p):  # time derivative along q(t) (the spins are already factored out)
        return sum((p.diff(qi) * qdi for qi, qdi in zip(q, qd, strict=True)), zero)

    def rs2(r):  # Rs(eps r) to eps**2
        (cx, sx), (cy, sy), (cz, sz) = ((1 - e**2 * x**2 / 2, e * x) for x in r)
        rx = [[one, zero, zero], [zero, cx, -sx], [zero, sx, cx]]
        ry = [[cy, zero, sy], [zero, one, zero], [-sy, zero, cy]]
        rz = [[cz, -sz, zero], [sz, cz, zero], [zero, zero, one]]
        return mul(mul(rx, ry), rz)

    Z = [[zero, -one, zero], [one, zero, zero], [zero, zero, zero]]
    A1 = [[c1_, -s1_, zero], [s1_, c1_, zero], [zero, zero, one]]
    Rf, Rl = rs2(q[3:6]), rs2(q[9:12])
    R0 = [R0x_, R0y_, R0z_]

    # Centre of mass in the spinning frame axes and its absolute velocity in those axes.
    local = [R0[i] + x for i, x in enumerate(mul(A1, [e * x for x in q[6:9]]))]
    rho = [e * q[i] + x for i, x in enumerate(mul(Rf, local))]
    v = [ddt(x) + Om_ * z for x, z in zip(rho, mul(Z, rho), strict=True)]
    # Orientation relative to the spinning frame (before the wheel spin) and body rate.
    B = mul(mul(Rf, A1), Rl)
    ZB = mul(Z, B)
    Bdot = [[ddt(B[i][j]) + Om_ * ZB[i][j] for j in range(3)] for i in range(3)]
    W = mul([list(r) for r in zip(*B, strict=True)], Bdot)
    w = [(W[2][1] - W[1][2]) / 2, (W[0][2] - W[2][0]) / 2, (W[1][0] - W[0][1]) / 2 + om_ - Om_]
    T = trunc((m_ * sum(x * x for x in v) + Id_ * (w[0] ** 2 + w[1] ** 2) + Ip_ * w[2] ** 2) / 2)
    T = T.rem([s1_**2 + c1_**2 - 1])

    # T = T0 + eps (F0.q + p0.q') + eps^2 (q'.M.q'/2 + q'.N.q + q.P.q/2): read the forms off.
    M, N, P = (sp.zeros(n, n) for _ in range(3))
    F0 = sp.zeros(n, 1)
    back = {c1: sp.cos(a1), s1: sp.sin(a1)}
    for mon, coeff in sorted(T.terms()):
        iq = [i for i in range(n) for _ in range(mon[1 + i])]
        iqd = [i for i in range(n) for _ in range(mon[1 + n + i])]
        c = ring({(0,) * (1 + 2 * n) + mon[1 + 2 * n :]: coeff}).as_expr().subs(back)
        if mon[0] == 1 and len(iq) == 1:
            F0[iq[0]] += c
        elif len(iqd) == 2:
            M[iqd[0], iqd[1]] += c
            M[iqd[1], iqd[0]] += c
        elif len(iq) == 2:
            P[iq[0], iq[1]] += c
            P[iq[1], iq[0]] += c
        elif len(iq) == 1 and len(iqd) == 1:
            N[iqd[0], iq[0]] += c
    return {
        "M": M.applyfunc(_tidy),
        "G": (N - N.T).applyfunc(_tidy),
        "K": (-P).applyfunc(_tidy),
        "F0": F0.applyfunc(_tidy),
    }


def _tidy(expr: sp.Expr) -> sp.Expr:
    """Collect an entry on the inertia parameters (deterministic, cheap)."""
    expr = sp.expand(expr)
    if expr == 0:
        return sp.S.Zero
    return sp.collect(expr, [m, Id, Ip])


def kernels() -> list[Kernel]:
    """The generated kernels of ``gearmodal/kernels/wheel.py``."""
    mats = derive()
    base = _args(m, Id, Ip, R0x, R0y, R0z, a1)
    rot = _args(m, Id, Ip, R0x, R0y, R0z, a1, Omega_f, omega_s)
    order = ", ".join(COORDINATES)
    return [
        Kernel(
            "wheel_mass",
            base,
            [mats["M"]],
            f"Mass matrix M (12, 12) of a floating-frame wheel (DESIGN 2.1).\n\n"
            f"Coordinates: ({order}); frame translations X, Y, Z and\n"
            "rotations RX, RY, RZ along the frame axes (spinning at Omega_f about global z),\n"
            "local ux, uy, uz, rx, ry, rz along the wheel axes A1 = Rz(a1).",
        ),
        Kernel(
            "wheel_gyroscopic",
            rot,
            [mats["G"]],
            "Gyroscopic/Coriolis matrix G = N - N^T (12, 12), skew (DESIGN 2.1).\n\n"
            "Enters M q'' + G q' + K q = F0 + Q.",
        ),
        Kernel(
            "wheel_centripetal",
            rot,
            [mats["K"]],
            "Centripetal softening K = -d2T/dqdq (12, 12) at q = q' = 0 (DESIGN 2.1).\n\n"
            "Enters M q'' + G q' + K q = F0 + Q; Lin & Parker 1999: -m Omega^2 I on translations.",
        ),
        Kernel(
            "wheel_centrifugal_force",
            rot,
            [mats["F0"]],
            "Centrifugal force F0 = dT/dq (12,) at q = q' = 0 (DESIGN 2.1).\n\n"
            "Right-hand side of M q'' + G q' + K q = F0 + Q.",
        ),
    ]


def generate_source() -> str:
    """Text of ``gearmodal/kernels/wheel.py``."""
    return print_module(SOURCE, DESCRIPTION, kernels())
