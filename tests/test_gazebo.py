"""The Gazebo/SDF world reader: known cells, exact rasterisation, BARN worlds, bad input."""

from __future__ import annotations

import gzip
import math
from pathlib import Path

import numpy as np
import pytest

import pathfuse
from pathfuse.io import map_from_spec
from pathfuse.io.gazebo import read_gazebo_world, world_footprints
from pathfuse.io.shapes import Footprint, add_disc, add_polygon, convex_hull
from pathfuse.result import ConfigError, MapError, MapFormatError

DATA = Path(__file__).parent / "data"
KNOWN = DATA / "gazebo" / "known_cells.world"
BARN = DATA / "barn" / "worlds"

# the hand-made world at 1 m cells, bounds (0, 0, 8, 6), top row first (see the file)
KNOWN_ROWS = [
    "#.#.....",
    ".###....",
    "..#..#..",
    ".#.....#",
    "###.....",
    ".#..###.",
]


def _rows(grid: pathfuse.GridMap) -> list[str]:
    return ["".join("#" if v else "." for v in row) for row in grid.occupied[::-1]]


def test_known_cells():
    g = read_gazebo_world(KNOWN, 1.0, bounds=(0, 0, 8, 6))
    assert g.origin == (0.0, 0.0) and g.shape == (6, 8)
    assert _rows(g) == KNOWN_ROWS
    assert g.meta["skipped"]["dynamic"] == ["robot"]
    assert g.meta["skipped"]["outside_z_range"] == ["ceiling/link/collision"]
    assert g.meta["skipped"]["ground"] == ["ground_plane/link/collision"]
    assert g.meta["state_poses"] == 2
    assert g.name == "known_cells"


def test_known_cells_gzipped_and_via_load_map_and_spec(tmp_path):
    gz = tmp_path / "known.world.gz"
    gz.write_bytes(gzip.compress(KNOWN.read_bytes()))
    a = pathfuse.load_map(gz, resolution=1.0, bounds=(0, 0, 8, 6))
    b = map_from_spec({"gazebo": "known.world.gz", "resolution": 1.0, "bounds": [0, 0, 8, 6]},
                      tmp_path)
    sdf = tmp_path / "known.sdf"
    sdf.write_bytes(KNOWN.read_bytes())
    c = pathfuse.load_map(sdf, resolution=1.0, bounds=(0, 0, 8, 6))
    for g in (a, b, c):
        assert _rows(g) == KNOWN_ROWS


def test_default_bounds_follow_the_shapes_with_a_margin():
    g = read_gazebo_world(KNOWN, 0.5)
    # shapes span x 0.9..8.0 (the touch disc reaches 8.0), y 0..5.8; margin 1 m, snapped
    fps = g.meta["footprints"]
    boxes = np.array([fp.bbox() for fp in fps])
    x0, y0, x1, y1 = g.bounds
    assert x0 <= boxes[:, 0].min() - 1.0 and x0 > boxes[:, 0].min() - 1.5
    assert y0 <= boxes[:, 1].min() - 1.0 and x1 >= boxes[:, 2].max() + 1.0
    assert y1 >= boxes[:, 3].max() + 1.0
    assert abs(x0 / 0.5 - round(x0 / 0.5)) < 1e-9  # cell edges on multiples of the resolution


def test_state_link_pose_overrides_and_deletions(tmp_path):
    text = KNOWN.read_text().replace(
        '<model name="post">\n        <pose frame="">1.5 1.5 0.5 0 0 0</pose>\n      </model>',
        '<model name="post"><link name="link"><pose>4.5 2.5 0.5 0 0 0</pose></link></model>'
        '<deletions><name>wall</name></deletions>')
    p = tmp_path / "moved.world"
    p.write_text(text)
    g = read_gazebo_world(p, 1.0, bounds=(0, 0, 8, 6))
    rows = _rows(g)
    assert rows[5 - 0] == "........"  # the wall is deleted, the post moved away
    assert rows[5 - 2] == "...###.#"  # the post at (4.5, 2.5), r 0.6: a plus around (2, 4)
    assert rows[5 - 1][4] == "#" and rows[5 - 3][4] == "#"


