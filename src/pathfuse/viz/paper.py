"""Figures of the paper reproduction: Fig. 3 and the R_length box plot."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from pathfuse.viz.figures import PLANNER_COLOURS, draw_astar, draw_map, plt

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
    """Box plot of R_length = (L_fusion - L_ref) / L_ref per reference, in percent.

    Horizontal boxes, one row per reference (its label and the number of maps both
    planners solved on the left, the first reference at the top), as the study
    report's box plots (:func:`pathfuse.viz.report.plot_boxes`): long labels such as
    "Artificial potential field method" stay readable.  A dashed line marks 0.

    Parameters
    ----------
    r_by_ref : mapping
        Reference name -> R_length values (fractions, one per map); references
        without a value are left out.
    n_maps : int
        The number of maps of the run (for the title).
    labels : mapping
        Reference name -> the label shown (the name itself when missing).
    out : str or path
        The PNG written.
    dpi : int
        Resolution of the PNG.
    """
    from pathfuse.viz.report import plot_boxes

    names = [k for k in r_by_ref if np.asarray(r_by_ref[k]).size]
    plot_boxes([labels.get(k, k) for k in names],
               [100 * np.asarray(r_by_ref[k], dtype=float) for k in names], out,
               xlabel="R_length = (L_fusion - L_ref) / L_ref  [%]",
               title=f"Fusion path length relative to each reference over {n_maps} maps "
                     "(left of 0: fusion shorter)", dpi=dpi, zero=True)
