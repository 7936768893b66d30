"""Effects measured over paired turbulence seeds, with confidence intervals (issue 22, item 4).

Two variants run on the same seeds (the same turbulence) give per seed ``s`` the ratio
``r_s = a_s / b_s`` of a quantity (a DEL, a 99th-percentile load). Its logarithm removes what
the seed does to both; over ``n`` seeds the effect is the geometric-mean ratio with the
Student-t interval of the mean log ratio::

    d_s = ln(a_s / b_s),   R = exp(mean d),
    [R_lo, R_hi] = exp(mean d -+ t_(1 - alpha/2, n-1) sd(d) / sqrt(n))                   (C1)

A decision (the effect differs from 1) holds when the interval excludes 1. With the spread
seen, the seeds it needs are the smallest ``n`` with ``t_(n-1) sd / sqrt(n) < |mean d|``  (C2).
"""

from __future__ import annotations

import math

import numpy as np

from .errors import ModelError

#: seeds_needed beyond this is reported as NaN (an effect too small to decide)
MAX_SEEDS = 100_000


def paired_ratio(a, b, level: float = 0.95) -> dict:
    """(C1), (C2) for the values ``a`` and ``b`` of two variants on the same seeds (same
    order): ``ratio``, ``low``, ``high`` (NaN with one seed), ``n``, ``differs`` (the
    interval excludes 1), ``seeds_needed`` (C2; NaN when the mean log ratio is 0 or there
    is one seed, or above ``MAX_SEEDS``). Values must be > 0 (a ratio of loads)."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if a.shape != b.shape or a.ndim != 1 or a.size < 1:
        raise ModelError("paired_ratio", "needs two equal-length 1-D sequences (same seeds)")
    if not (0.5 < level < 1.0):
        raise ModelError("level", f"= {level!r}: a confidence level between 0.5 and 1")
    if np.any(~np.isfinite(a) | ~np.isfinite(b)) or np.any(a <= 0) or np.any(b <= 0):
        nan = math.nan
        return {"ratio": nan, "low": nan, "high": nan, "n": int(a.size), "differs": False,
                "seeds_needed": nan}
    d = np.log(a / b)
    n = d.size
    mean = float(d.mean())
    if n < 2:
        return {"ratio": math.exp(mean), "low": math.nan, "high": math.nan, "n": 1,
                "differs": False, "seeds_needed": math.nan}
    sd = float(d.std(ddof=1))
    from scipy import stats  # loaded when needed (scipy.stats: 30 MB of a process)

    half = float(stats.t.ppf(0.5 + level / 2, n - 1)) * sd / math.sqrt(n)
    need = math.nan
    if mean != 0.0:
        # t_(k-1) > z, so no k below (z sd / mean)^2 decides: search up from there
        z = float(stats.norm.ppf(0.5 + level / 2))
        k = max(2, int((z * sd / abs(mean)) ** 2))
        while k <= MAX_SEEDS:
            if float(stats.t.ppf(0.5 + level / 2, k - 1)) * sd / math.sqrt(k) < abs(mean):
                need = k
                break
            k += 1
    return {"ratio": math.exp(mean), "low": math.exp(mean - half), "high": math.exp(mean + half),
            "n": n, "differs": bool(mean - half > 0 or mean + half < 0), "seeds_needed": need}


def paired_effects(runs, effects, level: float = 0.95):
    """Each effect over the seeds both variants ran: ``runs`` a table with columns ``case``,
    ``seed`` and the quantities; ``effects`` ``[(variant, against, [quantity, ...]), ...]``.
    Returns a DataFrame, one row per effect and quantity: ``effect`` ("variant / against"),
    ``quantity`` and :func:`paired_ratio`'s columns."""
    import pandas as pd

    rows = []
    for var, base, quantities in effects:
        a = runs[runs.case == var].set_index("seed").sort_index()
        b = runs[runs.case == base].set_index("seed").sort_index()
        seeds = a.index.intersection(b.index)
        for q in quantities:
            r = paired_ratio(a.loc[seeds, q], b.loc[seeds, q], level)
            rows.append({"effect": f"{var} / {base}", "quantity": q, **r})
    return pd.DataFrame(rows)