def test_include_dynamic_models():
    g = read_gazebo_world(KNOWN, 1.0, bounds=(0, 0, 8, 6), include_dynamic=True)
    assert g.occupied[2, 3]  # the robot's box at (3.5, 2.5)
    assert g.meta["skipped"]["dynamic"] == []


# --------------------------------------------------------------------- exact rule
def _brute_overlaps(fp: Footprint, x0: float, y0: float, res: float, n: int = 60) -> float:
    """Least signed distance from the cell's interior samples to the shape (< 0: overlap)."""
    s = (np.arange(n) + 0.5) / n * res
    xx, yy = np.meshgrid(x0 + s, y0 + s)
    pts = np.stack([xx.ravel(), yy.ravel()], axis=1)
    return float(fp.distance(pts).min())


@pytest.mark.parametrize("seed", range(6))
def test_rasterisation_against_sampling(seed):
    rng = np.random.default_rng(seed)
    res = 0.25
    shape = (16, 16)
    for _ in range(20):
        if rng.random() < 0.5:
            fp = Footprint("disc", (float(rng.uniform(0.5, 3.5)), float(rng.uniform(0.5, 3.5))),
                           radius=float(rng.uniform(0.05, 0.8)))
            occ = np.zeros(shape, dtype=bool)
            add_disc(occ, fp.center, fp.radius, (0.0, 0.0), res)
        else:
            c = rng.uniform(1.0, 3.0, 2)
            a = rng.uniform(0, math.pi)
            hx, hy = rng.uniform(0.05, 0.6, 2)
            rot = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
            corners = np.array([[-hx, -hy], [hx, -hy], [hx, hy], [-hx, hy]]) @ rot.T + c
            hull = convex_hull(corners)
            fp = Footprint("polygon", (float(c[0]), float(c[1])), vertices=hull)
            occ = np.zeros(shape, dtype=bool)
            add_polygon(occ, hull, (0.0, 0.0), res)
        for r in range(shape[0]):
            for col in range(shape[1]):
                d = _brute_overlaps(fp, col * res, r * res, res)
                if d < -0.01:  # clearly overlapping: sampled points inside
                    assert occ[r, col], (fp, r, col, d)
                # clearly apart: every interior sample (spacing res/60) farther than the gap
                # a missed overlap could hide in
                elif d > res / 60:
                    assert not occ[r, col], (fp, r, col, d)


# --------------------------------------------------------------------- BARN
def test_barn_world_cylinders_and_grid():
    shapes = world_footprints(BARN / "world_0.world.gz")
    assert len(shapes.footprints) == 209 and shapes.state_poses == 210
    assert {fp.radius for fp in shapes.footprints} == {0.075}
    c = np.array([fp.center for fp in shapes.footprints])
    # centres on BARN's 0.15 m lattice (x = -0.075 - 0.15 k, y = 0.075 + 0.15 k)
    assert np.allclose((c[:, 0] + 0.075) / 0.15, np.round((c[:, 0] + 0.075) / 0.15), atol=1e-6)
    assert np.allclose((c[:, 1] - 0.075) / 0.15, np.round((c[:, 1] - 0.075) / 0.15), atol=1e-6)
    g = read_gazebo_world(BARN / "world_0.world.gz", 0.05, bounds=(-5.6, -1.0, 1.1, 14.0))
    # at 0.05 m every cylinder centre lies mid-cell and covers exactly its 3 x 3 cells
    assert g.origin == pytest.approx((-5.6, -1.0))
    expect = np.zeros(g.shape, dtype=bool)
    for fp in shapes.footprints:
        rc = g.world_to_cell(fp.center)[0]
        expect[rc[0] - 1:rc[0] + 2, rc[1] - 1:rc[1] + 2] = True
    assert np.array_equal(g.occupied, expect)


