"""The speed page's generated blocks are exactly what their benchmarks last measured.

``benchmarks/run_all.py`` runs the benchmarks, keeps their JSON in
``benchmarks/results/`` and writes each block of ``docs/speed.md`` between its markers;
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

TEXT = (ROOT / "docs" / "speed.md").read_text()


def test_the_speed_section_has_every_block_once():
    for name in run_all.BLOCKS:
        assert TEXT.count(f"<!-- speed:{name} begin") == 1, name
        assert TEXT.count(f"<!-- speed:{name} end -->") == 1, name
    assert run_all.SPEED_PAGE == ROOT / "docs" / "speed.md"  # where run_all.py writes them
    assert TEXT.startswith("# Speed\n")
    assert set(run_all.blocks_in(TEXT)) == set(run_all.BLOCKS)


@pytest.mark.parametrize("name", run_all.BLOCKS)
def test_block_is_its_latest_measurement(name):
    body = run_all.blocks_in(TEXT)[name]
    assert body == run_all.render(name), (
        f"docs/speed.md block speed:{name} differs from benchmarks/results/{name}.json: run "
        f"`python benchmarks/run_all.py --no-run --only {name}` (or re-measure without "
        f"--no-run)")
    assert re.search(r"\d", body)  # a block says something measured


def test_rendering_is_deterministic_and_total():
    """Every block renders from its JSON alone, the same twice."""
    for name in run_all.BLOCKS:
        assert run_all.render(name) == run_all.render(name)
