"""Start-up of the command line: `pathfuse --help` loads no numpy, and the defaults its
help text writes out agree with the library's."""

from __future__ import annotations

import subprocess
import sys

import pytest


def test_help_imports_no_numpy():
    code = ("import sys, contextlib, io\n"
            "from pathfuse.cli import main\n"
            "with contextlib.redirect_stdout(io.StringIO()):\n"
            "    try:\n"
            "        main(['--help'])\n"
            "    except SystemExit:\n"
            "        pass\n"
            "print(sorted(m for m in ('numpy', 'numba', 'scipy') if m in sys.modules))\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, timeout=60)
    assert out.stdout.strip() == "[]", out.stdout


def test_barn_help_states_the_jackal_defaults():
    from pathfuse.cli import build_parser
    from pathfuse.studies.barn import JACKAL_MAX_SPEED_M_S, JACKAL_RADIUS_M

    parser = build_parser()
    sub = next(a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction")
    text = sub.choices["barn"].format_help()
    flat = " ".join(text.split())
    assert f"(default {JACKAL_RADIUS_M:g}: the Jackal's" in flat
    assert f"(default {JACKAL_MAX_SPEED_M_S:g}, the Jackal's)" in flat


def test_a_static_plan_compiles_only_what_it_runs():
    """`pathfuse plan` on a static map: the fusion loop in its signature without disc
    arrays and without a safety margin only (its moving-disc and margin code is never
    compiled), A* with one signature of the euclidean heuristic's kernel (the octile one's
    not compiled), no other planner's loop, and no scipy.ndimage (the
    paper map's regions are labelled by a flood fill)."""
    code = ("import sys, contextlib, io\n"
            "from pathfuse.cli import main\n"
            "with contextlib.redirect_stdout(io.StringIO()):\n"
            "    main(['plan', '--map', 'paper', '--planner', 'fusion'])\n"
            "from pathfuse.field import kernels as k\n"
            "from pathfuse.search.kernel import _astar_radix, _astar_ring\n"
            "print([[str(t) for t in s[-4:]] for s in k.fusion_loop.signatures])\n"
            "print(len(_astar_ring.signatures), len(_astar_radix.signatures),\n"
            "      len(k.field_loop.signatures))\n"
            "print('scipy.ndimage' in sys.modules)\n")
    import os

    # compiled: were the cache cold, the plan would run its kernels interpreted
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, timeout=600,
                         env={**os.environ, "PATHFUSE_KERNELS": "compiled"})
    assert out.stdout.split("\n")[:3] == ["[['none', 'none', 'none', 'omitted(default=None)']]",
                                        "1 0 0", "False"], \
        out.stdout


@pytest.mark.parametrize("planner", ["astar", "fusion"])
def test_a_plan_imports_only_its_planner(planner):
    """`pathfuse plan` imports the module of the planner it runs, not the others (dwa,
    mppi, the shield, the moving-disc worlds): their imports and numba dispatchers are part
    of every start-up otherwise; the registry lists every built-in planner all the same."""
    others = ("pathfuse.planners.controllers.dwa", "pathfuse.planners.controllers.mppi",
              "pathfuse.planners.controllers.apf", "pathfuse.planners.controllers.anyangle",
              "pathfuse.shield", "pathfuse.robot", "pathfuse.world", "matplotlib")
    code = ("import sys, contextlib, io\n"
            "from pathfuse.cli import main\n"
            "with contextlib.redirect_stdout(io.StringIO()):\n"
            f"    main(['plan', '--map', 'paper', '--planner', {planner!r}])\n"
            f"print(sorted(m for m in {others!r} if m in sys.modules))\n"
            "from pathfuse.planners.registry import planner_names\n"
            "print(planner_names())\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, timeout=600)
    from pathfuse.planners.registry import _BUILTIN

    assert out.stdout.split("\n")[:2] == ["[]", str(list(_BUILTIN))], out.stdout


def test_is_cached_tells_a_field_loop_s_static_and_online_signatures(tmp_path):
    """The cold-cache notice: a field loop whose index holds only a static plan's signature
    (``None`` for the discs) is cached for a plan, not for an episode, and the reverse."""
    from types import SimpleNamespace

    from numba import types

    from pathfuse.planners.kernel_cache import is_cached

    index = tmp_path / "loop.nbi"
    arr = types.float64[:, ::1]
    static = ((arr, types.none, types.none, types.none), "magic")
    online = ((arr, arr, arr, types.float64), "magic")

    def dispatcher(keys):
        cf = SimpleNamespace(_index_path=str(index), _load_index=lambda: dict.fromkeys(keys))
        return SimpleNamespace(_cache=SimpleNamespace(_cache_file=cf))

    assert not is_cached(dispatcher([static]))  # no index on disk
    index.write_bytes(b"")
    assert [is_cached(dispatcher([static]), k) for k in (None, False, True)] == [True, True, False]
    assert [is_cached(dispatcher([online]), k) for k in (None, False, True)] == [True, False, True]
    assert is_cached(dispatcher([static, online]), True) and is_cached(dispatcher([]), None)


def test_each_heuristic_compiles_its_own_a_star_kernel(tmp_path):
    """The euclidean and octile heuristics run two kernels made by one factory: warming one
    compiles it alone, and the cold-cache notice tells them apart although they share
    numba's index file."""
    import os

    code = ("from pathfuse.search.astar import warmup\n"
            "from pathfuse.search.kernel import _astar_radix, _astar_ring\n"
            "from pathfuse.planners.kernel_cache import is_cached\n"
            "print(is_cached(_astar_ring), is_cached(_astar_radix))\n"
            "warmup(('euclidean',))\n"
            "print(len(_astar_ring.signatures), len(_astar_radix.signatures))\n"
            "print(is_cached(_astar_ring), is_cached(_astar_radix))\n"
            "from pathfuse.planners.kernel_cache import cold_kernels\n"
            "from pathfuse.planners.registry import get_planner, make_params\n"
            "s = get_planner('astar')\n"
            "print(len(cold_kernels(s, make_params(s, {'heuristic': 'euclidean'}))),\n"
            "      len(cold_kernels(s, make_params(s, {'heuristic': 'octile'}))))\n")
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path)}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, timeout=600, env=env)
    # the notice for an octile plan: its kernel is still cold though the euclidean one is not
    assert out.stdout.split("\n")[:4] == ["False False", "1 0", "True False", "0 1"], \
        out.stdout
