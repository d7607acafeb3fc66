"""Static figures of maps and planned paths (matplotlib, Agg backend).

What a plan figure shows, and its legend (below the map, never over it) says:

* free cells white, occupied cells black;
* **unknown** cells of a ROS map mid grey when blocked (the default: a robot
  does not plan through unexplored space), light grey when ``unknown="free"``;
  the view is cropped to the known part of the map (with the start and goal);
* with a robot radius, the **c-space margin**: free cells that the disc robot's
  centre cannot occupy (obstacles and the map's edge grown by the radius,
  ``GridMap.cspace``), shaded orange;
* the global A* path as a thin dashed line (its points as dots only when they
  are few enough to be seen apart), and each planner's path as a solid line.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from pathfuse.grid import GridMap  # noqa: E402
from pathfuse.result import PlanResult  # noqa: E402

__all__ = ["draw_map", "plot_plan", "map_legend_handles", "draw_astar", "PLANNER_COLOURS",
           "legend_below", "boxplot_key", "MEAN_PROPS"]

MEAN_PROPS: dict[str, Any] = {"marker": "^", "markerfacecolor": "#d62728",
                              "markeredgecolor": "#d62728", "markersize": 6}
"""How every box plot draws its mean (``boxplot(..., showmeans=True, meanprops=MEAN_PROPS)``)."""

PLANNER_COLOURS = {
    "astar": "#1f77b4",
    "apf": "#ff7f0e",
    "fusion": "#d62728",
    "ref6": "#2ca02c",
    "ref7": "#9467bd",
}

CSPACE_COLOUR = "#f4a261"
UNKNOWN_BLOCKED_GREY = 0.55
UNKNOWN_FREE_GREY = 0.85


def _unknown(grid: GridMap) -> np.ndarray | None:
    unk = grid.meta.get("unknown")
    if unk is None or np.shape(unk) != grid.shape or not np.any(unk):
        return None
    return np.asarray(unk, dtype=bool)


def draw_map(ax: Any, grid: GridMap, *, unknown: bool = True, robot_radius_m: float = 0.0,
             crop: bool = False, keep: Sequence[Sequence[float]] = ()) -> dict[str, bool]:
    """Draw ``grid`` on ``ax`` in world coordinates: obstacles black, free white.

    Row 0 is drawn at the bottom (``origin="lower"``), so the picture matches
    the world frame.  Unknown cells (ROS maps) are drawn grey when present
    (mid grey when blocked, light grey when planned through); with
    ``robot_radius_m`` > 0 the c-space margin (free cells the robot's centre
    cannot reach) is shaded orange.  ``crop`` limits the view to
    the known part of the map plus the points ``keep``.  Returns which layers
    were drawn (``unknown_blocked``, ``unknown_free``, ``cspace``) for
    :func:`map_legend_handles`.
    """
    x0, y0, x1, y1 = grid.bounds
    img = np.where(grid.occupied, 0.0, 1.0)
    unk = _unknown(grid) if unknown else None
    if unk is not None:
        img = np.where(unk & ~grid.occupied, UNKNOWN_FREE_GREY, img)
        img = np.where(unk & grid.occupied, UNKNOWN_BLOCKED_GREY, img)
    ax.imshow(
        img, cmap="gray", vmin=0.0, vmax=1.0, origin="lower", extent=(x0, x1, y0, y1),
        interpolation="nearest",
    )
    drawn = {"unknown_blocked": unk is not None and bool((unk & grid.occupied).any()),
             "unknown_free": unk is not None and bool((unk & ~grid.occupied).any()),
             "cspace": False}
    if robot_radius_m > 0:
        margin = grid.cspace(robot_radius_m).occupied & ~grid.occupied
        if unk is not None:
            margin &= ~unk
        if margin.any():
            rgba = np.zeros((*grid.shape, 4))
            rgba[margin] = matplotlib.colors.to_rgba(CSPACE_COLOUR, 0.75)
            ax.imshow(rgba, origin="lower", extent=(x0, x1, y0, y1), interpolation="nearest")
            drawn["cspace"] = True
    lim = (x0, y0, x1, y1)
    if crop and unk is not None:
        lim = _known_box(grid, unk, keep)
    ax.set_xlim(lim[0], lim[2])
    ax.set_ylim(lim[1], lim[3])
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    return drawn


def _known_box(grid: GridMap, unk: np.ndarray, keep: Sequence[Sequence[float]]
               ) -> tuple[float, float, float, float]:
    rows, cols = np.nonzero(~unk)
    if rows.size == 0:
        return grid.bounds
    res, (ox, oy) = grid.resolution, grid.origin
    bx0, bx1 = ox + cols.min() * res, ox + (cols.max() + 1) * res
    by0, by1 = oy + rows.min() * res, oy + (rows.max() + 1) * res
    for p in keep:
        bx0, bx1 = min(bx0, p[0]), max(bx1, p[0])
        by0, by1 = min(by0, p[1]), max(by1, p[1])
    pad = 0.05 * max(bx1 - bx0, by1 - by0) + 2 * res
    x0, y0, x1, y1 = grid.bounds
    return max(x0, bx0 - pad), max(y0, by0 - pad), min(x1, bx1 + pad), min(y1, by1 + pad)


def map_legend_handles(drawn: dict[str, bool], robot_radius_m: float = 0.0) -> list[Any]:
    """Legend entries explaining the map's layers (occupied, unknown, c-space margin)."""
    from matplotlib.patches import Patch

    out = [Patch(facecolor="black", edgecolor="black", label="occupied")]
    if drawn.get("unknown_blocked"):
        out.append(Patch(facecolor=str(UNKNOWN_BLOCKED_GREY), edgecolor="0.4",
                         label="unknown, blocked (the default)"))
    if drawn.get("unknown_free"):
        out.append(Patch(facecolor=str(UNKNOWN_FREE_GREY), edgecolor="0.5",
                         label="unknown, planned through (unknown='free')"))
    if drawn.get("cspace"):
        out.append(Patch(facecolor=CSPACE_COLOUR, edgecolor=CSPACE_COLOUR, alpha=0.75,
                         label=f"c-space margin: {robot_radius_m:g} m robot radius"))
    return out


