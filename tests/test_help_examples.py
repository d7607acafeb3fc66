"""Every example printed by ``pathfuse --help`` and ``pathfuse COMMAND --help`` works.

Every file an example reads must exist in the repository (a new user copies the
examples from a clone), and the quick examples (``plan``, ``scen``, ``simulate``,
``planners``, ``examples``) are run, from the repository's root, with their output files
redirected into a temporary folder.  The long studies (``paper``, ``dynamic``, ``bench``,
``report``, ``barn``, ``serve``) and ``data`` (it needs the network) are only checked for
their input files.
"""

from __future__ import annotations

import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
COMMANDS = ("plan", "scen", "paper", "simulate", "dynamic", "bench", "report", "planners",
            "barn", "serve", "examples", "data")
OUTPUT_OPTIONS = ("--plot", "--gif", "--mp4", "--db", "--out", "--copy", "--to")
RUN = ("plan", "scen", "simulate", "planners", "examples")


def _help(*args: str) -> str:
    p = subprocess.run([sys.executable, "-m", "pathfuse.cli", *args, "--help"],
                       capture_output=True, text=True, timeout=60)
    assert p.returncode == 0, p.stderr
    return p.stdout


def _examples(text: str) -> list[list[str]]:
    """The example commands of a help text (``\\``-continued lines joined)."""
    out: list[list[str]] = []
    lines = text.splitlines()
    i = 0
    in_examples = False
    while i < len(lines):
        line = lines[i]
        if line.rstrip() in ("examples:", "example:"):
            in_examples = True
        elif in_examples and line.strip().startswith("pathfuse "):
            cmd = line.strip()
            while cmd.endswith("\\"):
                i += 1
                cmd = cmd[:-1] + " " + lines[i].strip()
            out.append(shlex.split(cmd, comments=True)[1:])
        elif in_examples and line and not line.startswith(" "):
            in_examples = False
        i += 1
    return out


HELP = {"pathfuse": _help(), **{cmd: _help(cmd) for cmd in COMMANDS}}


def _all_examples() -> list[tuple[str, list[str]]]:
    return [(where, ex) for where, text in HELP.items() for ex in _examples(text)]


EXAMPLES = _all_examples()


def _inputs(argv: list[str]) -> list[str]:
    """The files an example reads: path-like arguments that are not output options' values
    (nor ``report``'s database, which ``bench`` writes)."""
    files = []
    skip_next = False
    for k, tok in enumerate(argv):
        if skip_next:
            skip_next = False
            continue
        if tok in OUTPUT_OPTIONS or tok in ("--scheduler", "--only", "--mirror"):
            skip_next = True
            continue
        if tok.startswith("-"):
            continue
        if argv[0] == "report" and k == 1:
            continue
        if "/" in tok or Path(tok).suffix in (".map", ".scen", ".yaml", ".png", ".pgm", ".npy"):
            files.append(tok)
    return files


def test_every_help_has_examples():
    assert {ex[0] for _, ex in EXAMPLES} >= set(COMMANDS)
    assert len(EXAMPLES) >= 25


@pytest.mark.parametrize("where", sorted(HELP))
def test_example_lines_have_no_runs_of_spaces(where):
    """An example is printed as typed: its words one space apart (a ``\\``-newline that the
    Python string swallowed once glued a continuation line's indent into the command)."""
    lines = HELP[where].splitlines()
    start = next(i for i, ln in enumerate(lines) if ln.rstrip() == "examples:")
    seen = 0
    for ln in lines[start + 1:]:
        if ln and not ln.startswith(" "):
            break  # the text after the examples
        command = ln.split(" #", 1)[0].strip()  # aligned comments may keep their padding
        if command:
            seen += 1
            assert "  " not in command, f"pathfuse {where} --help: {ln!r}"
    assert seen


@pytest.mark.parametrize("where, argv", EXAMPLES,
                         ids=[f"{w}:{' '.join(a)[:60]}" for w, a in EXAMPLES])
def test_example_inputs_exist(where, argv):
    for f in _inputs(argv):
        path = (ROOT / f).resolve()
        assert path.is_relative_to(ROOT) and path.exists(), \
            f"{where} --help names {f}, which is not in the repository"


RUNNABLE = [(w, a) for w, a in EXAMPLES if a[0] in RUN]


@pytest.mark.parametrize("where, argv", RUNNABLE,
                         ids=[f"{w}:{' '.join(a)[:60]}" for w, a in RUNNABLE])
def test_quick_examples_run(where, argv, tmp_path):
    if "--mp4" in argv and shutil.which("ffmpeg") is None:
        pytest.skip("MP4 needs ffmpeg")
    argv = list(argv)
    for k, tok in enumerate(argv[:-1]):
        if tok in OUTPUT_OPTIONS:
            argv[k + 1] = str(tmp_path / Path(argv[k + 1]).name)
    p = subprocess.run([sys.executable, "-m", "pathfuse.cli", *argv], capture_output=True,
                       text=True, timeout=300, cwd=ROOT)
    assert "Traceback" not in p.stderr, p.stderr
    # simulate exits 1 when the robot does not reach the goal (the point of head_on + astar)
    assert p.returncode in ((0, 1) if argv[0] == "simulate" else (0,)), (argv, p.stderr)
    for k, tok in enumerate(argv[:-1]):
        if tok in OUTPUT_OPTIONS:
            assert Path(argv[k + 1]).exists(), argv
