"""The shipped scenario examples end as their comments (and the docs) say."""

from __future__ import annotations

from pathlib import Path

import pytest

import pathfuse

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "examples" / "scenarios"


@pytest.mark.parametrize("planner, params, status, t_s, hit", [
    (None, {}, "COLLISION", 13.7, 2),                       # the file's own: astar-replan, 1 Hz
    ("astar-replan", {"replan_period_s": 0.2}, "COLLISION", 13.4, 2),
    ("astar", {}, "SUCCESS", 28.8, None),
    ("ref6", {}, "SUCCESS", 28.9, None),
    ("ref7", {}, "SUCCESS", 28.7, None),
    ("apf", {}, "SUCCESS", 52.1, None),
    ("fusion", {}, "LOCAL_MINIMUM", 40.5, None),
])
def test_warehouse_patrol_shows_the_failure_its_comment_describes(planner, params, status, t_s,
                                                                   hit):
    path = EXAMPLES / "warehouse_patrol.yaml"
    assert "shows a FAILURE, on purpose" in path.read_text()
    choice = None if planner is None else {"name": planner, "params": params}
    ep = pathfuse.simulate(str(path), planner=choice)
    assert ep.status.name == status, ep.message
    assert ep.times[-1] == pytest.approx(t_s, abs=1e-9)
    if hit is not None:
        assert str(ep.collision_with) == str(hit)
        assert ep.collision_at_fault is False  # the shield stopped the robot in time


def test_head_on_astar_collides_and_fusion_passes():
    path = EXAMPLES / "head_on.yaml"
    ep = pathfuse.simulate(str(path), planner="astar")
    assert ep.status.name == "COLLISION" and ep.collision_at_fault is False
    # without the shield the blind follower walks into the disc itself
    ep = pathfuse.simulate(str(path), planner="astar", robot={"radius": 0.2, "shield": False})
    assert ep.status.name == "COLLISION" and ep.collision_at_fault is True
    assert pathfuse.simulate(str(path), planner="fusion").status.name == "SUCCESS"


def _as_commented(value: object, shown: str) -> str:
    """``value`` as the comment ``shown`` writes it (floats to its decimals)."""
    if isinstance(value, float) and not isinstance(value, bool):
        decimals = len(shown.split(".", 1)[1]) if "." in shown else 0
        return f"{value:.{decimals}f}"
    return str(value)


def test_the_docs_moving_obstacles_example_prints_what_its_comments_say(monkeypatch):
    """Each ``ep.<attr>, ...   # value, ...`` line of the first example of the moving
    obstacles' guide (docs/guide/moving-obstacles.md) is run; the values before a comment's
    first ':' are what it prints."""
    section = (ROOT / "docs" / "guide" / "moving-obstacles.md").read_text(encoding="utf-8")
    assert section.startswith("# Moving obstacles")
    code = section[section.index("```python") + len("```python"):]
    code = code[:code.index("```")]
    monkeypatch.chdir(ROOT)  # the page's paths are those of a clone
    env: dict[str, object] = {}
    checked = 0
    for line in code.splitlines():
        stmt, _, comment = line.partition("#")
        if not stmt.strip():
            continue
        if not stmt.startswith("ep.") or not comment.strip():
            exec(stmt, env)  # noqa: S102 - the page's own example
            continue
        got = eval(stmt, env)  # noqa: S307
        got = got if isinstance(got, tuple) else (got,)
        want = [w.strip() for w in comment.split(":", 1)[0].split(",")]
        assert len(want) == len(got), line
        assert [_as_commented(g, w) for g, w in zip(got, want, strict=True)] == want, line
        checked += 1
    assert checked >= 2

