"""Animations of dynamic episodes (GIF, MP4) and the dynamic benchmark's figure.

:func:`animate_episode` draws a :class:`~pathfuse.world.episode.Episode` tick
by tick: the map, the start and the goal (with its tolerance circle), the
planner's global A* path (the current one bold, superseded replans faint),
the moving discs (filled when the robot senses them) with their recent
trails, the robot disc with its sensing circle and its whole trail, the
clock, and on the last frame the outcome (status text; a cross where a
collision happened, the disc hit outlined in red).

Rendering is headless (Agg, no pyplot state) and fast: the static layers are
drawn once and every frame only redraws the moving artists on a copy of that
background (blitting).  Frames are every ``frame_step``-th tick plus always
the final tick, so a long episode does not produce hundreds of frames unless
asked; the last frame is held for ``hold_s`` seconds.

* GIF is written with pillow and works everywhere.
* MP4 pipes the frames into ``ffmpeg`` (H.264); when ffmpeg is not on
  ``PATH`` (``matplotlib.rcParams["animation.ffmpeg_path"]``) an
  :class:`AnimationError` says so in one line.

Examples
--------
>>> import tempfile, os
>>> from PIL import Image
>>> from pathfuse.world import simulate
>>> ep = simulate({"map": {"rows": ["......"] * 3}, "start": [0.5, 1.5],
...                "goal": [5.5, 1.5]}, planner="astar-follow")
>>> ep.n_ticks, frame_ticks(ep.n_ticks, 20).tolist()
(48, [0, 20, 40, 48])
>>> with tempfile.TemporaryDirectory() as d:
...     info = animate_episode(ep, os.path.join(d, "ep.gif"), frame_step=20, dpi=40)
...     Image.open(info.path).n_frames
4
"""

from __future__ import annotations

import math
import shutil
import subprocess
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import numpy as np  # noqa: E402
from matplotlib.backends.backend_agg import FigureCanvasAgg  # noqa: E402
from matplotlib.collections import LineCollection  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.patches import Circle, Patch  # noqa: E402

from pathfuse.result import PathfuseError  # noqa: E402
from pathfuse.viz.dynamic import ONLINE_COLOURS, plot_success_vs_moving  # noqa: E402,F401
from pathfuse.viz.figures import draw_map, map_legend_handles  # noqa: E402

__all__ = [
    "AnimationError",
    "AnimationInfo",
    "animate_episode",
    "frame_ticks",
    "auto_frame_step",
    "ffmpeg_path",
    "require_ffmpeg",
    "render_frames",
    "plot_success_vs_moving",
    "ONLINE_COLOURS",
    "FORMATS",
]

FORMATS = ("gif", "mp4")


class AnimationError(PathfuseError):
    """An animation cannot be written (no ffmpeg, bad option, ffmpeg failed)."""


@dataclass(frozen=True)
class AnimationInfo:
    """What :func:`animate_episode` wrote.

    Attributes
    ----------
    path : Path
        The file written.
    format : str
        ``"gif"`` or ``"mp4"``.
    ticks : (F,) int array
        The episode tick drawn in each distinct frame.
    frame_step : int
        Ticks between two frames (the last frame is always the final tick).
    fps : float
        Frames per second of playback.
    hold_s : float
        How long the last frame is shown.
    size_px : (int, int)
        Width and height of a frame in pixels.
    render_s : float
        Wall-clock seconds spent drawing and encoding.
    """

    path: Path
    format: str
    ticks: np.ndarray
    frame_step: int
    fps: float
    hold_s: float
    size_px: tuple[int, int]
    render_s: float

    @property
    def n_frames(self) -> int:
        """Distinct frames (the held last frame counts once)."""
        return int(self.ticks.size)

    def speedup(self, dt: float) -> float:
        """How many times faster than real time the animation plays."""
        return self.frame_step * self.fps * dt


