"""``pathfuse examples`` (the shipped example files) and ``pathfuse data download``."""

from __future__ import annotations

import argparse
import sys
from typing import Any

from pathfuse.cli.args import EXIT_FAIL, _fmt, _positive_float

__all__ = ["add_examples_parser", "add_data_parser", "cmd_examples", "cmd_data"]


def add_examples_parser(sub: Any) -> None:
    """Register ``examples`` on the parser's sub-parsers."""
    e = sub.add_parser(
        "examples",
        help="list the example scenarios and experiment files that ship with pathfuse",
        description="List the example scenarios and experiment files that ship with "
        "pathfuse (a pip install has them too).  Every command that reads a scenario or an "
        "experiment file also takes one of these by name: 'pathfuse simulate head_on'.",
        epilog=_fmt("""
examples:
  pathfuse examples
  pathfuse examples --copy my-examples
  pathfuse simulate head_on --planner astar
  pathfuse bench fusion-sweep-r1-r2-step --db sweep.db --seeds 5
"""),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    e.add_argument("--copy", metavar="DIR",
                   help="copy them into DIR (examples/, experiments/ and the BARN worlds one "
                   "scenario uses, as in a clone) to read or edit; an existing file is never "
                   "overwritten")
    e.set_defaults(func=cmd_examples)


def cmd_examples(args: argparse.Namespace) -> int:
    from pathfuse.shipped import copy_examples, examples

    if args.copy:
        written = copy_examples(args.copy)
        print(f"copied {len(written)} files into {args.copy} (examples/, experiments/, "
              "tests/data/barn/)")
        return 0
    found = examples()
    width = max((len(e.name) for e in found), default=0)
    kind = ""
    for e in found:
        if e.kind != kind:
            kind = e.kind
            print(f"{'' if e is found[0] else chr(10)}{kind} files:")
        print(f"  {e.name:<{width}}  {e.summary}")
    return 0


def add_data_parser(sub: Any) -> None:
    """Register ``data`` (``data download``) on the parser's sub-parsers."""
    d = sub.add_parser(
        "data",
        help="download the BARN and MovingAI benchmark data from their publishers",
        description="Download a benchmark dataset from its publisher's repository at a "
        "pinned commit, every file checked against the SHA-256 pathfuse ships: 'barn' (the "
        "300 BARN worlds and reference paths, Daffan/the-barn-challenge, MIT; the worlds "
        "stored gzipped, 168 MB fetched) or 'movingai' (11 MovingAI maps and their "
        "scenario files, 3.4 MB; research data, not re-licensed).  A file already there "
        "with the right checksum is kept, one with another checksum stops the command; a "
        "failed download keeps nothing of that file, and the same command resumes.  Exit "
        "status 0 when every file is in place, 1 when a download failed, 2 for bad input.",
        epilog=_fmt("""
examples:
  pathfuse data download barn --to barn-data
  pathfuse data download movingai --to movingai-data
  pathfuse data download barn --only 'worlds/world_1?.world' --only 'path_files/path_1?.npy'

Then: pathfuse barn barn-data --worlds 0-49 --out barn-out
"""),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    dsub = d.add_subparsers(dest="data_command", metavar="ACTION", parser_class=type(d))
    dl = dsub.add_parser("download", help="download a dataset and check its checksums",
                         description="Download a dataset and check each file's SHA-256.")
    dl.add_argument("dataset", choices=("barn", "movingai"), help="which dataset")
    dl.add_argument("--to", metavar="DIR", default=None,
                    help="the folder to fill (default: ./barn or ./movingai)")
    dl.add_argument("--only", action="append", metavar="GLOB",
                    help="only the files whose path matches, repeatable (e.g. "
                    "'worlds/world_1?.world')")
    dl.add_argument("--mirror", metavar="URL",
                    help="fetch from a mirror serving the files under their paths "
                    "(URL/worlds/world_0.world) instead of the publishers")
    dl.add_argument("--timeout", type=_positive_float, default=60.0,
                    help="seconds a connection may stall (default 60)")
    dl.add_argument("--quiet", action="store_true", help="no progress display")
    d.set_defaults(func=cmd_data)


def cmd_data(args: argparse.Namespace) -> int:
    if getattr(args, "data_command", None) != "download":
        print("pathfuse data: error: say what to do: pathfuse data download barn|movingai",
              file=sys.stderr)
        return 2
    from pathfuse.datasets import DownloadError, download

    try:
        report = download(args.dataset, args.to, mirror=args.mirror, only=args.only,
                          progress=not args.quiet, timeout=args.timeout)
    except DownloadError as exc:
        print(f"pathfuse data: error: {exc}", file=sys.stderr)
        return EXIT_FAIL
    print(report)
    return 0
