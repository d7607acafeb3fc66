"""Fuzzing every reader of user input (issue 9): any input ends in a valid result or a
:class:`pathfuse.PathfuseError` with a one-line message, never another exception.

The documents are built from each reader's own vocabulary (its keys, plausible and
hostile values: huge, tiny, negative, non-finite, wrong types, deep lists), dumped as
YAML and sometimes mutated byte by byte, so that the fuzzer reaches past the parser
into the checks of every key.
"""

from __future__ import annotations

import math
import os
import warnings
from pathlib import Path

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from pathfuse.bench.parse import parse_experiment
from pathfuse.grid import GridMap
from pathfuse.io import load_map, read_movingai, read_scen
from pathfuse.io.inline import read_rows_yaml
from pathfuse.result import PathfuseError
from pathfuse.safeyaml import load_yaml
from pathfuse.world import load_scenario

DATA = Path(__file__).parent / "data"
PGM = (DATA / "ros" / "nav2_tb3_sandbox" / "tb3_sandbox.pgm").resolve()
# PATHFUSE_FUZZ_EXAMPLES=2000 python -m pytest tests/test_fuzz_inputs.py fuzzes longer
FUZZ = settings(max_examples=int(os.environ.get("PATHFUSE_FUZZ_EXAMPLES", "150")), deadline=None,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture,
                                       HealthCheck.filter_too_much])

NUMBERS = st.one_of(
    st.integers(min_value=-(2**70), max_value=2**70),
    st.sampled_from([0, 1, 2, -1, 10**9, 2**63, 0.5, 1e-300, 1e300, 1e308, -0.0]),
    st.floats(allow_nan=True, allow_infinity=True),
)
SCALARS = st.one_of(st.none(), st.booleans(), NUMBERS,
                    st.text(max_size=12), st.sampled_from(["1e-2", "....", "#.#", "x", ""]))


def values(keys: list[str]) -> st.SearchStrategy:
    return st.recursive(
        SCALARS,
        lambda inner: st.one_of(
            st.lists(inner, max_size=4),
            st.dictionaries(st.sampled_from(keys), inner, max_size=4),
        ),
        max_leaves=12,
    )


def documents(keys: list[str], base: dict) -> st.SearchStrategy:
    """A valid base document with some keys replaced, added or removed."""
    return st.builds(
        lambda changes, drop: {**{k: v for k, v in base.items() if k not in drop}, **changes},
        st.dictionaries(st.sampled_from(keys), values(keys), max_size=4),
        st.sets(st.sampled_from(sorted(base)), max_size=2),
    )


def dump(doc) -> str:
    return yaml.safe_dump(doc, sort_keys=False, allow_unicode=True)


@st.composite
def mutated(draw, text_strategy):
    text = draw(text_strategy)
    for _ in range(draw(st.integers(0, 3))):
        if not text:
            break
        i = draw(st.integers(0, len(text) - 1))
        text = text[:i] + draw(st.sampled_from(["[", "]", "{", "}", ":", "&a ", "*a", "\n",
                                                "- ", "'", "\t", "? ", "!!", "#"])) + text[i:]
    return text


