"""The dynamic benchmark's figure: success rate against the number of moving discs, one
panel per planner; and a distinct colour per online planner (:func:`planner_colours`)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import numpy as np  # noqa: E402
from matplotlib.backends.backend_agg import FigureCanvasAgg  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

__all__ = ["ONLINE_COLOURS", "planner_colours", "plot_success_vs_moving"]

#: Line colours of the online planners (benchmark figure, animation title).
ONLINE_COLOURS = {
    "fusion": "#d62728",
    "apf": "#ff7f0e",
    "astar": "#1f77b4",
    "astar-replan": "#17becf",
    "ref6": "#2ca02c",
    "ref7": "#9467bd",
}
#: Colours for planners without an entry in ONLINE_COLOURS, in the order they are handed out.
_FALLBACK_COLOURS = ("#8c564b", "#e377c2", "#bcbd22", "#000000", "#393b79", "#00665e",
                     "#e7ba52", "#7b4173", "#637939", "#7f7f7f")
#: The other planners, drawn faint behind each panel's own.
_CONTEXT_COLOUR = "#c7c7c7"


def planner_colours(names: Sequence[str]) -> dict[str, str]:
    """A colour per planner: ONLINE_COLOURS' when it has one and no earlier planner took
    it, else the first fallback colour no planner has yet (distinct for up to 16
    planners; beyond that the fallbacks repeat).

    >>> planner_colours(["fusion", "dwa", "mppi"])
    {'fusion': '#d62728', 'dwa': '#8c564b', 'mppi': '#e377c2'}
    """
    out: dict[str, str] = {}
    for name in names:
        c = ONLINE_COLOURS.get(name)
        if c is not None and c not in out.values():
            out[name] = c
    spare = [c for c in _FALLBACK_COLOURS if c not in out.values()] or list(_FALLBACK_COLOURS)
    i = 0
    for name in names:
        if name not in out:
            out[name] = spare[i % len(spare)]
            i += 1
    return out


def plot_success_vs_moving(
    rows: Sequence[Mapping[str, Any]],
    out: str | Path | None = None,
    *,
    title: str | None = None,
    dpi: int = 120,
    ncols: int = 4,
) -> Figure:
    """Success rate (with its 95 % Wilson interval) against the number of moving discs,
    as small multiples: one panel per planner.

    Each panel draws its planner's rates as a line with the Wilson interval shaded
    around it, and the other planners' lines faint grey behind it for comparison; the
    panels share their axes (the same scale everywhere).  The key sits under the
    panels, never over a point.

    Parameters
    ----------
    rows : sequence of mapping
        Summary rows of :func:`pathfuse.studies.dynamic.summary_rows` (keys
        ``planner``, ``moving``, ``reached_rate``, ``reached_ci_low``,
        ``reached_ci_high``); planners in order of first appearance.
    out : str or path, optional
        Save the figure there (PNG).
    title : str, optional
        The figure's title, above the panels.
    dpi : int
        Resolution of the PNG.
    ncols : int
        Panels per row (fewer when there are fewer planners).

    Returns
    -------
    matplotlib.figure.Figure
        The figure; its first ``len(planners)`` axes are the panels, in planner order.
    """
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    planners: list[str] = []
    for r in rows:
        if r["planner"] not in planners:
            planners.append(r["planner"])
    moving = sorted({int(r["moving"]) for r in rows})
    colours = planner_colours(planners)
    series: dict[str, tuple[np.ndarray, ...]] = {}
    for name in planners:
        rs = sorted((r for r in rows if r["planner"] == name), key=lambda r: int(r["moving"]))
        x = np.array([int(r["moving"]) for r in rs], dtype=float)
        y = 100 * np.array([float(r["reached_rate"]) for r in rs])
        # an interval end that rounding put a hair beyond the rate is drawn at the rate
        lo = np.minimum(100 * np.array([float(r["reached_ci_low"]) for r in rs]), y)
        hi = np.maximum(100 * np.array([float(r["reached_ci_high"]) for r in rs]), y)
        series[name] = (x, y, lo, hi)
    n = max(len(planners), 1)
    nc = max(1, min(int(ncols), n))
    nr = -(-n // nc)
    key_in, head_in = 0.35, 0.45 if title else 0.15
    fig = Figure(figsize=(2.45 * nc + 0.6, 1.95 * nr + key_in + head_in + 0.35))
    FigureCanvasAgg(fig)
    axes = fig.subplots(nr, nc, sharex=True, sharey=True, squeeze=False)
    for i, ax in enumerate(axes.ravel()):
        if i >= len(planners):
            ax.set_visible(False)
            continue
        name = planners[i]
        for other in planners:
            if other != name:
                ax.plot(series[other][0], series[other][1], "-", color=_CONTEXT_COLOUR,
                        lw=0.9, zorder=1)
        x, y, lo, hi = series[name]
        if x.size > 1:
            ax.fill_between(x, lo, hi, color=colours[name], alpha=0.18, lw=0, zorder=2)
        else:  # one disc count: no band to shade, the interval as a bar
            ax.errorbar(x, y, yerr=np.vstack([y - lo, hi - y]), fmt="none", capsize=3,
                        color=colours[name], alpha=0.6, zorder=2)
        ax.plot(x, y, "-o", color=colours[name], ms=3.5, lw=1.6, zorder=3)
        ax.set_title(name, fontsize=9, pad=3)
        ax.grid(alpha=0.3)
        ax.tick_params(labelsize=8)
        ax.set_xticks(moving)
        ax.set_ylim(-3, 103)
        ax.set_yticks([0, 50, 100])
        row, col = divmod(i, nc)
        if col == 0:
            ax.set_ylabel("success [%]", fontsize=8)
        if row == nr - 1 or i + nc >= len(planners):  # the lowest panel of its column
            ax.tick_params(labelbottom=True)
            ax.set_xlabel("moving discs", fontsize=8)
    handles: list[Any] = [
        (Patch(fc="0.35", alpha=0.25, lw=0), Line2D([], [], color="0.2", marker="o", ms=3.5)),
        Line2D([], [], color=_CONTEXT_COLOUR, lw=0.9),
    ]
    from matplotlib.legend_handler import HandlerTuple

    fig.legend(handles, ["the panel's planner: success rate, 95% Wilson interval shaded",
                         "the other planners"], loc="lower center", ncol=2, fontsize=8,
               frameon=False, bbox_to_anchor=(0.5, 0.0), handler_map={tuple: HandlerTuple()})
    if title:
        fig.suptitle(title, fontsize=10)
    h = fig.get_figheight()
    fig.tight_layout(rect=(0, key_in / h, 1, 1 - (0.1 if title else 0.0) / h), h_pad=0.6)
    if out is not None:
        fig.savefig(out, dpi=dpi)
    return fig
