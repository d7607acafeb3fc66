"""Small statistics and table helpers shared by the benchmarks.

* :func:`mean_ci` - a mean with its Student-t confidence interval;
* :func:`bootstrap_mean_ci` - a mean with a seeded percentile-bootstrap interval, which
  stays within the range of the data (a time's interval never goes below zero);
* :func:`wilson_ci` - a success rate with its Wilson score interval;
* :func:`markdown_table` - a list of rows as a GitHub Markdown table;
* :func:`write_csv` - dict rows (or plain rows) to a CSV file.

Used by the study engine (:mod:`pathfuse.bench.summary`) and its presets.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["mean_ci", "bootstrap_mean_ci", "wilson_ci", "markdown_table", "write_csv", "counted"]


def mean_ci(values: Sequence[float], level: float = 0.95) -> tuple[float, float, float]:
    """Mean and Student-t confidence interval of the mean: (mean, low, high).

    NaN for an empty sample; a zero-width interval for one value.

    >>> m, lo, hi = mean_ci([1.0, 2.0, 3.0])
    >>> m, round(lo, 3), round(hi, 3)
    (2.0, -0.484, 4.484)
    """
    x = np.asarray(values, dtype=float)
    if x.size == 0:
        return (math.nan, math.nan, math.nan)
    m = float(x.mean())
    if x.size == 1:
        return (m, m, m)
    from scipy.special import stdtrit  # what scipy.stats.t.ppf computes, without importing
    # scipy.stats (over a second)

    half = float(stdtrit(x.size - 1, 0.5 + level / 2) * x.std(ddof=1) / math.sqrt(x.size))
    return (m, m - half, m + half)


def bootstrap_mean_ci(values: Sequence[float], level: float = 0.95, n_boot: int = 2000,
                      seed: int = 0) -> tuple[float, float, float]:
    """Mean and percentile-bootstrap confidence interval of the mean: (mean, low, high).

    ``n_boot`` resamples with replacement, drawn from ``numpy.random.default_rng(seed)``, so
    the same values always give the same interval.  The ends are means of resamples, so they
    lie within the range of the data: the interval of a positive quantity (a time) never
    goes below zero, unlike the Student-t interval of a skewed sample.  NaN for an empty
    sample; a zero-width interval for one value.

    Examples
    --------
    >>> times = [0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 20.0]   # skewed, like timings
    >>> round(mean_ci(times)[1], 2) < 0 < bootstrap_mean_ci(times)[1]
    True
    >>> [round(v, 3) for v in bootstrap_mean_ci(times)]
    [2.09, 0.1, 6.07]
    """
    x = np.asarray(values, dtype=float)
    if x.size == 0:
        return (math.nan, math.nan, math.nan)
    m = float(x.mean())
    if x.size == 1:
        return (m, m, m)
    rng = np.random.default_rng(seed)
    means = np.empty(n_boot)
    chunk = max(1, min(n_boot, 2_000_000 // x.size))  # bounded memory for large groups
    for i in range(0, n_boot, chunk):
        k = min(chunk, n_boot - i)
        means[i:i + k] = x[rng.integers(0, x.size, size=(k, x.size))].mean(axis=1)
    lo, hi = np.quantile(means, [0.5 - level / 2, 0.5 + level / 2])
    return (m, float(lo), float(hi))


def wilson_ci(successes: int, n: int, level: float = 0.95) -> tuple[float, float, float]:
    """Success rate with a Wilson score interval: (rate, low, high).

    NaN for ``n == 0``.

    Examples
    --------
    >>> [round(v, 4) for v in wilson_ci(95, 100)]
    [0.95, 0.8882, 0.9785]
    >>> wilson_ci(0, 50)[:2], wilson_ci(50, 50)[::2]
    ((0.0, 0.0), (1.0, 1.0))
    """
    if n == 0:
        return (math.nan, math.nan, math.nan)
    from scipy.special import ndtri  # = scipy.stats.norm.ppf

    z = float(ndtri(0.5 + level / 2))
    p = successes / n
    den = 1 + z * z / n
    centre = (p + z * z / (2 * n)) / den
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / den
    # the interval reaches 0 (1) exactly when there are no successes (failures); rounding
    # in centre -/+ half would leave a 1e-17 gap
    low = 0.0 if successes == 0 else max(0.0, centre - half)
    high = 1.0 if successes == n else min(1.0, centre + half)
    return (p, low, high)


def markdown_table(table: Sequence[Sequence[Any]]) -> str:
    """A GitHub Markdown table; ``table[0]`` is the header row.

    >>> print(markdown_table([["a", "b"], [1, 2]]))
    | a | b |
    |---|---|
    | 1 | 2 |
    """
    out = ["| " + " | ".join(str(c) for c in table[0]) + " |", "|" + "---|" * len(table[0])]
    out += ["| " + " | ".join(str(c) for c in row) + " |" for row in table[1:]]
    return "\n".join(out)


def write_csv(path: str | Path, rows: Sequence[dict[str, Any]] | Sequence[Sequence[Any]]) -> None:
    """Write dict rows (header = the first row's keys) or plain rows to ``path``."""
    with open(path, "w", newline="") as fh:
        if rows and isinstance(rows[0], dict):
            w = csv.DictWriter(fh, fieldnames=list(rows[0]))
            w.writeheader()
            w.writerows(rows)  # type: ignore[arg-type]
        else:
            csv.writer(fh).writerows(rows)  # type: ignore[arg-type]


def counted(n: int, noun: str, plural: str | None = None) -> str:
    """``n`` and ``noun``, plural (``plural``, default ``noun + "s"``) unless ``n`` is 1.

    >>> counted(1, "run"), counted(0, "run"), counted(3, "episode"), counted(1, "disc count")
    ('1 run', '0 runs', '3 episodes', '1 disc count')
    """
    return f"{n} {noun if n == 1 else (plural or noun + 's')}"
