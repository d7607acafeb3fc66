"""One way to check input: the value checks that every file, option and parameter uses.

Every check raises a :class:`~pathfuse.result.ConfigError` (or the subclass
passed as ``error``) with **one line** in one format::

    KEY: must be WHAT, got VALUE

``KEY`` names the value as the user wrote it (``planners[1].params.r1_m``,
``robot.radius``, ``--step``); ``VALUE`` is its ``repr``, shortened to
:data:`SHOWN` characters so that a huge value never floods a message.

Planner parameters are frozen dataclasses whose fields are declared with
:func:`param`: the default, the constraint, the unit and a help text live in
the field's metadata, and :func:`check_fields` (called from
``__post_init__``) enforces them.  The same metadata is what ``pathfuse
planners`` prints, so a constraint is written once.

Examples
--------
>>> number("1e-2", "step_m", gt=0)     # YAML 1.1 reads 1e-2 as a string
0.01
>>> number(-1, "r1_m", gt=0)
Traceback (most recent call last):
...
pathfuse.result.ConfigError: r1_m: must be a number > 0, got -1
>>> choice("behind", "ahead", ("progress", "paper-x"))
Traceback (most recent call last):
...
pathfuse.result.ConfigError: ahead: must be one of 'progress', 'paper-x', got 'behind'
>>> short("x" * 100)[:12], len(short("x" * 100))
("'xxxxxxxxxxx", 60)
"""

from __future__ import annotations

import dataclasses
import math
import re
from collections.abc import Mapping, Sequence
from typing import Any, TypeVar

from pathfuse.result import ConfigError, PathfuseError

__all__ = [
    "SHOWN",
    "short",
    "number",
    "integer",
    "flag",
    "choice",
    "text",
    "point",
    "mapping",
    "param",
    "ParamSpec",
    "param_spec",
    "check_fields",
    "build",
]

SHOWN = 60
"""Values are shown in messages up to this many characters."""

_EXP_FLOAT = re.compile(r"\s*[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?\s*")
T = TypeVar("T")


def short(value: Any, n: int = SHOWN) -> str:
    """``repr(value)`` cut to ``n`` characters (``...`` marks the cut).

    The cost is bounded whatever the value: containers are shown a few items
    and levels deep (:mod:`reprlib`), so a deeply nested, self-referencing or
    alias-expanded value costs no more than ``n`` characters.

    >>> short([1, 2, 3])
    '[1, 2, 3]'
    >>> short([[[[[[1]]]]]])
    '[[[[...]]]]'
    """
    if isinstance(value, (str, bytes)):
        text_ = repr(value[: n + 2])
    else:
        try:
            text_ = _REPR.repr(value)
        except Exception:  # a broken __repr__ must not hide the real error
            text_ = f"<{type(value).__name__}>"
    return text_ if len(text_) <= n else text_[: n - 3] + "..."


def _make_repr() -> Any:
    import reprlib

    r = reprlib.Repr()
    r.maxlevel = 3
    r.maxlist = r.maxtuple = r.maxset = r.maxfrozenset = r.maxdeque = r.maxarray = 8
    r.maxdict = 6
    r.maxstring = SHOWN
    r.maxother = SHOWN
    r.maxlong = 40
    return r


_REPR = _make_repr()


def _fail(key: str, what: str, value: Any,
          error: type[ConfigError] | type[PathfuseError]) -> PathfuseError:
    return error(f"{key}: must be {what}, got {short(value)}")


def _is_number(value: Any) -> bool:
    import numbers

    return isinstance(value, numbers.Real) and not isinstance(value, bool) \
        and type(value).__name__ != "bool_"


def _bounds(gt: float | None, ge: float | None, lt: float | None, le: float | None) -> str:
    parts = []
    if gt is not None:
        parts.append(f"> {gt:g}")
    if ge is not None:
        parts.append(f">= {ge:g}")
    if lt is not None:
        parts.append(f"< {lt:g}")
    if le is not None:
        parts.append(f"<= {le:g}")
    return " and ".join(parts)


def number(value: Any, key: str, *, gt: float | None = None, ge: float | None = None,
           lt: float | None = None, le: float | None = None,
           error: type[ConfigError] | type[PathfuseError] = ConfigError) -> float:
    """A finite float within the bounds; numeric strings such as ``"1e-2"`` are accepted.

    >>> number(3, "k_att", gt=0)
    3.0
    """
    bounds = _bounds(gt, ge, lt, le)
    what = "a number" + (f" {bounds}" if bounds else "")
    if isinstance(value, str) and _EXP_FLOAT.fullmatch(value):
        v = float(value)
    elif _is_number(value):
        try:
            v = float(value)
        except OverflowError:
            raise _fail(key, "a finite " + what[2:], value, error) from None
    else:
        raise _fail(key, what, value, error)
    if not math.isfinite(v):
        raise _fail(key, "a finite " + what[2:], value, error)
    if (gt is not None and not v > gt) or (ge is not None and not v >= ge) or \
            (lt is not None and not v < lt) or (le is not None and not v <= le):
        raise _fail(key, what, value, error)
    return v


