"""Animations of dynamic episodes: frame choice, GIF contents, MP4 / ffmpeg handling."""

import math
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from pathfuse.viz import animate as anim
from pathfuse.viz.animate import (
    AnimationError,
    animate_episode,
    auto_frame_step,
    frame_ticks,
    render_frames,
)
from pathfuse.world import simulate

EXAMPLES = Path(__file__).resolve().parents[1] / "examples" / "scenarios"


@pytest.fixture(scope="module")
def collision_ep():
    ep = simulate(EXAMPLES / "head_on.yaml", planner="astar")
    assert ep.status.name == "COLLISION"
    return ep


@pytest.fixture(scope="module")
def reached_ep():
    ep = simulate(EXAMPLES / "head_on.yaml", planner="fusion")
    assert ep.status.name == "SUCCESS"
    return ep


def expected_frames(n_ticks: int, step: int) -> list[int]:
    """Independent statement of the frame rule: every step-th tick, plus the last tick."""
    ticks = [t for t in range(n_ticks + 1) if t % step == 0]
    if ticks[-1] != n_ticks:
        ticks.append(n_ticks)
    return ticks


def gif_durations(path):
    im = Image.open(path)
    out = []
    for i in range(im.n_frames):
        im.seek(i)
        out.append(im.info["duration"])
    return out


@pytest.mark.parametrize("n_ticks,step", [(0, 1), (1, 1), (57, 1), (57, 3), (57, 19), (57, 57),
                                          (57, 100), (600, 7), (600, 5)])
def test_frame_ticks_follow_the_rule(n_ticks, step):
    assert frame_ticks(n_ticks, step).tolist() == expected_frames(n_ticks, step)


@pytest.mark.parametrize("bad", [0, -1, 1.5, True, "2"])
def test_frame_step_must_be_a_positive_integer(bad):
    with pytest.raises(AnimationError, match="frame_step"):
        frame_ticks(10, bad)


def test_auto_frame_step_real_time_when_short_capped_when_long():
    # dt 0.1 s at 10 fps is real time with one tick per frame
    assert auto_frame_step(100, 0.1, 10) == 1
    assert auto_frame_step(100, 0.05, 10) == 2
    # a 60 s episode would need 601 frames in real time: the smallest step within max_frames
    for n in (149, 150, 151, 600, 6000):
        step = auto_frame_step(n, 0.1, 10, max_frames=150)
        assert math.ceil((n + 1) / step) <= 150  # (+ the final tick when it is off the grid)
        assert math.ceil((n + 1) / (step - 1)) > 150 if step > 1 else n + 1 <= 150


@pytest.mark.parametrize("step", [1, 4, 10])
def test_gif_has_one_frame_per_chosen_tick(tmp_path, collision_ep, step):
    out = tmp_path / f"ep{step}.gif"
    info = animate_episode(collision_ep, out, frame_step=step, fps=10, hold_s=1.5, dpi=40)
    want = expected_frames(collision_ep.n_ticks, step)
    assert info.ticks.tolist() == want
    im = Image.open(out)
    assert im.format == "GIF" and im.n_frames == len(want) == info.n_frames
    assert im.size == info.size_px
    d = gif_durations(out)
    assert d[:-1] == [100] * (len(want) - 1)
    assert d[-1] == 100 + 1500  # the outcome frame is held


def test_default_gif_of_a_long_episode_stays_small(tmp_path):
    # a 60 m corridor at 1 m/s: ~600 ticks; the default must not write 600 frames
    sc = {"map": {"rows": ["." * 62] * 2}, "start": [0.5, 1.0], "goal": [61.5, 1.0],
          "time_limit": 70, "robot": {"radius": 0.2}}
    ep = simulate(sc, planner="astar")
    assert ep.status.name == "SUCCESS" and ep.n_ticks > 590
    info = animate_episode(ep, tmp_path / "long.gif", dpi=30)
    assert info.frame_step == auto_frame_step(ep.n_ticks, 0.1, 10.0)
    n = Image.open(info.path).n_frames
    assert n == len(expected_frames(ep.n_ticks, info.frame_step)) <= 151
    # every tick when asked
    info1 = animate_episode(ep, tmp_path / "all.gif", frame_step=1, dpi=20, size_in=2)
    assert Image.open(info1.path).n_frames == ep.n_ticks + 1


def test_single_tick_episode_gives_a_one_frame_gif(tmp_path):
    # no path at all: the robot never moves, one tick to draw
    sc = {"map": {"rows": ["..#..", "..#..", "..#.."]}, "start": [0.5, 1.5],
          "goal": [4.5, 1.5]}
    ep = simulate(sc, planner="astar")
    assert ep.status.name == "NO_PATH" and ep.n_ticks == 0
    info = animate_episode(ep, tmp_path / "one.gif", dpi=30)
    assert info.n_frames == 1 and Image.open(info.path).n_frames == 1


def _axes_pixels(r, rgba, colour):
    """Centroid (display x, y) of the pixels of exactly ``colour`` inside the axes."""
    h = rgba.shape[0]
    x0, y0, x1, y1 = r.ax.bbox.extents
    rows, cols = np.nonzero(np.all(rgba[:, :, :3] == colour, axis=2))
    y = h - rows - 0.5
    x = cols + 0.5
    keep = (x > x0) & (x < x1) & (y > y0) & (y < y1)
    return x[keep], y[keep]


