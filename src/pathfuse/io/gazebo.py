"""Read Gazebo worlds (SDF ``.world`` / ``.sdf``, plain or gzipped) into an occupancy grid.

:func:`read_gazebo_world` parses the file with a real XML parser (expat, through
:class:`xml.etree.ElementTree.TreeBuilder`; document type declarations and
entities are refused, so no entity expansion can blow up), collects the
**collision geometry of the static models**, and rasterises its 2-D footprint
exactly (:mod:`pathfuse.io.shapes`: a cell is occupied when a shape's interior
overlaps its square).

What is read
------------
* ``<world>/<model>`` (nested models too), each with its ``<pose>``, its
  ``<link>`` s and their ``<pose>``, and their ``<collision>`` s with their
  ``<pose>`` and ``<geometry>``.  The poses compose: world <- model <- link <-
  collision (SDF's ``x y z roll pitch yaw``, radians; ``degrees="true"`` and
  ``rotation_format="quat_xyzw"`` are understood).
* Geometry: ``box`` (any orientation: the footprint is the convex hull of its
  eight projected corners), ``cylinder`` and ``capsule`` (upright: a disc),
  ``sphere`` (a disc).  ``plane`` (the ground) and ``empty`` are skipped.
  Anything else (``mesh``, ``heightmap``, ``polyline``, a tilted cylinder ...)
  is a :class:`~pathfuse.result.MapFormatError` naming the model, link,
  collision and line.
* Only shapes whose height range overlaps ``z_range_m`` (default 0 to 2 m) are
  obstacles, so the ground plane, a floor slab below z = 0 or a ceiling do not
  block the map.
* ``<static>false</static>`` models (robots, movable objects) are left out
  unless ``include_dynamic=True``; their names are in ``meta["skipped"]``.
* **The ``<state>`` block.**  Gazebo saves a world with a ``<state>`` that
  repeats every model's pose (BARN's worlds do); when Gazebo loads the world it
  applies that state, so here too the state's ``<model><pose>`` overrides the
  model's pose and a state ``<link><pose>`` (a pose in the world frame, as
  Gazebo writes it) overrides the link's.  State ``<insertions>`` add models
  and ``<deletions>`` remove them; several states apply in file order.
* ``<include>`` of ``model://ground_plane`` and ``model://sun`` is skipped;
  any other ``<include>`` cannot be resolved without Gazebo's model path and
  is an error (inline the model, e.g. with ``gz sdf -p``).

Map bounds
----------
By default the bounding box of the obstacle footprints grown by ``margin_m``
(1 m); give ``bounds=(x_min, y_min, x_max, y_max)`` to choose them (BARN uses
its arena with the goal, :data:`pathfuse.studies.barn.BARN_BOUNDS`).  The
lower-left corner is moved down to a multiple of the resolution, so cell edges
lie on multiples of it.  The map's edge is a wall for the planners.

Examples
--------
>>> import tempfile, pathlib
>>> sdf = '''<sdf version="1.6"><world name="w">
...   <model name="post"><static>1</static><pose>1.5 1.5 0 0 0 0</pose>
...     <link name="l"><collision name="c"><geometry>
...       <cylinder><radius>0.6</radius><length>1</length></cylinder>
...     </geometry></collision></link></model>
... </world></sdf>'''
>>> with tempfile.TemporaryDirectory() as d:
...     p = pathlib.Path(d) / "post.world"
...     _ = p.write_text(sdf)
...     g = read_gazebo_world(p, resolution=1.0, bounds=(0, 0, 3, 3))
>>> g.occupied[::-1].astype(int).tolist()   # top row first
[[0, 1, 0], [1, 1, 1], [0, 1, 0]]
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any
from xml.etree import ElementTree as ET

import numpy as np

from pathfuse.grid import GridMap
from pathfuse.io.sdf_xml import (
    IDENTITY,
    MAX_WORLD_BYTES,
    Pose,
    SdfDoc,
    compose,
    floats,
    pose_of,
    read_world_bytes,
)
from pathfuse.io.shapes import OVERLAP_EPS_M, Footprint, convex_hull, rasterise
from pathfuse.result import ConfigError, MapError, MapFormatError

__all__ = ["read_gazebo_world", "world_footprints", "GAZEBO_SUFFIXES", "MAX_WORLD_BYTES",
           "MAX_CELLS", "is_gazebo_path"]

GAZEBO_SUFFIXES = (".world", ".sdf", ".world.gz", ".sdf.gz")
"""File name endings read as Gazebo worlds."""
MAX_CELLS = 100_000_000
"""The largest grid built (cells); larger bounds or finer resolutions are refused."""
_SKIP_INCLUDES = ("model://ground_plane", "model://sun")


def is_gazebo_path(path: str | os.PathLike[str]) -> bool:
    """Whether the file name ends like a Gazebo world (see :data:`GAZEBO_SUFFIXES`)."""
    return os.fspath(path).lower().endswith(GAZEBO_SUFFIXES)


# --------------------------------------------------------------------------- model tree
@dataclass
class _Collision:
    name: str
    el: ET.Element
    pose: Pose


@dataclass
class _Link:
    name: str
    pose: Pose
    collisions: list[_Collision]


@dataclass
class _Model:
    name: str
    el: ET.Element
    static: bool
    pose: Pose
    links: list[_Link]
    models: list[_Model] = field(default_factory=list)


def _bool(doc: SdfDoc, el: ET.Element | None, default: bool) -> bool:
    if el is None:
        return default
    t = (el.text or "").strip().lower()
    if t in ("1", "true"):
        return True
    if t in ("0", "false"):
        return False
    raise doc.fail(el, f"<{el.tag}>: must be true/false/1/0, got {t!r}")


def _name(doc: SdfDoc, el: ET.Element, kind: str) -> str:
    n = el.get("name")
    if not n:
        raise doc.fail(el, f"a <{kind}> without a name attribute")
    return n


def _parse_model(doc: SdfDoc, el: ET.Element) -> _Model:
    name = _name(doc, el, "model")
    model = _Model(name=name, el=el, static=_bool(doc, el.find("static"), False),
                   pose=pose_of(doc, el, f"model {name!r}", ("world",)), links=[])
    for link_el in el.findall("link"):
        lname = _name(doc, link_el, "link")
        lwhat = f"model {name!r} link {lname!r}"
        link = _Link(lname, pose_of(doc, link_el, lwhat, ("__model__", name)), [])
        for c_el in link_el.findall("collision"):
            cname = _name(doc, c_el, "collision")
            link.collisions.append(_Collision(
                cname, c_el, pose_of(doc, c_el, f"{lwhat} collision {cname!r}", (lname,))))
        model.links.append(link)
    for sub in el.findall("model"):
        model.models.append(_parse_model(doc, sub))
    for inc in el.findall("include"):
        _check_include(doc, inc)
    return model


def _check_include(doc: SdfDoc, inc: ET.Element) -> None:
    uri = (inc.findtext("uri") or "").strip()
    if uri.rstrip("/") in _SKIP_INCLUDES:
        return
    raise doc.fail(inc, f"<include> of {uri or '(no uri)'!r} cannot be resolved without "
                        "Gazebo's model path; inline the model (for example with "
                        "'gz sdf -p') and read that file")


def _world(doc: SdfDoc) -> ET.Element:
    root = doc.root
    if root.tag == "world":
        return root
    if root.tag != "sdf":
        raise doc.fail(root, f"not an SDF world: the root element is <{root.tag}>, "
                             "expected <sdf>")
    worlds = root.findall("world")
    if len(worlds) != 1:
        raise doc.fail(root, f"expected one <world> in <sdf>, found {len(worlds)}")
    return worlds[0]


@dataclass
class _State:
    models: dict[tuple[str, ...], Pose] = field(default_factory=dict)
    links: dict[tuple[tuple[str, ...], str], Pose] = field(default_factory=dict)
    count: int = 0


def _read_state(doc: SdfDoc, st: ET.Element, models: list[_Model], state: _State) -> None:
    ins = st.find("insertions")
    if ins is not None:
        for m_el in ins.findall("model"):
            new = _parse_model(doc, m_el)
            models[:] = [m for m in models if m.name != new.name] + [new]
    dels = st.find("deletions")
    if dels is not None:
        gone = {(n.text or "").strip() for n in dels.findall("name")}
        models[:] = [m for m in models if m.name not in gone]

    def walk(m_el: ET.Element, prefix: tuple[str, ...]) -> None:
        path = (*prefix, _name(doc, m_el, "model"))
        if m_el.find("pose") is not None:
            state.models[path] = pose_of(doc, m_el, f"state of model {path[-1]!r}", ())
            state.count += 1
        for l_el in m_el.findall("link"):
            if l_el.find("pose") is not None:
                state.links[(path, _name(doc, l_el, "link"))] = pose_of(
                    doc, l_el, f"state of model {path[-1]!r} link {l_el.get('name')!r}", ())
        for sub in m_el.findall("model"):
            walk(sub, path)

    for m_el in st.findall("model"):
        walk(m_el, ())


# --------------------------------------------------------------------------- geometry
def _positive(doc: SdfDoc, el: ET.Element | None, parent: ET.Element, what: str,
              n: int = 1) -> list[float]:
    if el is None:
        raise doc.fail(parent, f"{what}: missing")
    vals = floats(doc, el, what, n)
    if any(v <= 0 for v in vals):
        raise doc.fail(el, f"<{el.tag}> of {what}: must be > 0, got "
                           f"{(el.text or '').strip()!r}")
    return vals


def _footprint(doc: SdfDoc, col: _Collision, pose: Pose, what: str
               ) -> tuple[Footprint | None, tuple[float, float], str]:
    """(footprint or None, z range, kind) of one collision in the world frame."""
    geo = col.el.find("geometry")
    if geo is None:
        raise doc.fail(col.el, f"{what}: no <geometry>")
    shapes = list(geo)
    if len(shapes) != 1:
        raise doc.fail(geo, f"{what}: <geometry> must hold one shape, found "
                            f"{len(shapes)}")
    g = shapes[0]
    rot, t = pose
    src = f"{what} ({doc.where(g)})"
    if g.tag in ("plane", "empty"):
        return None, (0.0, 0.0), g.tag
    if g.tag == "box":
        sx, sy, sz = _positive(doc, g.find("size"), g, f"{what} box size", 3)
        corners = np.array([[a * sx, b * sy, c * sz] for a in (-0.5, 0.5)
                            for b in (-0.5, 0.5) for c in (-0.5, 0.5)])
        world = corners @ rot.T + t
        hull = convex_hull(world[:, :2])
        z = (float(world[:, 2].min()), float(world[:, 2].max()))
        if hull.shape[0] < 3:  # a box seen edge-on from above has no area
            return None, z, "box"
        return Footprint("polygon", (float(hull[:, 0].mean()), float(hull[:, 1].mean())),
                         vertices=hull, source=src), z, "box"
    if g.tag in ("cylinder", "capsule", "sphere"):
        (r,) = _positive(doc, g.find("radius"), g, f"{what} {g.tag} radius")
        half = 0.0
        if g.tag != "sphere":
            (length,) = _positive(doc, g.find("length"), g, f"{what} {g.tag} length")
            if abs(abs(rot[2, 2]) - 1.0) > 1e-9:
                raise doc.fail(g, f"{what}: unsupported geometry: a tilted <{g.tag}> (only "
                                  "upright ones have a disc footprint)")
            half = 0.5 * length
        zt = (float(t[2] - half - (r if g.tag != "cylinder" else 0.0)),
              float(t[2] + half + (r if g.tag != "cylinder" else 0.0)))
        return Footprint("disc", (float(t[0]), float(t[1])), radius=r, source=src), zt, g.tag
    raise doc.fail(g, f"{what}: unsupported geometry <{g.tag}> (supported: box, cylinder, "
                      "capsule, sphere; plane and empty are skipped)")


@dataclass
class WorldShapes:
    """The obstacle footprints of a world and what was left out."""

    footprints: list[Footprint]
    skipped: dict[str, list[str]]
    models: int
    state_poses: int


def world_footprints(path: str | os.PathLike[str], *,
                     z_range_m: tuple[float, float] = (0.0, 2.0),
                     include_dynamic: bool = False) -> WorldShapes:
    """Parse a world file into its obstacle footprints (see the module docstring).

    Raises
    ------
    MapFormatError
        Missing or unreadable file, malformed XML, a DTD, unsupported geometry,
        malformed numbers (the message names the file, line and element).
    """
    p = Path(os.path.expanduser(os.fspath(path)))
    doc = SdfDoc(p, read_world_bytes(p))
    world = _world(doc)
    for inc in world.findall("include"):
        _check_include(doc, inc)
    models = [_parse_model(doc, m) for m in world.findall("model")]
    state = _State()
    for st in world.findall("state"):
        _read_state(doc, st, models, state)
    z0, z1 = z_range_m
    out: list[Footprint] = []
    skipped: dict[str, list[str]] = {"dynamic": [], "outside_z_range": [], "ground": []}
    n_models = 0

    def walk(m: _Model, parent: Pose, prefix: tuple[str, ...], static: bool) -> None:
        nonlocal n_models
        path_ = (*prefix, m.name)
        n_models += 1
        is_static = static or m.static
        wpose = state.models.get(path_) or compose(parent, m.pose)
        label = "::".join(path_)
        if not is_static and not include_dynamic:
            if any(link.collisions for link in m.links):
                skipped["dynamic"].append(label)
        else:
            for link in m.links:
                lpose = state.links.get((path_, link.name)) or compose(wpose, link.pose)
                for col in link.collisions:
                    what = f"model {label!r} link {link.name!r} collision {col.name!r}"
                    fp, (za, zb), kind = _footprint(doc, col, compose(lpose, col.pose), what)
                    tag = f"{label}/{link.name}/{col.name}"
                    if kind in ("plane", "empty"):
                        skipped["ground"].append(tag)
                    elif min(zb, z1) - max(za, z0) <= OVERLAP_EPS_M:
                        skipped["outside_z_range"].append(tag)
                    elif fp is not None:
                        out.append(fp)
        for sub in m.models:
            walk(sub, wpose, path_, is_static)

    for m in models:
        walk(m, IDENTITY, (), False)
    return WorldShapes(out, skipped, n_models, state.count)


def _grid_frame(fps: list[Footprint], resolution: float,
                bounds: tuple[float, float, float, float] | None, margin_m: float,
                path: Path) -> tuple[tuple[float, float], tuple[int, int]]:
    if bounds is None:
        boxes = np.array([fp.bbox() for fp in fps])
        x0, y0 = boxes[:, 0].min() - margin_m, boxes[:, 1].min() - margin_m
        x1, y1 = boxes[:, 2].max() + margin_m, boxes[:, 3].max() + margin_m
    else:
        x0, y0, x1, y1 = bounds
    ox = math.floor(x0 / resolution + 1e-9) * resolution
    oy = math.floor(y0 / resolution + 1e-9) * resolution
    w = math.ceil((x1 - ox) / resolution - 1e-9)
    h = math.ceil((y1 - oy) / resolution - 1e-9)
    if w < 1 or h < 1:
        raise MapError(f"{path}: bounds {bounds} hold no cell")
    if w * h > MAX_CELLS:
        raise MapError(f"{path}: a {w} x {h} grid ({w * h:,} cells) at {resolution:g} m is "
                       f"larger than {MAX_CELLS:,} cells; use a coarser resolution or "
                       "smaller bounds")
    return (float(ox), float(oy)), (int(h), int(w))


def _check_bounds(bounds: Any) -> tuple[float, float, float, float] | None:
    if bounds is None:
        return None
    try:
        b = tuple(float(v) for v in bounds)
    except (TypeError, ValueError):
        raise ConfigError(f"bounds: must be [x_min, y_min, x_max, y_max] in metres, "
                          f"got {bounds!r}") from None
    if len(b) != 4 or not all(math.isfinite(v) for v in b) or b[0] >= b[2] or b[1] >= b[3]:
        raise ConfigError(f"bounds: must be [x_min, y_min, x_max, y_max] with x_min < x_max "
                          f"and y_min < y_max, got {bounds!r}")
    return b  # type: ignore[return-value]


def _check_number(v: Any, key: str, *, gt: float | None = None,
                  ge: float | None = None) -> float:
    ok = not isinstance(v, bool) and isinstance(v, (int, float))
    f = float(v) if ok else math.nan
    if not ok or not math.isfinite(f) or (gt is not None and f <= gt) or (
            ge is not None and f < ge):
        cond = f"> {gt:g}" if gt is not None else f">= {ge:g}"
        raise ConfigError(f"{key}: must be a number {cond}, got {v!r}")
    return f


def read_gazebo_world(
    path: str | os.PathLike[str],
    resolution: float = 0.05,
    *,
    bounds: Any = None,
    margin_m: float = 1.0,
    z_range_m: tuple[float, float] = (0.0, 2.0),
    include_dynamic: bool = False,
    name: str | None = None,
) -> GridMap:
    """Rasterise a Gazebo world's static collision geometry into a :class:`GridMap`.

    Parameters
    ----------
    path : path-like
        A ``.world`` or ``.sdf`` file, plain or gzipped (detected by content).
    resolution : float
        Cell side in metres (default 0.05, a common costmap resolution).
    bounds : (x_min, y_min, x_max, y_max), optional
        The map's extent in metres (default: the obstacles' box grown by
        ``margin_m``).
    margin_m : float
        Free border around the obstacles when ``bounds`` is not given.
    z_range_m : (float, float)
        Heights (m) at which a shape blocks the robot.
    include_dynamic : bool
        Also rasterise models that are not ``<static>``.
    name : str, optional
        The map's name (default: the file name without its endings).

    Returns
    -------
    GridMap
        ``meta`` holds ``format`` ("gazebo"), ``source``, ``footprints`` (the
        exact shapes, :class:`~pathfuse.io.shapes.Footprint`), ``skipped``
        (non-static models, ground planes, shapes outside ``z_range_m``),
        ``models`` and ``state_poses`` (poses taken from ``<state>``).

    Raises
    ------
    MapFormatError
        As :func:`world_footprints`, and a world with no obstacle geometry.
    MapError
        A grid of more than :data:`MAX_CELLS` cells.
    ConfigError
        A bad ``resolution``, ``bounds``, ``margin_m`` or ``z_range_m``.
    """
    res = _check_number(resolution, "resolution", gt=0)
    b = _check_bounds(bounds)
    margin = _check_number(margin_m, "margin_m", ge=0)
    try:
        za, zb = (float(v) for v in z_range_m)
    except (TypeError, ValueError):
        raise ConfigError(f"z_range_m: must be (low, high) in metres, got {z_range_m!r}") \
            from None
    if not za < zb:
        raise ConfigError(f"z_range_m: low must be below high, got {z_range_m!r}")
    p = Path(os.path.expanduser(os.fspath(path)))
    shapes = world_footprints(p, z_range_m=(za, zb), include_dynamic=include_dynamic)
    if not shapes.footprints:
        left = {k: len(v) for k, v in shapes.skipped.items() if v}
        raise MapFormatError(
            f"{p}: the world holds no static obstacle geometry (box, cylinder, capsule or "
            f"sphere between z = {za:g} and {zb:g} m) in {shapes.models} model(s)"
            + (f"; skipped: {left}" if left else ""))
    origin, shape = _grid_frame(shapes.footprints, res, b, margin, p)
    occ = rasterise(shapes.footprints, shape, origin, res)
    stem = p.name
    for suf in GAZEBO_SUFFIXES:
        if stem.lower().endswith(suf):
            stem = stem[: -len(suf)]
            break
    meta = {"format": "gazebo", "source": str(p), "footprints": shapes.footprints,
            "skipped": shapes.skipped, "models": shapes.models,
            "state_poses": shapes.state_poses}
    return GridMap(occ, res, origin, name or stem, meta)
