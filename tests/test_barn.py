"""The BARN preset: protocol, every episode re-checked for collision, `pathfuse barn` end to end."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from pathfuse.io.gazebo import world_footprints
from pathfuse.metrics import evaluate, segment_clearances
from pathfuse.result import ConfigError, PlanResult, Status
from pathfuse.studies.barn import (
    BARN_BOUNDS,
    BARN_GOAL,
    BARN_START,
    BarnConfig,
    barn_metric,
    find_worlds,
    parse_world_selection,
    path_to_world,
    reference_length,
    run_barn,
)
from pathfuse.studies.barn_report import summary_rows

BARN = Path(__file__).parent / "data" / "barn"


# --------------------------------------------------------------------- protocol
def test_reference_length_is_the_polyline_start_path_goal():
    ij = np.load(BARN / "path_files" / "path_17.npy")
    pts = np.vstack([BARN_START, path_to_world(ij), BARN_GOAL])
    expect = sum(math.dist(a, b) for a, b in zip(pts[:-1], pts[1:], strict=True))
    assert reference_length(ij) == pytest.approx(expect, rel=1e-12)
    assert path_to_world([[0, 0]]).tolist() == [[-4.575, 5.075]]


@pytest.mark.parametrize("time_s, metric", [(1.0, 0.5), (10.0, 0.5), (20.0, 0.25),
                                            (80.0, 0.125), (99.0, 0.125)])
def test_metric_clips_between_2_and_8_optimal_times(time_s, metric):
    assert barn_metric(True, time_s, 10.0 / 2.0 * 1.0) == pytest.approx(
        5.0 / min(max(time_s, 10.0), 40.0))
    assert barn_metric(True, time_s, 5.0) == pytest.approx(metric)
    assert barn_metric(False, time_s, 5.0) == 0.0


def test_world_selection_and_folder_errors(tmp_path):
    assert parse_world_selection("20, 0-1,17") == ((0, 1), (17, 17), (20, 20))
    assert parse_world_selection(None) is None
    assert parse_world_selection(((0, 1), (17, 17))) == ((0, 1), (17, 17))  # idempotent
    for bad in ("", "a", "3-1", "1,,x"):
        with pytest.raises(ConfigError, match="worlds"):
            parse_world_selection(bad)
    assert [w.index for w in find_worlds(BARN)] == [0, 17, 20, 43]
    assert [w.index for w in find_worlds(BARN / "worlds", [20])] == [20]
    with pytest.raises(ConfigError, match="no world file for index 5"):
        find_worlds(BARN, [5])
    assert [w.index for w in find_worlds(BARN, "0-18")] == [0, 17]  # a range: those present
    with pytest.raises(ConfigError, match="no world file in 1-16"):
        find_worlds(BARN, "1-16")
    with pytest.raises(ConfigError, match="no such folder"):
        find_worlds(tmp_path / "nope")
    with pytest.raises(ConfigError, match="no BARN world"):
        find_worlds(tmp_path)
    (tmp_path / "worlds").mkdir()
    (tmp_path / "worlds" / "world_3.world.gz").write_bytes(
        (BARN / "worlds" / "world_0.world.gz").read_bytes())
    with pytest.raises(ConfigError, match=r"path_3\.npy: missing"):
        find_worlds(tmp_path)
    with pytest.raises(ConfigError, match="cannot run online|unknown planner"):
        BarnConfig(str(BARN), planners=("nope",))


# --------------------------------------------------------------------- episodes
def _segment_point_distance(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Least distance from each segment a[i]-b[i] (N, 2) to each point c (K, 2): (N, K)."""
    ab = b - a
    den = np.maximum(np.sum(ab * ab, axis=1), 1e-300)[:, None]
    t = np.clip(((c[None, :, 0] - a[:, None, 0]) * ab[:, None, 0]
                 + (c[None, :, 1] - a[:, None, 1]) * ab[:, None, 1]) / den, 0.0, 1.0)
    px = a[:, None, 0] + t * ab[:, None, 0]
    py = a[:, None, 1] + t * ab[:, None, 1]
    return np.hypot(px - c[None, :, 0], py - c[None, :, 1])


@pytest.fixture(scope="module")
def barn_run():
    cfg = BarnConfig(str(BARN), resolution=0.05)  # every online planner, every test world
    return run_barn(cfg, workers=1)


