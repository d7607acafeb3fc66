"""Build hook: ship the clone's example scenarios and experiment files inside the package.

Everything else is configured in ``pyproject.toml``.  The examples stay where a clone has
them (``examples/``, ``experiments/``, and ``tests/data/barn`` which one scenario names),
so their relative paths, the tests and the documentation keep working, and a new folder
under ``examples/`` travels without a change here.  At build time they are copied into
``pathfuse/_shipped/`` of the wheel, with the same layout; ``pathfuse.shipped`` finds them
there (and in the clone itself under ``pip install -e``).
"""

from __future__ import annotations

import shutil
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

ROOT = Path(__file__).resolve().parent
# the same list as pathfuse.shipped.SHIPPED_DIRS (tests/test_shipped.py checks the wheel)
SHIPPED_DIRS = ("examples", "experiments", "tests/data/barn")


class BuildWithExamples(build_py):
    """``build_py`` that also copies the shipped example folders into the package."""

    def run(self) -> None:
        super().run()
        if self.editable_mode:  # pip install -e: pathfuse.shipped reads the clone itself
            return
        dest = Path(self.build_lib) / "pathfuse" / "_shipped"
        for rel in SHIPPED_DIRS:
            src = ROOT / rel
            if not src.is_dir():
                raise SystemExit(f"setup.py: {src}: missing (the examples to ship)")
            for p in sorted(src.rglob("*")):
                if p.is_file() and "__pycache__" not in p.parts:
                    out = dest / p.relative_to(ROOT)
                    out.parent.mkdir(parents=True, exist_ok=True)
                    shutil.copyfile(p, out)


setup(cmdclass={"build_py": BuildWithExamples})