def test_barn_reference_path_lies_clear_of_the_cylinders():
    """SOURCES.md's transform of the path files: x = 0.15 i - 4.575, y = 0.15 j + 5.075."""
    shapes = world_footprints(BARN / "world_17.world.gz")
    c = np.array([fp.center for fp in shapes.footprints])
    p = np.load(DATA / "barn" / "path_files" / "path_17.npy")
    xy = np.stack([0.15 * p[:, 0] - 4.575, 0.15 * p[:, 1] + 5.075], axis=1)
    gap = np.hypot(xy[:, None, 0] - c[None, :, 0], xy[:, None, 1] - c[None, :, 1]).min(1)
    assert gap.min() - 0.075 > 0.2
    # the swapped reading (i as y, j as x) runs through cylinders: the transform is pinned
    yx = np.stack([0.15 * p[:, 1] - 4.575, 0.15 * p[:, 0] + 5.075], axis=1)
    gap = np.hypot(yx[:, None, 0] - c[None, :, 0], yx[:, None, 1] - c[None, :, 1]).min(1)
    assert gap.min() - 0.075 < 0


# --------------------------------------------------------------------- bad input
def _world(tmp_path: Path, body: str, name: str = "bad.world") -> Path:
    p = tmp_path / name
    p.write_text(f"<sdf version='1.6'><world name='w'>{body}</world></sdf>")
    return p


def _model(geometry: str, pose: str = "0 0 0.5 0 0 0", extra: str = "") -> str:
    return (f"<model name='m'><static>1</static><pose>{pose}</pose><link name='l'>"
            f"<collision name='c'><geometry>{geometry}</geometry></collision></link>{extra}"
            "</model>")


CYL = "<cylinder><radius>0.5</radius><length>1</length></cylinder>"


@pytest.mark.parametrize("body, fragment", [
    (_model("<mesh><uri>model://x.dae</uri></mesh>"), "unsupported geometry <mesh>"),
    (_model(CYL, pose="0 0 0.5 0.3 0 0"), "tilted <cylinder>"),
    (_model("<cylinder><radius>-1</radius><length>1</length></cylinder>"), "must be > 0"),
    (_model("<cylinder><radius>abc</radius><length>1</length></cylinder>"),
     "must be numbers"),
    (_model("<box><size>1 1</size></box>"), "must be 3 finite numbers"),
    (_model(CYL, pose="0 0 nan 0 0 0"), "finite numbers"),
    (_model(CYL, pose="1 2 3"), "must be 6 finite numbers"),
    ("<model name='m'><static>1</static><link name='l'><collision name='c'>"
     "</collision></link></model>", "no <geometry>"),
    ("<include><uri>model://bookshelf</uri></include>", "cannot be resolved"),
    (_model(CYL).replace("<pose>", "<pose relative_to='other'>"), "relative to another"),
    ("", "holds no static obstacle geometry"),
    ("<model name='g'><static>1</static><link name='l'><collision name='c'><geometry><plane>"
     "<normal>0 0 1</normal></plane></geometry></collision></link></model>",
     "holds no static obstacle geometry"),
])
def test_malformed_worlds(tmp_path, body, fragment):
    p = _world(tmp_path, body)
    with pytest.raises(MapFormatError) as err:
        read_gazebo_world(p, 0.1)
    msg = str(err.value)
    assert fragment in msg and str(p) in msg


def test_error_names_the_line_and_model(tmp_path):
    p = tmp_path / "lines.world"
    p.write_text("<sdf version='1.6'>\n<world name='w'>\n" + _model(CYL) + "\n"
                 + _model("<heightmap/>").replace("'m'", "'hill'") + "\n</world></sdf>")
    with pytest.raises(MapFormatError, match=r"line 4: model 'hill' link 'l' collision 'c': "
                                             r"unsupported geometry <heightmap>"):
        read_gazebo_world(p)