def test_every_episode_rechecked_for_collision(barn_run):
    """Each trajectory against the exact cylinders of its world (a check that knows nothing
    of grids) and against the grid (pathfuse.metrics), independently of the simulator."""
    from pathfuse.io.gazebo import read_gazebo_world

    cfg = barn_run.config
    radius = cfg.robot_radius_m
    worlds = {w.index: w for w in barn_run.worlds}
    assert len(barn_run.records) == len(worlds) * len(cfg.planners)
    checked = 0
    cylinders = {}
    grids = {}
    for i, w in worlds.items():
        shapes = world_footprints(w.world)
        cylinders[i] = (np.array([fp.center for fp in shapes.footprints]),
                        np.array([fp.radius for fp in shapes.footprints]))
        grids[i] = read_gazebo_world(w.world, cfg.resolution, bounds=BARN_BOUNDS)
    for rec in barn_run.records:
        centres, cyl_r = cylinders[rec["world"]]
        traj = np.array(rec["trajectory"])
        assert traj.shape[1] == 4 and traj[0].tolist()[:3] == [0.0, *BARN_START]
        assert np.allclose(np.diff(traj[:, 0]), cfg.dt)
        pos = traj[:, 1:3]
        m = evaluate(grids[rec["world"]], PlanResult(Status.SUCCESS, pos), radius)
        if rec["status"] == "collision":
            assert not m["collision_free"]  # the simulator's collision is real on the grid
            continue
        if pos.shape[0] > 1:
            # between two ticks a diff-drive robot drives an arc, not the chord between the
            # recorded poses: the arc leaves its chord by at most its sagitta, s |dtheta| / 8
            # (s the arc length, a hair above the chord), so each chord may come that much
            # closer to an obstacle than the robot did
            assert m["in_bounds"], rec["planner"]
            chord = np.hypot(*np.diff(pos, axis=0).T)
            turn = np.abs((np.diff(traj[:, 3]) + math.pi) % (2 * math.pi) - math.pi)
            sag = 1.01 * chord * turn / 8.0 + 1e-9
            seg = segment_clearances(grids[rec["world"]], pos)
            assert np.all(seg >= radius - sag), (rec["world"], rec["planner"],
                                                 float(np.min(seg - radius + sag)))
            gap = _segment_point_distance(pos[:-1], pos[1:], centres) - cyl_r[None, :]
            worst = gap.min(axis=1) - radius + sag
            assert worst.min() >= 0, (rec["world"], rec["planner"], worst.min())
        else:
            assert m["collision_free"], rec["planner"]
        checked += 1
        if rec["status"] == "success":
            assert math.dist(pos[-1], BARN_GOAL) <= 1.0 + 1e-9
            assert 0 < rec["metric"] <= 0.5
    assert checked >= len(barn_run.records) // 2


def test_summary_counts_every_episode(barn_run):
    rows = summary_rows(barn_run.records, barn_run.config.planners)
    for r in rows:
        assert r["success"] + r["collision"] + r["timeout"] == r["episodes"] == 4
    fusion = next(r for r in rows if r["planner"] == "fusion")
    assert fusion["success"] == 4 and fusion["collision"] == 0


# --------------------------------------------------------------------- CLI
def _cli(*args: object, cwd: Path | None = None,
         env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "pathfuse.cli", *map(str, args)],
                          capture_output=True, text=True, timeout=600, cwd=cwd, env=env)


def test_cli_end_to_end_on_two_worlds(tmp_path):
    out = tmp_path / "barn-out"
    p = _cli("barn", BARN, "--worlds", "17,20", "--planners", "fusion,astar", "--workers", 1,
             "--out", out, "--json")
    assert p.returncode == 0, p.stderr
    lines = [json.loads(s) for s in p.stdout.splitlines()]
    assert [(r["world"], r["planner"]) for r in lines] == [
        (17, "fusion"), (17, "astar"), (20, "fusion"), (20, "astar")]
    for r in lines:
        assert {"world", "planner", "status", "time_s", "metric", "robot_radius_m",
                "trajectory"} <= set(r)
        assert r["status"] in ("success", "collision", "timeout")
        assert r["robot_radius_m"] == pytest.approx(0.333)
        traj = np.array(r["trajectory"])
        assert traj.shape == (r["ticks"] + 1, 4)
    assert all(r["status"] == "success" for r in lines)
    for name in ("barn.md", "summary.csv", "episodes.csv", "study.db", "barn_planners.png"):
        assert (out / name).is_file()
    (world_png,) = out.glob("barn_world_*.png")  # one world's trajectories, a world run
    assert world_png.name in ("barn_world_17.png", "barn_world_20.png")
    assert f"wrote {world_png}" in p.stderr
    md = (out / "barn.md").read_text()
    assert "DWA (published)" in md and "not a like-for-like comparison" in md
    # the same command again resumes: nothing left to run, the same episodes
    q = _cli("barn", BARN, "--worlds", "17,20", "--planners", "fusion,astar", "--workers", 1,
             "--out", out)
    assert q.returncode == 0, q.stderr
    assert "fusion" in q.stdout and "DWA (published)" in q.stdout
    assert "2/2 = 100.0%" in q.stdout


