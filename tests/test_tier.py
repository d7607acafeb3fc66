"""pathfuse.tier: a plan whose kernels run interpreted gives the compiled kernels' result to
the bit, compiles nothing, and the rule (size, budget, cache, PATHFUSE_KERNELS) holds.

The interpreted runs are made in a fresh process on an empty numba cache (in this process
most kernels are compiled already, and a compiled kernel runs compiled)."""

from __future__ import annotations

import os
import pickle
import subprocess
import sys

import numpy as np
import pytest

from pathfuse import tier
from pathfuse.result import ConfigError

# the cases, built the same way here and in the fresh process
CASES = r"""
from pathfuse.generate import PAPER_GOAL, PAPER_START, paper_map, random_map
from pathfuse.grid import GridMap
from pathfuse.planners.registry import planner_names

def cases():
    rnd = random_map((24, 24), 1.0, density=0.25, seed=7,
                     keep_free=[(0.5, 0.5), (23.5, 23.5)],
                     connect=[((0.5, 0.5), (23.5, 23.5))])
    walled = GridMap.from_rows(["........", "........", "....###.", "....#.#.",
                                "....###.", "........"])
    small = GridMap.from_rows(["......", "..##..", "......", "......"])
    out = []
    for name in planner_names():
        if name in ("dwa", "mppi"):  # a tick costs 0.1-1 s interpreted: one small map each
            p = {"batch_size": 16, "time_steps": 8} if name == "mppi" else {}
            out.append((name, small, (0.5, 0.5), (5.5, 3.5), p, 0.0, 0.0))
            continue
        out.append((name, paper_map(0), PAPER_START, PAPER_GOAL, {}, 0.0, 0.0))
        out.append((name, paper_map(1), PAPER_START, PAPER_GOAL, {}, 0.2, 0.0))
        out.append((name, rnd, (0.5, 0.5), (23.5, 23.5), {}, 0.0, 0.1))
        out.append((name, walled, (0.5, 0.5), (5.5, 2.5), {}, 0.0, 0.0))  # walled in
        out.append((name, walled, (0.5, 0.5), (5.5, 3.5), {}, 0.0, 0.0))  # in a wall
    # random maps, sizes and densities (some queries without a path), both heuristics and
    # both corner rules of A*, and the paper's fusion and APF on them
    import numpy as np
    rng = np.random.default_rng(21)
    variants = [("astar", {}), ("astar", {"heuristic": "octile"}),
                ("astar", {"corner_cutting": True}), ("fusion", {}), ("apf", {}),
                ("jps", {}), ("thetastar", {})]
    for seed in range(10):
        w, h = (int(v) for v in rng.integers(8, 41, 2))
        g = random_map((w, h), 1.0, density=float(rng.uniform(0.05, 0.4)), seed=seed,
                       keep_free=[(0.5, 0.5), (w - 0.5, h - 0.5)])
        for n2, p2 in (variants[seed % len(variants)], variants[(seed + 3) % len(variants)]):
            out.append((n2, g, (0.5, 0.5), (w - 0.5, h - 0.5), p2, 0.0, 0.0))
    return out

def outcome(r):
    return (r.status.name, r.path.tobytes(), r.path.shape, r.length, r.expansions,
            r.iterations, r.message)

def run(case):
    from pathfuse.api import plan_query
    name, grid, start, goal, params, radius, clearance = case
    return plan_query(grid, start, goal, name, params, robot_radius_m=radius,
                      clearance_m=clearance)[0]
"""

FRESH = CASES + r"""
import pickle, sys
from numba.core import event

compiled = []

class Listener(event.Listener):
    def on_start(self, ev):
        compiled.append(ev.data["dispatcher"].py_func.__qualname__)

    def on_end(self, ev):
        pass

event.register("numba:compile", Listener())
out = []
for case in cases():
    r = run(case)
    out.append((case[0], outcome(r), r.info.get("kernels")))
with open(sys.argv[1], "wb") as f:
    pickle.dump((out, compiled), f)
"""


def _fresh(tmp_path, script, mode="interpreted"):
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache"), "PATHFUSE_KERNELS": mode}
    # interpreted, numpy's warnings are errors: its scalars warn (RuntimeWarning) where
    # compiled code is silent (an overflow, a division by zero), and a user would see them
    strict = ["-W", "error::RuntimeWarning"] if mode == "interpreted" else []
    proc = subprocess.run([sys.executable, *strict, "-c", script, str(tmp_path / "out.pkl")],
                          capture_output=True, text=True, env=env, timeout=900)
    assert proc.returncode == 0, proc.stderr[-3000:]
    with open(tmp_path / "out.pkl", "rb") as f:
        return pickle.load(f)


