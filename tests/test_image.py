"""Plain image and .npy maps: orientation, thresholds, round trips, bad input."""

from __future__ import annotations

import re

import numpy as np
import pytest
from PIL import Image

from pathfuse.generate import random_map
from pathfuse.io import read_image, read_npy
from pathfuse.result import MapError, MapFormatError

# a 3 x 4 picture, top row first: black = obstacle
PICTURE = np.array(
    [
        [0, 255, 255, 255],
        [255, 255, 0, 255],
        [255, 255, 255, 0],
    ],
    dtype=np.uint8,
)


@pytest.mark.parametrize("ext", [".png", ".pgm", ".bmp"])
def test_orientation_top_row_is_map_top(tmp_path, ext):
    p = tmp_path / ("pic" + ext)
    Image.fromarray(PICTURE).save(p)
    g = read_image(p, resolution=0.5, origin=(10.0, 20.0))
    assert g.shape == (3, 4)
    assert np.array_equal(g.occupied, (PICTURE == 0)[::-1])
    # top-left pixel centre: x = 10.25, y = 20 + 2.5 * 0.5 = 21.25
    assert g.is_free([[10.25, 21.25], [10.25, 20.25], [11.75, 20.25]]).tolist() == [
        False, True, False
    ]
    assert g.name == "pic" and g.meta["format"] == "image"


def test_threshold_and_negate(tmp_path):
    vals = np.array([[0, 64, 128, 192, 255]], dtype=np.uint8)
    p = tmp_path / "g.png"
    Image.fromarray(vals).save(p)
    # darkness (255 - v)/255 = 1, .749, .498, .247, 0
    assert read_image(p, 1.0).occupied.tolist() == [[True, True, False, False, False]]
    assert read_image(p, 1.0, threshold=0.2).occupied.tolist() == [[True, True, True, True, False]]
    assert read_image(p, 1.0, threshold=0.9).occupied.tolist() == [[True, False, False, False,
                                                                     False]]
    # negate: brightness v/255 = 0, .251, .502, .753, 1 > 0.5
    assert read_image(p, 1.0, negate=True).occupied.tolist() == [[False, False, True, True, True]]


def test_rgb_is_mean_of_channels(tmp_path):
    rgb = np.array([[[255, 0, 0], [255, 255, 0], [0, 0, 255]]], dtype=np.uint8)
    p = tmp_path / "c.png"
    Image.fromarray(rgb).save(p)
    # means 85, 170, 85 -> darkness .667, .333, .667
    assert read_image(p, 1.0).occupied.tolist() == [[True, False, True]]
    # a luminance conversion (yellow 226, blue 29) would flip these two:
    assert read_image(p, 1.0, threshold=0.2).occupied.tolist() == [[True, True, True]]
    assert read_image(p, 1.0, threshold=0.8).occupied.tolist() == [[False, False, False]]


def test_rgba_alpha_ignored(tmp_path):
    rgba = np.array([[[0, 0, 0, 0], [255, 255, 255, 0]]], dtype=np.uint8)
    p = tmp_path / "a.png"
    Image.fromarray(rgba).save(p)
    assert read_image(p, 1.0).occupied.tolist() == [[True, False]]


def test_palette_and_1bit_images(tmp_path):
    Image.fromarray(PICTURE).convert("P").save(tmp_path / "p.png")
    Image.fromarray(PICTURE).convert("1").save(tmp_path / "b.png")
    for name in ("p.png", "b.png"):
        g = read_image(tmp_path / name, 1.0)
        assert np.array_equal(g.occupied, (PICTURE == 0)[::-1]), name


def test_jpeg_blocks(tmp_path):
    big = np.kron(PICTURE, np.ones((8, 8), dtype=np.uint8))  # 8x8 blocks survive JPEG
    p = tmp_path / "j.jpg"
    Image.fromarray(big).save(p, quality=95)
    g = read_image(p, 0.1)
    assert np.array_equal(g.occupied, (big == 0)[::-1])


def test_missing_and_corrupt_files(tmp_path):
    with pytest.raises(MapFormatError, match=re.escape(str(tmp_path / "none.png"))):
        read_image(tmp_path / "none.png", 1.0)
    bad = tmp_path / "bad.png"
    bad.write_bytes(b"\x89PNG not really")
    with pytest.raises(MapFormatError, match=r"bad\.png"):
        read_image(bad, 1.0)
    with pytest.raises(MapFormatError, match="directory"):
        read_image(tmp_path, 1.0)


