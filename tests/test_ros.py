"""ROS map_server maps: real maps against published counts, every mode, bad input."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from pathfuse.generate import random_map
from pathfuse.grid import GridMap
from pathfuse.io import read_ros_map, write_ros_map
from pathfuse.result import ConfigError, MapFormatError

ROOT = Path(__file__).resolve().parents[1]
TB3 = ROOT / "tests" / "data" / "ros" / "nav2_tb3_sandbox" / "tb3_sandbox.yaml"
SHARED = ROOT.parent / "shared" / "data" / "rosmaps"


def parse_pgm_p5(path: Path) -> np.ndarray:
    """Independent P5 reader (8-bit), top row first, for use as an oracle."""
    data = path.read_bytes()
    tokens: list[bytes] = []
    pos = 0
    while len(tokens) < 4:
        while data[pos:pos + 1].isspace():
            pos += 1
        if data[pos:pos + 1] == b"#":
            pos = data.index(b"\n", pos) + 1
            continue
        end = pos
        while not data[end:end + 1].isspace():
            end += 1
        tokens.append(data[pos:end])
        pos = end
    pos += 1  # the single whitespace after maxval
    assert tokens[0] == b"P5" and int(tokens[3]) == 255
    w, h = int(tokens[1]), int(tokens[2])
    return np.frombuffer(data[pos:pos + w * h], dtype=np.uint8).reshape(h, w)


def write_yaml(folder: Path, image: str = "m.png", name: str = "m.yaml", **over) -> Path:
    keys = {
        "image": image,
        "resolution": 0.1,
        "origin": "[1.0, 2.0, 0.0]",
        "negate": 0,
        "occupied_thresh": 0.65,
        "free_thresh": 0.196,
    }
    keys.update(over)
    text = "".join(f"{k}: {v}\n" for k, v in keys.items() if v is not None)
    p = folder / name
    p.write_text(text)
    return p


# ----------------------------------------------------------------- real maps
def test_tb3_sandbox_counts_and_frame():
    g = read_ros_map(TB3)
    occ = g.meta["occupancy"]
    assert g.shape == (384, 384)
    assert g.resolution == 0.05
    assert g.origin == (-10.0, -10.0)
    # tests/data/ros/SOURCES.md (= /work/shared/data/SOURCES.md section 3)
    assert int((occ == 0).sum()) == 7903
    assert int((occ == 100).sum()) == 870
    assert int((occ == -1).sum()) == 138683
    assert int(g.meta["unknown"].sum()) == 138683
    # default: unknown is occupied
    assert g.free_count == 7903
    assert g.meta["unknown_policy"] == "occupied"
    assert g.meta["mode"] == "trinary" and g.meta["yaw"] == 0.0
    assert g.name == "tb3_sandbox"


def test_tb3_unknown_free_policy():
    g = read_ros_map(TB3, unknown="free")
    assert int(g.occupied.sum()) == 870
    assert g.free_count == 7903 + 138683


def test_tb3_matches_independent_pixel_oracle():
    """Cell (r, c) is image pixel (H-1-r, c), classified with p = (255 - v) / 255."""
    g = read_ros_map(TB3)
    pix = parse_pgm_p5(TB3.with_suffix(".pgm"))
    p = (255.0 - pix) / 255.0
    occupied_top_first = p > 0.65
    unknown_top_first = ~(p > 0.65) & ~(p < 0.196)
    assert np.array_equal(g.meta["unknown"], unknown_top_first[::-1])
    assert np.array_equal(g.occupied, (occupied_top_first | unknown_top_first)[::-1])
    # a concrete point: the world point of a known free pixel is free
    rows, cols = np.nonzero(p < 0.196)
    i, j = int(rows[0]), int(cols[0])
    x = -10.0 + (j + 0.5) * 0.05
    y = -10.0 + (384 - 1 - i + 0.5) * 0.05
    assert g.is_free([x, y]).tolist() == [True]


BIG = [
    # dir/yaml, shape (rows, cols), origin, (free, occupied, unknown) from SOURCES.md section 3
    ("nav2_warehouse/warehouse.yaml", (1674, 1006), (-15.1, -25.0), (1422292, 30951, 230801)),
    ("fetch_4_26_15/4_26_15.yaml", (1146, 1029), (-25.367399, -15.544381),
     (389199, 32973, 757062)),
    ("fetch_3_1_16/3_1_16_localization.yaml", (982, 958), (0.0, 0.0),
     (353097, 38416, 549243)),
]


@pytest.mark.parametrize("rel, shape, origin, counts", BIG, ids=[b[0].split("/")[0] for b in BIG])
def test_shared_big_maps_published_counts(rel, shape, origin, counts):
    path = SHARED / rel
    if not path.exists():
        pytest.skip(f"shared ROS map not present: {path}")
    g = read_ros_map(path)
    occ = g.meta["occupancy"]
    assert g.shape == shape
    assert g.origin == pytest.approx(origin, abs=0)
    assert g.resolution == 0.05 or g.resolution == 0.03
    free, occupied, unknown = counts
    assert int((occ == 0).sum()) == free
    assert int((occ == 100).sum()) == occupied
    assert int((occ == -1).sum()) == unknown


def test_shared_rgb_png_is_channel_mean_not_luminance():
    path = SHARED / "fetch_3_1_16" / "3_1_16_localization.yaml"
    if not path.exists():
        pytest.skip("shared fetch map not present")
    g = read_ros_map(path)
    rgb = np.asarray(Image.open(path.with_suffix(".png")).convert("RGB"), dtype=np.float64)
    p = 1.0 - rgb.mean(axis=2) / 255.0
    assert np.array_equal(g.meta["occupancy"] == 100, (p > 0.65)[::-1])


# ----------------------------------------------------------------- modes on made-up images
VALUES = np.array([[0, 100, 200, 230, 254, 255]], dtype=np.uint8)


def test_trinary_values(tmp_path):
    Image.fromarray(VALUES).save(tmp_path / "m.png")
    g = read_ros_map(write_yaml(tmp_path))
    # p = (255 - v)/255 = 1.0, .608, .216, .098, .004, 0
    assert g.meta["occupancy"].tolist() == [[100, -1, -1, 0, 0, 0]]
    assert g.occupied.tolist() == [[True, True, True, False, False, False]]
    assert read_ros_map(write_yaml(tmp_path), unknown="free").occupied.tolist() == [
        [True, False, False, False, False, False]
    ]


def test_trinary_negate(tmp_path):
    Image.fromarray(VALUES).save(tmp_path / "m.png")
    g = read_ros_map(write_yaml(tmp_path, negate=1))
    # p = v/255 = 0, .392, .784, .902, .996, 1.0
    assert g.meta["occupancy"].tolist() == [[0, -1, 100, 100, 100, 100]]
    assert g.meta["negate"] is True
    g2 = read_ros_map(write_yaml(tmp_path, negate="true"))
    assert np.array_equal(g2.meta["occupancy"], g.meta["occupancy"])


def test_scale_mode_values(tmp_path):
    Image.fromarray(VALUES).save(tmp_path / "m.png")
    g = read_ros_map(write_yaml(tmp_path, mode="scale"))
    # in between: rint((p - 0.196) / (0.65 - 0.196) * 100):
    #   v=100: (0.607843 - 0.196) / 0.454 = 0.9071 -> 91 ; v=200: 0.0434 -> 4
    assert g.meta["occupancy"].tolist() == [[100, 91, 4, 0, 0, 0]]
    # pathfuse rule: only 0 and 100 are certain; 91 and 4 are "unknown"
    assert g.meta["unknown"].tolist() == [[False, True, True, False, False, False]]
    assert g.occupied.tolist() == [[True, True, True, False, False, False]]
    assert read_ros_map(write_yaml(tmp_path, mode="scale"), unknown="free").free_count == 5


def test_scale_mode_transparent_is_unknown(tmp_path):
    la = np.zeros((1, 3, 2), dtype=np.uint8)
    la[0, :, 0] = [255, 255, 0]   # grey: white, white, black
    la[0, :, 1] = [255, 128, 255]  # alpha: opaque, half, opaque
    Image.fromarray(la, mode="LA").save(tmp_path / "m.png")
    g = read_ros_map(write_yaml(tmp_path, mode="scale"))
    assert g.meta["occupancy"].tolist() == [[0, -1, 100]]


def test_trinary_averages_alpha_in(tmp_path):
    la = np.zeros((1, 3, 2), dtype=np.uint8)
    la[0, :, 0] = [255, 255, 0]
    la[0, :, 1] = [255, 0, 0]
    Image.fromarray(la, mode="LA").save(tmp_path / "m.png")
    g = read_ros_map(write_yaml(tmp_path))
    # shade = (3 v + a) / 4 / 255: 1.0 -> free; 0.75 -> p 0.25 unknown; 0 -> occupied
    assert g.meta["occupancy"].tolist() == [[0, -1, 100]]


def test_raw_mode_values(tmp_path):
    vals = np.array([[0, 50, 100, 101, 255]], dtype=np.uint8)
    Image.fromarray(vals).save(tmp_path / "m.png")
    g = read_ros_map(write_yaml(tmp_path, mode="raw"))
    assert g.meta["occupancy"].tolist() == [[0, 50, 100, -1, -1]]
    assert g.occupied.tolist() == [[False, True, True, True, True]]
    assert read_ros_map(write_yaml(tmp_path, mode="raw"), unknown="free").occupied.tolist() == [
        [False, False, True, False, False]
    ]
    # negate does not apply to raw (as in nav2)
    g2 = read_ros_map(write_yaml(tmp_path, mode="raw", negate=1))
    assert np.array_equal(g2.meta["occupancy"], g.meta["occupancy"])


def test_rgb_pixels_are_averaged(tmp_path):
    rgb = np.array([[[255, 0, 0], [255, 255, 0], [0, 0, 0]]], dtype=np.uint8)
    Image.fromarray(rgb).save(tmp_path / "m.png")
    g = read_ros_map(write_yaml(tmp_path))
    # means 85, 170, 0 -> p .667 occupied, .333 unknown, 1 occupied
    # (a luminance conversion would call yellow (L=226, p=.11) free)
    assert g.meta["occupancy"].tolist() == [[100, -1, 100]]


def test_image_top_row_is_map_top(tmp_path):
    img = np.array([[0, 254, 254], [254, 254, 254]], dtype=np.uint8)  # black top-left
    Image.fromarray(img).save(tmp_path / "m.pgm")
    g = read_ros_map(write_yaml(tmp_path, image="m.pgm"))
    assert g.shape == (2, 3)
    assert g.occupied.tolist() == [[False, False, False], [True, False, False]]
    # origin (1, 2), 0.1 m: top-left cell centre is (1.05, 2.15)
    assert g.is_free([[1.05, 2.15], [1.05, 2.05]]).tolist() == [False, True]


def test_ascii_p2_and_16bit_pgm(tmp_path):
    (tmp_path / "a.pgm").write_text("P2\n# comment\n3 1\n255\n0 128 254\n")
    g = read_ros_map(write_yaml(tmp_path, image="a.pgm"))
    assert g.meta["occupancy"].tolist() == [[100, -1, 0]]
    px = np.array([0, 32768, 65535], dtype=">u2").tobytes()
    (tmp_path / "b.pgm").write_bytes(b"P5\n3 1\n65535\n" + px)
    g = read_ros_map(write_yaml(tmp_path, image="b.pgm"))
    assert g.meta["occupancy"].tolist() == [[100, -1, 0]]


def test_image_path_absolute_and_subfolder(tmp_path):
    (tmp_path / "img").mkdir()
    Image.fromarray(VALUES).save(tmp_path / "img" / "m.png")
    g1 = read_ros_map(write_yaml(tmp_path, image="img/m.png"))
    g2 = read_ros_map(write_yaml(tmp_path, image=str(tmp_path / "img" / "m.png"), name="b.yaml"))
    assert np.array_equal(g1.occupied, g2.occupied)
    assert g1.meta["image"] == str(tmp_path / "img" / "m.png")


def test_nonzero_yaw_warns_and_is_kept(tmp_path):
    Image.fromarray(VALUES).save(tmp_path / "m.png")
    with pytest.warns(UserWarning, match="yaw 0.5"):
        g = read_ros_map(write_yaml(tmp_path, origin="[1.0, 2.0, 0.5]"))
    assert g.meta["yaw"] == 0.5
    assert g.origin == (1.0, 2.0)


# ----------------------------------------------------------------- round trip
@pytest.mark.parametrize("seed", range(5))
@pytest.mark.parametrize("ext", [".pgm", ".png"])
def test_write_read_roundtrip(tmp_path, seed, ext):
    g = random_map((3.3, 2.1), resolution=0.03, density=0.3, seed=seed,
                   origin=(-1.25 + seed, 7.125))
    y = write_ros_map(g, tmp_path / "out.yaml", image_name="out" + ext)
    h = read_ros_map(y)
    assert np.array_equal(h.occupied, g.occupied)
    assert h.resolution == g.resolution and h.origin == g.origin
    assert not h.meta["unknown"].any()
    pix = np.asarray(Image.open(tmp_path / ("out" + ext)))
    assert set(np.unique(pix).tolist()) <= {0, 254}
    assert np.array_equal(pix == 0, g.occupied[::-1])


def test_written_pgm_is_standard_p5(tmp_path):
    g = GridMap.from_rows(["#..", "..#"], resolution=0.05)
    write_ros_map(g, tmp_path / "t.yaml")
    pix = parse_pgm_p5(tmp_path / "t.pgm")
    assert pix.tolist() == [[0, 254, 254], [254, 254, 0]]


def test_roundtrip_real_map_keep_unknown(tmp_path):
    g = read_ros_map(TB3)
    y = write_ros_map(g, tmp_path / "copy.yaml", keep_unknown=True)
    h = read_ros_map(y)
    assert np.array_equal(h.occupied, g.occupied)
    assert np.array_equal(h.meta["unknown"], g.meta["unknown"])
    assert h.origin == g.origin and h.resolution == g.resolution
    h_free = read_ros_map(y, unknown="free")
    assert np.array_equal(h_free.occupied, read_ros_map(TB3, unknown="free").occupied)


# ----------------------------------------------------------------- bad input
def test_missing_yaml(tmp_path):
    with pytest.raises(MapFormatError, match=re.escape(str(tmp_path / "nope.yaml"))):
        read_ros_map(tmp_path / "nope.yaml")


def test_yaml_syntax_error_names_file_and_line(tmp_path):
    p = tmp_path / "bad.yaml"
    p.write_text("image: m.png\nresolution: [0.05\norigin: [0, 0, 0]\n")
    with pytest.raises(MapFormatError, match=r"bad\.yaml: line \d+, column \d+: invalid YAML"):
        read_ros_map(p)


def test_yaml_not_a_mapping(tmp_path):
    p = tmp_path / "list.yaml"
    p.write_text("- 1\n- 2\n")
    with pytest.raises(MapFormatError, match="list.yaml.*mapping"):
        read_ros_map(p)
    (tmp_path / "empty.yaml").write_text("")
    with pytest.raises(MapFormatError, match="empty"):
        read_ros_map(tmp_path / "empty.yaml")


@pytest.mark.parametrize(
    "key", ["image", "resolution", "origin", "negate", "occupied_thresh", "free_thresh"]
)
def test_missing_key(tmp_path, key):
    Image.fromarray(VALUES).save(tmp_path / "m.png")
    p = write_yaml(tmp_path, **{key: None})
    with pytest.raises(MapFormatError, match=rf"m\.yaml: missing key '{key}'"):
        read_ros_map(p)


def test_image_missing_names_looked_for_path(tmp_path):
    p = write_yaml(tmp_path, image="gone.pgm")
    with pytest.raises(MapFormatError) as exc:
        read_ros_map(p)
    msg = str(exc.value)
    assert str(p) in msg and str(tmp_path / "gone.pgm") in msg


@pytest.mark.parametrize(
    "over, pattern",
    [
        ({"resolution": "abc"}, r"'resolution' must be a number, got 'abc'"),
        ({"resolution": "[0.05]"}, r"'resolution' must be a number"),
        ({"resolution": 0}, r"'resolution' must be > 0, got 0"),
        ({"resolution": -0.05}, r"'resolution' must be > 0, got -0.05"),
        ({"resolution": ".nan"}, r"'resolution' must be finite"),
        ({"occupied_thresh": 1.5}, r"'occupied_thresh' must be in \[0, 1\], got 1.5"),
        ({"free_thresh": -0.1}, r"'free_thresh' must be in \[0, 1\], got -0.1"),
        ({"free_thresh": 0.7}, r"'free_thresh' \(0.7\) must be smaller than 'occupied_thresh'"),
        ({"free_thresh": 0.65}, r"'free_thresh' \(0.65\) must be smaller"),
        ({"occupied_thresh": "high"}, r"'occupied_thresh' must be a number, got 'high'"),
        ({"mode": "fancy"}, r"'mode' must be one of trinary, scale, raw, got 'fancy'"),
        ({"origin": "[1.0, 2.0]"}, r"'origin' must be a list \[x, y, yaw\] of 3 numbers"),
        ({"origin": "[1.0, x, 0]"}, r"'origin' must be a number, got 'x'"),
        ({"negate": "maybe"}, r"'negate' must be 0/1 or true/false, got 'maybe'"),
        ({"image": "''"}, r"'image' must be a non-empty file name"),
    ],
)
def test_bad_values(tmp_path, over, pattern):
    Image.fromarray(VALUES).save(tmp_path / "m.png")
    p = write_yaml(tmp_path, **over)
    with pytest.raises(MapFormatError, match=re.escape(str(p)) + ".*" + pattern):
        read_ros_map(p)


def test_corrupt_image(tmp_path):
    (tmp_path / "m.pgm").write_bytes(b"this is not an image at all")
    p = write_yaml(tmp_path, image="m.pgm")
    with pytest.raises(MapFormatError, match=r"m\.yaml.*m\.pgm.*not a readable image"):
        read_ros_map(p)


def test_truncated_pgm(tmp_path):
    (tmp_path / "m.pgm").write_bytes(b"P5\n10 10\n255\n" + bytes(50))
    p = write_yaml(tmp_path, image="m.pgm")
    with pytest.raises(MapFormatError, match=r"m\.yaml.*m\.pgm.*(corrupt or truncated|readable)"):
        read_ros_map(p)


def test_truncated_png(tmp_path):
    Image.fromarray(np.zeros((40, 40), np.uint8) + np.arange(40, dtype=np.uint8)).save(
        tmp_path / "full.png"
    )
    data = (tmp_path / "full.png").read_bytes()
    (tmp_path / "m.png").write_bytes(data[: len(data) // 2])
    with pytest.raises(MapFormatError, match=r"m\.png: corrupt or truncated"):
        read_ros_map(write_yaml(tmp_path))


def test_unknown_policy_checked(tmp_path):
    with pytest.raises(ConfigError, match="'occupied' or 'free', got 'maybe'"):
        read_ros_map(TB3, unknown="maybe")


def test_write_rejects_other_image_types(tmp_path):
    g = GridMap.from_rows(["..", ".#"])
    with pytest.raises(ValueError, match=r"\.pgm or \.png"):
        write_ros_map(g, tmp_path / "x.yaml", image_name="x.jpg")
