"""Rotation matrices shared by the derivations.

Convention (used everywhere in gearmodal): a small-rotation vector ``r = (rx, ry, rz)`` maps
to the exact rotation ``Rs(r) = Rx(rx) @ Ry(ry) @ Rz(rz)`` of elementary right-handed
rotations, e.g. ``Rz(a) = [[cos a, -sin a, 0], [sin a, cos a, 0], [0, 0, 1]]``.
"""

from __future__ import annotations

from collections.abc import Sequence

import sympy as sp


def rot_x(c: sp.Expr, s: sp.Expr) -> sp.Matrix:
    """Rotation about x given cos and sin of the angle."""
    return sp.Matrix([[1, 0, 0], [0, c, -s], [0, s, c]])


def rot_y(c: sp.Expr, s: sp.Expr) -> sp.Matrix:
    """Rotation about y given cos and sin of the angle."""
    return sp.Matrix([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def rot_z(c: sp.Expr, s: sp.Expr) -> sp.Matrix:
    """Rotation about z given cos and sin of the angle."""
    return sp.Matrix([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def Rz(a: sp.Expr) -> sp.Matrix:
    """Exact rotation about z by the angle ``a``."""
    return rot_z(sp.cos(a), sp.sin(a))


def Rs(r: Sequence[sp.Expr]) -> sp.Matrix:
    """Exact ``Rx(rx) @ Ry(ry) @ Rz(rz)``."""
    rx, ry, rz = r
    return (
        rot_x(sp.cos(rx), sp.sin(rx))
        @ rot_y(sp.cos(ry), sp.sin(ry))
        @ rot_z(sp.cos(rz), sp.sin(rz))
    )
