"""Figures a user reads: legends off the map, the A* path as a line, c-space and unknown cells
explained, legible animations whose clock nothing covers, box plots that explain the mean."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from PIL import Image

import pathfuse
from pathfuse.generate import PAPER_GOAL, PAPER_START, paper_map
from pathfuse.io import load_map
from pathfuse.viz.figures import CSPACE_COLOUR, plot_plan

ROS = Path(__file__).resolve().parent / "data" / "ros" / "nav2_tb3_sandbox" / "tb3_sandbox.yaml"
EXAMPLES = Path(__file__).resolve().parent.parent / "examples" / "scenarios"


def _overlap(a, b) -> bool:
    return not (a.x1 <= b.x0 or b.x1 <= a.x0 or a.y1 <= b.y0 or b.y1 <= a.y0)


def _legend(fig):
    legends = [*fig.legends, *[ax.get_legend() for ax in fig.axes if ax.get_legend()]]
    assert len(legends) == 1
    return legends[0]


@pytest.fixture(scope="module")
def ros_plan():
    grid = load_map(str(ROS))
    start, goal = (-1.0, -0.5), (1.5, 0.5)
    res = pathfuse.plan(grid, start, goal, planner="fusion", robot_radius_m=0.1)
    assert res.success
    return grid, start, goal, res


def test_the_legend_is_below_the_map_and_explains_its_layers(ros_plan, tmp_path):
    grid, start, goal, res = ros_plan
    fig = plot_plan(grid, res, start, goal, title="t", astar_points=res.info["astar_path"],
                    robot_radius_m=0.1)
    fig.canvas.draw()
    leg = _legend(fig)
    r = fig.canvas.get_renderer()
    ax = fig.axes[0]
    assert not _overlap(leg.get_window_extent(r), ax.get_window_extent(r))
    assert leg.get_window_extent(r).y1 <= ax.get_window_extent(r).y0
    labels = [t.get_text() for t in leg.get_texts()]
    assert "c-space margin: 0.1 m robot radius" in labels
    assert "unknown, blocked (the default)" in labels and "occupied" in labels
    # the view is cropped to the known part of the 19 m map (the sandbox is about 6 m wide)
    assert np.ptp(ax.get_xlim()) < 8 and np.ptp(ax.get_ylim()) < 8
    out = tmp_path / "p.png"
    fig.savefig(out)
    px = np.asarray(Image.open(out).convert("RGB")).reshape(-1, 3)
    want = np.array([int(CSPACE_COLOUR[i:i + 2], 16) for i in (1, 3, 5)])
    blended = (0.75 * want + 0.25 * 255).round()  # the shading is 75 % opaque on white
    assert (np.abs(px - blended).max(axis=1) <= 2).sum() > 500


def test_on_a_fine_map_the_astar_path_is_a_line_not_a_band_of_dots(ros_plan):
    grid, start, goal, res = ros_plan
    fig = plot_plan(grid, res, start, goal, astar_points=res.info["astar_path"])
    ax = fig.axes[0]
    astar = [ln for ln in ax.lines if ln.get_color() == "#1f77b4"]
    assert len(res.info["astar_path"]) > 40
    assert len(astar) == 1 and astar[0].get_linestyle() == "--"
    assert astar[0].get_marker() in ("None", None, "")


def test_on_the_paper_map_the_few_astar_points_are_shown_too():
    grid = paper_map(3)
    res = pathfuse.plan(grid, PAPER_START, PAPER_GOAL, planner="fusion")
    fig = plot_plan(grid, res, PAPER_START, PAPER_GOAL, astar_points=res.info["astar_path"])
    markers = {ln.get_marker() for ln in fig.axes[0].lines if ln.get_color() == "#1f77b4"}
    assert "." in markers
    labels = [t.get_text() for t in _legend(fig).get_texts()]
    assert not any("c-space" in t or "unknown" in t for t in labels)  # nothing to explain


@pytest.fixture(scope="module")
def episode():
    return pathfuse.simulate(str(EXAMPLES / "warehouse_patrol.yaml"))


def test_animation_frames_are_legible_and_nothing_covers_the_clock(episode, tmp_path):
    from pathfuse.viz import animate as anim

    info = anim.animate_episode(episode, tmp_path / "w.gif")
    w, h = Image.open(info.path).size
    assert w >= 600 and h >= 450, (w, h)
    r = anim._EpisodeRenderer(episode, dpi=100, size_in=5.0, obstacle_trail_s=3.0,
                              robot_trail=True, title=None)
    r.render(episode.n_ticks)  # the last frame: the outcome banner is shown
    rend = r.canvas.get_renderer()
    texts = [t for t in r.fig.findobj(lambda a: hasattr(a, "get_fontsize")
                                      and hasattr(a, "get_text")) if t.get_text().strip()]
    assert texts and min(t.get_fontsize() for t in texts) >= 9
    clock = r.clock.get_window_extent(rend)
    assert r.clock.get_text().startswith("t = ")
    assert not _overlap(clock, r.outcome.get_window_extent(rend))
    assert not _overlap(clock, r.ax.get_window_extent(rend))  # above the map, not on it


def _success_rows(planners, moving=(0, 2, 4, 8)):
    from pathfuse.stats import wilson_ci

    rows = []
    for j, p in enumerate(planners):
        for k in moving:
            hits = max(0, 10 - j - k)
            rate, lo, hi = wilson_ci(hits, 10)
            rows.append({"planner": p, "moving": k, "reached_rate": rate,
                         "reached_ci_low": lo, "reached_ci_high": hi})
    return rows


def test_the_success_plot_keeps_its_legend_off_the_points():
    from pathfuse.viz.dynamic import plot_success_vs_moving

    rows = [{"planner": p, "moving": k, "reached_rate": v, "reached_ci_low": max(0, v - .1),
             "reached_ci_high": min(1, v + .1)}
            for p, base in (("fusion", 1.0), ("apf", 0.2)) for k, v in
            ((0, base), (4, base * 0.8))]
    fig = plot_success_vs_moving(rows)
    fig.canvas.draw()
    r = fig.canvas.get_renderer()
    leg = _legend(fig)
    for ax in fig.axes:
        assert not _overlap(leg.get_window_extent(r), ax.get_window_extent(r))


def test_the_success_plot_has_one_panel_per_planner_on_shared_axes(tmp_path):
    from pathfuse.viz.dynamic import planner_colours, plot_success_vs_moving

    names = ["astar", "astar-replan", "apf", "fusion", "ref6", "ref7", "astar-smooth",
             "thetastar", "lazy-thetastar", "shortest", "dwa", "mppi"]
    rows = _success_rows(names)
    out = tmp_path / "s.png"
    fig = plot_success_vs_moving(rows, out, title="t")
    assert Image.open(out).format == "PNG"
    panels = [ax for ax in fig.axes if ax.get_visible()]
    assert [ax.get_title() for ax in panels] == names
    assert len({ax.get_ylim() for ax in panels}) == 1  # one scale for every panel
    assert len({ax.get_xlim() for ax in panels}) == 1
    colours = planner_colours(names)
    assert len(set(colours.values())) == len(names)  # no two planners share a colour
    for ax, name in zip(panels, names, strict=True):
        own = [ln for ln in ax.lines if ln.get_color() == colours[name]]
        assert len(own) == 1  # the panel's planner, once, in its colour ...
        want = [100 * r["reached_rate"] for r in rows if r["planner"] == name]
        assert np.allclose(own[0].get_ydata(), want)
        others = [ln for ln in ax.lines if ln is not own[0]]
        assert len(others) == len(names) - 1  # ... the others behind it, all one grey
        assert len({ln.get_color() for ln in others}) == 1
        assert others[0].get_color() not in colours.values()
    # the panels do not overlap one another, nor their titles the panel above
    fig.canvas.draw()
    r = fig.canvas.get_renderer()
    boxes = [ax.get_tightbbox(r) for ax in panels]
    for i, a in enumerate(boxes):
        for b in boxes[i + 1:]:
            assert not _overlap(a, b)


def test_success_plot_with_one_disc_count_shows_the_interval_as_a_bar():
    from pathfuse.viz.dynamic import plot_success_vs_moving

    (row,) = _success_rows(["fusion"], moving=(3,))
    assert 0 < row["reached_ci_low"] < row["reached_ci_high"] < 1
    fig = plot_success_vs_moving([row])
    (ax,) = [a for a in fig.axes if a.get_visible()]
    spans = [seg[:, 1] for c in ax.collections for seg in c.get_segments()
             if len(seg) == 2 and seg[0, 0] == seg[1, 0] == 3]
    assert len(spans) == 1
    assert sorted(spans[0]) == pytest.approx([100 * row["reached_ci_low"],
                                              100 * row["reached_ci_high"]])


def test_box_plots_explain_their_mean_marker(tmp_path, monkeypatch):
    from pathfuse.viz import figures, paper, report

    keys = []

    def spy(fig, **kw):
        leg = figures.boxplot_key(fig, **kw)
        keys.append([t.get_text() for t in leg.get_texts()])
        return leg

    monkeypatch.setattr(report, "boxplot_key", spy)  # paper's R_length plot draws with it too
    report.plot_boxes(["a", "b"], [np.array([1.0, 2.0, 9.0]), np.array([2.0, 3.0])],
                      tmp_path / "b.png", xlabel="x", title="t")
    paper.plot_r_length({"astar": np.array([-0.1, -0.05, 0.01])}, 3, {"astar": "A*"},
                        tmp_path / "r.png")
    assert len(keys) == 2
    for k in keys:
        assert "mean" in k and "line: median" in k and "box: middle 50 % (quartiles)" in k


def test_the_r_length_box_plot_is_horizontal_with_readable_labels(tmp_path, monkeypatch):
    from pathfuse.studies.paper_config import PAPER_LABELS
    from pathfuse.viz import paper, report

    shown = []
    monkeypatch.setattr(report.plt, "close", shown.append)  # keep the figure to inspect it
    rng = np.random.default_rng(0)
    refs = ["astar", "apf", "ref6", "ref7", "astar-smooth", "thetastar", "shortest"]
    r = {k: rng.normal(-0.05, 0.05, 30 - 17 * (k == "apf")) for k in refs}
    out = tmp_path / "r.png"
    paper.plot_r_length(r, 30, PAPER_LABELS, out)
    assert Image.open(out).format == "PNG"
    (fig,) = shown
    ax = fig.axes[0]
    # one row per reference, its label and sample size on the y axis, the first at the top
    labels = [t.get_text() for t in ax.get_yticklabels()]
    assert labels == [f"{PAPER_LABELS[k]} (n={r[k].size})" for k in refs]
    assert list(ax.get_yticks()) == sorted(ax.get_yticks(), reverse=True)
    assert ax.get_xlabel().startswith("R_length") and "%" in ax.get_xlabel()
    assert any(ln.get_linestyle() == "--" and set(ln.get_xdata()) == {0.0} for ln in ax.lines)
    fig.canvas.draw()
    rend = fig.canvas.get_renderer()
    boxes = [t.get_window_extent(rend) for t in ax.get_yticklabels()]
    for i, a in enumerate(boxes):  # no label overlaps another, none leaves the figure
        assert a.x0 >= 0
        for b in boxes[i + 1:]:
            assert not _overlap(a, b)
    monkeypatch.undo()
    report.plt.close(fig)
