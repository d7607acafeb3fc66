"""Figures of study reports (:mod:`pathfuse.bench.report`): box plots and parameter plots.

matplotlib with the Agg backend; every function writes one PNG and closes its figure.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from pathfuse.viz.figures import MEAN_PROPS, boxplot_key, plt

__all__ = ["plot_boxes", "plot_parameter"]


def plot_boxes(labels: Sequence[str], values: Sequence[np.ndarray], out: str | Path, *,
               xlabel: str, title: str, dpi: int = 110, log: bool = False,
               zero: bool = False) -> None:
    """Horizontal box plots, one per label (the sample size beside each label).

    Empty samples get an empty row.  ``log`` uses a log axis when the data
    span more than two decades; ``zero`` draws a dashed line at 0.

    >>> import tempfile, pathlib
    >>> f = pathlib.Path(tempfile.mkdtemp()) / "b.png"
    >>> plot_boxes(["a", "b"], [np.array([1.0, 2.0, 3.0]), np.array([])], f,
    ...            xlabel="x", title="t")
    >>> f.read_bytes()[:4] == b"\\x89PNG"
    True
    """
    n = len(labels)
    key_in = 0.55  # the key of the box plot's parts, under the axes
    fig, ax = plt.subplots(figsize=(8.5, 1.2 + key_in + 0.32 * max(n, 2)))
    data = [np.asarray(v, dtype=float) for v in values]
    data = [v[np.isfinite(v)] for v in data]
    pos = np.arange(n, 0, -1)  # first label at the top
    keep = [i for i in range(n) if data[i].size]
    if keep:
        import matplotlib

        mpl = tuple(int(x) for x in matplotlib.__version__.split(".")[:2] if x.isdigit())
        # matplotlib 3.10 renamed vert=False to orientation="horizontal" (vert deprecated)
        horiz = {"orientation": "horizontal"} if mpl >= (3, 10) else {"vert": False}
        ax.boxplot([data[i] for i in keep], positions=[pos[i] for i in keep], **horiz,
                   showmeans=True, widths=0.6, flierprops={"markersize": 3},
                   meanprops=MEAN_PROPS)
        allv = np.concatenate([data[i] for i in keep])
        pos_v = allv[allv > 0]
        if log and pos_v.size == allv.size and pos_v.max() > 100 * pos_v.min():
            ax.set_xscale("log")
    ax.set_yticks(pos)
    ax.set_yticklabels([f"{lab} (n={data[i].size})" for i, lab in enumerate(labels)],
                       fontsize=8)
    ax.set_ylim(0.4, n + 0.6)
    if zero:
        ax.axvline(0.0, color="k", lw=0.8, ls="--")
    ax.set_xlabel(xlabel)
    ax.set_title(title, fontsize=10)
    ax.grid(axis="x", alpha=0.3)
    boxplot_key(fig, fontsize=7.5)
    fig.tight_layout(rect=(0, key_in / fig.get_figheight(), 1, 1))
    fig.savefig(out, dpi=dpi)
    plt.close(fig)


def plot_parameter(param: str, lines: Mapping[str, Sequence[Mapping[str, Any]]],
                   out: str | Path, *, numeric: bool, title: str, dpi: int = 110) -> None:
    """A parameter against success rate (Wilson bars) and mean path length (t bars).

    ``lines`` maps a line label (map entry) to rows of
    :func:`pathfuse.bench.report.parameter_rows` (``value``, ``success_rate``,
    ``success_ci_low/high``, ``length_mean_m``, ``length_ci_low/high_m``,
    ``runs``).  ``numeric``: the values are numbers (else categories, in
    order of first appearance).
    """
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4.2))
    cats: list[str] = []
    for rows in lines.values():
        for r in rows:
            if r["value"] not in cats:
                cats.append(str(r["value"]))
    if numeric:
        order = sorted(cats, key=float)
        cats = order

    def xs(rows: Sequence[Mapping[str, Any]]) -> np.ndarray:
        if numeric:
            return np.array([float(r["value"]) for r in rows])
        return np.array([cats.index(str(r["value"])) for r in rows], dtype=float)

    k = len(lines)
    span = 1.0
    if numeric and len(cats) > 1:
        span = float(max(map(float, cats)) - min(map(float, cats)))
    for j, (label, rows) in enumerate(lines.items()):
        rows = sorted(rows, key=lambda r: cats.index(str(r["value"])))
        x = xs(rows)
        if k > 1:  # side by side, so that the error bars of the lines do not hide each other
            x = x + (j - (k - 1) / 2) * (0.08 if not numeric else 0.012 * span)
        sr = np.array([r["success_rate"] for r in rows], dtype=float)
        lo = np.array([r["success_ci_low"] for r in rows], dtype=float)
        hi = np.array([r["success_ci_high"] for r in rows], dtype=float)
        # Wilson ends are exact at 0/1; clip so that float rounding never gives a negative
        # error bar (matplotlib refuses those)
        a1.errorbar(x, 100 * sr, yerr=100 * np.clip([sr - lo, hi - sr], 0, None), marker="o",
                    capsize=4, label=label)
        lm = np.array([r["length_mean_m"] for r in rows], dtype=float)
        llo = np.array([r["length_ci_low_m"] for r in rows], dtype=float)
        lhi = np.array([r["length_ci_high_m"] for r in rows], dtype=float)
        ok = np.isfinite(lm)
        a2.errorbar(x[ok], lm[ok], yerr=np.clip([lm[ok] - llo[ok], lhi[ok] - lm[ok]], 0, None),
                    marker="o", capsize=4, label=label)
    for ax in (a1, a2):
        ax.set_xlabel(param)
        ax.grid(alpha=0.3)
        if not numeric:
            ax.set_xticks(range(len(cats)))
            ax.set_xticklabels(cats, fontsize=8)
        elif cats:
            ax.set_xticks([float(c) for c in cats])
            ax.set_xticklabels(cats, fontsize=8)
    a1.set_ylabel("success rate [%] (95% Wilson CI)")
    a1.set_ylim(-3, 103)
    a2.set_ylabel("path length mean [m] (95% t CI, solved runs)")
    if k > 1:  # under the plots, never over their points
        fig.legend(*a1.get_legend_handles_labels(), loc="lower center", fontsize=8,
                   ncol=min(k, 4), frameon=False)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout(rect=(0, 0.1 if k > 1 else 0, 1, 1))
    fig.savefig(out, dpi=dpi)
    plt.close(fig)