@pytest.mark.parametrize("args, fragment", [
    (["barn", "/no/such/barn"], "no such folder"),
    (["barn", BARN, "--worlds", "99"], "no world file for index 99"),
    (["barn", BARN, "--planners", "nope"], "unknown planner"),
    (["barn", BARN, "--resolution", "-1"], "--resolution"),
    (["barn", BARN, "--worlds", "17", "--figure-world", "20"],
     "--figure-world: world 20 is not among the worlds run (17)"),
    (["barn", BARN, "--figure-world", "-1"], "--figure-world"),
])
def test_cli_bad_input(tmp_path, args, fragment):
    # an empty numba cache: the error must come before the compile notice, one line
    p = _cli(*args, "--out", tmp_path / "o",
             env={**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "numba")})
    assert p.returncode == 2
    assert fragment in p.stderr and "Traceback" not in p.stderr
    assert len(p.stderr.strip().splitlines()) == 1


# --------------------------------------------------------------------- figures
def _split(records, world):
    st = [r["status"] for r in records if r["world"] == world]
    ok = st.count("success")
    return min(ok, len(st) - ok)


def test_the_run_keeps_the_paths_of_the_world_its_figure_shows(barn_run):
    from pathfuse.studies.barn import pick_figure_world

    w = barn_run.figure_world
    assert w == pick_figure_world(barn_run.records)
    # no world splits the planners into successes and failures more evenly
    assert _split(barn_run.records, w) == max(_split(barn_run.records, x.index)
                                              for x in barn_run.worlds)
    assert list(barn_run.paths) == list(barn_run.config.planners)
    for r in barn_run.records:
        if r["world"] == w:
            assert np.array_equal(barn_run.paths[r["planner"]],
                                  np.array(r["trajectory"])[:, 1:3])
    cfg = BarnConfig(str(BARN), worlds="17,20", planners=("astar",))
    assert run_barn(cfg, figure_world=20).figure_world == 20
    none = run_barn(cfg, figure_world=None)
    assert none.figure_world is None and none.paths == {}
    with pytest.raises(ConfigError, match=r"figure_world: world 43 is not among the worlds "
                                          r"run \(17, 20\)"):
        run_barn(cfg, figure_world=43)


def test_the_planner_figure_shows_each_planner_and_the_reference(barn_run):
    from pathfuse.studies.barn import DWA_BASELINE
    from pathfuse.viz.barn import OUTCOME_COLOURS, plot_barn_planners

    rows = summary_rows(barn_run.records, barn_run.config.planners)
    fig = plot_barn_planners(rows, baseline=DWA_BASELINE)
    ax_o, ax_m = fig.axes[:2]
    labels = [t.get_text() for t in ax_o.get_yticklabels()]
    assert labels == [f"{r['planner']} (n=4)" for r in rows] + ["DWA (published): reference"]
    ys = list(ax_o.get_yticks())
    assert ys == sorted(ys, reverse=True)  # the first planner at the top
    want = [(r["success_rate"], r["collision_rate"], r["timeout_rate"], r["metric_mean"])
            for r in rows]
    want.append(tuple(DWA_BASELINE[k] for k in ("success", "collision", "timeout", "metric")))
    for y, (s, c, t, m) in zip(ys, want, strict=True):
        bars = sorted((b for b in ax_o.patches if abs(b.get_y() + b.get_height() / 2 - y) < 1e-9),
                      key=lambda b: b.get_x())
        assert [b.get_width() for b in bars] == pytest.approx([100 * s, 100 * c, 100 * t])
        assert [b.get_facecolor()[:3] for b in bars] == [
            pytest.approx(matplotlib_rgb(OUTCOME_COLOURS[o]))
            for o in ("success", "collision", "timeout")]
        # the mean metric is drawn at its value on the row
        assert any(np.allclose(ln.get_xydata(), [[m, y]]) for ln in ax_m.lines)


