"""Figures of the paper reproduction: Fig. 3 and the R_length box plot."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from pathfuse.viz.figures import (
    MEAN_PROPS,
    PLANNER_COLOURS,
    boxplot_key,
    draw_astar,
    draw_map,
    plt,
)

__all__ = ["plot_fig3", "plot_r_length"]

_FIG3_ORDER = (("apf", "(a)"), ("astar", "(b)"), ("ref6", "(c)"), ("ref7", "(d)"))


def plot_fig3(results: Mapping[str, Any], seed: int, labels: Mapping[str, str],
              out: str | Path, dpi: int = 120) -> None:
    """The paper's Fig. 3: the fusion path against each reference on the map of ``seed``.

    ``results`` maps planner names to their :class:`~pathfuse.PlanResult` on that map.
    """
    from pathfuse.generate import PAPER_GOAL, PAPER_START, paper_map

    PAPER_LABELS = labels  # noqa: N806
    grid = paper_map(seed)
    fusion = results.get("fusion")
    refs = [(k, tag) for k, tag in _FIG3_ORDER if k in results]
    ncol = 2
    nrow = max(1, (len(refs) + 1) // 2)
    fig, axes = plt.subplots(nrow, ncol, figsize=(10, 5.8 * nrow), squeeze=False)
    for ax in axes.ravel()[len(refs):]:
        ax.axis("off")
    for ax, (name, tag) in zip(axes.ravel(), refs, strict=False):
        draw_map(ax, grid)
        if fusion is not None and "astar_path" in fusion.info:
            draw_astar(ax, np.asarray(fusion.info["astar_path"]), label="A* path (grid)")
        for res in (results[name], fusion):
            if res is None or len(res.path) == 0:
                continue
            p = np.asarray(res.path)
            st = "" if res.success else f", {res.status.name}"
            ax.plot(p[:, 0], p[:, 1], "-", lw=2, color=PLANNER_COLOURS.get(res.planner),
                    label=f"{PAPER_LABELS.get(res.planner, res.planner)}: {res.length:.3f} m{st}")
        ax.plot(*PAPER_START, "o", color="#2ca02c", ms=9, mec="k", zorder=5, label="start")
        ax.plot(*PAPER_GOAL, "*", color="#ffbf00", ms=14, mec="k", zorder=5, label="goal")
        ax.set_title(f"{tag} compared with {PAPER_LABELS.get(name, name)}", fontsize=10)
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.13), ncol=2, fontsize=7,
                  frameon=False)
    fig.suptitle(f"Fusion path against the references, paper-setup map seed {seed}")
    fig.tight_layout()
    fig.savefig(out, dpi=dpi)
    plt.close(fig)


def plot_r_length(r_by_ref: Mapping[str, np.ndarray], n_maps: int, labels: Mapping[str, str],
                  out: str | Path, dpi: int = 120) -> None:
    """Box plot of R_length = (L_fusion - L_ref) / L_ref per reference, in percent."""
    PAPER_LABELS = labels  # noqa: N806

    names = [k for k in r_by_ref if r_by_ref[k].size]
    fig, ax = plt.subplots(figsize=(8, 5.2))
    if names:
        ax.boxplot([100 * r_by_ref[k] for k in names], showmeans=True, meanprops=MEAN_PROPS)
        ax.set_xticks(range(1, len(names) + 1))
        ax.set_xticklabels(
            [f"{PAPER_LABELS.get(k, k)}\n(n={r_by_ref[k].size})" for k in names], fontsize=8)
    ax.axhline(0.0, color="k", lw=0.8, ls="--")
    ax.set_ylabel("R_length = (L_fusion - L_ref) / L_ref  [%]")
    ax.set_title(f"Fusion path length relative to each reference over "
                 f"{n_maps} maps (below 0: fusion shorter)", fontsize=10)
    boxplot_key(fig)
    fig.tight_layout(rect=(0, 0.7 / fig.get_figheight(), 1, 1))
    fig.savefig(out, dpi=dpi)
    plt.close(fig)
