"""The public benchmark data pathfuse's studies read, downloaded from their publishers.

``pathfuse data download barn|movingai [--to DIR]`` (and :func:`download`) fetch each
file from the publisher's own repository at a pinned commit, check its size and SHA-256
against the manifest shipped beside this module (``barn.sha256``, ``movingai.sha256``),
and only then move it into place:

* **barn**: the 300 worlds and reference paths of the BARN challenge
  (Daffan/the-barn-challenge, MIT), its licence as ``LICENSE.BARN``; the worlds are
  stored gzipped (``worlds/world_N.world.gz``, 3.6 MB for 250 instead of 140 MB), as
  ``pathfuse barn`` reads them, after the checksum of their plain bytes has passed;
* **movingai**: the 22 MovingAI maps and scenario files the studies and tests use, from
  nathansttt/hog2 (the benchmarks' maintainer's repository) and three current-format
  ``.scen`` files from Lucas-707/PAStar.

The checksums were computed from bytes on hand: the git blobs of those commits.  The
publishers' zip archives (movingai.com's ``*-map.zip``, a GitHub archive of the
challenge) were not available when the manifests were made, so pathfuse downloads and
checks the files one by one and never an archive whose checksum it could not know.

A file already in place with the right checksum is kept; one with another checksum is
an error (pathfuse never overwrites a file it did not write).  A download that fails
half-way leaves nothing behind but the files finished before it, so running the same
command again resumes.
"""

from __future__ import annotations

import fnmatch
import gzip
import hashlib
import http.client
import os
import sys
import time
import urllib.error
import urllib.request
from collections.abc import Sequence
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import IO

from pathfuse.result import ConfigError, PathfuseError

__all__ = ["DATASETS", "DownloadError", "Dataset", "FileEntry", "DownloadReport",
           "dataset", "download", "missing_hint"]

DATASETS: dict[str, str] = {
    "barn": "BARN: 300 Gazebo worlds and reference paths (Perille et al., SSRR 2020)",
    "movingai": "MovingAI: 11 maps and their scenario files (Sturtevant 2012; Stern et al. "
                "2019)",
}
"""The datasets :func:`download` knows, with a one-line description."""

_GZIPPED = (".world",)  # stored as FILE.gz once checked
_CHUNK = 1 << 16


class DownloadError(PathfuseError):
    """A download failed (network, checksum, a file in the way); the message names the
    file and what to do."""


@dataclass(frozen=True)
class FileEntry:
    """One file of a dataset's manifest.

    Attributes
    ----------
    path : str
        Where it goes, relative to the dataset's folder (``worlds/world_0.world``).
    url : str
        The publisher's address of the file.
    sha256 : str
        The SHA-256 of its bytes (before any gzip of ours), lowercase hex.
    size : int
        Its length in bytes.
    """

    path: str
    url: str
    sha256: str
    size: int

    @property
    def stored_as(self) -> str:
        """The path it is kept under: ``.gz`` added for Gazebo worlds."""
        return self.path + ".gz" if self.path.endswith(_GZIPPED) else self.path


@dataclass(frozen=True)
class Dataset:
    """A named list of files to download.

    Attributes
    ----------
    name : str
        ``barn``, ``movingai``, or a name of the caller's (tests build small ones).
    files : tuple of FileEntry
    """

    name: str
    files: tuple[FileEntry, ...]

    @property
    def total_bytes(self) -> int:
        return sum(f.size for f in self.files)


@dataclass
class DownloadReport:
    """What :func:`download` did.

    Attributes
    ----------
    folder : pathlib.Path
        The dataset's folder.
    downloaded, kept : list of str
        The files fetched now, and those already in place with the right checksum.
    bytes : int
        Bytes fetched now.
    """

    folder: Path
    downloaded: list[str] = field(default_factory=list)
    kept: list[str] = field(default_factory=list)
    bytes: int = 0

    def __str__(self) -> str:
        return (f"{self.folder}: {len(self.downloaded)} file(s) downloaded "
                f"({self.bytes / 1e6:.1f} MB) and checked, {len(self.kept)} already there "
                "with the right SHA-256")


