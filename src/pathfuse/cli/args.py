"""Argument types of the command line: points, parameters, numbers, speeds, seeds.

A bad value is a :class:`CliError` (or an argparse error) naming the option:
one line on stderr and exit status 2, never a traceback.
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Sequence
from typing import Any

from pathfuse.result import ConfigError, PathfuseError
from pathfuse.validate import point
from pathfuse.validate import short as _shown

EXIT_FAIL = 1
EXIT_USAGE = 2


class CliError(PathfuseError):
    """A bad command-line value (exit status 2)."""


def _fmt(s: str) -> str:
    return s.strip("\n")


MAIN_EPILOG = _fmt("""
examples:
  pathfuse paper --seeds 100 --out paper-out
  pathfuse plan --map paper --seed 3 --plot plan.png
  pathfuse plan --map tests/data/movingai/den312d.map --start 10.5,70.5 --goal 60.5,8.5 --json
  pathfuse scen tests/data/movingai/maze-32-32-2.map tests/data/movingai/maze-32-32-2-random-1.scen
  pathfuse simulate examples/scenarios/head_on.yaml --planner astar --gif head_on.gif
  pathfuse dynamic --seeds 50 --moving 0 2 4 8 --out dynamic-out
  pathfuse barn tests/data/barn --out barn-out
  pathfuse bench experiments/fusion-sweep-r1-r2-step.yaml --db sweep.db --seeds 20
  pathfuse report sweep.db --out sweep-report
  pathfuse planners
  pathfuse examples
  pathfuse data download barn --to barn-data

The paths are those of a clone of the repository; 'pathfuse examples' lists the scenario
and experiment files every installation has, which commands also take by name.  Run
'pathfuse COMMAND --help' for the options of a command.
""")


# --------------------------------------------------------------------------- parsing helpers
def parse_point(text: str, what: str) -> tuple[float, float]:
    """``"1.5,2"`` -> (1.5, 2.0); :class:`CliError` naming ``what`` otherwise."""
    parts = [p.strip() for p in str(text).replace(";", ",").split(",")]
    if len(parts) != 2:
        raise CliError(f"{what}: must be X,Y (two numbers in metres), got {_shown(text)}")
    return point(parts, what, CliError)


def parse_params(items: Sequence[str] | None) -> dict[str, Any]:
    """``["r1=1.5", "ahead=paper-x"]`` -> {"r1": 1.5, "ahead": "paper-x"} (YAML scalars)."""
    from pathfuse.safeyaml import load_yaml

    out: dict[str, Any] = {}
    for item in items or []:
        key, sep, val = item.partition("=")
        if not sep or not key.strip():
            raise CliError(f"--param: must be KEY=VALUE, got {_shown(item)}")
        try:
            out[key.strip()] = load_yaml(val, f"--param {key.strip()}", CliError)
        except CliError:
            raise
        except ConfigError as exc:  # a limit
            raise CliError(str(exc)) from None
    return out


def _int_at_least(minimum: int, what: str):
    """An argparse type: an integer >= ``minimum`` (``what`` names it in the error)."""

    def parse(text: str) -> int:
        try:
            v = int(text)
        except ValueError:
            v = minimum - 1
        if v < minimum:
            raise argparse.ArgumentTypeError(f"must be {what}, got {_shown(text)}")
        return v

    return parse


_positive_int = _int_at_least(1, "a positive integer")
_nonneg_int = _int_at_least(0, "an integer >= 0")


def _float(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a number, got {_shown(text)}") from None
    if not math.isfinite(v):
        raise argparse.ArgumentTypeError(f"must be a finite number, got {_shown(text)}")
    return v


def _nonneg_float(text: str) -> float:
    v = _float(text)
    if v < 0:
        raise argparse.ArgumentTypeError(f"must be a number >= 0, got {_shown(text)}")
    return v


def _positive_float(text: str) -> float:
    v = _float(text)
    if v <= 0:
        raise argparse.ArgumentTypeError(f"must be a number > 0, got {_shown(text)}")
    return v


def parse_speed(text: str) -> tuple[float, float]:
    """``"0.3,0.8"`` -> (0.3, 0.8); one number ``V`` means ``V,V``; :class:`CliError` otherwise.

    >>> parse_speed("0.3,0.8"), parse_speed("0.5")
    ((0.3, 0.8), (0.5, 0.5))
    """
    parts = [p.strip() for p in str(text).split(",")]
    try:
        if len(parts) not in (1, 2):
            raise ValueError
        lo, hi = float(parts[0]), float(parts[-1])
        if not (math.isfinite(lo) and math.isfinite(hi) and 0 < lo <= hi):
            raise ValueError
    except ValueError:
        raise CliError(f"--speed: must be MIN,MAX in m/s with 0 < MIN <= MAX, "
                       f"got {_shown(text)}") from None
    return lo, hi


def parse_planner_list(text: str | None) -> tuple[str, ...]:
    """``"fusion, astar"`` -> ("fusion", "astar"); None -> () (all planners)."""
    if text is None:
        return ()
    names = tuple(n.strip() for n in str(text).split(",") if n.strip())
    if not names:
        raise CliError(f"--planners: must be comma-separated online planner names, "
                       f"got {_shown(text)}")
    return names


def parse_planner_params(items: Sequence[str] | None) -> dict[str, dict[str, Any]]:
    """``["fusion.repulsion=velocity"]`` -> {"fusion": {"repulsion": "velocity"}}."""
    out: dict[str, dict[str, Any]] = {}
    for key, val in parse_params(items).items():
        name, dot, param = key.partition(".")
        if not dot or not name or not param:
            raise CliError(f"--param: must be PLANNER.KEY=VALUE, got {_shown(key)}")
        out.setdefault(name, {})[param] = val
    return out


class _Parser(argparse.ArgumentParser):
    """argparse that reports errors in one line and exits with status 2."""

    def error(self, message: str):  # type: ignore[override]
        self.exit(EXIT_USAGE, f"{self.prog}: error: {message}\n")


def output_file(text: str, option: str, suffix: str) -> str:
    """An output file name checked before any work: not a folder, in a folder that exists;
    ``suffix`` is added when the name has none (``--plot out`` writes ``out.png``)."""
    from pathlib import Path

    p = Path(text).expanduser()
    if p.is_dir():
        raise CliError(f"{option}: {text} is a folder; give a file name such as "
                       f"{p / ('plan' + suffix)}")
    if not p.suffix:
        p = p.with_name(p.name + suffix)
    if not p.parent.is_dir():
        raise CliError(f"{option}: the folder {p.parent} does not exist")
    return str(p)


def _load_map(args: argparse.Namespace):
    from pathfuse.io import load_map

    return load_map(args.map, resolution=args.resolution, seed=args.seed,
                    unknown=getattr(args, "unknown", "occupied"))