# --------------------------------------------------------------------------- frame choice
def frame_ticks(n_ticks: int, frame_step: int) -> np.ndarray:
    """The ticks drawn: ``0, step, 2*step, ...`` and always the final tick ``n_ticks``.

    >>> frame_ticks(10, 3).tolist(), frame_ticks(9, 3).tolist(), frame_ticks(0, 5).tolist()
    ([0, 3, 6, 9, 10], [0, 3, 6, 9], [0])
    """
    if isinstance(frame_step, bool) or not isinstance(frame_step, (int, np.integer)) \
            or frame_step < 1:
        raise AnimationError(f"frame_step must be an integer >= 1, got {frame_step!r}")
    n = int(n_ticks)
    ticks = np.arange(0, n + 1, int(frame_step), dtype=np.int64)
    if ticks[-1] != n:
        ticks = np.append(ticks, n)
    return ticks


def auto_frame_step(n_ticks: int, dt: float, fps: float, max_frames: int = 150) -> int:
    """Default ``frame_step``: real time when that needs at most ``max_frames`` frames,
    otherwise as few ticks per frame as keep the frame count within ``max_frames``.

    >>> auto_frame_step(200, 0.1, 10), auto_frame_step(600, 0.1, 10), auto_frame_step(100, 0.1, 10)
    (2, 5, 1)
    """
    real_time = max(1, round(1.0 / (fps * dt)))
    fit = math.ceil((int(n_ticks) + 1) / max(1, int(max_frames)))
    return int(max(real_time, fit, 1))


# --------------------------------------------------------------------------- ffmpeg
def ffmpeg_path() -> str | None:
    """The ffmpeg executable matplotlib would use, or None when it is not found."""
    exe = str(matplotlib.rcParams.get("animation.ffmpeg_path", "ffmpeg") or "ffmpeg")
    return shutil.which(exe)


def require_ffmpeg() -> str:
    """ffmpeg's path; :class:`AnimationError` (one line) when it is missing."""
    exe = ffmpeg_path()
    if exe is None:
        raise AnimationError(
            "writing MP4 needs ffmpeg, which was not found on PATH "
            f"(matplotlib animation.ffmpeg_path = "
            f"{matplotlib.rcParams.get('animation.ffmpeg_path', 'ffmpeg')!r}); "
            "install ffmpeg or write a GIF instead (--gif)")
    return exe


# --------------------------------------------------------------------------- drawing
def _fmt_time(t: float, dt: float) -> str:
    dec = max(1, min(4, int(math.ceil(-math.log10(dt) - 1e-9)))) if dt < 1 else 1
    return f"{t:.{dec}f}"


