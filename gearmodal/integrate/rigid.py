"""A drivetrain's rigid rotation taken out of state rows: the elastic deflections and rates the
turbine run's and the following stepper's tables hold (their reference rotation is re-based, so
the rigid part of the state is bookkeeping, not deflection)."""

from __future__ import annotations

import numpy as np


def elastic(X: np.ndarray, n: int, r: np.ndarray, Mr: np.ndarray,
            J: float) -> tuple[np.ndarray, np.ndarray]:
    """``(q, v)`` of state rows ``X`` (rows, 2n) with the rigid rotation ``r`` taken out, column
    by column: its amount in each row is ``Mr . q / J`` (``Mr = M r``, ``J = r . M r``, the
    mass-weighted projection), for the rates likewise."""
    parts = []
    for block in (X[:, :n], X[:, n:]):
        phi = block @ (Mr / J)
        e = np.array(block)
        for j in np.flatnonzero(r):
            e[:, j] -= r[j] * phi
        parts.append(e)
    return parts[0], parts[1]
