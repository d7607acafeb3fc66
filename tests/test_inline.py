"""Inline text-row maps in YAML."""

from __future__ import annotations

import re

import numpy as np
import pytest

from pathfuse.io import read_rows_yaml
from pathfuse.result import ConfigError, MapFormatError


def test_list_rows_first_row_is_top(tmp_path):
    p = tmp_path / "m.yaml"
    p.write_text('rows:\n  - "#..."\n  - ".@.."\n  - "...#"\nresolution: 0.5\norigin: [1, -1]\n')
    g = read_rows_yaml(p)
    assert g.shape == (3, 4)
    assert g.occupied.tolist() == [
        [False, False, False, True],   # bottom = last text row
        [False, True, False, False],
        [True, False, False, False],   # top = first text row
    ]
    assert g.resolution == 0.5 and g.origin == (1.0, -1.0)
    assert g.name == "m"
    # the '#' in the top-left corner: cell centre (1.25, 0.25)
    assert g.is_free([[1.25, 0.25], [1.25, -0.75]]).tolist() == [False, True]


def test_multiline_string_equals_list(tmp_path):
    p = tmp_path / "b.yaml"
    p.write_text("rows: |\n  #...\n  .@..\n\n  ...#\n")
    q = tmp_path / "l.yaml"
    q.write_text("rows: ['#...', '.@..', '...#']\n")
    a, b = read_rows_yaml(p), read_rows_yaml(q)
    assert np.array_equal(a.occupied, b.occupied)
    assert a.resolution == 1.0 and a.origin == (0.0, 0.0)


def test_dict_source_and_defaults():
    g = read_rows_yaml({"rows": ["..", ".#"], "name": "tiny"})
    assert g.name == "tiny" and g.occupied.tolist() == [[False, True], [False, False]]
    g2 = read_rows_yaml({"rows": [".."]}, resolution=0.25, origin=(2, 3))
    assert g2.resolution == 0.25 and g2.origin == (2.0, 3.0)


def test_invalid_character_names_row_and_column(tmp_path):
    p = tmp_path / "m.yaml"
    p.write_text("rows:\n  - '....'\n  - '..x.'\n")
    msg = f"{p}: row 2 (from the top), column 3: invalid character 'x'"
    with pytest.raises(MapFormatError, match=re.escape(msg)):
        read_rows_yaml(p)
    with pytest.raises(MapFormatError, match=r"row 1 \(from the top\), column 2: .*' '"):
        read_rows_yaml({"rows": [". ."]})


def test_ragged_rows():
    with pytest.raises(MapFormatError, match=r"ragged rows: row 3 \(from the top\) has 2 "
                                             r"characters, row 1 has 3"):
        read_rows_yaml({"rows": ["...", "...", ".."]})


@pytest.mark.parametrize(
    "doc, pattern",
    [
        ({"resolution": 1.0}, "missing key 'rows'"),
        ({"rows": []}, "holds no row"),
        ({"rows": ""}, "holds no row"),
        ({"rows": [""]}, "row 1 .* is empty"),
        ({"rows": 5}, "'rows' must be a list of strings"),
        ({"rows": ["..", 10]}, r"'rows' entry 2 .*got 10"),
        ({"rows": [".."], "colour": "red"}, "unknown key 'colour'"),
        ({"rows": [".."], "resolution": 0}, "'resolution' must be a finite number > 0, got 0"),
        ({"rows": [".."], "resolution": "x"}, "'resolution' must be a number, got 'x'"),
        ({"rows": [".."], "origin": [1]}, r"'origin' must be \[x, y\]"),
        ({"rows": [".."], "origin": "00"}, r"'origin' must be \[x, y\]"),
    ],
)
def test_bad_documents(doc, pattern):
    with pytest.raises(MapFormatError, match=r"<dict>: .*" + pattern):
        read_rows_yaml(doc)


def test_yaml_number_row_is_an_error(tmp_path):
    p = tmp_path / "n.yaml"
    p.write_text("rows:\n  - 1010\n")
    with pytest.raises(MapFormatError, match=r"n\.yaml: 'rows' entry 1 .*got 1010"):
        read_rows_yaml(p)


def test_file_errors(tmp_path):
    with pytest.raises(MapFormatError, match=re.escape(str(tmp_path / "no.yaml"))):
        read_rows_yaml(tmp_path / "no.yaml")
    p = tmp_path / "s.yaml"
    p.write_text("rows: ['..', \n")
    with pytest.raises(MapFormatError, match=r"s\.yaml: line \d+, column \d+: invalid YAML"):
        read_rows_yaml(p)


def test_argument_conflicts_with_file():
    with pytest.raises(ConfigError, match="resolution is given both"):
        read_rows_yaml({"rows": [".."], "resolution": 1.0}, resolution=2.0)
