"""Static figures of maps and planned paths (matplotlib, Agg backend)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from pathfuse.grid import GridMap  # noqa: E402
from pathfuse.result import PlanResult  # noqa: E402

__all__ = ["draw_map", "plot_plan", "PLANNER_COLOURS"]

PLANNER_COLOURS = {
    "astar": "#1f77b4",
    "apf": "#ff7f0e",
    "fusion": "#d62728",
    "ref6": "#2ca02c",
    "ref7": "#9467bd",
}


def draw_map(ax, grid: GridMap, *, unknown: bool = True) -> None:
    """Draw ``grid`` on ``ax`` in world coordinates: obstacles black, free white.

    Row 0 is drawn at the bottom (``origin="lower"``), so the picture matches
    the world frame; unknown cells (ROS maps) are drawn grey when present.
    """
    x0, y0, x1, y1 = grid.bounds
    img = np.where(grid.occupied, 0.0, 1.0)
    unk = grid.meta.get("unknown") if unknown else None
    if unk is not None and np.shape(unk) == grid.shape:
        img = np.where(np.asarray(unk) & ~grid.occupied, 0.8, img)
        img = np.where(np.asarray(unk) & grid.occupied, 0.45, img)
    ax.imshow(
        img, cmap="gray", vmin=0.0, vmax=1.0, origin="lower", extent=(x0, x1, y0, y1),
        interpolation="nearest",
    )
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")


def _draw_result(ax, result: PlanResult, colour: str | None, label: str | None) -> None:
    p = np.asarray(result.path)
    if p.shape[0] == 0:
        return
    status = "" if result.success else f" ({result.status.name})"
    lab = label or f"{result.planner}: {result.length:.3f} m{status}"
    ax.plot(p[:, 0], p[:, 1], "-", color=colour, lw=1.8, label=lab)


def plot_plan(
    grid: GridMap,
    results: PlanResult | Sequence[PlanResult],
    start: Sequence[float],
    goal: Sequence[float],
    out: str | Path | None = None,
    *,
    title: str | None = None,
    astar_points: np.ndarray | None = None,
    dpi: int = 120,
):
    """Draw one or several plans on their map; save to ``out`` (PNG) when given.

    Returns the matplotlib Figure (closed after saving when ``out`` is given).
    """
    if isinstance(results, PlanResult):
        results = [results]
    w, h = grid.bounds[2] - grid.bounds[0], grid.bounds[3] - grid.bounds[1]
    scale = 6.0 / max(w, h)
    fig, ax = plt.subplots(figsize=(max(3.0, w * scale) + 1.5, max(3.0, h * scale) + 0.8))
    draw_map(ax, grid)
    if astar_points is not None and len(astar_points):
        a = np.asarray(astar_points)
        ax.plot(a[:, 0], a[:, 1], ".", color="#1f77b4", ms=5, alpha=0.7, label="A* points")
    for r in results:
        _draw_result(ax, r, PLANNER_COLOURS.get(r.planner), None)
    ax.plot(*start, "o", color="#2ca02c", ms=9, mec="k", label="start", zorder=5)
    ax.plot(*goal, "*", color="#ffbf00", ms=14, mec="k", label="goal", zorder=5)
    ax.legend(loc="upper left", fontsize=8, framealpha=0.9)
    if title:
        ax.set_title(title, fontsize=10)
    fig.tight_layout()
    if out is not None:
        fig.savefig(out, dpi=dpi)
        plt.close(fig)
    return fig
