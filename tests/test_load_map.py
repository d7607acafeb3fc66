"""load_map (dispatch on file type) and map_from_spec (scenario map sections)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from pathfuse.generate import paper_map, random_map
from pathfuse.grid import GridMap
from pathfuse.io import load_map, map_from_spec, write_movingai, write_ros_map
from pathfuse.result import ConfigError, MapError, MapFormatError

ROOT = Path(__file__).resolve().parents[1]
TB3 = ROOT / "tests" / "data" / "ros" / "nav2_tb3_sandbox" / "tb3_sandbox.yaml"

REF = GridMap.from_rows(["#....", "..#..", "....#"], resolution=1.0)
PIXELS = np.where(REF.occupied[::-1], 0, 255).astype(np.uint8)   # top row first


@pytest.fixture
def files(tmp_path: Path) -> Path:
    write_movingai(REF, tmp_path / "m.map")
    write_ros_map(REF, tmp_path / "ros.yaml")
    (tmp_path / "rows.yaml").write_text("rows: ['#....', '..#..', '....#']\n")
    for ext in (".png", ".pgm", ".bmp"):
        Image.fromarray(PIXELS).save(tmp_path / ("img" + ext))
    np.save(tmp_path / "a.npy", REF.occupied)
    return tmp_path


@pytest.mark.parametrize(
    "name, kwargs, fmt",
    [
        ("m.map", {}, "movingai"),
        ("ros.yaml", {}, "ros"),
        ("rows.yaml", {}, "rows"),
        ("img.png", {"resolution": 1.0}, "image"),
        ("img.pgm", {"resolution": 1.0}, "image"),
        ("img.bmp", {"resolution": 1.0}, "image"),
        ("a.npy", {"resolution": 1.0}, "npy"),
    ],
)
def test_dispatch_by_suffix(files, name, kwargs, fmt):
    g = load_map(files / name, **kwargs)
    assert g.meta["format"] == fmt
    assert np.array_equal(g.occupied, REF.occupied), name
    assert g.resolution == 1.0 and g.origin == (0.0, 0.0)
    g2 = load_map(str(files / name), **kwargs)   # str works like Path
    assert np.array_equal(g2.occupied, g.occupied)


def test_yml_and_upper_case_suffix(files):
    (files / "rows.YML").write_text((files / "rows.yaml").read_text())
    assert np.array_equal(load_map(files / "rows.YML").occupied, REF.occupied)


def test_resolution_and_origin_passed_on(files):
    for name in ("m.map", "img.png", "a.npy", "rows.yaml"):
        g = load_map(files / name, resolution=0.25, origin=(3.0, -1.0))
        assert g.resolution == 0.25 and g.origin == (3.0, -1.0), name
        assert np.array_equal(g.occupied, REF.occupied)


def test_paper_and_seed():
    assert np.array_equal(load_map("paper").occupied, paper_map(0).occupied)
    assert np.array_equal(load_map("paper", seed=9).occupied, paper_map(9).occupied)
    assert not np.array_equal(load_map("paper", seed=9).occupied, paper_map(8).occupied)
    with pytest.raises(ConfigError, match="paper map has a fixed resolution"):
        load_map("paper", resolution=0.5)


def test_gridmap_passes_through():
    assert load_map(REF) is REF


def test_ros_unknown_policy_and_fixed_frame():
    assert load_map(TB3).free_count == 7903
    assert load_map(TB3, unknown="free").free_count == 7903 + 138683
    with pytest.raises(ConfigError, match="sets its own resolution"):
        load_map(TB3, resolution=0.1)
    with pytest.raises(ConfigError, match="'occupied' or 'free'"):
        load_map(TB3, unknown="sometimes")


def test_missing_file_names_path(tmp_path):
    for name in ("gone.map", "gone.yaml", "gone.png", "gone.npy"):
        with pytest.raises(MapFormatError, match=re.escape(f"not found: {tmp_path / name}")):
            load_map(tmp_path / name, resolution=1.0)


def test_unknown_suffix_lists_supported(tmp_path):
    (tmp_path / "m.txt").write_text("....")
    with pytest.raises(MapFormatError, match=r"unsupported map file type '\.txt'; supported: "
                                             r"'paper', \.map, \.yaml, \.yml, \.png"):
        load_map(tmp_path / "m.txt")
    with pytest.raises(MapFormatError, match=r"'\(no extension\)'.*\.npy"):
        load_map(tmp_path / "noext")


def test_resolution_required_for_images_and_npy(files):
    for name in ("img.png", "a.npy"):
        with pytest.raises(MapError, match=rf"{re.escape(name)}: a resolution .* is required"):
            load_map(files / name)


def test_yaml_without_image_or_rows(tmp_path):
    (tmp_path / "x.yaml").write_text("resolution: 0.1\n")
    with pytest.raises(MapFormatError, match=r"x\.yaml: a map YAML needs an 'image' key .* "
                                             r"or a 'rows' key.*\['resolution'\]"):
        load_map(tmp_path / "x.yaml")


# ----------------------------------------------------------------- map_from_spec
def test_spec_files_relative_to_base_dir(files):
    specs = [
        {"movingai": "m.map"},
        {"ros": "ros.yaml"},
        {"image": "img.png", "resolution": 1.0},
        {"npy": "a.npy", "resolution": 1.0},
    ]
    for spec in specs:
        g = map_from_spec(spec, base_dir=files)
        assert np.array_equal(g.occupied, REF.occupied), spec
    g = map_from_spec({"movingai": str(files / "m.map"), "resolution": 0.5, "origin": [1, 2],
                       "name": "mm"}, base_dir="/nonexistent")
    assert g.resolution == 0.5 and g.origin == (1.0, 2.0) and g.name == "mm"
    assert np.array_equal(map_from_spec("rows.yaml", base_dir=files).occupied, REF.occupied)


def test_spec_image_options(files):
    g = map_from_spec({"image": "img.png", "resolution": 0.1, "negate": True,
                       "threshold": 0.5, "origin": [0, 1]}, base_dir=files)
    assert np.array_equal(g.occupied, ~REF.occupied)
    assert g.origin == (0.0, 1.0)


def test_spec_ros_unknown(tmp_path):
    g = map_from_spec({"ros": str(TB3), "unknown": "free"})
    assert g.free_count == 7903 + 138683


def test_spec_rows():
    g = map_from_spec({"rows": ["#....", "..#..", "....#"], "resolution": 2.0, "name": "r"})
    assert np.array_equal(g.occupied, REF.occupied) and g.resolution == 2.0 and g.name == "r"
    g2 = map_from_spec({"rows": "#....\n..#..\n....#\n"})
    assert np.array_equal(g2.occupied, REF.occupied)


def test_spec_random_and_paper():
    g = map_from_spec({"random": {"size": [15, 15], "resolution": 1.0, "obstacles": 50,
                                  "seed": 7}})
    assert np.array_equal(g.occupied, random_map((15, 15), 1.0, obstacles=50, seed=7).occupied)
    d = map_from_spec({"random": {"size": [10, 5], "resolution": 0.5, "density": 0.2,
                                  "seed": 1, "keep_free": [[0.1, 0.1]]}, "name": "dd"})
    assert d.shape == (10, 20) and int(d.occupied.sum()) == 40 and d.name == "dd"
    assert not d.occupied[0, 0]
    for spec, seed in (({"paper": {"seed": 3}}, 3), ({"paper": 4}, 4), ({"paper": None}, 0),
                       ({"paper": {}}, 0)):
        assert np.array_equal(map_from_spec(spec).occupied, paper_map(seed).occupied)
    assert np.array_equal(map_from_spec("paper").occupied, paper_map(0).occupied)


@pytest.mark.parametrize(
    "spec, pattern",
    [
        ({}, "exactly one of random, paper, movingai, ros, image, npy, rows, gazebo; it has no"),
        ({"rows": [".."], "paper": 1}, r"it has several \(paper, rows\)"),
        ({"rows": [".."], "colour": "red"}, "unknown key 'colour' in a 'rows' map spec"),
        ({"paper": 1, "resolution": 2}, "unknown key 'resolution' in a 'paper' map spec"),
        ({"ros": "x.yaml", "resolution": 2}, "unknown key 'resolution' in a 'ros' map spec"),
        ({"random": {"size": 5, "obstacles": 1, "sead": 3}}, "unknown key 'random.sead'"),
        ({"random": {"obstacles": 1}}, "needs 'size'"),
        ({"random": 5}, "'random' must be a mapping"),
        ({"random": {"size": 5}}, "exactly one of obstacles"),
        ({"paper": {"seed": 1, "size": 3}}, "unknown key 'paper.size'"),
        ({"paper": "three"}, "seed must be a non-negative integer, got 'three'"),
        ({"image": "img.png"}, "'image' map spec needs 'resolution'"),
        ({"npy": "a.npy"}, "'npy' map spec needs 'resolution'"),
        ({"movingai": 5}, "'movingai' must be a file path, got 5"),
        ({"image": "img.png", "resolution": 1, "negate": "yes"}, "'negate' must be true or false"),
        ({"rows": [".."], "name": 3}, "'name' must be a string"),
    ],
)
def test_spec_errors(files, spec, pattern):
    with pytest.raises(ConfigError, match=pattern):
        map_from_spec(spec, base_dir=files)


def test_spec_missing_file(tmp_path):
    with pytest.raises(MapFormatError, match=re.escape(str(tmp_path / "none.map"))):
        map_from_spec({"movingai": "none.map"}, base_dir=tmp_path)
    with pytest.raises(MapFormatError, match=re.escape(str(tmp_path / "none.yaml"))):
        map_from_spec({"ros": "none.yaml"}, base_dir=tmp_path)


def test_spec_random_impossible():
    with pytest.raises(MapError, match="map spec 'random': cannot place 30 obstacles"):
        map_from_spec({"random": {"size": 5, "obstacles": 30}})