def draw_astar(ax: Any, points: np.ndarray, label: str = "A* path (grid)") -> None:
    """The global A* path: a thin dashed line, with dots when its points are few enough to
    be told apart (on fine ROS maps they would merge into a thick band)."""
    a = np.asarray(points, dtype=float).reshape(-1, 2)
    if not len(a):
        return
    ax.plot(a[:, 0], a[:, 1], "--", color="#1f77b4", lw=1.2, alpha=0.9, label=label, zorder=3)
    x0, x1 = ax.get_xlim()
    y0, y1 = ax.get_ylim()
    step = np.hypot(*np.diff(a, axis=0).T).mean() if len(a) > 1 else 0.0
    if len(a) <= 80 and step >= 0.012 * max(x1 - x0, y1 - y0):
        ax.plot(a[:, 0], a[:, 1], ".", color="#1f77b4", ms=5, alpha=0.8, zorder=3)


def legend_below(ax: Any, handles: Sequence[Any] | None = None, ncol: int = 3,
                 fontsize: float = 8) -> None:
    """A legend under the axes (outside the map), in ``ncol`` columns."""
    if handles is None:
        handles, _ = ax.get_legend_handles_labels()
    ax.legend(handles=list(handles), loc="upper center", bbox_to_anchor=(0.5, -0.12),
              ncol=ncol, fontsize=fontsize, frameon=False)


def boxplot_key(fig: Any, fontsize: float = 8) -> Any:
    """A key under the figure that says what the parts of its box plots mean."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    handles = [
        Patch(facecolor="white", edgecolor="k", label="box: middle 50 % (quartiles)"),
        Line2D([], [], color="#ff7f0e", label="line: median"),
        Line2D([], [], ls="none", marker="^", mfc=MEAN_PROPS["markerfacecolor"],
               mec=MEAN_PROPS["markeredgecolor"], ms=MEAN_PROPS["markersize"], label="mean"),
        Line2D([], [], color="k", marker="|", ms=8, label="whiskers: last value within "
               "1.5 IQR of the box"),
        Line2D([], [], ls="none", marker="o", mfc="none", mec="k", ms=4,
               label="beyond the whiskers"),
    ]
    return fig.legend(handles=handles, loc="lower center", ncol=3, fontsize=fontsize,
                      frameon=False, bbox_to_anchor=(0.5, 0.0))


def _draw_result(ax: Any, result: PlanResult, colour: str | None, label: str | None) -> None:
    p = np.asarray(result.path)
    if p.shape[0] == 0:
        return
    status = "" if result.success else f" ({result.status.name})"
    lab = label or f"{result.planner}: {result.length:.3f} m{status}"
    ax.plot(p[:, 0], p[:, 1], "-", color=colour, lw=1.8, label=lab, zorder=4)


def plot_plan(
    grid: GridMap,
    results: PlanResult | Sequence[PlanResult],
    start: Sequence[float],
    goal: Sequence[float],
    out: str | Path | None = None,
    *,
    title: str | None = None,
    astar_points: np.ndarray | None = None,
    robot_radius_m: float = 0.0,
    dpi: int = 120,
):
    """Draw one or several plans on their map; save to ``out`` (PNG) when given.

    The legend sits below the map and explains its layers (unknown cells, the
    c-space margin of a ``robot_radius_m`` > 0).  Returns the matplotlib
    Figure (closed after saving when ``out`` is given).
    """
    if isinstance(results, PlanResult):
        results = [results]
    fig, ax = plt.subplots(figsize=(7.0, 7.6))
    drawn = draw_map(ax, grid, robot_radius_m=robot_radius_m, crop=True, keep=(start, goal))
    if astar_points is not None and len(astar_points):
        draw_astar(ax, astar_points)
    for r in results:
        _draw_result(ax, r, PLANNER_COLOURS.get(r.planner), None)
    ax.plot(*start, "o", color="#2ca02c", ms=9, mec="k", label="start", zorder=5)
    ax.plot(*goal, "*", color="#ffbf00", ms=14, mec="k", label="goal", zorder=5)
    handles, _ = ax.get_legend_handles_labels()
    legend_below(ax, [*handles, *map_legend_handles(drawn, robot_radius_m)])
    if title:
        ax.set_title(title, fontsize=10)
    fig.tight_layout()
    if out is not None:
        fig.savefig(out, dpi=dpi, bbox_inches="tight")
        plt.close(fig)
    return fig