@pytest.mark.slow
def test_every_planner_interpreted_gives_the_compiled_result_and_compiles_nothing(
        tmp_path, monkeypatch):
    ns: dict[str, object] = {}
    exec(CASES, ns)
    interpreted, compiled = _fresh(tmp_path, FRESH)
    assert compiled == [], f"compiled while interpreting: {compiled}"
    monkeypatch.setenv("PATHFUSE_KERNELS", "compiled")
    cases = ns["cases"]()  # type: ignore[operator]
    assert len(interpreted) == len(cases)
    statuses = set()
    for case, (name, got, how) in zip(cases, interpreted, strict=True):
        r = ns["run"](case)  # type: ignore[operator]
        assert "kernels" not in r.info
        assert how == "interpreted", name
        assert got == ns["outcome"](r), (name, case[4:], got[0], r.status.name)  # type: ignore[operator]
        statuses.add(got[0])
    # found paths and failures (of the search, of the query's checks), all compared
    assert {"SUCCESS", "NO_PATH", "GOAL_OCCUPIED"} <= statuses, statuses


AUTO = CASES + r"""
import pickle, sys
import pathfuse
from pathfuse import tier

out = []
g = paper_map(0)
r = pathfuse.plan(g, PAPER_START, PAPER_GOAL, planner="fusion")
out.append(("first", r.info.get("kernels"), outcome(r)))
tier.BUDGET_S = tier.spent_s() + 1e-6  # the budget runs out during the next plan
r = pathfuse.plan(g, PAPER_START, PAPER_GOAL, planner="fusion")
out.append(("over budget", r.info.get("kernels"), outcome(r)))
r = pathfuse.plan(g, PAPER_START, PAPER_GOAL, planner="astar")
out.append(("after", r.info.get("kernels"), outcome(r)))
with open(sys.argv[1], "wb") as f:
    pickle.dump(out, f)
"""


@pytest.mark.slow
def test_auto_interprets_until_the_budget_then_compiles(tmp_path, monkeypatch):
    """On an empty cache the first small plan runs interpreted; the plan during which the
    budget runs out is run again compiled (same result) and the process compiles from then
    on."""
    out = _fresh(tmp_path, AUTO, mode="auto")
    assert [(k, how) for k, how, _ in out] == [
        ("first", "interpreted"), ("over budget", None), ("after", None)]
    assert out[0][2] == out[1][2]
    import pathfuse
    from pathfuse.generate import PAPER_GOAL, PAPER_START, paper_map

    monkeypatch.setenv("PATHFUSE_KERNELS", "compiled")
    r = pathfuse.plan(paper_map(0), PAPER_START, PAPER_GOAL, planner="fusion")
    assert out[0][2][:2] == (r.status.name, r.path.tobytes())


@pytest.fixture
def fresh_rule(monkeypatch):
    """The rule's state as in a new process."""
    monkeypatch.setattr(tier, "_state", {"on": True, "spent": 0.0})
    monkeypatch.delenv("PATHFUSE_KERNELS", raising=False)


def test_admit_follows_size_cache_budget_and_mode(fresh_rule, monkeypatch):
    asked = []

    def cold() -> bool:
        asked.append(1)
        return True

    assert not tier.admit(4, cold, timed=True)  # a time limit needs the compiled speed
    assert tier.admit(tier.MAX_CELLS, cold)  # and did not end interpretation
    assert not tier.admit(tier.MAX_CELLS, lambda: False)  # compiled code is there: stop
    assert not tier.admit(1, cold)  # and the process compiles from then on
    monkeypatch.setattr(tier, "_state", {"on": True, "spent": 0.0})
    assert not tier.admit(tier.MAX_CELLS + 1, cold)  # a larger map compiles
    monkeypatch.setattr(tier, "_state", {"on": True, "spent": tier.BUDGET_S})
    assert not tier.admit(4, cold)  # the budget is spent
    monkeypatch.setattr(tier, "_state", {"on": True, "spent": 0.0})
    monkeypatch.setenv("PATHFUSE_KERNELS", "compiled")
    assert not tier.admit(4, cold)
    monkeypatch.setenv("PATHFUSE_KERNELS", " Interpreted ")
    n = len(asked)
    assert tier.admit(10**9, cold) and len(asked) == n  # always, without asking the cache
    assert tier.admit(4, cold, timed=True)


def test_a_bad_pathfuse_kernels_names_the_variable(fresh_rule, monkeypatch):
    monkeypatch.setenv("PATHFUSE_KERNELS", "jit")
    with pytest.raises(ConfigError, match="PATHFUSE_KERNELS: must be one of auto, compiled, "
                                          "interpreted, got 'jit'"):
        tier.admit(4, lambda: True)


def test_a_cli_plan_with_a_bad_pathfuse_kernels_is_one_line(tmp_path):
    env = {**os.environ, "PATHFUSE_KERNELS": "fast"}
    p = subprocess.run([sys.executable, "-m", "pathfuse.cli", "plan", "--map", "paper"],
                       capture_output=True, text=True, env=env, timeout=600)
    assert p.returncode != 0 and "Traceback" not in p.stderr
    assert p.stderr.strip().splitlines() == [
        "pathfuse plan: error: PATHFUSE_KERNELS: must be one of auto, compiled, interpreted, "
        "got 'fast'"], p.stderr


