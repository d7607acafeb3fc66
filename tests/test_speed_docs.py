"""The README's generated speed blocks are exactly what their benchmarks last measured.

``benchmarks/run_all.py`` runs the benchmarks, keeps their JSON in
``benchmarks/results/`` and writes each block of the README between its markers;
a figure typed into a block by hand, or a block left behind after a re-run, fails
here.  (Speed is never asserted: this only checks the text against the JSON.)
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
import run_all  # noqa: E402 - the renderer of the blocks

TEXT = (ROOT / "README.md").read_text()


def test_the_speed_section_has_every_block_once():
    for name in run_all.BLOCKS:
        assert TEXT.count(f"<!-- speed:{name} begin") == 1, name
        assert TEXT.count(f"<!-- speed:{name} end -->") == 1, name
    speed = TEXT.split("\n## Speed\n", 1)[1].split("\n## ", 1)[0]
    assert set(run_all.blocks_in(speed)) == set(run_all.BLOCKS)


@pytest.mark.parametrize("name", run_all.BLOCKS)
def test_block_is_its_latest_measurement(name):
    body = run_all.blocks_in(TEXT)[name]
    assert body == run_all.render(name), (
        f"README block speed:{name} differs from benchmarks/results/{name}.json: run "
        f"`python benchmarks/run_all.py --no-run --only {name}` (or re-measure without "
        f"--no-run)")
    assert re.search(r"\d", body)  # a block says something measured


def test_rendering_is_deterministic_and_total():
    """Every block renders from its JSON alone, the same twice."""
    for name in run_all.BLOCKS:
        assert run_all.render(name) == run_all.render(name)