@pytest.mark.parametrize("text, fragment", [
    ("<sdf><world name='w'><model name='m'></world></sdf>", "malformed XML: mismatched tag"),
    ("<sdf><world", "malformed XML"),
    ("not xml at all", "malformed XML"),
    ("   ", "the file is empty"),
    ("<?xml version='1.0'?><!DOCTYPE lolz [<!ENTITY lol 'lol'><!ENTITY lol2 "
     "'&lol;&lol;&lol;&lol;'>]><sdf><world name='w'>&lol2;</world></sdf>",
     "document type declarations and entities are refused"),
    ("<?xml version='1.0'?><!DOCTYPE sdf SYSTEM 'file:///etc/passwd'><sdf/>",
     "document type declarations"),
    ("<model name='m'/>", "root element is <model>"),
    ("<sdf version='1.6'></sdf>", "expected one <world>"),
])
def test_malformed_xml(tmp_path, text, fragment):
    p = tmp_path / "x.world"
    p.write_text(text)
    with pytest.raises(MapFormatError, match=fragment):
        read_gazebo_world(p)


def test_file_errors(tmp_path):
    with pytest.raises(MapFormatError, match="world file not found"):
        read_gazebo_world(tmp_path / "missing.world")
    fake = tmp_path / "fake.world.gz"
    fake.write_text("<sdf/>")
    with pytest.raises(MapFormatError, match="not gzip-compressed"):
        read_gazebo_world(fake)
    broken = tmp_path / "broken.world.gz"
    broken.write_bytes(gzip.compress(KNOWN.read_bytes())[:200])
    with pytest.raises(MapFormatError, match="corrupt gzip"):
        read_gazebo_world(broken)
    with pytest.raises(MapFormatError, match="unsupported map file type"):
        pathfuse.load_map(tmp_path / "w.world.bz2")


def test_argument_errors(tmp_path):
    with pytest.raises(ConfigError, match="resolution"):
        read_gazebo_world(KNOWN, 0)
    with pytest.raises(ConfigError, match="bounds"):
        read_gazebo_world(KNOWN, 1.0, bounds=(0, 0, -1, 5))
    with pytest.raises(ConfigError, match="bounds= applies to Gazebo worlds only"):
        pathfuse.load_map(DATA / "movingai" / "den312d.map", bounds=(0, 0, 1, 1))
    with pytest.raises(ConfigError, match="not origin"):
        pathfuse.load_map(KNOWN, origin=(0, 0))
    with pytest.raises(MapError, match="larger than"):
        read_gazebo_world(KNOWN, 1e-4)  # 1e10 cells: refused before allocating


def test_gazebo_map_in_a_bench_experiment_and_a_scenario(tmp_path):
    from pathfuse.bench import ResultStore, run_bench
    from pathfuse.world import load_scenario

    exp = tmp_path / "exp.yaml"
    exp.write_text(
        "name: g\nseeds: 1\nmaps:\n"
        f"  - name: known\n    map: {{gazebo: {KNOWN}, resolution: 0.5, bounds: [0, 0, 8, 6]}}\n"
        "    queries: [{start: [0.25, 3.25], goal: [7.75, 5.75]}]\n"
        "planners: [astar]\n")
    summary = run_bench(exp, tmp_path / "g.db", workers=1, progress=False)
    assert summary.errors == 0
    store = ResultStore(tmp_path / "g.db")
    try:
        (row,) = store.results()
    finally:
        store.close()
    assert row["status_name"] == "SUCCESS" and row["collision_free"]
    sc = load_scenario({"map": {"gazebo": str(KNOWN), "resolution": 1.0, "bounds": [0, 0, 8, 6]},
                        "start": [3.5, 2.5], "goal": [6.5, 5.5], "robot": {"radius": 0.2}})
    assert _rows(sc.grid) == KNOWN_ROWS