def integer(value: Any, key: str, *, ge: int | None = None, le: int | None = None,
            error: type[ConfigError] = ConfigError) -> int:
    """An integer within the bounds (a bool is not an integer; ``3.0`` is not either).

    >>> integer(40, "stall_steps", ge=1)
    40
    >>> integer(True, "stall_steps", ge=1)
    Traceback (most recent call last):
    ...
    pathfuse.result.ConfigError: stall_steps: must be an integer >= 1, got True
    """
    import numbers

    bounds = _bounds(None, ge, None, le)
    what = "an integer" + (f" {bounds}" if bounds else "")
    if isinstance(value, bool) or type(value).__name__ == "bool_" \
            or not isinstance(value, numbers.Integral):
        raise _fail(key, what, value, error)
    v = int(value)
    if (ge is not None and v < ge) or (le is not None and v > le):
        raise _fail(key, what, value, error)
    return v


def flag(value: Any, key: str, error: type[ConfigError] = ConfigError) -> bool:
    """``True`` or ``False`` (numpy booleans too; not 0/1 or ``"yes"``)."""
    if isinstance(value, bool) or type(value).__name__ == "bool_":
        return bool(value)
    raise _fail(key, "true or false", value, error)


def choice(value: Any, key: str, choices: Sequence[str],
           error: type[ConfigError] = ConfigError) -> str:
    """One of ``choices``."""
    if isinstance(value, str) and value in choices:
        return value
    raise _fail(key, "one of " + ", ".join(repr(c) for c in choices), value, error)


def text(value: Any, key: str, error: type[ConfigError] = ConfigError) -> str:
    """A string."""
    if isinstance(value, str):
        return value
    raise _fail(key, "a string", value, error)


def point(value: Any, key: str,
          error: type[ConfigError] | type[PathfuseError] = ConfigError) -> tuple[float, float]:
    """Two finite numbers ``[x, y]``: a list, a tuple or an array of two (numbers, numpy
    scalars or numeric strings).  The one point check of every caller: files, web
    requests, :meth:`pathfuse.problem.Problem.create` (``error`` :class:`QueryError`)
    and the command line (``--start X,Y``, split on the comma first).

    >>> point([1, "2.5"], "start")
    (1.0, 2.5)
    >>> point((1.0, float("inf")), "goal")
    Traceback (most recent call last):
    ...
    pathfuse.result.ConfigError: goal[1]: must be a finite number, got inf
    """
    if type(value) is not tuple:  # a tuple (plan()'s usual case) has no tolist to look up
        if hasattr(value, "tolist") and not isinstance(value, (str, bytes)):
            value = value.tolist()
        if not isinstance(value, (list, tuple)):
            raise _fail(key, "two numbers [x, y]", value, error)
    if len(value) != 2:
        raise _fail(key, "two numbers [x, y]", value, error)
    x, y = value
    if type(x) is float and type(y) is float and math.isfinite(x) and math.isfinite(y):
        return x, y  # the common case, without the general checks (plan() calls this)
    if isinstance(x, float) and isinstance(y, float) and math.isfinite(x) and math.isfinite(y):
        return float(x), float(y)  # numpy float64 (a float subclass): what number() returns
    return (number(x, f"{key}[0]", error=error), number(y, f"{key}[1]", error=error))


def mapping(value: Any, key: str, allowed: Sequence[str] | None = None, what: str = "a mapping",
            error: type[ConfigError] = ConfigError) -> Mapping[str, Any]:
    """A mapping whose keys are strings among ``allowed`` (when given).

    >>> mapping({"radius": 1, "speed": 2}, "robot", ("radius",))
    Traceback (most recent call last):
    ...
    pathfuse.result.ConfigError: robot.speed: unknown key (allowed: radius)
    """
    if not isinstance(value, Mapping):
        raise _fail(key, what, value, error)
    for k in value:
        if not isinstance(k, str):
            raise error(f"{key}: keys must be names, got {short(k)}")
        if allowed is not None and k not in allowed:
            name = f"{key}.{k}" if key else k
            raise error(f"{name}: unknown key (allowed: {', '.join(allowed)})")
    return value


