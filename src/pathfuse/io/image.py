"""Occupancy grids from plain images (PNG, PGM, JPEG, BMP) and numpy ``.npy`` arrays.

Orientation rules
-----------------
* **Images** are stored top row first.  The *top* image row becomes the
  *top* map row, i.e. pathfuse row ``H - 1``; image column ``x`` is map
  column ``x``.  So a picture of a map looks the same as a plot of the
  :class:`~pathfuse.grid.GridMap` with y pointing up.
* **.npy arrays** are taken as ``occupied[row, col]`` in pathfuse's own
  convention (row 0 = *bottom*): exactly what ``np.save(path,
  grid.occupied)`` writes, so :func:`read_npy` gives that grid back.  No
  flip is applied.

Grey level and thresholds
-------------------------
A pixel's grey value ``v`` (0..255) is the mean of its colour channels (R, G,
B; a grey image's single channel; 16-bit images are scaled to 0..255).  The
alpha channel is ignored.  A pixel is occupied when its darkness
``(255 - v) / 255`` exceeds ``threshold``: dark = occupied.  ``negate=True``
swaps this: occupied when ``v / 255 > threshold``.

Examples
--------
>>> import tempfile, pathlib
>>> import numpy as np
>>> from PIL import Image
>>> pix = np.array([[0, 255, 255],
...                 [255, 255, 0]], dtype=np.uint8)   # top row first
>>> with tempfile.TemporaryDirectory() as d:
...     p = pathlib.Path(d) / "two.png"
...     Image.fromarray(pix).save(p)
...     g = read_image(p, resolution=0.1)
>>> g.occupied.astype(int).tolist()   # row 0 (bottom) is the last image row
[[0, 0, 1], [1, 0, 0]]
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np

from pathfuse.grid import GridMap
from pathfuse.limits import check_cells
from pathfuse.result import MapError, MapFormatError, PathfuseError
from pathfuse.validate import short as _shown

__all__ = ["read_image", "read_npy", "load_pixels", "IMAGE_SUFFIXES"]

IMAGE_SUFFIXES = (".png", ".pgm", ".jpg", ".jpeg", ".bmp")
"""File name endings read as images."""


def _check_file(path: Path, what: str, context: str = "") -> None:
    if not path.exists():
        raise MapFormatError(f"{context}{what} not found: {path}")
    if path.is_dir():
        raise MapFormatError(f"{context}{what} is a directory, not a file: {path}")


def load_pixels(
    path: str | os.PathLike[str], context: str = ""
) -> tuple[np.ndarray, np.ndarray | None]:
    """Read an image as ``(grey, alpha)`` arrays in the image's own row order (top first).

    ``grey`` is float64 ``(H, W)``, the mean of the colour channels on a
    0..255 scale (the channels of an RGB pixel averaged, as ROS map_server
    does); ``alpha`` is float64 ``(H, W)`` on 0..255 (255 = opaque) or
    ``None`` when the image has no alpha channel.  ``context`` is put in
    front of error messages (for example the YAML file that named the
    image).

    Raises
    ------
    MapFormatError
        Missing, unreadable, truncated or corrupt file, or an image mode that
        is not grey, grey+alpha, palette, RGB or RGBA (8 or 16 bit).
    """
    from PIL import Image, UnidentifiedImageError

    path = Path(path)
    _check_file(path, "image file", context)
    img: Image.Image  # an ImageFile until converted below
    try:
        with Image.open(path) as im:
            w, h = im.size  # from the header: check before decoding
            check_cells(h, w, f"{context}{path}: image")
            im.load()
            img = im
    except PathfuseError:
        raise
    except UnidentifiedImageError:
        raise MapFormatError(f"{context}{path}: not a readable image (unknown or corrupt format)") \
            from None
    except Image.DecompressionBombError as exc:
        raise MapFormatError(f"{context}{path}: image too large ({exc})") from None
    except (OSError, SyntaxError, ValueError, EOFError) as exc:
        raise MapFormatError(f"{context}{path}: corrupt or truncated image ({exc})") from None

    mode = img.mode
    alpha: np.ndarray | None = None
    if mode == "P":
        img = img.convert("RGBA" if "transparency" in img.info else "RGB")
        mode = img.mode
    elif mode == "PA":
        img = img.convert("RGBA")
        mode = "RGBA"
    elif mode in ("CMYK", "YCbCr", "LAB", "HSV"):
        img = img.convert("RGB")
        mode = "RGB"
    if mode == "1":
        grey = np.asarray(img, dtype=np.float64) * 255.0
    elif mode == "L":
        grey = np.asarray(img, dtype=np.float64)
    elif mode == "LA":
        arr = np.asarray(img, dtype=np.float64)
        grey, alpha = arr[..., 0], arr[..., 1]
    elif mode in ("RGB", "RGBA"):
        arr = np.asarray(img, dtype=np.float64)
        grey = arr[..., :3].sum(axis=2) / 3.0
        if mode == "RGBA":
            alpha = arr[..., 3]
    elif mode.startswith("I;16") or mode == "I":
        arr = np.asarray(img, dtype=np.float64)
        if mode == "I" and arr.size and arr.max() > 65535:
            raise MapFormatError(f"{context}{path}: 32-bit integer images are not supported")
        grey = arr / 65535.0 * 255.0
    else:
        raise MapFormatError(
            f"{context}{path}: unsupported image mode {_shown(mode)} "
            "(use grey, grey+alpha, palette, RGB or RGBA)"
        )
    if grey.ndim != 2 or grey.size == 0:
        raise MapFormatError(f"{context}{path}: image has no pixels (shape {grey.shape})")
    return grey, alpha


def _resolution(value: object, path: Path) -> float:
    if value is None:
        raise MapError(f"{path}: a resolution (metres per cell) is required for this map file")
    if isinstance(value, bool):
        raise MapError(f"{path}: resolution must be a number, got {_shown(value)}")
    try:
        res = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise MapError(f"{path}: resolution must be a number, got {_shown(value)}") from None
    if not math.isfinite(res) or res <= 0:
        raise MapError(f"{path}: resolution must be a finite number > 0, got {_shown(value)}")
    return res


def _origin(value: object, path: Path) -> tuple[float, float]:
    try:
        # any iterable of two numbers; a TypeError is reported below
        ox, oy = (float(v) for v in value)  # type: ignore[attr-defined]
    except (TypeError, ValueError):
        raise MapError(f"{path}: origin must be two numbers (x, y), got {_shown(value)}") from None
    if not (math.isfinite(ox) and math.isfinite(oy)):
        raise MapError(f"{path}: origin must be finite, got {_shown(value)}")
    return ox, oy


def read_image(
    path: str | os.PathLike[str],
    resolution: float | None,
    origin: tuple[float, float] = (0.0, 0.0),
    threshold: float = 0.5,
    negate: bool = False,
    name: str | None = None,
) -> GridMap:
    """Read a picture of a map: dark pixels are obstacles.

    Parameters
    ----------
    path : str or path-like
        PNG, PGM (P5 or P2), JPEG or BMP file.
    resolution : float
        Metres per pixel (required: images carry no scale).
    origin : (float, float)
        World position of the lower-left corner of the *bottom-left* pixel.
    threshold : float
        In ``[0, 1]``.  Occupied where ``(255 - v) / 255 > threshold`` (``v``
        = mean of R, G, B; alpha ignored).
    negate : bool
        If true, light pixels are obstacles: occupied where ``v / 255 >
        threshold``.
    name : str, optional
        Defaults to the file name without its extension.

    Returns
    -------
    GridMap
        The top image row is the top map row (row ``H - 1``).  ``meta`` has
        ``source``, ``format`` ("image"), ``threshold`` and ``negate``.

    Raises
    ------
    MapFormatError
        Missing, corrupt or truncated file, unsupported image mode.
    MapError
        Missing or invalid ``resolution``/``origin``/``threshold``.
    """
    path = Path(path)
    res = _resolution(resolution, path)
    org = _origin(origin, path)
    try:
        thr = float(threshold)
    except (TypeError, ValueError):
        raise MapError(f"{path}: threshold must be a number in [0, 1], got {_shown(threshold)}") \
            from None
    if not (0.0 <= thr <= 1.0):
        raise MapError(f"{path}: threshold must be in [0, 1], got {_shown(threshold)}")
    grey, _alpha = load_pixels(path)
    shade = grey / 255.0
    occ = shade if negate else 1.0 - shade
    occupied = (occ > thr)[::-1]
    return GridMap(
        occupied,
        resolution=res,
        origin=org,
        name=name if name is not None else path.stem,
        meta={"source": str(path), "format": "image", "threshold": thr, "negate": bool(negate)},
    )


def read_npy(
    path: str | os.PathLike[str],
    resolution: float | None,
    origin: tuple[float, float] = (0.0, 0.0),
    name: str | None = None,
) -> GridMap:
    """Read a 2-D ``.npy`` array as ``occupied[row, col]`` with row 0 at the bottom.

    The array is taken in pathfuse's convention (no flip): ``np.save(p,
    grid.occupied)`` followed by ``read_npy(p, grid.resolution,
    grid.origin)`` gives ``grid`` back.  A boolean array is used as is; a
    numeric one is occupied where non-zero.

    Raises
    ------
    MapFormatError
        Missing or corrupt file, pickled/object arrays, an array that is not
        2-D, is empty, is not boolean or real numeric, or holds NaN.
    MapError
        Missing or invalid ``resolution``/``origin``.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> import numpy as np
    >>> occ = np.array([[True, False], [False, False]])   # row 0 = bottom
    >>> with tempfile.TemporaryDirectory() as d:
    ...     p = pathlib.Path(d) / "a.npy"
    ...     np.save(p, occ)
    ...     g = read_npy(p, resolution=0.5)
    >>> bool(g.occupied[0, 0]), g.is_free([0.25, 0.25]).tolist()
    (True, [False])
    """
    path = Path(path)
    res = _resolution(resolution, path)
    org = _origin(origin, path)
    _check_file(path, "array file")
    try:
        # the header first (a memory map reads no data), so a huge array is refused unread
        head = np.load(path, allow_pickle=False, mmap_mode="r")
        if isinstance(head, np.ndarray) and head.ndim == 2:
            check_cells(head.shape[0], head.shape[1], f"{path}: array")
        arr = np.array(head) if isinstance(head, np.memmap) else head
        del head
    except PathfuseError:
        raise
    except ValueError as exc:
        msg = str(exc)
        if "allow_pickle" in msg or "pickle" in msg.lower() or "Python objects" in msg:
            raise MapFormatError(
                f"{path}: holds an object (pickled) array; save a bool or numeric array"
            ) from None
        raise MapFormatError(f"{path}: not a valid .npy file ({_shown(msg, 120)})") from None
    except (OSError, EOFError) as exc:
        raise MapFormatError(f"{path}: cannot read .npy file ({exc})") from None
    except Exception as exc:  # noqa: BLE001 - numpy's header parser raises what Python's does
        raise MapFormatError(f"{path}: not a valid .npy file (a malformed header: "
                             f"{type(exc).__name__})") from None
    if not isinstance(arr, np.ndarray):
        raise MapFormatError(f"{path}: holds {type(arr).__name__}, not a single array")
    if arr.ndim != 2:
        raise MapFormatError(f"{path}: array must be 2-D (rows, cols), got shape {arr.shape}")
    if arr.size == 0:
        raise MapFormatError(f"{path}: array is empty (shape {arr.shape})")
    if arr.dtype != np.bool_:
        if not (np.issubdtype(arr.dtype, np.integer) or np.issubdtype(arr.dtype, np.floating)):
            raise MapFormatError(
                f"{path}: array dtype {arr.dtype} is not boolean or real numeric"
            )
        if np.issubdtype(arr.dtype, np.floating) and np.isnan(arr).any():
            r, c = np.argwhere(np.isnan(arr))[0]
            raise MapFormatError(f"{path}: array holds NaN (first at row {r}, col {c})")
        arr = arr != 0
    return GridMap(
        arr,
        resolution=res,
        origin=org,
        name=name if name is not None else path.stem,
        meta={"source": str(path), "format": "npy"},
    )