def ends_well(f, *args, **kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            return f(*args, **kwargs)
        except PathfuseError as exc:
            msg = str(exc)
            assert "\n" not in msg and len(msg) < 2000, msg
            return None


# ---------------------------------------------------------------------------------- YAML
@FUZZ
@given(st.one_of(st.text(max_size=200),
                 mutated(st.builds(dump, values(["a", "b", "rows", "name"])))))
def test_load_yaml(text):
    ends_well(load_yaml, text, "f.yaml")


ROWS_KEYS = ["rows", "resolution", "origin", "name", "other"]
ROWS_BASE = {"rows": ["..#", "..."], "resolution": 1.0, "origin": [0, 0]}


@FUZZ
@given(documents(ROWS_KEYS, ROWS_BASE))
def test_rows_maps_from_dicts(doc):
    g = ends_well(read_rows_yaml, doc)
    assert g is None or isinstance(g, GridMap)


@FUZZ
@given(mutated(st.builds(dump, documents(ROWS_KEYS, ROWS_BASE))))
def test_rows_map_files(tmp_path_factory, text):
    p = tmp_path_factory.mktemp("rows") / "m.yaml"
    p.write_text(text)
    g = ends_well(load_map, p)
    assert g is None or isinstance(g, GridMap)


ROS_KEYS = ["image", "resolution", "origin", "negate", "occupied_thresh", "free_thresh",
            "mode", "extra"]
ROS_BASE = {"image": str(PGM), "resolution": 0.05, "origin": [-10.0, -10.0, 0.0], "negate": 0,
            "occupied_thresh": 0.65, "free_thresh": 0.196}


@FUZZ
@given(mutated(st.builds(dump, documents(ROS_KEYS, ROS_BASE))))
def test_ros_map_files(tmp_path_factory, text):
    p = tmp_path_factory.mktemp("ros") / "m.yaml"
    p.write_text(text)
    g = ends_well(load_map, p)
    assert g is None or isinstance(g, GridMap)
    if g is not None:
        x0, y0, x1, y1 = g.bounds
        assert all(math.isfinite(v) for v in (x0, y0, x1, y1))


SC_KEYS = ["map", "start", "goal", "robot", "dt", "time_limit", "goal_tolerance", "stall_time",
           "stall_radius", "seed", "obstacles", "planner", "name", "description", "radius",
           "max_speed", "position", "velocity", "waypoints", "speed", "rows", "paper", "random",
           "size", "obstacles"]
SC_BASE = {"map": {"rows": ["......", "......", "......"]}, "start": [0.5, 1.5],
           "goal": [5.5, 1.5], "dt": 0.1, "time_limit": 10,
           "obstacles": [{"position": [3, 0.5], "velocity": [0, 0.1], "radius": 0.2}]}


@FUZZ
@given(documents(SC_KEYS, SC_BASE))
def test_scenarios_from_dicts(doc):
    ends_well(load_scenario, doc)


@FUZZ
@given(mutated(st.builds(dump, documents(SC_KEYS, SC_BASE))))
def test_scenario_files(tmp_path_factory, text):
    p = tmp_path_factory.mktemp("sc") / "s.yaml"
    p.write_text(text)
    ends_well(load_scenario, p)


EXP_KEYS = ["name", "description", "seeds", "limits", "robot_radius_m", "reference", "maps",
            "planners", "store_paths", "params", "map", "queries", "start", "goal", "r1_m",
            "step_m", "time_limit_s", "max_iterations", "count", "random", "paper"]
EXP_BASE = {"seeds": 2, "maps": [{"name": "p", "map": "paper"}],
            "planners": ["astar", {"name": "fusion", "params": {"r1_m": [1.0, 2.0]}}]}


@FUZZ
@given(mutated(st.builds(dump, documents(EXP_KEYS, EXP_BASE))))
def test_experiment_files(tmp_path_factory, text):
    d = tmp_path_factory.mktemp("exp")
    exp = ends_well(parse_experiment, text, d / "e.yaml")
    if exp is not None:
        runs = ends_well(exp.expand)
        assert runs is None or isinstance(runs, list)


# ---------------------------------------------------------------------------- map files
MAI = b"type octile\nheight 3\nwidth 4\nmap\n..@.\n....\n.T..\n"


@st.composite
def mutated_bytes(draw, base: bytes):
    data = bytearray(base)
    for _ in range(draw(st.integers(0, 4))):
        op = draw(st.integers(0, 2))
        i = draw(st.integers(0, max(len(data) - 1, 0)))
        if op == 0 and data:
            del data[i]
        elif op == 1:
            data[i:i] = draw(st.binary(min_size=1, max_size=4))
        elif data:
            data[i] = draw(st.integers(0, 255))
    return bytes(data)


@FUZZ
@given(st.one_of(mutated_bytes(MAI), st.binary(max_size=64),
                 st.builds(lambda h, w: f"type octile\nheight {h}\nwidth {w}\nmap\n".encode()
                           + b"....\n" * 3, st.integers(-5, 10**12), st.integers(-5, 10**12))))
def test_movingai_files(tmp_path_factory, data):
    p = tmp_path_factory.mktemp("mai") / "m.map"
    p.write_bytes(data)
    g = ends_well(read_movingai, p)
    assert g is None or isinstance(g, GridMap)


SCEN = b"version 1\n0\tm.map\t4\t3\t0\t0\t3\t2\t3.82842712\n"


@FUZZ
@given(st.one_of(mutated_bytes(SCEN), st.binary(max_size=64)))
def test_scen_files(tmp_path_factory, data):
    p = tmp_path_factory.mktemp("scen") / "m.map.scen"
    p.write_bytes(data)
    ends_well(read_scen, p, GridMap(np.zeros((3, 4), bool)))


@pytest.fixture(scope="module")
def image_bytes():
    import io

    from PIL import Image

    out = {}
    for fmt in ("PNG", "BMP", "PPM"):
        buf = io.BytesIO()
        Image.fromarray(np.full((6, 5), 200, np.uint8)).save(buf, format=fmt)
        out[fmt] = buf.getvalue()
    buf = io.BytesIO()
    np.save(buf, np.zeros((4, 3), bool))
    out["NPY"] = buf.getvalue()
    return out


@FUZZ
@given(fmt=st.sampled_from(["PNG", "BMP", "PPM", "NPY"]), data=st.data())
def test_image_and_array_files(tmp_path_factory, image_bytes, fmt, data):
    raw = data.draw(mutated_bytes(image_bytes[fmt]))
    suffix = {"PNG": ".png", "BMP": ".bmp", "PPM": ".pgm", "NPY": ".npy"}[fmt]
    p = tmp_path_factory.mktemp("img") / f"m{suffix}"
    p.write_bytes(raw)
    g = ends_well(load_map, p, resolution=0.1)
    assert g is None or isinstance(g, GridMap)