# --------------------------------------------------------------------------- dataclass params
@dataclasses.dataclass(frozen=True)
class ParamSpec:
    """What a parameter field accepts, with its unit and help text.

    Attributes
    ----------
    kind : {"float", "int", "bool", "choice", "str"}
    help : str
        One sentence for ``pathfuse planners`` and generated forms.
    unit : str
        ``"m"``, ``"s"``, ``"m/s"``, ... or ``""``.
    gt, ge, le : float or None
        Bounds of a number.
    choices : tuple of str
        The values of a choice.
    optional : bool
        ``None`` is allowed (and means "derived from the map", as the help says).
    """

    kind: str
    help: str
    unit: str = ""
    gt: float | None = None
    ge: float | None = None
    le: float | None = None
    choices: tuple[str, ...] = ()
    optional: bool = False

    def check(self, value: Any, key: str, error: type[ConfigError] = ConfigError) -> Any:
        """The checked (and normalised: ints to floats) value."""
        if value is None and self.optional:
            return None
        # a value below the lower bound is told that bound alone (the message it always had);
        # a value above the upper bound is told the whole range
        if self.kind == "float":
            v = number(value, key, gt=self.gt, ge=self.ge, error=error)
            if self.le is not None and not v <= self.le:
                raise _fail(key, "a number " + _bounds(self.gt, self.ge, None, self.le), value,
                            error)
            return v
        if self.kind == "int":
            ge = None if self.ge is None else int(self.ge)
            le = None if self.le is None else int(self.le)
            n = integer(value, key, ge=ge, error=error)
            if le is not None and n > le:
                raise _fail(key, "an integer " + self._range(), value, error)
            return n
        if self.kind == "bool":
            return flag(value, key, error)
        if self.kind == "choice":
            return choice(value, key, self.choices, error)
        return text(value, key, error)

    def _range(self) -> str:
        """The bounds in words (an integer's bounds as integers, every digit)."""
        if self.kind != "int":
            return _bounds(self.gt, self.ge, None, self.le)
        parts = [f"{op} {int(v)}" for op, v in ((">", self.gt), (">=", self.ge), ("<=", self.le))
                 if v is not None]
        return " and ".join(parts)

    def describe(self) -> str:
        """The constraint in words: ``"> 0 m"``, ``"one of 'a', 'b'"``."""
        if self.kind == "choice":
            return "one of " + ", ".join(repr(c) for c in self.choices)
        if self.kind == "bool":
            return "true or false"
        b = self._range()
        kind = {"float": "number", "int": "integer", "str": "text"}.get(self.kind, self.kind)
        optional = " or null" if self.optional else ""
        return " ".join(x for x in (kind, b, self.unit) if x) + optional


def param(default: Any, *, help: str, unit: str = "", gt: float | None = None,
          ge: float | None = None, le: float | None = None,
          choices: Sequence[str] = (), optional: bool = False, kind: str | None = None) -> Any:
    """A dataclass field with its constraint, unit and help (see :class:`ParamSpec`).

    The kind is taken from the default (``choices`` make a choice; a ``None``
    default is a float unless ``kind`` says otherwise).
    """
    if kind is not None:
        pass
    elif choices:
        kind = "choice"
    elif isinstance(default, bool):
        kind = "bool"
    elif isinstance(default, int) and not isinstance(default, bool) and default is not None:
        kind = "int"
    elif isinstance(default, str):
        kind = "str"
    else:
        kind = "float"
    spec = ParamSpec(kind, help, unit, gt, ge, le, tuple(choices), optional)
    return dataclasses.field(default=default, metadata={"param": spec})


def param_spec(field: dataclasses.Field) -> ParamSpec | None:
    """The :class:`ParamSpec` of a field declared with :func:`param` (None otherwise)."""
    spec = field.metadata.get("param")
    return spec if isinstance(spec, ParamSpec) else None


def check_fields(obj: Any, error: type[ConfigError] = ConfigError) -> None:
    """Check and normalise every :func:`param` field of a frozen dataclass instance."""
    for f in dataclasses.fields(obj):
        spec = param_spec(f)
        if spec is None:
            continue
        value = getattr(obj, f.name)
        checked = spec.check(value, f.name, error)
        if checked is not value:
            object.__setattr__(obj, f.name, checked)


def build(cls: type[T], values: Mapping[str, Any] | None, key: str = "",
          error: type[ConfigError] = ConfigError) -> T:
    """``cls(**values)`` with unknown keys and bad values reported as ``key.name: ...``.

    >>> @dataclasses.dataclass(frozen=True)
    ... class P:
    ...     r1_m: float = param(2.0, help="radius", unit="m", gt=0)
    ...     def __post_init__(self):
    ...         check_fields(self)
    >>> build(P, {"r1_m": 1}).r1_m
    1.0
    >>> build(P, {"r2_m": 1}, key="params")
    Traceback (most recent call last):
    ...
    pathfuse.result.ConfigError: params.r2_m: unknown parameter (parameters: r1_m)
    """
    values = dict(values or {})
    names = [f.name for f in dataclasses.fields(cls)]  # type: ignore[arg-type]
    prefix = f"{key}." if key else ""
    for k in values:
        if k not in names:
            name = k if isinstance(k, str) else short(k)
            raise error(f"{prefix}{name}: unknown parameter (parameters: {', '.join(names)})")
    try:
        return cls(**values)
    except ConfigError as exc:
        raise (type(exc) if isinstance(exc, error) else error)(f"{prefix}{exc}") from None
