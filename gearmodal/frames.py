"""Frames and rotations: where a body's centre is and how its coordinates move its centre, at an
input azimuth (DESIGN 2.1). Used by the assembly and by the coupling of models.

A body's local axes are ``Rz(frame angle + orientation)`` inside its frame, which turns about
global z at ``speed_ratio`` times the input azimuth.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["body_selector", "body_transform", "centre", "rz", "skew"]


def rz(a: float) -> np.ndarray:
    """The 3 x 3 rotation about z by ``a`` (rad)."""
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def skew(a: np.ndarray) -> np.ndarray:
    """[a]x: the matrix of ``a x (.)``."""
    return np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])


def body_transform(model, body, azimuth: float) -> np.ndarray:
    """T (6 x n_b): global (ux, uy, uz, rx, ry, rz) of the body centre from its coordinates.

    The local axes are ``Rz(frame angle + orientation)``; a scaled rotation ``u = r theta``
    contributes ``1/r`` to theta.
    """
    frame = model.frames[body.frame]
    R = rz(frame.speed_ratio * azimuth + body.orientation)
    R6 = np.zeros((6, 6))
    R6[:3, :3] = R
    R6[3:, 3:] = R
    T = R6[:, list(body.local_indices)].copy()
    if body.rotation_scale is not None:
        T[:, -1] /= body.rotation_scale
    return T


def body_selector(body) -> np.ndarray:
    """S (6 x n_b): local 6-vector from the body's coordinates (with the rotation scale)."""
    S = np.eye(6)[:, list(body.local_indices)].copy()
    if body.rotation_scale is not None:
        S[:, -1] /= body.rotation_scale
    return S


def centre(model, body, azimuth: float) -> np.ndarray:
    """Global position (m) of ``body``'s centre at input azimuth ``azimuth`` (rad)."""
    frame = model.frames[body.frame]
    return rz(frame.speed_ratio * azimuth) @ np.asarray(body.position, dtype=float)
