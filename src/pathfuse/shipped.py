"""The example scenarios and experiment files that ship with pathfuse, found by name.

A wheel carries them as package data in ``pathfuse/_shipped/`` (``setup.py`` copies
them there at build time, keeping the clone's layout so that their relative paths
still work); a clone installed with ``pip install -e`` reads them from the clone's own
``examples/`` and ``experiments/`` folders.  Every YAML file under ``examples/`` (any
subfolder) is a *scenario*-like example and every file under ``experiments/`` an
experiment; each is known by its file name without ``.yaml`` (``head_on``), or, when two
share a name, by its folder too (``scenarios/head_on``).

:func:`resolve` is what the command line calls on a file argument: an existing path
is returned as given, a shipped name becomes its path, and anything else is a
:class:`~pathfuse.ConfigError` listing the names.

>>> resolve("no/such/file.yaml", "scenario")  # doctest: +ELLIPSIS
Traceback (most recent call last):
...
pathfuse.result.ConfigError: no/such/file.yaml: no such file...
"""

from __future__ import annotations

import re
import shutil
from dataclasses import dataclass
from pathlib import Path

from pathfuse.result import ConfigError

__all__ = ["Example", "SHIPPED_DIRS", "shipped_root", "examples", "resolve", "copy_examples"]

SHIPPED_DIRS: tuple[str, ...] = ("examples", "experiments", "tests/data/barn")
"""The folders of the clone that travel with the package, as paths relative to its root
(``tests/data/barn`` holds the four BARN worlds that ``barn_world_17.yaml`` names).
``setup.py`` copies the same list."""


def _kind(root: Path, path: Path) -> str:
    """``experiment`` under ``experiments/``; under ``examples/``, the first folder's name
    in the singular (``scenarios/`` -> ``scenario``, ``irsim/`` -> ``irsim``)."""
    parts = path.relative_to(root).parts
    if parts[0] == "experiments":
        return "experiment"
    sub = parts[1] if len(parts) > 2 else "examples"
    return sub[:-1] if sub.endswith("s") else sub


@dataclass(frozen=True)
class Example:
    """One shipped example file.

    Attributes
    ----------
    name : str
        Its name: the file name without ``.yaml`` (or ``folder/stem`` when two files
        share a stem).
    kind : str
        ``"experiment"`` under ``experiments/``; under ``examples/``, its folder's name in
        the singular: ``"scenario"`` for ``examples/scenarios/``.
    path : pathlib.Path
        Where it is on this machine.
    summary : str
        The first comment line of the file ("" when it has none).
    """

    name: str
    kind: str
    path: Path
    summary: str


def shipped_root() -> Path:
    """The folder holding ``examples/`` and ``experiments/``: the package's data when
    installed from a wheel, the clone's root when installed from a clone.

    Raises
    ------
    ConfigError
        When neither exists (a broken installation).
    """
    packaged = Path(__file__).resolve().parent / "_shipped"
    if (packaged / "examples").is_dir():
        return packaged
    clone = Path(__file__).resolve().parents[2]
    if (clone / "examples").is_dir() and (clone / "pyproject.toml").is_file():
        return clone
    raise ConfigError(f"{packaged}: no shipped examples (the installation is incomplete; "
                      "reinstall pathfuse)")


def _summary(path: Path) -> str:
    """The first sentence of the file's leading comment ("" when it has none)."""
    words: list[str] = []
    try:
        with path.open(encoding="utf-8") as fh:
            for line in fh:
                text = line.strip()
                if not text.startswith("#"):
                    break
                words += text.lstrip("#").split()
    except (OSError, UnicodeDecodeError):
        return ""
    text = " ".join(words)
    end = re.search(r"(?<!\bal)(?<!\bSec)(?<!\be\.g)\.\s+(?=[A-Z`])", text)
    text = text if end is None else text[:end.start() + 1]
    return text if len(text) <= 100 else text[:97].rstrip() + "..."


def examples(kind: str | None = None) -> list[Example]:
    """Every shipped example file, sorted by kind and name.

    Parameters
    ----------
    kind : str, optional
        Only the files of this kind (``"scenario"``, ``"experiment"``, ...; default: all).

    Returns
    -------
    list of Example
    """
    root = shipped_root()
    found: list[tuple[str, Path]] = []
    for top in ("examples", "experiments"):
        base = root / top
        if base.is_dir():
            found += [(_kind(root, p), p) for p in sorted(base.rglob("*.yaml")) if p.is_file()]
    found = [(k, p) for k, p in found if kind is None or k == kind]
    stems: dict[str, int] = {}
    for _, p in found:
        stems[p.stem] = stems.get(p.stem, 0) + 1
    out = []
    for k, p in found:
        name = p.stem if stems[p.stem] == 1 else f"{p.parent.name}/{p.stem}"
        out.append(Example(name, k, p, _summary(p)))
    return sorted(out, key=lambda e: (e.kind, e.name))


def resolve(arg: str | Path, kind: str) -> str:
    """``arg`` when it names an existing file, else the path of the shipped example of that
    name.

    Parameters
    ----------
    arg : str or pathlib.Path
        A file path, or the name of a shipped example (``head_on``,
        ``barn-jackal``; ``.yaml`` may be added).
    kind : str
        The kind of file the command reads (``"scenario"``, ``"experiment"``); only those
        names are looked up, and the error lists them.

    Returns
    -------
    str
        The path to read.

    Raises
    ------
    ConfigError
        When ``arg`` is neither a file nor a shipped name; the message lists the names.
    """
    text = str(arg)
    if Path(text).expanduser().exists():
        return text
    want = text[:-5] if text.endswith(".yaml") else text
    try:
        known = examples(kind)
    except ConfigError:
        known = []
    for ex in known:
        if want == ex.name or want == f"{ex.path.parent.name}/{ex.path.stem}":
            return str(ex.path)
    names = ", ".join(e.name for e in known) or "none"
    raise ConfigError(f"{text}: no such file, and no shipped {kind} of that name (shipped: "
                      f"{names}; 'pathfuse examples' lists them)")


def copy_examples(dest: str | Path) -> list[Path]:
    """Copy the shipped examples into ``dest`` with the layout of a clone
    (``examples/``, ``experiments/``, ``tests/data/barn/``), so their relative paths hold.

    Parameters
    ----------
    dest : str or pathlib.Path
        The folder to copy into (created when missing).

    Returns
    -------
    list of pathlib.Path
        The files written.

    Raises
    ------
    ConfigError
        When ``dest`` is a file, or a file to write exists already (nothing is written
        then).
    """
    target = Path(dest).expanduser()
    if target.exists() and not target.is_dir():
        raise ConfigError(f"{target}: not a folder")
    root = shipped_root()
    pairs: list[tuple[Path, Path]] = []
    for rel in SHIPPED_DIRS:
        src = root / rel
        if not src.is_dir():
            continue
        for p in sorted(src.rglob("*")):
            if p.is_file() and "__pycache__" not in p.parts:
                pairs.append((p, target / p.relative_to(root)))
    clash = [d for _, d in pairs if d.exists()]
    if clash:
        more = f" and {len(clash) - 1} more" if len(clash) > 1 else ""
        raise ConfigError(f"{clash[0]}: exists already{more}; copy into an empty folder")
    for src, dst in pairs:
        dst.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(src, dst)
    return [d for _, d in pairs]
