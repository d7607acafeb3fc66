"""Figures of a BARN study (:mod:`pathfuse.studies.barn`): the planners side by side, and
one world's trajectories.

:func:`plot_barn_planners` draws, per planner (one row each, the first at the top), its
outcomes as a bar split into success, collision and timeout (with the success rate's
95 % Wilson interval) and its mean metric with a 95 % Student-t interval; the
challenge's published baseline sits in its own row below, marked as a reference.
:func:`plot_barn_world` draws one world as small multiples: a panel per planner with its
trajectory bold in its colour, the other planners' faint grey behind it, where it
collided or stopped, the start and the goal with its tolerance circle.

Both take plain values (summary rows, arrays), write one PNG and return the figure.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import numpy as np  # noqa: E402
from matplotlib.backends.backend_agg import FigureCanvasAgg  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.patches import Circle, Patch  # noqa: E402

from pathfuse.grid import GridMap  # noqa: E402
from pathfuse.viz.dynamic import planner_colours  # noqa: E402
from pathfuse.viz.figures import draw_map, map_legend_handles  # noqa: E402

__all__ = ["OUTCOME_COLOURS", "plot_barn_planners", "plot_barn_world"]

#: Bar colours of the three outcomes of the challenge.
OUTCOME_COLOURS = {"success": "#2ca02c", "collision": "#d62728", "timeout": "#a6a6a6"}
_CONTEXT_COLOUR = "#c7c7c7"


def _canvas(width_in: float, height_in: float) -> Figure:
    fig = Figure(figsize=(width_in, height_in))
    FigureCanvasAgg(fig)
    return fig


def plot_barn_planners(
    rows: Sequence[Mapping[str, Any]],
    out: str | Path | None = None,
    *,
    baseline: Mapping[str, Any] | None = None,
    title: str | None = None,
    dpi: int = 120,
) -> Figure:
    """Outcomes and mean metric by planner.

    Parameters
    ----------
    rows : sequence of mapping
        Summary rows of :func:`pathfuse.studies.barn_report.summary_rows` (``planner``,
        ``episodes``, ``success_rate``, ``success_ci_low``, ``success_ci_high``,
        ``collision_rate``, ``timeout_rate``, ``metric_mean``, ``metric_ci_low``,
        ``metric_ci_high``).
    out : str or path, optional
        Save the figure there (PNG).
    baseline : mapping, optional
        A published reference (``planner``, ``success``, ``collision``, ``timeout``,
        ``metric`` as fractions, e.g. :data:`pathfuse.studies.barn.DWA_BASELINE`): one more
        row, hatched, labelled as a reference.
    title : str, optional
        The figure's title.
    dpi : int
        Resolution of the PNG.

    Returns
    -------
    matplotlib.figure.Figure
        Its first two axes are the outcome bars and the metric; their y tick labels
        name the rows (``planner (n=episodes)``, top to bottom).
    """
    labels = [f"{r['planner']} (n={r['episodes']})" for r in rows]
    if baseline:
        labels.append(f"{baseline['planner']}: reference")
    n = len(labels)
    key_in, head_in = 0.6, 0.5 if title else 0.2
    fig = _canvas(11.0, 0.9 + key_in + head_in + 0.34 * max(n, 2))
    ax_o, ax_m = fig.subplots(1, 2, sharey=True, gridspec_kw={"width_ratios": (1.35, 1.0)})
    pos = np.arange(n, 0, -1, dtype=float)  # the first row at the top
    for i, r in enumerate(rows):
        if not r["episodes"]:
            continue
        left = 0.0
        for o in ("success", "collision", "timeout"):
            w = 100 * float(r[f"{o}_rate"])
            ax_o.barh(pos[i], w, left=left, height=0.62, color=OUTCOME_COLOURS[o], lw=0)
            left += w
        s, lo, hi = (100 * float(r[k]) for k in ("success_rate", "success_ci_low",
                                                  "success_ci_high"))
        ax_o.errorbar(s, pos[i], xerr=[[max(s - lo, 0.0)], [max(hi - s, 0.0)]], fmt="none",
                      ecolor="k", elinewidth=1.0, capsize=3, zorder=4)
        m, mlo, mhi = (float(r[k]) for k in ("metric_mean", "metric_ci_low", "metric_ci_high"))
        if np.isfinite(m):
            err = [[max(m - mlo, 0.0)], [max(mhi - m, 0.0)]] if np.isfinite(mlo) else None
            ax_m.errorbar(m, pos[i], xerr=err, fmt="o", color="#1f77b4", ms=5, capsize=3,
                          zorder=4)
    if baseline:
        y = pos[-1]
        left = 0.0
        for o in ("success", "collision", "timeout"):
            w = 100 * float(baseline[o])
            ax_o.barh(y, w, left=left, height=0.62, color=OUTCOME_COLOURS[o], lw=0.8,
                      ec="k", hatch="//", alpha=0.55)
            left += w
        ax_m.plot(float(baseline["metric"]), y, "D", mfc="white", mec="k", ms=6, zorder=4)
        for ax in (ax_o, ax_m):
            ax.axhline(y + 0.5, color="0.5", lw=0.6)
    ax_o.set_yticks(pos)
    ax_o.set_yticklabels(labels, fontsize=8)
    ax_o.set_ylim(0.4, n + 0.6)
    ax_o.set_xlim(0, 100)
    ax_o.set_xlabel("episodes [%]: success | collision | timeout (95% Wilson interval of "
                    "the success rate)", fontsize=8)
    ax_m.set_xlim(-0.01, 0.51)
    ax_m.set_xlabel("mean metric (0 for a failure, at most 0.5), 95% t interval", fontsize=8)
    for ax in (ax_o, ax_m):
        ax.grid(axis="x", alpha=0.3)
        ax.tick_params(labelsize=8)
    handles: list[Any] = [Patch(fc=OUTCOME_COLOURS[o], label=o)
                          for o in ("success", "collision", "timeout")]
    handles.append(Line2D([], [], color="#1f77b4", marker="o", ls="none", label="mean metric"))
    if baseline:
        handles.append(Patch(fc="white", ec="k", hatch="//",
                             label=f"{baseline['planner']}: measured in Gazebo, a reference "
                                   "line, not a like-for-like comparison"))
    fig.legend(handles=handles, loc="lower center", ncol=5 if not baseline else 3,
               fontsize=8, frameon=False, bbox_to_anchor=(0.5, 0.0))
    if title:
        fig.suptitle(title, fontsize=10)
    h = fig.get_figheight()
    fig.tight_layout(rect=(0, key_in / h, 1, 1 - (0.05 if title else 0.0) / h), w_pad=2.0)
    if out is not None:
        fig.savefig(out, dpi=dpi)
    return fig


def plot_barn_world(
    grid: GridMap,
    tracks: Sequence[Mapping[str, Any]],
    out: str | Path | None = None,
    *,
    start: Sequence[float],
    goal: Sequence[float],
    goal_tolerance_m: float,
    robot_radius_m: float = 0.0,
    title: str | None = None,
    ncols: int = 6,
    dpi: int = 110,
) -> Figure:
    """One world's trajectories, a panel per planner.

    Parameters
    ----------
    grid : GridMap
        The world's map (drawn with its c-space margin for ``robot_radius_m``).
    tracks : sequence of mapping
        One per planner, in panel order: ``planner``, ``positions`` ((N, 2) robot
        centres per tick), ``status`` (``success``, ``collision`` or ``timeout``) and
        ``time_s`` (the challenge's time of the episode, or None).
    out : str or path, optional
        Save the figure there (PNG).
    start, goal : (x, y)
        The start and the goal (m); a dotted circle of ``goal_tolerance_m`` around the
        goal marks where it counts as reached.
    goal_tolerance_m : float
        Radius of that circle (m).
    robot_radius_m : float
        The robot disc's radius (m), for the c-space margin.
    title : str, optional
        The figure's title.
    ncols : int
        Panels per row (fewer when there are fewer planners).
    dpi : int
        Resolution of the PNG.

    Returns
    -------
    matplotlib.figure.Figure
        Its first ``len(tracks)`` axes are the panels; each panel's title names its
        planner and outcome.
    """
    names = [str(t["planner"]) for t in tracks]
    colours = planner_colours(names)
    x0, y0, x1, y1 = grid.bounds
    n = max(len(tracks), 1)
    nc = max(1, min(int(ncols), n))
    nr = -(-n // nc)
    panel_w = 2.0
    panel_h = panel_w * (y1 - y0) / (x1 - x0)
    key_cols = 4 if nc >= 4 else 2
    key_in, head_in = (0.65 if key_cols == 4 else 1.2), 0.55 if title else 0.2
    fig = _canvas(max(panel_w * nc + 0.9, 4.8),
                  (panel_h + 0.55) * nr + key_in + head_in + 0.1)
    axes = fig.subplots(nr, nc, sharex=True, sharey=True, squeeze=False)
    drawn: dict[str, bool] = {}
    for i, ax in enumerate(axes.ravel()):
        if i >= len(tracks):
            ax.set_visible(False)
            continue
        t = tracks[i]
        drawn = draw_map(ax, grid, robot_radius_m=robot_radius_m)
        for other in tracks:
            if other is not t:
                p = np.asarray(other["positions"], dtype=float).reshape(-1, 2)
                ax.plot(p[:, 0], p[:, 1], "-", color=_CONTEXT_COLOUR, lw=0.9, zorder=3)
        p = np.asarray(t["positions"], dtype=float).reshape(-1, 2)
        ax.plot(p[:, 0], p[:, 1], "-", color=colours[names[i]], lw=1.8, zorder=4)
        status = str(t["status"])
        if status == "collision":
            ax.plot(*p[-1], "X", color="#ff0000", mec="k", ms=9, zorder=6)
        elif status != "success":
            ax.plot(*p[-1], "s", mfc="white", mec="k", ms=6, zorder=6)
        ax.plot(*start, "o", color="#2ca02c", ms=6, mec="k", zorder=5)
        ax.plot(*goal, "*", color="#ffbf00", ms=11, mec="k", zorder=5)
        ax.add_patch(Circle((float(goal[0]), float(goal[1])), goal_tolerance_m, fill=False,
                            ec="#b08800", lw=0.8, ls=":", zorder=5))
        time_s = t.get("time_s")
        when = f", {float(time_s):.1f} s" if time_s is not None and status != "timeout" else ""
        ax.set_title(f"{names[i]}\n{status}{when}", fontsize=8.5, color=colours[names[i]],
                     pad=3)
        ax.tick_params(labelsize=7)
        row, col = divmod(i, nc)
        ax.set_xlabel("x [m]" if row == nr - 1 or i + nc >= len(tracks) else "", fontsize=7)
        if i + nc >= len(tracks):
            ax.tick_params(labelbottom=True)
        ax.set_ylabel("y [m]" if col == 0 else "", fontsize=7)
    handles = [
        Line2D([], [], color="0.2", lw=1.8, label="the panel's planner"),
        Line2D([], [], color=_CONTEXT_COLOUR, lw=0.9, label="the other planners"),
        Line2D([], [], marker="X", ls="none", color="#ff0000", mec="k", ms=8,
               label="collision"),
        Line2D([], [], marker="s", ls="none", mfc="white", mec="k", ms=6,
               label="stopped: timeout"),
        Line2D([], [], marker="o", ls="none", color="#2ca02c", mec="k", ms=6, label="start"),
        Line2D([], [], marker="*", ls="none", color="#ffbf00", mec="k", ms=9,
               label=f"goal (reached within {goal_tolerance_m:g} m)"),
        *map_legend_handles(drawn, robot_radius_m),
    ]
    fig.legend(handles=handles, loc="lower center", ncol=key_cols, fontsize=8, frameon=False,
               bbox_to_anchor=(0.5, 0.0))
    if title:
        fig.suptitle(title, fontsize=10)
    h = fig.get_figheight()
    fig.tight_layout(rect=(0, key_in / h, 1, 1 - (0.05 if title else 0.0) / h))
    if out is not None:
        fig.savefig(out, dpi=dpi)
    return fig
