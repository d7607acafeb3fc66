"""Statuses, plan results, budgets and the exception classes shared by every planner.

Every planner in pathfuse returns a :class:`PlanResult`; none raises on an
ordinary planning failure (no path, local minimum, budget exhausted).  Bad
*input* (a malformed file, a NaN coordinate, an unknown parameter) raises a
subclass of :class:`PathfuseError` whose message names the file, key or value.
"""

from __future__ import annotations

import enum
import math
import numbers
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # numpy is imported on first use: this module is on the CLI's start-up path
    import numpy as np

__all__ = [
    "Status",
    "PlanResult",
    "Budget",
    "PathfuseError",
    "MapError",
    "MapFormatError",
    "QueryError",
    "ConfigError",
    "PlanningFailed",
    "CODE_SUCCESS",
    "CODE_NO_PATH",
    "CODE_LOCAL_MINIMUM",
    "CODE_MAX_ITERATIONS",
    "CODE_TIMEOUT",
    "CODE_COLLISION",
    "CODE_RUNNING",
    "CODE_GROW",
    "refined",
    "code_outcome",
]


class PathfuseError(Exception):
    """Base class of every error pathfuse raises on purpose."""


class MapError(PathfuseError, ValueError):
    """A map is unusable: empty, no free cell, bad resolution or origin."""


class MapFormatError(MapError):
    """A map or scenario file cannot be read; the message names the file and line."""


class QueryError(PathfuseError, ValueError):
    """A start or goal is not a finite (x, y) pair."""


class ConfigError(PathfuseError, ValueError):
    """An unknown planner, an unknown parameter, or a parameter out of range."""


class PlanningFailed(PathfuseError):
    """Raised by :meth:`PlanResult.raise_for_status` when a plan did not succeed."""

    def __init__(self, result: PlanResult):
        super().__init__(f"{result.planner}: {result.status.name}: {result.message}")
        self.result = result


class Status(enum.Enum):
    """How a planning query ended.  Only ``SUCCESS`` carries a complete path."""

    SUCCESS = "success"
    NO_PATH = "no_path"
    START_OCCUPIED = "start_occupied"
    GOAL_OCCUPIED = "goal_occupied"
    START_OUT_OF_BOUNDS = "start_out_of_bounds"
    GOAL_OUT_OF_BOUNDS = "goal_out_of_bounds"
    LOCAL_MINIMUM = "local_minimum"
    MAX_ITERATIONS = "max_iterations"
    TIMEOUT = "timeout"
    COLLISION = "collision"

    @property
    def ok(self) -> bool:
        return self is Status.SUCCESS

    @property
    def code(self) -> int:
        """The integer a numba kernel returns for this outcome: its place in the enum
        (see :data:`CODE_SUCCESS` and the other ``CODE_*`` below).

        >>> Status.SUCCESS.code, Status.COLLISION.code
        (0, 9)
        """
        return _CODES[self]

    @property
    def key(self) -> str:
        """The lowercase word for this outcome in :meth:`pathfuse.world.World.step`'s
        ``event`` and in the moving-obstacle study's rows: the value, except
        ``"reached"`` for ``SUCCESS`` (the word both have always used).

        >>> Status.SUCCESS.key, Status.COLLISION.key, Status.LOCAL_MINIMUM.key
        ('reached', 'collision', 'local_minimum')
        """
        return "reached" if self is Status.SUCCESS else self.value

    @property
    def label(self) -> str:
        """The outcome's words in a table heading.

        >>> Status.SUCCESS.label, Status.LOCAL_MINIMUM.label, Status.NO_PATH.label
        ('success', 'local min', 'no path')
        """
        return "local min" if self is Status.LOCAL_MINIMUM else self.value.replace("_", " ")

    @classmethod
    def from_key(cls, key: str) -> Status:
        """The status whose :attr:`key` is ``key``.

        >>> Status.from_key("reached")
        <Status.SUCCESS: 'success'>
        """
        for s in cls:
            if s.key == key:
                return s
        raise ValueError(f"outcome: must be one of {[s.key for s in cls]}, got {key!r}")


_CODES: dict[Status, int] = {s: i for i, s in enumerate(Status)}
_BY_CODE: tuple[Status, ...] = tuple(Status)