class _EpisodeRenderer:
    """Draws frames of one episode by blitting the moving artists on a fixed background."""

    def __init__(self, ep: Any, *, dpi: float, size_in: float, obstacle_trail_s: float | None,
                 robot_trail: bool, title: str | None) -> None:
        self.ep = ep
        sc = ep.scenario
        grid = ep.grid
        self.dt = float(sc.dt)
        x0, y0, x1, y1 = grid.bounds
        w, h = x1 - x0, y1 - y0
        # the map's longer side is size_in; a header (title, clock) and a footer (axis
        # label, legend) outside the map, so nothing covers the clock or the map
        aw, ah = size_in * w / max(w, h), size_in * h / max(w, h)
        head, foot, left = 0.55, 1.25, 0.7
        fw, fh = max(aw + left + 0.25, 6.4), ah + head + foot
        fig = Figure(figsize=(fw, fh), dpi=dpi)
        self.canvas = FigureCanvasAgg(fig)
        self.fig = fig
        ax = fig.add_axes((max(left, (fw - aw) / 2 + 0.2) / fw, foot / fh, aw / fw, ah / fh))
        self.ax = ax
        drawn = draw_map(ax, grid)
        ax.tick_params(labelsize=9)
        ax.xaxis.label.set_fontsize(9)
        ax.yaxis.label.set_fontsize(9)
        fig.text(0.02, 1 - 0.2 / fh, title if title is not None else f"{sc.name}: {ep.planner}",
                 ha="left", va="top", fontsize=11)
        ax.plot(*sc.start, "o", color="#2ca02c", ms=8, mec="k", zorder=6)
        ax.plot(*sc.goal, "*", color="#ffbf00", ms=14, mec="k", zorder=6)
        ax.add_patch(Circle(sc.goal, sc.goal_tolerance, fill=False, ec="#b08800", lw=0.8,
                            ls=":", zorder=6))

        anim: list[Any] = []

        def add(a: Any) -> Any:
            a.set_animated(True)
            anim.append(a)
            return a

        # paths: superseded replans faint, the current one bold
        self.updates = [(int(k), np.asarray(p, dtype=float)) for k, p in ep.path_updates]
        self.old_paths = add(LineCollection([], colors="#1f77b4", linewidths=0.8, alpha=0.25,
                                            zorder=3))
        ax.add_collection(self.old_paths)
        (self.cur_path,) = ax.plot([], [], "--", color="#1f77b4", lw=1.4, zorder=3)
        add(self.cur_path)
        # moving discs and their trails
        self.radii = np.asarray(ep.obstacle_radii, dtype=float)
        self.obs_pos = np.asarray(ep.obstacle_positions, dtype=float)
        k_obs = self.radii.size
        self.trail_ticks = None if obstacle_trail_s is None \
            else max(1, int(round(obstacle_trail_s / self.dt)))
        self.obs_trails = add(LineCollection([], colors="#ff7f0e", linewidths=1.0, alpha=0.5,
                                             zorder=4))
        ax.add_collection(self.obs_trails)
        self.discs = []
        for j in range(k_obs):
            c = Circle(tuple(self.obs_pos[0, j]), self.radii[j], zorder=5)
            ax.add_patch(c)
            self.discs.append(add(c))
        # robot
        self.pos = np.asarray(ep.positions, dtype=float)
        self.robot_trail = robot_trail
        (self.trail,) = ax.plot([], [], "-", color="#d62728", lw=1.3, zorder=6)
        add(self.trail)
        self.sense = add(Circle(tuple(self.pos[0]), sc.robot.sensing_radius_m, fill=False,
                                ec="#d62728", lw=0.8, ls="--", alpha=0.6, zorder=6))
        ax.add_patch(self.sense)
        self.robot = add(Circle(tuple(self.pos[0]), max(sc.robot.radius_m, 0.02), fc="#d62728",
                                ec="k", lw=0.8, zorder=7))
        ax.add_patch(self.robot)
        (self.mark,) = ax.plot([], [], "X", color="#ff0000", mec="k", ms=14, zorder=9)
        add(self.mark)
        self.clock = add(fig.text(0.98, 1 - 0.2 / fh, "", ha="right", va="top", fontsize=10,
                                  family="monospace"))
        self.outcome = add(ax.text(0.5, 0.5, "", transform=ax.transAxes, ha="center",
                                   va="center", fontsize=12, weight="bold", zorder=11,
                                   bbox={"boxstyle": "round,pad=0.4", "fc": "white",
                                         "ec": "k", "alpha": 0.9}))
        self.outcome.set_visible(False)
        self.anim = anim
        handles = [
            Line2D([], [], ls="--", color="#1f77b4", label="A* path"),
            Line2D([], [], ls="-", color="#1f77b4", alpha=0.3, label="earlier paths"),
            Line2D([], [], marker="o", ls="none", color="#d62728", mec="k", label="robot"),
            Line2D([], [], ls="--", color="#d62728", alpha=0.6, label="sensing range"),
            Patch(fc="#ff7f0e", ec="#8a4500", label="moving obstacle (sensed)"),
            Patch(fc="#f4d3b0", ec="#8a4500", label="moving obstacle"),
            Line2D([], [], marker="o", ls="none", color="#2ca02c", mec="k", ms=7, label="start"),
            Line2D([], [], marker="*", ls="none", color="#ffbf00", mec="k", ms=9, label="goal"),
            *map_legend_handles(drawn)[1:],  # unknown cells of a ROS map, when there are any
        ]
        fig.legend(handles=handles, loc="lower center", ncol=4 if fw >= 7 else 3, fontsize=9,
                   frameon=False, handlelength=1.6, columnspacing=1.0,
                   bbox_to_anchor=(0.5, 0.0))
        self.canvas.draw()
        self.background = self.canvas.copy_from_bbox(fig.bbox)
        w_px, h_px = self.canvas.get_width_height()
        self.size_px = (int(w_px), int(h_px))
        self.n_ticks = int(ep.n_ticks)

    def _path_at(self, k: int) -> tuple[np.ndarray | None, list[np.ndarray]]:
        cur = None
        old: list[np.ndarray] = []
        for tick, p in self.updates:
            if tick > k:
                break
            if cur is not None:
                old.append(cur)
            cur = p
        return cur, old

    def render(self, k: int) -> np.ndarray:
        """The RGBA pixels (H, W, 4) of tick ``k``."""
        ep = self.ep
        final = k == self.n_ticks
        cur, old = self._path_at(k)
        self.old_paths.set_segments(old)
        if cur is None:
            self.cur_path.set_data([], [])
        else:
            self.cur_path.set_data(cur[:, 0], cur[:, 1])
        lo = 0 if self.trail_ticks is None else max(0, k - self.trail_ticks)
        if self.radii.size:
            self.obs_trails.set_segments(
                [self.obs_pos[lo:k + 1, j] for j in range(self.radii.size)] if k > lo else [])
        sensed = np.asarray(ep.sensed[k]) if len(ep.sensed) > k else np.zeros(self.radii.size,
                                                                              dtype=bool)
        hit = ep.collision_with if (final and ep.status.name == "COLLISION") else None
        for j, c in enumerate(self.discs):
            c.set_center(tuple(self.obs_pos[k, j]))
            c.set_facecolor("#ff7f0e" if sensed[j] else "#f4d3b0")
            if hit is not None and hit != "static" and int(hit) == j:
                c.set_edgecolor("#ff0000")
                c.set_linewidth(2.5)
            else:
                c.set_edgecolor("#8a4500")
                c.set_linewidth(0.8)
        p = self.pos[k]
        if self.robot_trail:
            self.trail.set_data(self.pos[:k + 1, 0], self.pos[:k + 1, 1])
        self.sense.set_center(tuple(p))
        self.robot.set_center(tuple(p))
        t = float(ep.times[k])
        self.clock.set_text(f"t = {_fmt_time(t, self.dt)} s  tick {k}/{self.n_ticks}")
        if final:
            self.outcome.set_visible(True)
            self.outcome.set_text(_outcome_text(ep))
            self.outcome.set_color("#1a7f1a" if ep.status.name == "SUCCESS" else "#c00000")
            # keep the text off the robot: top or bottom third, away from it
            y_rel = (p[1] - self.ax.get_ylim()[0]) / max(np.ptp(self.ax.get_ylim()), 1e-9)
            self.outcome.set_position((0.5, 0.2 if y_rel > 0.5 else 0.8))
            if ep.status.name == "COLLISION":
                self.mark.set_data([p[0]], [p[1]])
            else:
                self.mark.set_data([], [])
        else:
            self.outcome.set_visible(False)
            self.mark.set_data([], [])
        self.canvas.restore_region(self.background)
        for a in self.anim:
            self.ax.draw_artist(a)
        return np.asarray(self.canvas.buffer_rgba()).copy()


