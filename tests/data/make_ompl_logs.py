"""Make the OMPL benchmark logs of ``tests/data/ompl`` with OMPL's own ``Benchmark`` class.

The logs are what an OMPL user collects and merges into a database with
``ompl_benchmark_statistics -a -d STUDY.db LOG...``; ``tests/test_store_ompl.py``
merges them into a pathfuse study.  Made with the official Python bindings
(PyPI ``ompl`` 2.0.1)::

    pip install ompl==2.0.1
    python tests/data/make_ompl_logs.py          # writes tests/data/ompl/*.log

The problem is the 10 m x 10 m room of the test study ``merge`` (entry ``room``):
a point robot from (1, 1) to (9, 1) around a wall at 4 <= x <= 6, y <= 7.  The
experiment is named ``merge/room`` like the pathfuse experiment, so Planner
Arena lists both under one problem.  ``merge/walled`` closes the room
(the wall spans the whole height): RRTConnect times out (OMPL status 4,
Timeout) and RRT* returns an approximate solution (status 5).  Timings differ
from run to run; the tests read the statuses, names and columns, not the
numbers.
"""

from __future__ import annotations

import sys
from pathlib import Path

OUT = Path(__file__).resolve().parent / "ompl"
TIME_LIMIT_S = 0.1
RUNS = 3


def _valid(wall_top: float):
    def valid(state) -> bool:  # noqa: ANN001  (an OMPL state)
        x, y = state[0], state[1]
        return not (4.0 <= x <= 6.0 and y <= wall_top)
    return valid


def write_log(name: str, wall_top: float, path: Path) -> None:
    """Benchmark RRTConnect and RRT* on the room and save OMPL's log to ``path``."""
    import ompl.base as ob
    import ompl.geometric as og
    import ompl.tools as ot
    import ompl.util as ou

    ou.RNG.setSeed(22)
    space = ob.RealVectorStateSpace(2)
    bounds = ob.RealVectorBounds(2)
    bounds.setLow(0.0)
    bounds.setHigh(10.0)
    space.setBounds(bounds)
    ss = og.SimpleSetup(space)
    ss.setStateValidityChecker(_valid(wall_top))
    start, goal = space.allocState(), space.allocState()
    start[0], start[1] = 1.0, 1.0
    goal[0], goal[1] = 9.0, 1.0
    ss.setStartAndGoalStates(start, goal, 0.05)
    si = ss.getSpaceInformation()
    bench = ot.Benchmark(ss, name)
    bench.addPlanner(og.RRTConnect(si))
    bench.addPlanner(og.RRTstar(si))
    # maxTime, maxMem (MB), runCount, timeBetweenUpdates, displayProgress,
    # saveConsoleOutput, simplify
    bench.benchmark(ot.Request(TIME_LIMIT_S, 1024.0, RUNS, 0.05, False, False, True))
    if not bench.saveResultsToFile(str(path)):
        raise SystemExit(f"OMPL could not write {path}")


def main() -> int:
    OUT.mkdir(exist_ok=True)
    write_log("merge/room", 7.0, OUT / "merge-room.log")
    write_log("merge/walled", 10.0, OUT / "merge-walled.log")
    print(f"wrote {OUT}/merge-room.log and merge-walled.log")
    return 0


if __name__ == "__main__":
    sys.exit(main())