def missing_hint(name: str) -> str:
    """The sentence an error about a missing dataset folder or file ends with.

    >>> missing_hint("barn")
    "get the BARN worlds with 'pathfuse data download barn --to DIR'"
    """
    what = {"barn": "the BARN worlds", "movingai": "the MovingAI maps"}.get(name, name)
    return f"get {what} with 'pathfuse data download {name} --to DIR'"


def _parse_manifest(name: str, text: str) -> Dataset:
    files = []
    for n, line in enumerate(text.splitlines(), 1):
        if not line.strip() or line.startswith("#"):
            continue
        parts = line.split()
        if len(parts) != 4 or len(parts[0]) != 64 or not parts[1].isdigit():
            raise ConfigError(f"{name}.sha256: line {n}: expected 'SHA256 BYTES PATH URL', "
                              f"got {line[:80]!r}")
        files.append(FileEntry(path=parts[2], url=parts[3], sha256=parts[0].lower(),
                               size=int(parts[1])))
    return Dataset(name, tuple(files))


def dataset(name: str) -> Dataset:
    """The dataset ``name`` (a key of :data:`DATASETS`) with its manifest.

    Raises
    ------
    ConfigError
        For an unknown name; the message lists the known ones.
    """
    if name not in DATASETS:
        raise ConfigError(f"dataset: must be one of {', '.join(DATASETS)}, got {name!r}")
    text = (resources.files("pathfuse.datasets") / f"{name}.sha256").read_text("utf-8")
    return _parse_manifest(name, text)


class _Progress:
    """Bytes fetched of the total: a bar redrawn in place on a terminal, otherwise a line
    at the start, every 30 s and at the end."""

    def __init__(self, label: str, total: int, stream: IO[str] | None, tty: bool) -> None:
        self.label, self.total, self.stream, self.tty = label, max(total, 1), stream, tty
        self.done = 0
        self.t0 = self.last = time.monotonic()
        if stream is not None and not tty:
            print(f"{label}: fetching {total / 1e6:.1f} MB", file=stream, flush=True)

    def add(self, n: int) -> None:
        self.done += n
        now = time.monotonic()
        if self.stream is None:
            return
        if self.tty and now - self.last >= 0.1:
            self.last = now
            self._draw(now, "\r")
        elif not self.tty and now - self.last >= 30.0:
            self.last = now
            self._draw(now, "")

    def _draw(self, now: float, lead: str) -> None:
        assert self.stream is not None
        frac = min(self.done / self.total, 1.0)
        bar = "#" * int(24 * frac) + "-" * (24 - int(24 * frac))
        rate = self.done / max(now - self.t0, 1e-9) / 1e6
        end = "" if lead else "\n"
        self.stream.write(f"{lead}{self.label} [{bar}] {100 * frac:3.0f}%  "
                          f"{self.done / 1e6:.1f}/{self.total / 1e6:.1f} MB  "
                          f"{rate:.1f} MB/s{end}")
        self.stream.flush()

    def close(self) -> None:
        if self.stream is not None and (self.tty or self.done):
            self._draw(time.monotonic(), "\r" if self.tty else "")
            if self.tty:
                self.stream.write("\n")
                self.stream.flush()


def _digest_of(path: Path) -> str:
    h = hashlib.sha256()
    opener = gzip.open if path.suffix == ".gz" else open
    with opener(path, "rb") as fh:  # type: ignore[operator]
        while chunk := fh.read(_CHUNK):
            h.update(chunk)
    return h.hexdigest()