def _outcome_text(ep: Any) -> str:
    name = ep.status.name
    dt = float(ep.scenario.dt)
    if name == "SUCCESS":
        return f"REACHED the goal in {_fmt_time(float(ep.time_to_goal_s), dt)} s, " \
               f"{ep.path_length_m:.2f} m"
    t = _fmt_time(float(ep.times[-1]), dt)
    if name == "COLLISION":
        what = "the static map" if ep.collision_with == "static" \
            else f"moving obstacle {ep.collision_with}"
        return f"COLLISION with {what}\nat t = {t} s"
    return f"{name} at t = {t} s"


def render_frames(ep: Any, ticks: Sequence[int] | None = None, *, dpi: float = 100,
                  size_in: float = 5.0, obstacle_trail_s: float | None = 3.0,
                  robot_trail: bool = True, title: str | None = None):
    """Yield the RGBA frames (H, W, 4 uint8 arrays) of ``ticks`` (default: every tick).

    Parameters are those of :func:`animate_episode`.
    """
    r = _EpisodeRenderer(ep, dpi=dpi, size_in=size_in, obstacle_trail_s=obstacle_trail_s,
                         robot_trail=robot_trail, title=title)
    ticks = range(ep.n_ticks + 1) if ticks is None else ticks
    for k in ticks:
        k = int(k)
        if not 0 <= k <= ep.n_ticks:
            raise AnimationError(f"tick {k} is outside the episode (0..{ep.n_ticks})")
        yield r.render(k)


