"""GridMap: frame convention, conversions, inflation, distance field, validation."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import ndimage

from pathfuse import GridMap, MapError


def test_row_zero_is_bottom_and_origin_is_lower_left_corner():
    g = GridMap.from_rows(["#..", "..."], resolution=0.5, origin=(10.0, -2.0))
    # the '#' is in the top text row -> highest row index
    assert g.occupied[1, 0] and not g.occupied[0, 0]
    assert g.bounds == (10.0, -2.0, 11.5, -1.0)
    assert g.cell_to_world([1, 0]).tolist() == [[10.25, -1.25]]
    assert not g.is_free([10.25, -1.25])[0]
    assert g.is_free([10.25, -1.75])[0]


@settings(max_examples=60, deadline=None)
@given(
    h=st.integers(1, 20), w=st.integers(1, 20),
    res=st.floats(0.01, 5.0), ox=st.floats(-100, 100), oy=st.floats(-100, 100),
)
def test_cell_world_round_trip(h, w, res, ox, oy):
    g = GridMap(np.zeros((h, w), bool), resolution=res, origin=(ox, oy))
    rows, cols = np.meshgrid(np.arange(h), np.arange(w), indexing="ij")
    cells = np.stack([rows.ravel(), cols.ravel()], axis=1)
    assert np.array_equal(g.world_to_cell(g.cell_to_world(cells)), cells)
    assert g.in_bounds(g.cell_to_world(cells)).all()


def test_bounds_checks_and_out_of_map_points():
    g = GridMap(np.zeros((3, 4), bool), resolution=1.0)
    pts = [[-0.01, 1], [0, 0], [3.99, 2.99], [4.0, 1], [1, 3.0]]
    assert g.in_bounds(pts).tolist() == [False, True, True, False, False]
    assert g.is_free(pts).tolist() == [False, True, True, False, False]
    assert not g.in_bounds([np.nan, 1.0])[0]


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(occupied=np.zeros((0, 3), bool)), "empty"),
        (dict(occupied=np.zeros(5, bool)), "2-D"),
        (dict(occupied=np.zeros((2, 2), bool), resolution=0), "resolution"),
        (dict(occupied=np.zeros((2, 2), bool), resolution=float("nan")), "resolution"),
        (dict(occupied=np.zeros((2, 2), bool), resolution="abc"), "resolution"),
        (dict(occupied=np.zeros((2, 2), bool), origin=(0, float("inf"))), "origin"),
        (dict(occupied=np.zeros((2, 2), bool), origin=(1,)), "origin"),
        (dict(occupied=np.array([["a", "b"]])), "dtype"),
    ],
)
def test_bad_maps_raise_map_error(kwargs, match):
    with pytest.raises(MapError, match=match):
        GridMap(**kwargs)


def test_from_rows_rejects_ragged_rows():
    with pytest.raises(MapError, match="same length"):
        GridMap.from_rows(["...", ".."])


def test_occupancy_is_read_only_copy():
    arr = np.zeros((2, 2), bool)
    g = GridMap(arr)
    arr[0, 0] = True
    assert not g.occupied[0, 0]
    with pytest.raises(ValueError):
        g.occupied[0, 0] = True


def test_map_arrays_cannot_be_made_writeable_again_even_after_pickling():
    """The searchers, inflations and labels cached per map rely on the map never changing:
    numpy lets an array's owner turn writing back on, and an unpickled array (a study's
    worker) is writeable; a map's arrays refuse both."""
    import pickle

    import pathfuse

    g = GridMap.from_rows(["....#", ".##.#", "....."], resolution=0.5)
    before = pathfuse.plan(g, (0.25, 0.25), (1.75, 1.25), planner="astar")
    assert before.success
    _ = g.components, g.distance_field
    h = pickle.loads(pickle.dumps(g))
    for m in (g, h):
        for a in (m.occupied, m.components, m.distance_field):
            assert not a.flags.writeable
            with pytest.raises(ValueError):
                a.setflags(write=True)
            with pytest.raises(ValueError):
                a[0, 0] = 1
    assert np.array_equal(h.occupied, g.occupied)
    again = pathfuse.plan(h, (0.25, 0.25), (1.75, 1.25), planner="astar")
    assert again.success and again.length == before.length
    assert np.array_equal(again.path, before.path)