def matplotlib_rgb(colour):
    from matplotlib.colors import to_rgb

    return to_rgb(colour)


def test_the_world_figure_draws_each_trajectory_in_its_panel(barn_run, tmp_path):
    from PIL import Image

    from pathfuse.io.gazebo import read_gazebo_world
    from pathfuse.studies.barn_report import write_barn_outputs
    from pathfuse.viz.barn import plot_barn_world
    from pathfuse.viz.dynamic import planner_colours

    w = barn_run.figure_world
    files = write_barn_outputs(barn_run, tmp_path)
    assert files["planners_png"] == tmp_path / "barn_planners.png"
    assert files["world_png"] == tmp_path / f"barn_world_{w}.png"
    for key in ("planners_png", "world_png"):
        assert Image.open(files[key]).format == "PNG"
    md = files["report_md"].read_text(encoding="utf-8")
    assert "](barn_planners.png)" in md and f"](barn_world_{w}.png)" in md
    cfg = barn_run.config
    recs = {r["planner"]: r for r in barn_run.records if r["world"] == w}
    tracks = [{"planner": n, "status": recs[n]["status"], "time_s": recs[n]["time_s"],
               "positions": barn_run.paths[n]} for n in cfg.planners]
    (world,) = [x for x in barn_run.worlds if x.index == w]
    grid = read_gazebo_world(world.world, cfg.resolution, bounds=BARN_BOUNDS)
    fig = plot_barn_world(grid, tracks, start=BARN_START, goal=BARN_GOAL,
                          goal_tolerance_m=1.0, robot_radius_m=cfg.robot_radius_m)
    panels = [ax for ax in fig.axes if ax.get_visible()]
    colours = planner_colours(list(cfg.planners))
    assert len(panels) == len(tracks)
    for ax, t in zip(panels, tracks, strict=True):
        name, status = t["planner"], t["status"]
        assert ax.get_title().split("\n")[0] == name and status in ax.get_title()
        (own,) = [ln for ln in ax.lines
                  if ln.get_color() == colours[name] and ln.get_linestyle() == "-"]
        assert np.array_equal(own.get_xydata(), t["positions"])
        crosses = [ln for ln in ax.lines if ln.get_marker() == "X"]
        assert len(crosses) == (status == "collision")
    fig.canvas.draw()  # the key under the panels, over none of them
    r = fig.canvas.get_renderer()
    (key,) = fig.legends
    kb = key.get_window_extent(r)
    assert all(kb.y1 <= ax.get_tightbbox(r).y0 for ax in panels)


def test_online_subgoal_planners_do_not_jump_over_a_fine_subgoal(barn_run):
    """At 2 m/s and dt 0.1 s a move is 0.2 m; a sub-goal passed only within a fraction of a
    0.05 m cell was jumped over back and forth until the time limit (before the default
    tolerance became at least one move).  ref6 reaches these two worlds offline."""
    got = {(r["world"], r["planner"]): r["status"] for r in barn_run.records}
    assert got[(0, "ref6")] == "success" and got[(20, "ref6")] == "success"


def test_default_subgoal_tolerance_is_at_least_one_move():
    from pathfuse.grid import GridMap
    from pathfuse.planners.controllers.refs import (
        Ref6Controller,
        Ref6Params,
        Ref7Controller,
        Ref7Params,
    )
    from pathfuse.planners.registry import get_planner
    from pathfuse.planners.run import start_online
    from pathfuse.problem import Problem

    g = GridMap.from_rows(["." * 40] * 10, resolution=0.05)
    prob = Problem.create(g, (0.125, 0.125), (1.875, 0.375), 0.0)
    for name, params in (("ref6", Ref6Params()), ("ref7", Ref7Params())):
        online = start_online(get_planner(name), prob, params, 0.1, 2.0)
        assert isinstance(online, (Ref6Controller, Ref7Controller))
        assert online.subgoal_tolerance() == pytest.approx(0.2)  # the move, not 1/2 or 1/4 cell
    explicit = start_online(get_planner("ref7"), prob, Ref7Params(subgoal_tolerance_m=0.01),
                            0.1, 2.0)
    assert explicit.subgoal_tolerance() == 0.01


