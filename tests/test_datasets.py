"""``pathfuse data download``: files from a loopback HTTP server, checked by SHA-256.

There is no network here, so a server on 127.0.0.1 plays the publisher: it serves the
small files of ``tests/data/download`` (and the BARN copies of ``tests/data/barn``,
decompressed, for the real manifest), and can cut a file short or serve other bytes.
"""

from __future__ import annotations

import gzip
import hashlib
import http.server
import subprocess
import sys
import threading
from collections.abc import Iterator
from pathlib import Path

import pytest

from pathfuse import ConfigError
from pathfuse.datasets import Dataset, DownloadError, FileEntry, dataset, download

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "tests" / "data" / "download"
BARN = ROOT / "tests" / "data" / "barn"
# the SHA-256 of the two shipped test files, written out (not computed by the tests)
TINY = {"maps/tiny.map": ("7bb2d12b50d6de886579507a44b91be1cbb33abc603ea652963a363c2a2b0c07", 41),
        "maps/tiny.map.scen": ("4f80d09e7be1bd74a0876907f9cd4a12c6c2c0aab564e18abcb8373ffbc955c3",
                               44)}


class _Server:
    """A loopback HTTP server: ``files`` maps a URL path to bytes; paths in ``cut`` send
    their full Content-Length but only half the bytes, then close."""

    def __init__(self) -> None:
        self.files: dict[str, bytes] = {}
        self.cut: set[str] = set()
        self.hits: list[str] = []
        outer = self

        class Handler(http.server.BaseHTTPRequestHandler):
            def do_GET(self) -> None:  # noqa: N802 - http.server's name
                outer.hits.append(self.path)
                body = outer.files.get(self.path)
                if body is None:
                    self.send_error(404)
                    return
                self.send_response(200)
                self.send_header("Content-Length", str(len(body)))
                self.end_headers()
                if self.path in outer.cut:
                    self.wfile.write(body[: len(body) // 2])
                    self.wfile.flush()
                    self.close_connection = True
                    return
                self.wfile.write(body)

            def log_message(self, *args: object) -> None:
                pass

        self.httpd = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Handler)
        self.url = f"http://127.0.0.1:{self.httpd.server_address[1]}"
        self.thread = threading.Thread(target=self.httpd.serve_forever, daemon=True)
        self.thread.start()

    def close(self) -> None:
        self.httpd.shutdown()
        self.httpd.server_close()


@pytest.fixture
def server() -> Iterator[_Server]:
    s = _Server()
    for rel in TINY:
        s.files[f"/pub/{rel}"] = (DATA / rel).read_bytes()
    yield s
    s.close()


def _tiny(server: _Server) -> Dataset:
    return Dataset("tiny", tuple(FileEntry(rel, f"{server.url}/pub/{rel}", sha, size)
                                 for rel, (sha, size) in TINY.items()))


def test_download_checks_and_places_every_file(server, tmp_path):
    out = tmp_path / "tiny"
    rep = download(_tiny(server), out, progress=False)
    assert sorted(rep.downloaded) == sorted(TINY) and rep.kept == [] and rep.bytes == 85
    for rel in TINY:
        assert (out / rel).read_bytes() == (DATA / rel).read_bytes()
    assert not list(out.rglob("*.part"))
    # run again: every file is already there with the right checksum, nothing is fetched
    before = len(server.hits)
    again = download(_tiny(server), out, progress=False)
    assert again.downloaded == [] and sorted(again.kept) == sorted(TINY)
    assert len(server.hits) == before


def test_a_checksum_mismatch_keeps_nothing_of_that_file(server, tmp_path):
    server.files["/pub/maps/tiny.map"] = server.files["/pub/maps/tiny.map"].replace(b"@", b".")
    out = tmp_path / "tiny"
    with pytest.raises(DownloadError, match=r"tiny\.map: SHA-256 mismatch for maps/tiny\.map: "
                       r"expected 7bb2d12b.*got [0-9a-f]{64}; nothing was kept"):
        download(_tiny(server), out, progress=False)
    assert not (out / "maps" / "tiny.map").exists()
    assert not list(out.rglob("*.part"))


def test_a_partial_download_keeps_nothing_and_the_same_call_resumes(server, tmp_path):
    server.cut.add("/pub/maps/tiny.map.scen")
    out = tmp_path / "tiny"
    with pytest.raises(DownloadError, match=r"tiny\.map\.scen: (download failed|incomplete).*"
                       r"nothing was kept of maps/tiny\.map\.scen, run the same command again"):
        download(_tiny(server), out, progress=False)
    assert (out / "maps" / "tiny.map").is_file()  # finished before the failure: kept
    assert not (out / "maps" / "tiny.map.scen").exists() and not list(out.rglob("*.part"))
    server.cut.clear()
    rep = download(_tiny(server), out, progress=False)
    assert rep.downloaded == ["maps/tiny.map.scen"] and rep.kept == ["maps/tiny.map"]


def test_an_existing_file_with_other_bytes_is_never_overwritten(server, tmp_path):
    out = tmp_path / "tiny"
    (out / "maps").mkdir(parents=True)
    (out / "maps" / "tiny.map").write_bytes(b"mine\n")
    with pytest.raises(DownloadError, match=r"tiny\.map: exists with another SHA-256 .*does "
                       r"not overwrite it"):
        download(_tiny(server), out, progress=False)
    assert (out / "maps" / "tiny.map").read_bytes() == b"mine\n"
    assert server.hits == []  # checked before fetching anything


def test_a_server_error_is_one_message_naming_the_url(server, tmp_path):
    ds = Dataset("tiny", (FileEntry("x.map", f"{server.url}/pub/missing.map", "0" * 64, 3),))
    with pytest.raises(DownloadError, match=r"/pub/missing\.map: download failed \(Not Found\)"):
        download(ds, tmp_path / "t", progress=False)


def test_the_progress_lines_off_a_terminal(server, tmp_path):
    import io

    buf = io.StringIO()
    download(_tiny(server), tmp_path / "tiny", stream=buf)
    lines = buf.getvalue().splitlines()
    assert lines[0] == "tiny: fetching 0.0 MB"
    assert lines[-1].startswith("tiny [########################] 100%")


def test_the_barn_manifest_matches_the_shipped_worlds_and_paths():
    """The manifest's SHA-256 of the four BARN worlds and paths of tests/data (their plain
    bytes) are those of the copies here: the checksums are of the publisher's files."""
    ds = dataset("barn")
    assert len(ds.files) == 601 and ds.total_bytes == 167_583_750
    by_path = {f.path: f for f in ds.files}
    for i in (0, 17, 20, 43):
        w = by_path[f"worlds/world_{i}.world"]
        assert hashlib.sha256(gzip.decompress((BARN / "worlds" / f"world_{i}.world.gz")
                                              .read_bytes())).hexdigest() == w.sha256
        assert w.url.startswith("https://raw.githubusercontent.com/Daffan/the-barn-challenge/"
                                "bf5a226f6088ec96bf0d2dbee3253a8ea6119b83/jackal_helper/worlds/"
                                "BARN/")
        p = by_path[f"path_files/path_{i}.npy"]
        assert hashlib.sha256((BARN / "path_files" / f"path_{i}.npy").read_bytes()) \
            .hexdigest() == p.sha256
    lic = by_path["LICENSE.BARN"]
    assert hashlib.sha256((BARN / "LICENSE.BARN").read_bytes()).hexdigest() == lic.sha256


def test_the_movingai_manifest_matches_the_shipped_copies():
    ds = dataset("movingai")
    assert len(ds.files) == 22
    here = ROOT / "tests" / "data" / "movingai"
    checked = 0
    for f in ds.files:
        if (here / f.path).is_file():
            assert hashlib.sha256((here / f.path).read_bytes()).hexdigest() == f.sha256, f.path
            checked += 1
    assert checked >= 8
    assert all(f.url.startswith(("https://raw.githubusercontent.com/nathansttt/hog2/",
                                 "https://raw.githubusercontent.com/Lucas-707/PAStar/"))
               for f in ds.files)


def test_unknown_dataset_and_empty_selection_are_config_errors(tmp_path):
    with pytest.raises(ConfigError, match=r"dataset: must be one of barn, movingai, got 'x'"):
        dataset("x")
    with pytest.raises(ConfigError, match=r"--only nothing\*: matches no file of barn"):
        download("barn", tmp_path, only=["nothing*"])
    (tmp_path / "f").write_text("")
    with pytest.raises(ConfigError, match="not a folder"):
        download("barn", tmp_path / "f")


def _cli(*args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "pathfuse.cli", *args], capture_output=True,
                          text=True, cwd=cwd, timeout=120)


