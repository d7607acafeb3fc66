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


# a speed figure: a number with a unit of time, a rate or a ratio ("12.5 ms", "3.9 M",
# "1.84×", "550 runs/s", "40 %"); counts such as "7 × 16" or "512 × 512" are not figures
FIGURE = re.compile(r"(?<![\w.])\d[\d,.]*(?:\s?(?:ms|µs|ns|s|min|M|MiB|GiB|%|ticks/s|runs/s|"
                    r"steps/s)|×|x)(?![\w/])")


def outside_blocks(text: str) -> str:
    """The page without its generated blocks, code spans and fenced code."""
    text = re.sub(r"<!-- speed:(\w+) begin.*?<!-- speed:\1 end -->", "", text, flags=re.S)
    text = re.sub(r"```.*?```", "", text, flags=re.S)
    return re.sub(r"`[^`]*`", "", text)


def test_no_speed_figure_is_typed_outside_the_blocks():
    """Every measured figure of the speed page comes from a benchmark's JSON (issue 21)."""
    found = FIGURE.findall(outside_blocks(TEXT))
    assert not found, (f"docs/speed.md has figures outside its generated blocks: {found}; "
                       "make them part of a benchmark's block, or move dated measurements "
                       "to docs/speed-log.md")


def test_the_figure_rule_catches_hand_typed_figures():
    page = ("Prose with 7 × 16 samples on 512 × 512 maps and 32-bit words.\n"
            "<!-- speed:x begin -->\n12.5 ms\n<!-- speed:x end -->\n`--seeds 1000` `1.5 s`\n")
    assert FIGURE.findall(outside_blocks(page)) == []
    for typed in ("took 12.5 ms", "6.2 M expansions", "1.84× faster", "550 runs/s", "3 s",
                  "40 %", "2x", "0.3µs"):
        assert FIGURE.findall(outside_blocks(page + typed)), typed