def test_the_intrinsics_python_functions_match_them():
    from numba import njit

    from pathfuse.search.kernel import _bit_length, _bits_of, _trailing_zeros

    @njit
    def compiled(x, f):
        return _bit_length(x), _trailing_zeros(x), _bits_of(f)

    rng = np.random.default_rng(0)
    xs = [np.uint64(1), np.uint64(2**63), np.uint64(2**64 - 1),
          *rng.integers(1, 2**63, 200, dtype=np.uint64)]
    fs = [0.0, 2.5, 5e-324, *rng.random(200) * 1e6]
    twin = tier.interpreted(compiled)
    for x, f in zip(xs, fs, strict=True):
        got = twin(x, f)
        assert got == compiled(x, f), (x, f)  # numba boxes its uint64 as a Python int
        assert type(got[2]) is np.uint64  # the twin keeps numba's type inside the kernels


def test_a_twin_compiles_nothing_and_an_unknown_intrinsic_is_named():
    from numba import njit, types
    from numba.extending import intrinsic

    @intrinsic
    def _mystery(typingctx, x):
        def codegen(context, builder, signature, args):
            return args[0]
        return types.int64(types.int64), codegen

    @njit
    def uses(x):
        return _mystery(x) + 1

    with pytest.raises(TypeError, match="the intrinsic '_mystery' has no Python function"):
        tier.interpreted(uses)
    assert uses not in tier._TWINS
    assert uses.signatures == []


def test_the_docs_state_the_rule_s_constants():
    """The map size and the budget the pages give are the module's."""
    from pathlib import Path

    docs = Path(__file__).resolve().parents[1] / "docs"
    side = int(np.sqrt(tier.MAX_CELLS))
    assert side * side == tier.MAX_CELLS
    speed = (docs / "speed.md").read_text()
    arch = (docs / "architecture.md").read_text()
    for text in (speed, arch, (docs / "getting-started.md").read_text()):
        assert f"{side} × {side} cells" in " ".join(text.split())
    assert f"{tier.BUDGET_S:g} s of CPU" in " ".join(arch.split())
    assert f"`tier.BUDGET_S = {tier.BUDGET_S}`" in " ".join(speed.split())


TIMED = CASES + r"""
import pickle, sys
import pathfuse
from pathfuse.generate import PAPER_GOAL, PAPER_START, paper_map

g = paper_map(0)
a = pathfuse.plan(g, PAPER_START, PAPER_GOAL, budget=pathfuse.Budget(time_limit_s=60.0))
b = pathfuse.plan(g, PAPER_START, PAPER_GOAL)
with open(sys.argv[1], "wb") as f:
    pickle.dump([(r.info.get("kernels"), outcome(r)) for r in (a, b)], f)
"""


@pytest.mark.slow
def test_a_plan_with_a_time_limit_compiles(tmp_path):
    """Interpreted, a time limit could end a plan that compiled code finishes: such a plan
    compiles (and the process compiles from then on)."""
    out = _fresh(tmp_path, TIMED, mode="auto")
    assert [how for how, _ in out] == [None, None]
    assert out[0][1] == out[1][1] and out[0][1][0] == "SUCCESS"


NOTICE = r"""
import sys
from pathfuse import tier
from pathfuse.cli import main

tier.BUDGET_S = 1e-9  # the budget runs out during the plan (after its first kernel call)
sys.exit(main(["plan", "--map", "paper", "--planner", "fusion", "--json"]))
"""


@pytest.mark.slow
def test_a_cli_plan_that_compiles_after_all_says_so_first(tmp_path):
    """`pathfuse plan` prints no compile notice for a plan it runs interpreted; when the
    budget runs out halfway and the plan compiles after all, the notice comes then."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache")}
    env.pop("PATHFUSE_KERNELS", None)
    p = subprocess.run([sys.executable, "-c", NOTICE], capture_output=True, text=True,
                       env=env, timeout=600)
    assert p.returncode == 0, p.stderr[-2000:]
    assert p.stderr.splitlines()[0] == ("pathfuse: compiling the kernels of fusion (first "
                                        "run only; cached afterwards)"), p.stderr
    assert p.stderr.count("pathfuse:") == 1, p.stderr
    import json

    assert json.loads(p.stdout)["kernels"] == "compiled"
    p = subprocess.run([sys.executable, "-m", "pathfuse.cli", "plan", "--map", "paper",
                        "--planner", "fusion"], capture_output=True, text=True,
                       env={**env, "NUMBA_CACHE_DIR": str(tmp_path / "cold")}, timeout=600)
    assert p.returncode == 0 and p.stderr == "", p.stderr
    assert "(kernels interpreted: not compiled yet; see PATHFUSE_KERNELS)" in p.stdout