# --- The integer outcome codes of the numba kernels (numba compiles module-level ints
# as constants and cannot return an Enum).  Every code a kernel returns is one of:
# a status's code (its place in the enum), a refinement of one (``refined``: a second
# way of ending with that status that the caller words apart), or a negative code
# for a loop that paused without an outcome.  New members go at the end of Status:
# numba's cache keys a kernel on its own file, so renumbering these needs the
# caches cleared (tests/test_outcome_codes.py pins the numbers).
CODE_SUCCESS = Status.SUCCESS.code
CODE_NO_PATH = Status.NO_PATH.code
CODE_LOCAL_MINIMUM = Status.LOCAL_MINIMUM.code
CODE_MAX_ITERATIONS = Status.MAX_ITERATIONS.code
CODE_TIMEOUT = Status.TIMEOUT.code
CODE_COLLISION = Status.COLLISION.code
#: Paused at a step or clock cap: call again.
CODE_RUNNING = -1
#: Paused because a buffer (the open list) is full: grow it and call again.
CODE_GROW = -2
#: The distance between a status's code and its refinements.
REFINE_STEP = 100


def refined(code: int, k: int = 1) -> int:
    """The ``k``-th refinement of the status code ``code``.

    >>> refined(CODE_LOCAL_MINIMUM), code_outcome(refined(CODE_LOCAL_MINIMUM))
    (106, <Status.LOCAL_MINIMUM: 'local_minimum'>)
    """
    if not 0 <= code < len(_BY_CODE) or k < 1:
        raise ValueError(f"code: must be a status code with k >= 1, got {code!r}, k={k!r}")
    return code + k * REFINE_STEP


def code_outcome(code: int) -> Status | None:
    """The :class:`Status` a kernel's code (or refinement) stands for; ``None`` for a
    paused loop (negative code).

    >>> code_outcome(CODE_NO_PATH), code_outcome(CODE_RUNNING)
    (<Status.NO_PATH: 'no_path'>, None)
    """
    if code < 0:
        return None
    s = code % REFINE_STEP
    if s >= len(_BY_CODE):
        raise ValueError(f"code: must be a kernel outcome code, got {code!r}")
    return _BY_CODE[s]


@dataclass(frozen=True)
class Budget:
    """Limits that end every planning loop.

    Attributes
    ----------
    max_iterations : int or None
        Cap on expansions (A*) or steps (APF-style planners).  ``None`` means
        the planner's own default, which is always finite.
    time_limit_s : float or None
        Wall-clock limit in seconds, checked between batches of work.
    """

    max_iterations: int | None = None
    time_limit_s: float | None = None

    def __post_init__(self) -> None:
        m = self.max_iterations
        if m is not None and (isinstance(m, bool) or not isinstance(m, numbers.Integral)
                              or m < 1):
            raise ConfigError(f"max_iterations: must be a positive integer, got {m!r}")
        t = self.time_limit_s
        if t is not None and (isinstance(t, bool) or not isinstance(t, numbers.Real)
                              or not math.isfinite(float(t)) or t <= 0):
            raise ConfigError(f"time_limit_s: must be a positive number, got {t!r}")


def _empty_path() -> np.ndarray:
    import numpy as np

    return np.zeros((0, 2), dtype=np.float64)