@pytest.mark.parametrize(
    "res, pattern",
    [
        (None, r"a resolution \(metres per cell\) is required"),
        (0, "resolution must be a finite number > 0, got 0"),
        (-1.0, "resolution must be a finite number > 0, got -1.0"),
        (float("nan"), "resolution must be a finite number > 0, got nan"),
        ("fine", "resolution must be a number, got 'fine'"),
        (True, "resolution must be a number, got True"),
    ],
)
def test_bad_resolution(tmp_path, res, pattern):
    p = tmp_path / "pic.png"
    Image.fromarray(PICTURE).save(p)
    with pytest.raises(MapError, match=r"pic\.png: " + pattern):
        read_image(p, res)
    np.save(tmp_path / "a.npy", PICTURE == 0)
    with pytest.raises(MapError, match=r"a\.npy: " + pattern):
        read_npy(tmp_path / "a.npy", res)


def test_bad_threshold_and_origin(tmp_path):
    p = tmp_path / "pic.png"
    Image.fromarray(PICTURE).save(p)
    with pytest.raises(MapError, match=r"threshold must be in \[0, 1\], got 1.5"):
        read_image(p, 1.0, threshold=1.5)
    with pytest.raises(MapError, match="origin must be two numbers"):
        read_image(p, 1.0, origin=(1.0,))
    with pytest.raises(MapError, match="origin must be finite"):
        read_image(p, 1.0, origin=(0.0, float("inf")))


# ----------------------------------------------------------------- npy
@pytest.mark.parametrize("seed", range(3))
def test_npy_roundtrip_of_np_save(tmp_path, seed):
    g = random_map((2.0, 1.5), resolution=0.1, density=0.4, seed=seed, origin=(-3.0, 4.5))
    p = tmp_path / "g.npy"
    np.save(p, g.occupied)
    h = read_npy(p, g.resolution, g.origin)
    assert np.array_equal(h.occupied, g.occupied)   # no flip: row 0 stays the bottom row
    assert h.origin == g.origin and h.resolution == g.resolution
    assert h.name == "g"


def test_npy_numeric_nonzero_is_occupied(tmp_path):
    arr = np.array([[0.0, 0.5, -2.0], [0.0, 0.0, np.inf]])
    np.save(tmp_path / "f.npy", arr)
    np.save(tmp_path / "i.npy", np.array([[0, 3], [255, 0]], dtype=np.uint8))
    assert read_npy(tmp_path / "f.npy", 1.0).occupied.tolist() == [[False, True, True],
                                                                    [False, False, True]]
    assert read_npy(tmp_path / "i.npy", 1.0).occupied.tolist() == [[False, True], [True, False]]


@pytest.mark.parametrize(
    "arr, pattern",
    [
        (np.zeros((2, 2, 2)), r"must be 2-D \(rows, cols\), got shape \(2, 2, 2\)"),
        (np.zeros(5), r"must be 2-D .*got shape \(5,\)"),
        (np.zeros((0, 3)), r"empty \(shape \(0, 3\)\)"),
        (np.array([[1.0, np.nan]]), r"NaN \(first at row 0, col 1\)"),
        (np.array([[1 + 1j]]), "not boolean or real numeric"),
        (np.array([["a", "b"]]), "not boolean or real numeric"),
    ],
)
def test_npy_bad_arrays(tmp_path, arr, pattern):
    p = tmp_path / "x.npy"
    np.save(p, arr)
    with pytest.raises(MapFormatError, match=r"x\.npy: .*" + pattern):
        read_npy(p, 1.0)


def test_npy_object_missing_corrupt(tmp_path):
    p = tmp_path / "o.npy"
    np.save(p, np.array([[None, 1]], dtype=object), allow_pickle=True)
    with pytest.raises(MapFormatError, match=r"o\.npy: holds an object"):
        read_npy(p, 1.0)
    with pytest.raises(MapFormatError, match=r"not found: .*gone\.npy"):
        read_npy(tmp_path / "gone.npy", 1.0)
    (tmp_path / "c.npy").write_bytes(b"\x93NUMPY garbage")
    with pytest.raises(MapFormatError, match=r"c\.npy"):
        read_npy(tmp_path / "c.npy", 1.0)
    full = tmp_path / "full.npy"
    np.save(full, np.zeros((50, 50)))
    (tmp_path / "t.npy").write_bytes(full.read_bytes()[:300])
    with pytest.raises(MapFormatError, match=r"t\.npy"):
        read_npy(tmp_path / "t.npy", 1.0)