def _fetch(entry: FileEntry, url: str, part: Path, bar: _Progress, timeout: float) -> None:
    """``url`` into ``part``, checked against ``entry``; raises DownloadError."""
    h = hashlib.sha256()
    got = 0
    try:
        with urllib.request.urlopen(url, timeout=timeout) as resp:  # noqa: S310 - https/http
            opener = gzip.open if entry.stored_as.endswith(".gz") else open
            with opener(part, "wb") as out:  # type: ignore[operator]
                while True:
                    chunk = resp.read(_CHUNK)
                    if not chunk:
                        break
                    got += len(chunk)
                    if got > entry.size:
                        raise DownloadError(f"{url}: more than the {entry.size} bytes of "
                                            f"{entry.path}; nothing was kept of it")
                    h.update(chunk)
                    out.write(chunk)
                    bar.add(len(chunk))
    except DownloadError:
        raise
    except (urllib.error.URLError, http.client.HTTPException, OSError, ValueError) as exc:
        reason = getattr(exc, "reason", None) or exc.__class__.__name__
        if exc.__class__.__name__ == "IncompleteRead":
            reason = f"the connection closed after {got} of {entry.size} bytes"
        raise DownloadError(f"{url}: download failed ({reason}); nothing was kept of "
                            f"{entry.path}, run the same command again to resume") from None
    if got != entry.size:
        raise DownloadError(f"{url}: incomplete, {got} of {entry.size} bytes; nothing was kept "
                            f"of {entry.path}, run the same command again to resume")
    if h.hexdigest() != entry.sha256:
        raise DownloadError(f"{url}: SHA-256 mismatch for {entry.path}: expected "
                            f"{entry.sha256}, got {h.hexdigest()}; nothing was kept of it")


def download(data: str | Dataset, to: str | Path | None = None, *,
             mirror: str | None = None, only: Sequence[str] | None = None,
             progress: bool | None = None, stream: IO[str] | None = None,
             timeout: float = 60.0) -> DownloadReport:
    """Download a dataset into a folder, each file checked against its SHA-256.

    Parameters
    ----------
    data : str or Dataset
        ``"barn"`` or ``"movingai"`` (or a :class:`Dataset`).
    to : str or pathlib.Path, optional
        The folder (created when missing; default ``./NAME``).
    mirror : str, optional
        A base URL serving the files under their local paths (``MIRROR/worlds/
        world_0.world``) instead of the publishers' addresses.
    only : sequence of str, optional
        Glob patterns of local paths (``worlds/world_1?.world``): only those files.
    progress : bool, optional
        Show progress on ``stream`` (default: when it is a terminal, as a bar; otherwise
        a few plain lines).  ``False``: silent.
    stream : file, optional
        Where progress goes (default ``sys.stderr``).
    timeout : float
        Seconds a connection may stall.

    Returns
    -------
    DownloadReport

    Raises
    ------
    ConfigError
        An unknown dataset, a pattern that selects nothing, or ``to`` naming a file.
    DownloadError
        A failed or incomplete download, a checksum mismatch, or a file in the way whose
        checksum differs; files finished before it stay.
    """
    ds = dataset(data) if isinstance(data, str) else data
    folder = Path(to if to is not None else ds.name).expanduser()
    if folder.exists() and not folder.is_dir():
        raise ConfigError(f"--to {folder}: not a folder")
    files = list(ds.files)
    if only:
        files = [f for f in files if any(fnmatch.fnmatchcase(f.path, g) for g in only)]
        if not files:
            raise ConfigError(f"--only {' '.join(only)}: matches no file of {ds.name}")
    report = DownloadReport(folder)
    todo = []
    for f in files:
        have = [p for p in (folder / f.stored_as, folder / f.path) if p.is_file()]
        if not have:
            todo.append(f)
            continue
        try:
            digest = _digest_of(have[0])
        except (OSError, EOFError, gzip.BadGzipFile) as exc:
            raise DownloadError(f"{have[0]}: exists and cannot be read ({exc}); move it away "
                                "or choose another --to") from None
        if digest != f.sha256:
            raise DownloadError(f"{have[0]}: exists with another SHA-256 ({digest}, expected "
                                f"{f.sha256}); pathfuse does not overwrite it: move it away "
                                "or choose another --to")
        report.kept.append(f.path)
    out = sys.stderr if stream is None else stream
    tty = bool(getattr(out, "isatty", lambda: False)())
    show = (progress if progress is not None else True) and bool(todo)
    bar = _Progress(ds.name, sum(f.size for f in todo), out if show else None, tty)
    try:
        for f in todo:
            url = f"{mirror.rstrip('/')}/{f.path}" if mirror else f.url
            dest = folder / f.stored_as
            dest.parent.mkdir(parents=True, exist_ok=True)
            part = dest.with_name(dest.name + ".part")
            try:
                _fetch(f, url, part, bar, timeout)
                os.replace(part, dest)
            finally:
                part.unlink(missing_ok=True)
            report.downloaded.append(f.path)
            report.bytes += f.size
    finally:
        bar.close()
    return report