# --------------------------------------------------------------------------- writers
def _check_number(name: str, v: Any, lo: float, lo_ok: bool = False) -> float:
    ok = not isinstance(v, bool) and isinstance(v, (int, float, np.integer, np.floating)) \
        and math.isfinite(float(v)) and (float(v) >= lo if lo_ok else float(v) > lo)
    if not ok:
        raise AnimationError(f"{name} must be a finite number {'>=' if lo_ok else '>'} {lo:g}, "
                             f"got {v!r}")
    return float(v)


def animate_episode(
    ep: Any,
    out: str | Path,
    *,
    format: str | None = None,  # noqa: A002 - the natural name
    fps: float = 10.0,
    frame_step: int | None = None,
    max_frames: int = 150,
    hold_s: float = 1.5,
    dpi: float = 100,
    size_in: float = 5.0,
    obstacle_trail_s: float | None = 3.0,
    robot_trail: bool = True,
    title: str | None = None,
) -> AnimationInfo:
    """Write an animation of ``ep`` to ``out`` (GIF via pillow, MP4 via ffmpeg).

    Parameters
    ----------
    ep : Episode
        From :func:`pathfuse.simulate`.
    out : path
        Output file.
    format : {"gif", "mp4"}, optional
        Default: from the suffix of ``out`` (``.mp4`` -> MP4, anything else GIF).
    fps : float
        Frames per second of playback.
    frame_step : int, optional
        Ticks between frames.  Default :func:`auto_frame_step`: real time
        (``1 / (fps * dt)`` ticks per frame) unless that needs more than
        ``max_frames`` frames.  ``1`` draws every tick.
    max_frames : int
        Cap used by the default ``frame_step``.
    hold_s : float
        Seconds the final frame (with the outcome) is shown.
    dpi, size_in : float
        Resolution and the size of the map's longer side in inches (defaults:
        640 x 680 pixels for a square map, 9-12 pt text; the title and the clock
        sit above the map, the legend below it).
    obstacle_trail_s : float or None
        Length of the discs' trails in simulated seconds (None: whole run).
    robot_trail : bool
        Draw the robot's trajectory so far.
    title : str, optional
        Default ``"<scenario>: <planner>"``.

    Returns
    -------
    AnimationInfo

    Raises
    ------
    AnimationError
        Bad options, MP4 without ffmpeg, or ffmpeg failing.
    """
    out = Path(out)
    fmt = (format or ("mp4" if out.suffix.lower() == ".mp4" else "gif")).lower()
    if fmt not in FORMATS:
        raise AnimationError(f"format must be one of {', '.join(FORMATS)}, got {format!r}")
    fps = _check_number("fps", fps, 0.0)
    hold_s = _check_number("hold_s", hold_s, 0.0, lo_ok=True)
    _check_number("dpi", dpi, 0.0)
    _check_number("size_in", size_in, 0.0)
    if obstacle_trail_s is not None:
        _check_number("obstacle_trail_s", obstacle_trail_s, 0.0, lo_ok=True)
    exe = require_ffmpeg() if fmt == "mp4" else None
    dt = float(ep.scenario.dt)
    if frame_step is None:
        if isinstance(max_frames, bool) or not isinstance(max_frames, (int, np.integer)) \
                or max_frames < 1:
            raise AnimationError(f"max_frames must be an integer >= 1, got {max_frames!r}")
        frame_step = auto_frame_step(ep.n_ticks, dt, fps, max_frames)
    ticks = frame_ticks(ep.n_ticks, frame_step)
    t0 = time.perf_counter()
    r = _EpisodeRenderer(ep, dpi=dpi, size_in=size_in, obstacle_trail_s=obstacle_trail_s,
                         robot_trail=robot_trail, title=title)
    if fmt == "gif":
        size = _write_gif(r, ticks, out, fps, hold_s)
    else:
        size = _write_mp4((r.render(int(k)) for k in ticks), out, fps, hold_s,
                          exe)  # type: ignore[arg-type]
    return AnimationInfo(path=out, format=fmt, ticks=ticks, frame_step=int(frame_step),
                         fps=fps, hold_s=hold_s, size_px=size,
                         render_s=time.perf_counter() - t0)


