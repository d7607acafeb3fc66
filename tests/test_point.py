"""One point checker: plan(), experiment files, scenario files and the command line
all check an (x, y) point with pathfuse.validate.point, in one message form."""

import numpy as np
import pytest

from pathfuse import GridMap
from pathfuse.bench.parse import _point as experiment_point
from pathfuse.cli.args import CliError, parse_point
from pathfuse.problem import Problem
from pathfuse.result import ConfigError, QueryError
from pathfuse.validate import point

GRID = GridMap.from_rows(["...."])


def test_the_checks_agree_on_good_points():
    for v in ([1, 0.5], (1.0, 0.5), np.array([1.0, 0.5]), [np.float32(1.0), "0.5"]):
        assert point(v, "start") == (1.0, 0.5)
        assert Problem.create(GRID, v, (3.5, 0.5)).start == (1.0, 0.5)
        assert experiment_point(v, "maps[0].start") == [1.0, 0.5]
    assert parse_point("1, 0.5", "--start") == (1.0, 0.5)
    assert parse_point("1;0.5", "--start") == (1.0, 0.5)


@pytest.mark.parametrize("value, message", [
    ((1.0, "x"), "KEY[1]: must be a number, got 'x'"),
    ((1.0, float("nan")), "KEY[1]: must be a finite number, got nan"),
    ((float("inf"), 1.0), "KEY[0]: must be a finite number, got inf"),
    ((True, 1.0), "KEY[0]: must be a number, got True"),
    ((1.0, 2.0, 3.0), "KEY: must be two numbers [x, y], got (1.0, 2.0, 3.0)"),
    ("12", "KEY: must be two numbers [x, y], got '12'"),
])
def test_one_message_for_a_bad_point(value, message):
    with pytest.raises(ConfigError) as e:
        point(value, "KEY")
    assert str(e.value) == message
    with pytest.raises(QueryError) as q:  # plan() and Problem.create
        Problem.create(GRID, value, (3.5, 0.5))
    assert str(q.value) == message.replace("KEY", "start")
    with pytest.raises(ConfigError) as x:  # experiment files
        experiment_point(value, "maps[0].start")
    assert str(x.value) == message.replace("KEY", "maps[0].start")


def test_command_line_points():
    with pytest.raises(CliError, match=r"^--goal\[1\]: must be a number, got 'x'$"):
        parse_point("1,x", "--goal")
    with pytest.raises(CliError, match=r"^--goal: must be X,Y \(two numbers in metres\), "
                                       r"got '1'$"):
        parse_point("1", "--goal")
    with pytest.raises(ConfigError, match=r"^maps\[0\]\.start: missing"):
        experiment_point(None, "maps[0].start")