def test_the_command_fetches_real_barn_files_from_a_mirror_gzips_the_world(tmp_path):
    """``pathfuse data download barn --only ... --mirror URL``: the real manifest's
    checksums pass on the publisher's bytes, the world is stored as world_20.world.gz,
    and a BARN folder missing is an error naming the command."""
    s = _Server()
    try:
        s.files["/m/worlds/world_20.world"] = gzip.decompress(
            (BARN / "worlds" / "world_20.world.gz").read_bytes())
        s.files["/m/path_files/path_20.npy"] = (BARN / "path_files" / "path_20.npy").read_bytes()
        p = _cli("data", "download", "barn", "--to", "b", "--mirror", f"{s.url}/m", "--only",
                 "worlds/world_20.world", "--only", "path_files/path_20.npy", cwd=tmp_path)
        assert p.returncode == 0, p.stderr
        assert "2 file(s) downloaded" in p.stdout
        assert gzip.decompress((tmp_path / "b" / "worlds" / "world_20.world.gz").read_bytes()) \
            == s.files["/m/worlds/world_20.world"]
        # the other bytes for the path file: exit 1, one line, nothing kept
        s.files["/m/path_files/path_20.npy"] = b"\x00" * 608
        (tmp_path / "b" / "path_files" / "path_20.npy").unlink()
        p = _cli("data", "download", "barn", "--to", "b", "--mirror", f"{s.url}/m", "--only",
                 "path_files/path_20.npy", "--quiet", cwd=tmp_path)
        assert p.returncode == 1 and len(p.stderr.strip().splitlines()) == 1
        assert "SHA-256 mismatch for path_files/path_20.npy" in p.stderr
    finally:
        s.close()
    p = _cli("barn", "no-such-barn", cwd=tmp_path)
    assert p.returncode == 2
    assert "no such folder" in p.stderr and "pathfuse data download barn" in p.stderr


@pytest.mark.parametrize("call, hint", [
    (["plan", "--map", "nowhere/den312d.map", "--start", "1,1", "--goal", "2,2"],
     "pathfuse data download movingai"),
    (["scen", "tests/data/movingai/den312d.map", "nowhere/den312d.map.scen"],
     "pathfuse data download movingai"),
])
def test_missing_movingai_files_name_the_command(call, hint):
    p = _cli(*call, cwd=ROOT)
    assert p.returncode == 2 and hint in p.stderr and len(p.stderr.strip().splitlines()) == 1