def _write_gif(r: _EpisodeRenderer, ticks: np.ndarray, out: Path, fps: float,
               hold_s: float) -> tuple[int, int]:
    from PIL import Image

    # Pillow < 9.1 has no Quantize/Dither enums: the plain ints then
    mediancut: Any = getattr(getattr(Image, "Quantize", Image), "MEDIANCUT", 0)
    no_dither: Any = getattr(getattr(Image, "Dither", Image), "NONE", 0)

    def rgb(k: int) -> Any:
        return Image.fromarray(np.ascontiguousarray(r.render(int(k))[:, :, :3]), "RGB")

    # One palette for the whole GIF, from the first, a middle and the last frame stacked
    # (they hold every kind of colour drawn: map, paths, sensed and unsensed discs, outcome).
    # Mapping each frame onto it is ~40x faster than a per-frame adaptive palette.
    probe = [rgb(k) for k in sorted({int(ticks[0]), int(ticks[len(ticks) // 2]),
                                     int(ticks[-1])})]
    w, h = probe[0].size
    mosaic = Image.new("RGB", (w, h * len(probe)))
    for i, im in enumerate(probe):
        mosaic.paste(im, (0, i * h))
    palette = mosaic.quantize(colors=255, method=mediancut, dither=no_dither)
    images = [rgb(k).quantize(palette=palette, dither=no_dither) for k in ticks]
    n = len(images)
    step_ms = 1000.0 / fps
    durations = [int(round(step_ms))] * n
    durations[-1] = int(round(step_ms + 1000.0 * hold_s))
    images[0].save(out, format="GIF", save_all=True, append_images=images[1:],
                   duration=durations if n > 1 else durations[0], loop=0, disposal=1,
                   optimize=False)
    return (w, h)


def _write_mp4(frames: Any, out: Path, fps: float, hold_s: float, exe: str) -> tuple[int, int]:
    proc = None
    size = (0, 0)
    last = None
    try:
        for rgba in frames:
            if proc is None:
                h, w = rgba.shape[:2]
                size = (int(w), int(h))
                cmd = [exe, "-y", "-loglevel", "error", "-f", "rawvideo", "-pix_fmt", "rgba",
                       "-s", f"{w}x{h}", "-r", f"{fps:g}", "-i", "-",
                       "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2:color=white",
                       "-c:v", "libx264", "-pix_fmt", "yuv420p", "-movflags", "+faststart",
                       str(out)]
                proc = subprocess.Popen(cmd, stdin=subprocess.PIPE, stdout=subprocess.DEVNULL,
                                        stderr=subprocess.PIPE)
            proc.stdin.write(np.ascontiguousarray(rgba).tobytes())  # type: ignore[union-attr]
            last = rgba
        if proc is None:
            raise AnimationError("no frames to write")
        for _ in range(int(round(hold_s * fps))):
            proc.stdin.write(np.ascontiguousarray(last).tobytes())  # type: ignore[union-attr]
        _, err = proc.communicate()
    except BrokenPipeError:
        _, err = proc.communicate() if proc is not None else (b"", b"")
    if proc is not None and proc.returncode != 0:
        msg = (err or b"").decode(errors="replace").strip().splitlines()
        raise AnimationError(f"ffmpeg failed writing {out} (exit {proc.returncode}): "
                             f"{msg[-1] if msg else 'no message'}")
    return size