@dataclass(frozen=True)
class PlanResult:
    """The outcome of one planning query.

    Attributes
    ----------
    status : Status
        How the query ended.
    path : ndarray, shape (N, 2)
        Waypoints in world coordinates (metres).  On ``SUCCESS`` the first
        point is the start and the last the goal (cell centres for grid
        planners); on failure it is the partial path a local planner walked,
        or empty ``(0, 2)`` for a grid search.
    length : float
        Length of ``path`` in metres (sum of segment lengths).
    time_s : float
        Wall-clock planning time in seconds (numba compilation excluded: the
        kernels are compiled and cached before timing starts, or the plan ran
        them interpreted, as ``info["kernels"]`` then says: see
        :mod:`pathfuse.tier`).
    planner : str
        Registry name of the planner.
    expansions : int
        Nodes expanded by grid search (0 if none ran).
    iterations : int
        Steps taken by a local planner (0 if none ran).
    message : str
        A human sentence about the outcome.
    info : dict
        Planner-specific extras (for example the A* global path of fusion);
        ``"kernels": "interpreted"`` when the plan ran its kernels interpreted.
    """

    status: Status
    path: np.ndarray = field(default_factory=_empty_path)
    length: float = 0.0
    time_s: float = 0.0
    planner: str = ""
    expansions: int = 0
    iterations: int = 0
    message: str = ""
    info: dict[str, Any] = field(default_factory=dict)

    def __bool__(self) -> bool:
        return self.status is Status.SUCCESS

    @classmethod
    def _made(cls, status: Status, path: np.ndarray, length: float, time_s: float,
              planner: str, expansions: int, iterations: int, message: str | None,
              info: dict[str, Any]) -> PlanResult:
        """``cls(...)`` with every field given: stored as the frozen dataclass's ``__init__``
        stores them, without its ``object.__setattr__`` call per field (about 1 us of a
        tiny ``plan()``'s 17 us; :func:`pathfuse.planners.run.solve` builds its results so).
        ``message`` None leaves it to the class: a :class:`_FoundPath` writes it on first
        read."""
        obj = object.__new__(cls)
        d = obj.__dict__
        d["status"] = status
        d["path"] = path
        d["length"] = length
        d["time_s"] = time_s
        d["planner"] = planner
        d["expansions"] = expansions
        d["iterations"] = iterations
        if message is not None:
            d["message"] = message
        d["info"] = info
        return obj

    @property
    def success(self) -> bool:
        return self.status is Status.SUCCESS

    def raise_for_status(self) -> PlanResult:
        """Return ``self`` on success, else raise :class:`PlanningFailed`.

        Examples
        --------
        >>> PlanResult(Status.SUCCESS).raise_for_status().status
        <Status.SUCCESS: 'success'>
        """
        if self.status is not Status.SUCCESS:
            raise PlanningFailed(self)
        return self

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dict (path as a list of ``[x, y]``; ``kernels``: how the kernels ran,
        ``"interpreted"`` or ``"compiled"``, see :mod:`pathfuse.tier`)."""
        import numpy as np

        return {
            "planner": self.planner,
            "status": self.status.name,
            "length": float(self.length),
            "time_s": float(self.time_s),
            "expansions": int(self.expansions),
            "iterations": int(self.iterations),
            "message": self.message,
            "path": np.asarray(self.path, dtype=float).tolist(),
            "kernels": self.info.get("kernels", "compiled"),
        }



class _FoundMessage:
    """The ``message`` of a :class:`_FoundPath`: written on first read (a non-data
    descriptor, so the instance's own ``message``, once stored, is read directly)."""

    def __get__(self, obj: Any, cls: Any = None) -> str:
        if obj is None:
            return ""  # the field's default, as on PlanResult
        msg = (f"path through {obj.path.shape[0]} cells, {obj.length:.6g} m, "
               f"{obj.expansions} expansions")
        obj.__dict__["message"] = msg
        return msg


class _FoundPath(PlanResult):
    """A :class:`PlanResult` of a grid path found (``plan()``'s A* lane) whose message,
    ``"path through N cells, L m, E expansions"`` (``found_message`` of
    :mod:`pathfuse.planners.globals.astar`), is written when first read: formatting it
    was about a tenth of a query on a 32 x 32 map (issue 21).  Everything else is a
    :class:`PlanResult`'s: its fields, its ``repr``, and pickling and copying make a
    plain :class:`PlanResult` with the message written.

    >>> import numpy as np
    >>> r = _FoundPath._made(Status.SUCCESS, np.zeros((3, 2)), 2.5, 0.0, "astar", 7, 0,
    ...                      None, {})
    >>> r.message, repr(r).startswith("PlanResult(status=")
    ('path through 3 cells, 2.5 m, 7 expansions', True)
    """

    message = _FoundMessage()  # type: ignore[assignment]

    def __reduce__(self) -> Any:
        return (PlanResult._made, (self.status, self.path, self.length, self.time_s,
                                   self.planner, self.expansions, self.iterations,
                                   self.message, self.info))


_FoundPath.__qualname__ = "PlanResult"  # its repr is a PlanResult's


def path_length(path: np.ndarray) -> float:
    """Sum of segment lengths of an (N, 2) path; 0 for fewer than two points.

    >>> path_length([[0.0, 0.0], [3.0, 4.0], [3.0, 5.0]])
    6.0
    """
    import numpy as np

    p = np.asarray(path, dtype=np.float64)
    if p.shape[0] < 2:
        return 0.0
    return float(np.hypot(*np.diff(p, axis=0).T).sum())
