"""The exact peaks' building blocks (gearmodal/integrate/peaks.py and the kernel's poly_max)."""

import math

import numpy as np
import pytest

import gearmodal as gm
from gearmodal.integrate.peaks import PeakTracker
from gearmodal.integrate.system import PiecewiseLinearSystem
from gearmodal.integrate.taylor import DEPTH, poly_max


def series(rng, n):
    """Scaled Taylor coefficients like a piece's: three modes of up to 8 rad over [0, 1]."""
    k = np.arange(n)
    fact = np.array([float(math.factorial(int(x))) for x in k])
    c = np.zeros(n)
    for _ in range(3):
        A, w, ph = rng.normal(), rng.uniform(0, 8), rng.uniform(0, 6.3)
        c += A * np.real(np.exp(1j * ph) * (1j * w) ** k / fact)
    c[0] += 3 * rng.normal()
    return c


def test_poly_max_finds_the_maximum_of_random_series():
    """Against the polynomial sampled 20 001 times: never below the samples (a maximum missed
    shows as one), above them by at most the sampling's own miss (curvature 8^2 times the
    amplitude, half a sample step squared over 2: 1e-8); with a threshold, only maxima above
    it are reported (else a value at most the threshold). 1 000 series, including the case a
    first version missed: a search starting where its function was positive."""
    rng = np.random.default_rng(1)
    for _ in range(1000):
        n = int(rng.integers(5, 41))
        c = series(rng, n)
        b = rng.uniform(0.3, 1.0)
        a = 0.0 if rng.uniform() < 0.5 else rng.uniform(0.0, 0.9 * b)  # a bin's later part
        thr = -np.inf if rng.uniform() < 0.5 else rng.normal()
        v, t = poly_max(c, a, b, thr, np.zeros(n), np.zeros(n),
                        np.empty((DEPTH + 5) * n), np.empty((2, DEPTH + 1)),
                        np.zeros(7, dtype=np.int64))
        assert a <= t <= b
        x = np.linspace(a, b, 20001)
        p = np.polynomial.polynomial.polyval(x, c)
        scale = np.abs(c).sum()
        assert p.max() <= max(v, thr) + 1e-12 * scale
        if p.max() > thr:
            assert v - p.max() <= 1e-8 * scale
            assert np.polynomial.polynomial.polyval(t, c) == pytest.approx(v, abs=1e-12 * scale)


def test_tracker_watches_the_planet_bearings_radial_forces():
    stage = gm.load("studies/models/planetary_clearance.toml")
    tr = PeakTracker(PiecewiseLinearSystem(stage.assemble()))
    assert tr.channels == [f"planet{i}_bearing.radial" for i in (1, 2, 3)]
    assert len(tr.names) == len(stage.assemble().contacts.element)
    with pytest.raises(gm.ModelError, match="peak_bin"):
        PeakTracker(PiecewiseLinearSystem(stage.assemble()), 0.0)
