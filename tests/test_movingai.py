"""MovingAI .map / .scen readers: real files, orientation, round trip, every malformed case."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from pathfuse.grid import GridMap
from pathfuse.io.movingai import (
    cell_to_movingai,
    movingai_to_cell,
    read_movingai,
    write_movingai,
)
from pathfuse.io.scenario import ScenProblem, read_scen, scen_map_name
from pathfuse.result import MapFormatError

DATA = Path(__file__).parent / "data" / "movingai"


def _raw_rows(path: Path) -> list[str]:
    """Map rows straight from the file text (top row first), independent of the reader."""
    lines = path.read_bytes().decode("ascii").replace("\r\n", "\n").split("\n")
    start = lines.index("map") + 1
    h = int(lines[1].split()[1])
    return lines[start:start + h]


# ----------------------------------------------------------------------------- maps
@pytest.mark.parametrize(
    "name, h, w",
    [("random-32-32-20", 32, 32), ("den312d", 81, 65), ("Boston_0_256", 256, 256),
     ("room-64-64-8", 64, 64), ("maze-32-32-2", 32, 32)],
)
def test_read_real_maps_orientation(name, h, w):
    path = DATA / f"{name}.map"
    g = read_movingai(path)
    assert g.shape == (h, w)
    assert g.name == name
    assert g.meta["source"] == str(path)
    rows = _raw_rows(path)
    blocked = np.array([[ch in "@OTW" for ch in row] for row in rows])
    # MovingAI (x, y) with y = 0 at the top is pathfuse (row = H - 1 - y, col = x)
    assert np.array_equal(g.occupied, blocked[::-1])
    ys, xs = np.nonzero(blocked)
    for y, x in list(zip(ys, xs, strict=True))[:50]:
        r, c = movingai_to_cell(x, y, h)
        assert g.occupied[r, c]
        assert cell_to_movingai(r, c, h) == (x, y)


def test_tree_cell_is_blocked():
    # random-32-32-20 holds a single 'T' at MovingAI (x=30, y=17)
    rows = _raw_rows(DATA / "random-32-32-20.map")
    assert rows[17][30] == "T"
    g = read_movingai(DATA / "random-32-32-20.map")
    assert g.occupied[32 - 1 - 17, 30]


def test_crlf_file_reads_same_as_lf(tmp_path):
    src = DATA / "Boston_0_256.map"
    assert b"\r\n" in src.read_bytes()[:40]
    lf = tmp_path / "boston_lf.map"
    lf.write_bytes(src.read_bytes().replace(b"\r\n", b"\n"))
    a, b = read_movingai(src), read_movingai(lf)
    assert np.array_equal(a.occupied, b.occupied)
    assert a.free_count == 47768


def test_resolution_origin_name():
    g = read_movingai(DATA / "maze-32-32-2.map", resolution=0.25, origin=(-1.0, 2.0), name="m")
    assert (g.resolution, g.origin, g.name) == (0.25, (-1.0, 2.0), "m")
    assert g.bounds == (-1.0, 2.0, 7.0, 10.0)


def test_all_map_characters(tmp_path):
    p = tmp_path / "chars.map"
    p.write_text("type octile\nheight 2\nwidth 7\nmap\n.GS@OTW\n.......\n")
    g = read_movingai(p)
    # first text row is the top row (row 1)
    assert g.occupied[1].tolist() == [False, False, False, True, True, True, True]
    assert not g.occupied[0].any()


def test_round_trip(tmp_path):
    rng = np.random.default_rng(7)
    occ = rng.random((13, 21)) < 0.3
    g = GridMap(occ, resolution=0.5, name="rand")
    p = tmp_path / "rand.map"
    write_movingai(g, p)
    back = read_movingai(p, resolution=0.5)
    assert np.array_equal(back.occupied, g.occupied)
    # and the writer is stable: write(read(write(g))) is the same bytes
    p2 = tmp_path / "again.map"
    write_movingai(back, p2)
    assert p.read_bytes() == p2.read_bytes()


def test_round_trip_real_map(tmp_path):
    g = read_movingai(DATA / "den312d.map")
    p = tmp_path / "den.map"
    write_movingai(g, p)
    assert np.array_equal(read_movingai(p).occupied, g.occupied)


GOOD = "type octile\nheight 3\nwidth 4\nmap\n....\n.@@.\n....\n"


@pytest.mark.parametrize(
    "text, line, fragment",
    [
        ("", 1, "empty"),
        ("\n\n  \n", 1, "empty"),
        ("typo octile\nheight 3\nwidth 4\nmap\n....\n....\n....\n", 1, "type octile"),
        ("type hex\nheight 3\nwidth 4\nmap\n....\n....\n....\n", 1, "unsupported map type"),
        ("type octile\nheigth 3\nwidth 4\nmap\n....\n....\n....\n", 2, "height or width"),
        ("type octile\nheight x3\nwidth 4\nmap\n....\n....\n....\n", 2, "integer"),
        ("type octile\nheight 3\nwidth 2.5\nmap\n....\n....\n....\n", 3, "integer"),
        ("type octile\nheight 0\nwidth 4\nmap\n", 2, "> 0"),
        ("type octile\nheight 3\nwidth -4\nmap\n", 3, "> 0"),
        ("type octile\nheight 3\nwidth 4\nmop\n....\n....\n....\n", 4, "must be 'map'"),
        ("type octile\nheight 3\n", 3, "header"),
        ("type octile\nheight 3\nwidth 4\nmap\n....\n....\n", 7, "truncated"),
        ("type octile\nheight 3\nwidth 4\nmap\n....\n....", 7, "truncated"),
        ("type octile\nheight 3\nwidth 4\nmap\n....\n.....\n....\n", 6, "5 characters"),
        ("type octile\nheight 3\nwidth 4\nmap\n....\n...\n....\n", 6, "3 characters"),
        ("type octile\nheight 3\nwidth 4\nmap\n....\n\n....\n", 6, "0 characters"),
        ("type octile\nheight 3\nwidth 4\nmap\n....\n....\n....\nxx\n", 8, "after the 3 map rows"),
    ],
)
def test_malformed_maps(tmp_path, text, line, fragment):
    p = tmp_path / "bad.map"
    p.write_text(text)
    with pytest.raises(MapFormatError) as err:
        read_movingai(p)
    msg = str(err.value)
    assert str(p) in msg
    assert fragment in msg
    if text.strip():
        assert f"line {line}" in msg


def test_unknown_character_names_line_column_and_char(tmp_path):
    p = tmp_path / "bad.map"
    p.write_text(GOOD.replace(".@@.", ".@X."))
    with pytest.raises(MapFormatError, match=r"line 6, column 3: unknown map character 'X'"):
        read_movingai(p)


def test_unknown_character_in_crlf_file(tmp_path):
    p = tmp_path / "bad.map"
    p.write_bytes(GOOD.replace(".@@.", "..?.").replace("\n", "\r\n").encode())
    with pytest.raises(MapFormatError, match=r"line 6, column 3: unknown map character '\?'"):
        read_movingai(p)


def test_good_text_reads(tmp_path):
    p = tmp_path / "ok.map"
    p.write_text(GOOD)
    g = read_movingai(p)
    assert g.occupied.sum() == 2 and g.occupied[1, 1] and g.occupied[1, 2]
    p.write_text(GOOD + "\n\n")  # trailing blank lines are fine
    assert np.array_equal(read_movingai(p).occupied, g.occupied)


def test_missing_file_and_directory(tmp_path):
    missing = tmp_path / "nope.map"
    with pytest.raises(MapFormatError, match="nope.map: no such map file"):
        read_movingai(missing)
    with pytest.raises(MapFormatError, match="is a directory"):
        read_movingai(tmp_path)


# ----------------------------------------------------------------------------- scenarios
def test_read_scen_real_file_frame():
    g = read_movingai(DATA / "den312d.map", resolution=0.5, origin=(10.0, -3.0))
    probs = read_scen(DATA / "den312d.map.scen", g)
    assert len(probs) == 290
    raw = (DATA / "den312d.map.scen").read_text().splitlines()
    assert raw[0] == "version 1"
    cols = raw[1].split("\t")
    p = probs[0]
    assert isinstance(p, ScenProblem)
    assert p.line == 2 and p.bucket == int(cols[0]) and p.map_name == cols[1]
    assert (p.map_width, p.map_height) == (65, 81)
    sx, sy, gx, gy = (int(v) for v in cols[4:8])
    assert p.start_cell == (81 - 1 - sy, sx)
    assert p.goal_cell == (81 - 1 - gy, gx)
    assert p.start == pytest.approx((10.0 + (sx + 0.5) * 0.5, -3.0 + (80 - sy + 0.5) * 0.5))
    assert np.allclose(g.cell_to_world([p.goal_cell])[0], p.goal)
    assert p.optimal_length == pytest.approx(float(cols[8]) * 0.5)
    # every start and goal of this file is a free cell
    for q in probs:
        assert not g.occupied[q.start_cell] and not g.occupied[q.goal_cell]


def test_scen_skips_blank_lines_and_counts_lines(tmp_path):
    g = GridMap(np.zeros((4, 5), dtype=bool))
    p = tmp_path / "s.scen"
    p.write_text("version 1.0\n0\tm.map\t5\t4\t0\t0\t4\t3\t5.2\n\n1\tm.map\t5\t4\t1\t1\t1\t1\t0\n")
    probs = read_scen(p, g)
    assert [q.line for q in probs] == [2, 4]
    assert probs[1].start_cell == probs[1].goal_cell == (2, 1)
    assert scen_map_name(p) == "m.map"


def test_scen_crlf_and_legacy_space_separated(tmp_path):
    g = GridMap(np.zeros((4, 5), dtype=bool))
    p = tmp_path / "s.scen"
    p.write_bytes(b"version 1\r\n3 maps/x/m.map 5 4 0 0 4 3 5.25\r\n")
    (q,) = read_scen(p, g)
    assert q.map_name == "maps/x/m.map" and q.bucket == 3 and q.optimal_length == 5.25


SCEN_HEAD = "version 1\n"
ROW = "0\tm.map\t5\t4\t0\t0\t4\t3\t5.0\n"


@pytest.mark.parametrize(
    "text, line, fragment",
    [
        ("", 1, "empty"),
        ("version 2\n" + ROW, 1, "version 1"),
        ("0\tm.map\t5\t4\t0\t0\t4\t3\t5.0\n", 1, "version 1"),
        (SCEN_HEAD + "0\tm.map\t5\t4\t0\t0\t4\t3\n", 2, "must have 9 columns"),
        (SCEN_HEAD + ROW + "0\tm.map\t5\t4\t0\t0\t4\t3\t5\t9\n", 3, "got 10"),
        (SCEN_HEAD + ROW.replace("\t0\t0\t", "\tzero\t0\t"), 2, "start x must be an integer"),
        (SCEN_HEAD + ROW.replace("5.0", "five"), 2, "optimal length"),
        (SCEN_HEAD + ROW.replace("5.0", "nan"), 2, "optimal length"),
        (SCEN_HEAD + ROW.replace("5.0", "-1"), 2, "optimal length"),
        (SCEN_HEAD + ROW.replace("m.map\t5\t4", "m.map\t6\t4"), 2, "differs from map"),
        (SCEN_HEAD + ROW.replace("\t4\t3\t5.0", "\t5\t3\t5.0"), 2, "goal (5, 3) is outside"),
        (SCEN_HEAD + ROW.replace("\t0\t0\t4", "\t0\t-1\t4"), 2, "start (0, -1) is outside"),
    ],
)
def test_malformed_scen(tmp_path, text, line, fragment):
    g = GridMap(np.zeros((4, 5), dtype=bool), name="m")
    p = tmp_path / "bad.scen"
    p.write_text(text)
    with pytest.raises(MapFormatError) as err:
        read_scen(p, g)
    msg = str(err.value)
    assert str(p) in msg and f"line {line}" in msg and fragment in msg


def test_scen_missing_file(tmp_path):
    g = GridMap(np.zeros((4, 5), dtype=bool))
    with pytest.raises(MapFormatError, match="no such scenario file"):
        read_scen(tmp_path / "none.scen", g)
    p = tmp_path / "only_header.scen"
    p.write_text("version 1\n")
    with pytest.raises(MapFormatError, match=r"only_header.scen: .*no problem line"):
        read_scen(p, g)   # an empty benchmark is an error, not "0/0 match" (issue 9)
    with pytest.raises(MapFormatError, match="no problem line"):
        scen_map_name(p)