def test_barn_experiment_file(tmp_path):
    from pathfuse.studies.barn import load_barn_file

    f = tmp_path / "barn.yaml"
    f.write_text(f"name: t\ndirectory: {BARN}\nworlds: 17-20\nplanners: [fusion]\n"
                 "robot: {model: holonomic, radius: 0.3, max_speed: 1.0}\n"
                 "params: {fusion: {r1_m: 1.0}}\n")
    cfg, meta = load_barn_file(f)
    assert meta["name"] == "t" and cfg.planners == ("fusion",)
    assert [w.index for w in find_worlds(cfg.directory, cfg.worlds)] == [17, 20]
    assert cfg.robot["model"] == "holonomic" and cfg.robot_radius_m == 0.3
    bad = tmp_path / "bad.yaml"
    bad.write_text(f"directory: {BARN}\nplanner: [fusion]\n")
    with pytest.raises(ConfigError, match=r"bad\.yaml: unknown key 'planner'"):
        load_barn_file(bad)
    bad.write_text(f"directory: {BARN}\nresolution: -1\n")
    with pytest.raises(ConfigError, match=r"bad\.yaml: resolution: must be a number > 0"):
        load_barn_file(bad)
    # through the command line, an option overriding the file
    p = _cli("barn", f, "--planners", "astar", "--worlds", "20", "--workers", 1,
             "--out", tmp_path / "o")
    assert p.returncode == 0, p.stderr
    assert "astar" in p.stdout and "1/1 = 100.0%" in p.stdout and "fusion " not in p.stdout
    p = _cli("barn", f, "--workers", 1, "--out", tmp_path / "o2")  # the file's own worlds
    assert p.returncode == 0, p.stderr
    assert "2 episodes (1 planner x 2 worlds)" in p.stdout


def test_shipped_experiment_file_reads():
    from pathfuse.studies.barn import load_barn_file

    cfg, meta = load_barn_file(Path(__file__).parents[1] / "experiments" / "barn-jackal.yaml")
    assert meta["name"] == "barn-jackal" and cfg.robot["model"] == "diff-drive"
    assert cfg.worlds is None and cfg.resolution == 0.05


def test_barn_on_a_dask_cluster_equals_the_local_run(tmp_path):
    distributed = pytest.importorskip("distributed")
    cfg = BarnConfig(str(BARN), worlds="17", planners=("fusion", "astar"))
    local = run_barn(cfg, workers=1)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True,
                                  host="127.0.0.1", dashboard_address=None,
                                  silence_logs=40) as cluster:
        remote = run_barn(cfg, scheduler=cluster.scheduler_address, db_path=tmp_path / "d.db")
    assert local.records == remote.records


@pytest.mark.parametrize("planner", ["astar-smooth", "thetastar", "lazy-thetastar", "shortest"])
def test_any_angle_followers_keep_the_radius_at_corners(planner):
    """An any-angle path is taut: it turns where it touches the robot's clearance around a
    cylinder.  A holonomic robot walking it at 2 m/s must not cut across those corners
    (on world 43 the followers once came 3 mm too close and collided); each tick's
    straight move is re-checked against the grid and the exact cylinders."""
    from pathfuse.io.gazebo import read_gazebo_world
    from pathfuse.studies.barn import _scenario, jackal_robot
    from pathfuse.world import simulate

    (w,) = find_worlds(BARN, [43])
    cfg = BarnConfig(str(BARN), resolution=0.05, robot=jackal_robot("holonomic"))
    sc = _scenario(cfg, w, "0" * 16)  # the protocol's scenario of this world, at 2 m/s
    assert sc["robot"]["model"] == "holonomic" and sc["robot"]["max_speed"] == 2.0
    ep = simulate(sc, planner=planner)
    assert ep.status is Status.SUCCESS, ep.message
    pos = np.asarray(ep.positions)
    radius = cfg.robot_radius_m
    grid = read_gazebo_world(w.world, cfg.resolution, bounds=BARN_BOUNDS)
    assert segment_clearances(grid, pos).min() >= radius
    shapes = world_footprints(w.world)
    centres = np.array([fp.center for fp in shapes.footprints])
    cyl_r = np.array([fp.radius for fp in shapes.footprints])
    gap = _segment_point_distance(pos[:-1], pos[1:], centres) - cyl_r[None, :]
    assert gap.min() >= radius