def _square_distance_oracle(occ, res, r):
    """Brute force: centre-to-square distance < r for any occupied square."""
    h, w = occ.shape
    out = occ.copy()
    occ_cells = np.argwhere(occ)
    for i in range(h):
        for j in range(w):
            for oi, oj in occ_cells:
                dx = max(abs(j - oj) - 0.5, 0.0) * res
                dy = max(abs(i - oi) - 0.5, 0.0) * res
                if np.hypot(dx, dy) < r:
                    out[i, j] = True
    return out


@settings(max_examples=40, deadline=None)
@given(
    occ=st.lists(st.lists(st.booleans(), min_size=6, max_size=6), min_size=5, max_size=5),
    res=st.sampled_from([0.05, 0.5, 1.0]),
    r_cells=st.floats(0.0, 3.0),
)
def test_inflate_matches_brute_force(occ, res, r_cells):
    occ = np.array(occ, bool)
    g = GridMap(occ, resolution=res)
    got = g.inflate(r_cells * res).occupied
    assert np.array_equal(got, _square_distance_oracle(occ, res, r_cells * res))


def test_inflate_rejects_negative_radius():
    with pytest.raises(MapError, match="radius"):
        GridMap(np.zeros((2, 2), bool)).inflate(-1)


def _cspace_oracle(occ, res, r):
    """Brute force: a cell is blocked when its centre is closer than r to an occupied
    square or to the outside of the map."""
    out = _square_distance_oracle(occ, res, r)
    h, w = occ.shape
    for i in range(h):
        for j in range(w):
            edge = min(j + 0.5, w - j - 0.5, i + 0.5, h - i - 0.5) * res
            if edge < r:
                out[i, j] = True
    return out


@settings(max_examples=40, deadline=None)
@given(
    occ=st.lists(st.lists(st.booleans(), min_size=7, max_size=7), min_size=6, max_size=6),
    res=st.sampled_from([0.05, 0.5, 1.0]),
    r_cells=st.floats(0.0, 3.0),
    origin=st.tuples(st.floats(-20, 20), st.floats(-20, 20)),
)
def test_cspace_matches_brute_force(occ, res, r_cells, origin):
    occ = np.array(occ, bool)
    g = GridMap(occ, resolution=res, origin=origin)
    cs = g.cspace(r_cells * res)
    assert cs.shape == g.shape and cs.resolution == g.resolution and cs.origin == g.origin
    assert np.array_equal(cs.occupied, _cspace_oracle(occ, res, r_cells * res))


def test_cspace_grows_the_map_edge_and_is_cached():
    g = GridMap.from_rows([".....", ".....", "....."], resolution=0.5)
    assert g.cspace(0) is g and g.cspace(0.0) is g
    cs = g.cspace(0.3)   # edge cell centres are 0.25 m in
    assert cs.occupied.astype(int).tolist() == [[1, 1, 1, 1, 1], [1, 0, 0, 0, 1],
                                                [1, 1, 1, 1, 1]]
    assert g.cspace(0.3) is cs
    assert not g.cspace(0.25).occupied.any()   # touching the edge is allowed
    assert not g.inflate(0.3).occupied.any()   # inflate grows obstacles only
    for bad in (-0.1, float("nan"), float("inf")):
        with pytest.raises(MapError, match="radius"):
            g.cspace(bad)


def test_distance_field_is_metric_and_cached():
    occ = np.zeros((5, 7), bool)
    occ[2, 3] = True
    g = GridMap(occ, resolution=0.5)
    df = g.distance_field
    assert df is g.distance_field
    assert df[2, 3] == 0.0
    assert df[2, 6] == pytest.approx(1.5)
    assert df[0, 1] == pytest.approx(0.5 * np.hypot(2, 2))
    assert np.isinf(GridMap(np.zeros((2, 2), bool)).distance_field).all()


def test_components_are_four_connected():
    g = GridMap.from_rows([".#", "#."])
    lab = g.components
    assert lab[0, 1] != lab[1, 0]  # diagonal only: not connected without corner cutting
    assert lab[0, 0] == 0 and lab[1, 1] == 0
    ref, n = ndimage.label(~g.occupied)
    assert n == 2
