"""The ``pathfuse`` command line.  Thin: parses arguments and calls the library.

Every error a user can cause ends in one line on stderr and a non-zero exit
status (2 for bad input, 1 for a failed check such as a scen mismatch or a
plan that did not succeed), never a traceback.
"""

from __future__ import annotations

from pathfuse.cli.args import EXIT_FAIL, EXIT_USAGE, CliError
from pathfuse.cli.parser import build_parser, main

__all__ = ["main", "build_parser", "CliError", "EXIT_FAIL", "EXIT_USAGE"]
