"""Safe XML and SDF poses for :mod:`pathfuse.io.gazebo`.

* :class:`SdfDoc` parses bytes with expat into an :mod:`xml.etree.ElementTree`
  tree, remembering each element's line, and refuses document type
  declarations and entities (no entity expansion, no external entities).
* :func:`read_world_bytes` reads a plain or gzipped file with a size cap.
* :func:`pose_of` reads an SDF ``<pose>`` (``x y z roll pitch yaw``; ``degrees``
  and ``rotation_format="quat_xyzw"``) as a rotation matrix and a translation;
  :func:`compose` chains them.

>>> rot, t = compose((rpy(0, 0, math.pi / 2), np.zeros(3)), (np.eye(3), np.array([1.0, 0, 0])))
>>> np.round(t, 12).tolist()
[0.0, 1.0, 0.0]
"""

from __future__ import annotations

import gzip
import math
import xml.parsers.expat
from pathlib import Path
from typing import Any
from xml.etree import ElementTree as ET

import numpy as np

from pathfuse.result import MapFormatError

__all__ = ["SdfDoc", "read_world_bytes", "pose_of", "compose", "rpy", "floats", "IDENTITY",
           "MAX_WORLD_BYTES", "Pose"]

MAX_WORLD_BYTES = 256 * 1024 * 1024
"""The largest (decompressed) world file read, in bytes."""
Pose = tuple[np.ndarray, np.ndarray]  # rotation (3, 3), translation (3,)


class SdfDoc:
    """An element tree with the line number of every element."""

    def __init__(self, path: Path, data: bytes) -> None:
        self.path = path
        self.lines: dict[int, int] = {}
        builder = ET.TreeBuilder()
        parser = xml.parsers.expat.ParserCreate()
        parser.buffer_text = True  # one data call per text run, not per chunk

        def start(tag: str, attrs: dict[str, str]) -> None:
            el = builder.start(tag, attrs)
            self.lines[id(el)] = parser.CurrentLineNumber

        def refuse(*_: Any) -> None:
            raise MapFormatError(
                f"{path}, line {parser.CurrentLineNumber}: document type declarations and "
                "entities are refused (an SDF world needs none)")

        parser.StartElementHandler = start
        parser.EndElementHandler = builder.end
        parser.CharacterDataHandler = builder.data
        parser.StartDoctypeDeclHandler = refuse
        parser.EntityDeclHandler = refuse
        try:
            parser.Parse(data, True)
        except xml.parsers.expat.ExpatError as exc:
            raise MapFormatError(
                f"{path}, line {exc.lineno}, column {exc.offset + 1}: malformed XML: "
                f"{xml.parsers.expat.ErrorString(exc.code)}") from None
        self.root = builder.close()

    def where(self, el: ET.Element) -> str:
        line = self.lines.get(id(el))
        return f"{self.path}, line {line}" if line else str(self.path)

    def fail(self, el: ET.Element, what: str) -> MapFormatError:
        return MapFormatError(f"{self.where(el)}: {what}")


def read_world_bytes(path: Path) -> bytes:
    try:
        with open(path, "rb") as fh:
            head = fh.read(2)
            fh.seek(0)
            if head == b"\x1f\x8b":
                try:
                    with gzip.GzipFile(fileobj=fh) as gz:
                        data = gz.read(MAX_WORLD_BYTES + 1)
                except (OSError, EOFError) as exc:
                    raise MapFormatError(f"{path}: corrupt gzip file ({exc})") from None
            else:
                if path.name.lower().endswith(".gz"):
                    raise MapFormatError(f"{path}: the name ends in .gz but the file is not "
                                         "gzip-compressed")
                data = fh.read(MAX_WORLD_BYTES + 1)
    except FileNotFoundError:
        raise MapFormatError(f"world file not found: {path}") from None
    except IsADirectoryError:
        raise MapFormatError(f"world path is a directory, not a file: {path}") from None
    except PermissionError:
        raise MapFormatError(f"{path}: permission denied") from None
    if len(data) > MAX_WORLD_BYTES:
        raise MapFormatError(f"{path}: larger than {MAX_WORLD_BYTES // 2**20} MiB "
                             "(decompressed); refused")
    if not data.strip():
        raise MapFormatError(f"{path}: the file is empty")
    return data


# --------------------------------------------------------------------------- poses
def rpy(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """SDF's rotation: roll about x, then pitch about y, then yaw about z (fixed axes)."""
    cr, sr = math.cos(roll), math.sin(roll)
    cp, sp = math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    rz = np.array([[cy, -sy, 0.0], [sy, cy, 0.0], [0.0, 0.0, 1.0]])
    ry = np.array([[cp, 0.0, sp], [0.0, 1.0, 0.0], [-sp, 0.0, cp]])
    rx = np.array([[1.0, 0.0, 0.0], [0.0, cr, -sr], [0.0, sr, cr]])
    return rz @ ry @ rx


def _quat(x: float, y: float, z: float, w: float) -> np.ndarray:
    n = math.sqrt(x * x + y * y + z * z + w * w)
    if n == 0.0:
        raise ValueError("a zero quaternion")
    x, y, z, w = x / n, y / n, z / n, w / n
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


IDENTITY: Pose = (np.eye(3), np.zeros(3))


def compose(a: Pose, b: Pose) -> Pose:
    """The pose ``b`` (given in frame ``a``) in ``a``'s parent frame."""
    return a[0] @ b[0], a[0] @ b[1] + a[1]


def floats(doc: SdfDoc, el: ET.Element, what: str, n: int | tuple[int, ...]) -> list[float]:
    text = (el.text or "").split()
    counts = (n,) if isinstance(n, int) else n
    try:
        vals = [float(t) for t in text]
    except ValueError:
        raise doc.fail(el, f"<{el.tag}> of {what}: must be numbers, got "
                           f"{(el.text or '').strip()!r}") from None
    if len(vals) not in counts or not all(math.isfinite(v) for v in vals):
        want = " or ".join(str(c) for c in counts)
        raise doc.fail(el, f"<{el.tag}> of {what}: must be {want} finite numbers, got "
                           f"{(el.text or '').strip()!r}")
    return vals


def pose_of(doc: SdfDoc, parent: ET.Element, what: str, frames: tuple[str, ...]) -> Pose:
    """The ``<pose>`` child of ``parent`` (identity without one).

    ``frames`` are the ``relative_to``/``frame`` values that mean the default
    frame (the parent's); any other frame is refused.
    """
    el = parent.find("pose")
    if el is None:
        return IDENTITY
    for attr in ("relative_to", "frame"):
        f = el.get(attr)
        if f not in (None, "", *frames):
            raise doc.fail(el, f"<pose {attr}={f!r}> of {what}: poses relative to another "
                               "frame are not supported (only the parent's)")
    fmt = el.get("rotation_format", "euler_rpy")
    if fmt == "quat_xyzw":
        x, y, z, qx, qy, qz, qw = floats(doc, el, what, 7)
        try:
            rot = _quat(qx, qy, qz, qw)
        except ValueError:
            raise doc.fail(el, f"<pose> of {what}: a zero quaternion") from None
    elif fmt == "euler_rpy":
        x, y, z, r, p, yw = floats(doc, el, what, 6)
        if el.get("degrees", "false").strip().lower() in ("true", "1"):
            r, p, yw = math.radians(r), math.radians(p), math.radians(yw)
        rot = rpy(r, p, yw)
    else:
        raise doc.fail(el, f"<pose rotation_format={fmt!r}> of {what}: must be euler_rpy "
                           "or quat_xyzw")
    return rot, np.array([x, y, z])
