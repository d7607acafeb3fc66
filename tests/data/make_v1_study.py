"""Make ``tests/data/study-v1.sql``: a study written by pathfuse's schema-1 store.

Schema 1 is the store of pathfuse before issue 22 (pathfuse's columns inside
OMPL's tables).  ``tests/test_store_migrate.py`` loads this SQL text dump into a
database and checks that the current pathfuse migrates it (in place for
``pathfuse bench``, in memory for readers) without misreading a value.

How it was made (the schema-1 store module from git history, the current runner)::

    git show 71f9583:src/pathfuse/bench/store.py > /tmp/store_v1.py
    python tests/data/make_v1_study.py /tmp/store_v1.py

The experiment has a static room (two A* configurations that share the name
``astar``, APF stuck in a local minimum, paths stored) and the shipped
``crossing`` scenario (dynamic runs of the fusion planner).
"""

from __future__ import annotations

import importlib.util
import sqlite3
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]

EXPERIMENT = f"""
name: legacy
seeds: 2
store_paths: true
maps:
  - name: room
    map:
      rows: ["..........", "..........", "..........", "....##....", "....##....",
             "....##....", "....##....", "....##....", "....##....", "....##...."]
    start: [1.0, 1.0]
    goal: [9.0, 1.0]
  - name: crossing
    dynamic: {REPO / "examples" / "scenarios" / "crossing.yaml"}
    seeds: [0]
planners:
  - {{name: astar, params: {{heuristic: octile}}}}
  - {{name: astar, params: {{heuristic: euclidean}}}}
  - apf
  - fusion
"""


def main(store_v1: str) -> int:
    spec = importlib.util.spec_from_file_location("store_v1", store_v1)
    assert spec is not None and spec.loader is not None
    v1 = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(v1)
    assert v1.SCHEMA_VERSION == 1, "pass the schema-1 store module"
    import pathfuse.bench.runner as runner

    runner.ResultStore = v1.ResultStore  # type: ignore[misc]
    with tempfile.TemporaryDirectory() as d:
        exp = Path(d) / "legacy.yaml"
        exp.write_text(EXPERIMENT)
        db = Path(d) / "legacy.db"
        s = runner.run_bench(exp, db, workers=1, progress=False)
        print(f"{s.ran} runs, {s.errors} errors")
        conn = sqlite3.connect(db)
        text = "\n".join(conn.iterdump()) + "\n"
        conn.close()
    host = __import__("socket").gethostname()
    out = HERE / "study-v1.sql"
    out.write_text(text.replace(str(REPO), "REPO").replace(host, "host"), encoding="utf-8")
    print(f"wrote {out} ({len(text)} characters)")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