def test_robot_and_discs_are_drawn_where_the_episode_has_them(reached_ep):
    ep = reached_ep
    r = anim._EpisodeRenderer(ep, dpi=60, size_in=5.0, obstacle_trail_s=0.0, robot_trail=False,
                              title=None)
    px_per_m = r.ax.transData.transform((1, 0))[0] - r.ax.transData.transform((0, 0))[0]
    for k in (0, ep.n_ticks // 3, 2 * ep.n_ticks // 3):
        rgba = r.render(k)
        # robot: fill colour #d62728
        x, y = _axes_pixels(r, rgba, (0xD6, 0x27, 0x28))
        assert x.size > 10
        cx, cy = r.ax.transData.transform(ep.positions[k])
        assert abs(x.mean() - cx) < 1.5 and abs(y.mean() - cy) < 1.5
        # the one disc: sensed (#ff7f0e) or not (#f4d3b0), centred on its position
        colour = (0xFF, 0x7F, 0x0E) if ep.sensed[k, 0] else (0xF4, 0xD3, 0xB0)
        x, y = _axes_pixels(r, rgba, colour)
        dx, dy = r.ax.transData.transform(ep.obstacle_positions[k, 0])
        assert x.size > 10
        # the robot may hide part of the disc: allow a robot radius of shift
        tol = 1.5 + ep.robot_radius * px_per_m
        assert abs(x.mean() - dx) < tol and abs(y.mean() - dy) < tol


def test_the_legend_names_every_marker_drawn_on_the_map_start_included(reached_ep):
    r = anim._EpisodeRenderer(reached_ep, dpi=60, size_in=5.0, obstacle_trail_s=0.0,
                              robot_trail=False, title=None)
    (legend,) = r.fig.legends
    entries = {t.get_text(): h for t, h in zip(legend.get_texts(), legend.legend_handles,
                                                strict=True)}
    assert {"start", "goal", "robot"} <= set(entries)
    # the start's key looks like the start drawn on the map: a green dot with a black edge
    start = entries["start"]
    assert start.get_marker() == "o" and start.get_color() == "#2ca02c"
    on_map = [ln for ln in r.ax.lines if ln.get_marker() == "o"
              and tuple(ln.get_xydata()[0]) == tuple(reached_ep.scenario.start)]
    assert on_map and on_map[0].get_color() == start.get_color()


def test_collision_is_marked_only_on_the_last_frame(collision_ep):
    frames = list(render_frames(collision_ep, [0, collision_ep.n_ticks // 2,
                                               collision_ep.n_ticks], dpi=50))
    red = [(np.all(f[:, :, :3] == (255, 0, 0), axis=2)).sum() for f in frames]
    assert red[0] == 0 and red[1] == 0 and red[2] > 10
    # the frames differ (the clock at least): GIF writers would merge identical ones
    assert not np.array_equal(frames[0], frames[1])


def test_same_episode_same_gif_bytes(tmp_path, collision_ep):
    a = animate_episode(collision_ep, tmp_path / "a.gif", frame_step=5, dpi=30)
    b = animate_episode(collision_ep, tmp_path / "b.gif", frame_step=5, dpi=30)
    assert a.path.read_bytes() == b.path.read_bytes()


def test_mp4_without_ffmpeg_is_one_clear_error(tmp_path, collision_ep, monkeypatch):
    monkeypatch.setattr(shutil, "which", lambda *a, **k: None)
    out = tmp_path / "ep.mp4"
    with pytest.raises(AnimationError) as exc:
        animate_episode(collision_ep, out)
    msg = str(exc.value)
    assert "ffmpeg" in msg and "--gif" in msg and "\n" not in msg
    assert not out.exists()


@pytest.mark.skipif(anim.ffmpeg_path() is None, reason="ffmpeg not installed")
def test_mp4_with_ffmpeg(tmp_path, collision_ep):  # pragma: no cover - needs ffmpeg
    info = animate_episode(collision_ep, tmp_path / "ep.mp4", frame_step=3, dpi=40)
    data = info.path.read_bytes()
    assert info.format == "mp4" and data[4:8] == b"ftyp"


@pytest.mark.parametrize("kw,what", [({"fps": 0}, "fps"), ({"fps": float("nan")}, "fps"),
                                     ({"hold_s": -1}, "hold_s"), ({"format": "avi"}, "format"),
                                     ({"dpi": 0}, "dpi"), ({"max_frames": 0}, "max_frames")])
def test_bad_options(tmp_path, collision_ep, kw, what):
    with pytest.raises(AnimationError, match=what):
        animate_episode(collision_ep, tmp_path / "x.gif", **kw)


def test_headless_even_when_a_gui_backend_is_requested(tmp_path):
    env = {k: v for k, v in os.environ.items() if k != "DISPLAY"}
    env["MPLBACKEND"] = "TkAgg"
    out = tmp_path / "h.gif"
    code = ("import matplotlib, pathfuse; from pathfuse.viz.animate import animate_episode;"
            f"ep = pathfuse.simulate({str(EXAMPLES / 'head_on.yaml')!r});"
            f"i = animate_episode(ep, {str(out)!r}, frame_step=20, dpi=20);"
            "print(matplotlib.get_backend().lower(), i.n_frames)")
    p = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                       timeout=120)
    assert p.returncode == 0, p.stderr
    backend, n = p.stdout.split()
    assert backend == "agg" and int(n) == Image.open(out).n_frames
