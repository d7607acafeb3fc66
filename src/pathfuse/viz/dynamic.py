"""The dynamic benchmark's figure: success rate against the number of moving discs."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import numpy as np  # noqa: E402
from matplotlib.backends.backend_agg import FigureCanvasAgg  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

__all__ = ["ONLINE_COLOURS", "plot_success_vs_moving"]

#: Line colours of the online planners (benchmark figure, animation title).
ONLINE_COLOURS = {
    "fusion": "#d62728",
    "apf": "#ff7f0e",
    "astar-follow": "#1f77b4",
    "astar": "#1f77b4",
    "astar-replan": "#17becf",
    "ref6": "#2ca02c",
    "ref7": "#9467bd",
}
_FALLBACK_COLOURS = ("#8c564b", "#e377c2", "#7f7f7f", "#bcbd22", "#000000")


def plot_success_vs_moving(
    rows: Sequence[Mapping[str, Any]],
    out: str | Path | None = None,
    *,
    title: str | None = None,
    dpi: int = 120,
) -> Figure:
    """Success rate (with its 95 % Wilson interval) against the number of moving discs.

    ``rows`` are summary rows of :func:`pathfuse.studies.dynamic.summary_rows` (keys
    ``planner``, ``moving``, ``reached_rate``, ``reached_ci_low``,
    ``reached_ci_high``); one line per planner, the points of different
    planners nudged sideways so their error bars do not overlap.  Saved to
    ``out`` (PNG) when given.
    """
    planners: list[str] = []
    for r in rows:
        if r["planner"] not in planners:
            planners.append(r["planner"])
    moving = sorted({int(r["moving"]) for r in rows})
    gaps = np.diff(moving) if len(moving) > 1 else np.array([1.0])
    nudge = 0.08 * float(gaps.min()) if gaps.size else 0.08
    fig = Figure(figsize=(6.4, 4.8))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(1, 1, 1)
    for i, name in enumerate(planners):
        rs = sorted((r for r in rows if r["planner"] == name), key=lambda r: int(r["moving"]))
        x = np.array([int(r["moving"]) for r in rs], dtype=float)
        x = x + (i - (len(planners) - 1) / 2) * nudge
        y = np.array([float(r["reached_rate"]) for r in rs])
        lo = np.array([float(r["reached_ci_low"]) for r in rs])
        hi = np.array([float(r["reached_ci_high"]) for r in rs])
        colour = ONLINE_COLOURS.get(name, _FALLBACK_COLOURS[i % len(_FALLBACK_COLOURS)])
        yerr = np.clip(100 * np.vstack([y - lo, hi - y]), 0.0, None)  # no -1e-15 from rounding
        ax.errorbar(x, 100 * y, yerr=yerr, fmt="-o", ms=4,
                    capsize=3, lw=1.5, color=colour, label=name)
    ax.set_xticks(moving)
    ax.set_xlabel("moving obstacles per scenario")
    ax.set_ylabel("success rate [%] (95% Wilson CI)")
    ax.set_ylim(-3, 103)
    ax.grid(alpha=0.3)
    # below the axes, never over the points (apf's low rates sit in the lower left)
    ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.16),
              ncol=min(len(planners), 4) or 1, frameon=False)
    if title:
        ax.set_title(title, fontsize=10)
    fig.tight_layout()
    if out is not None:
        fig.savefig(out, dpi=dpi, bbox_inches="tight")
    return fig
