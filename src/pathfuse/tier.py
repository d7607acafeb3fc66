"""Running the numba kernels in the interpreter where compiling them would cost more.

numba compiles a kernel the first time a process calls it, or loads it from
its on-disk cache.  On an empty cache that compile is most of a small plan:
``pathfuse plan --map paper --planner fusion`` compiles 28 functions for about
13 s of CPU, then plans the 15 x 15 map in 0.07 ms; the same kernels run as
plain Python plan it in about 6 ms.  So a plan on a small map whose kernels are
not compiled yet runs them *interpreted*: the same Python source numba compiles
(its ``py_func``), with every kernel it calls interpreted too (:func:`interpreted`)
and numba's intrinsics replaced by Python functions registered beside them
(:func:`python_for`).  The results are the same as the compiled kernels' to the
bit (``tests/test_tier.py`` holds them equal); only the time differs.

The rule (``auto``, the default) is a ski rental: rent (interpret) until the
rent paid would buy (compile).  :func:`admit`, asked by
:func:`pathfuse.planners.run.solve` before each plan whose kernels are not warm in
the process, lets the plan run interpreted when

* the plan has no time limit (an interpreted plan is tens of times slower: with a
  limit, its outcome could differ),
* the map has at most :data:`MAX_CELLS` cells (a search interpreted expands
  every cell at worst: this bounds what one plan can cost),
* some kernel it runs is neither compiled in this process nor in numba's cache
  (compiled code that is there costs little to load), and
* the process has spent less than :data:`BUDGET_S` seconds of CPU running
  kernels interpreted.

Past the budget, on a larger map, or once anything in the process compiles
(:func:`stop`: a study, a simulation, :func:`pathfuse.planners.run.warm`),
everything runs compiled, as before.  A plan never mixes the two: one that runs
out of budget halfway (:class:`OverBudget`, checked at each call from Python
into a kernel: the searches and the stepping loops are called in chunks while
interpreted) starts again compiled.  The
environment variable ``PATHFUSE_KERNELS`` sets the rule: ``auto``, ``compiled``
(always compile: timings comparable with a warm cache) or ``interpreted``
(every plan runs its kernels interpreted, whatever its map, budget or time limit,
in a process that has not compiled them: a debugger steps through their source).
A plan that ran interpreted says so in ``result.info["kernels"]``; its ``time_s``
is the interpreter's time.

This module is ours, not the paper's; it changes which machine code runs, never
what is computed.
"""

from __future__ import annotations

import contextlib
import contextvars
import os
import time
import types
from collections.abc import Callable, Iterator
from typing import Any

from numba.core.dispatcher import Dispatcher, OmittedArg
from numba.core.extending import _Intrinsic

from pathfuse.result import ConfigError

__all__ = ["MODES", "MAX_CELLS", "BUDGET_S", "mode", "admit", "stop", "running",
           "interpreting", "interpreted", "python_for", "spent_s", "OverBudget"]

#: The rules ``PATHFUSE_KERNELS`` may name.
MODES = ("auto", "compiled", "interpreted")
#: The largest map (in cells) a plan may run interpreted on under ``auto``.
MAX_CELLS = 128 * 128
#: The CPU seconds a process may spend interpreting kernels under ``auto`` before it
#: compiles them (about the cheapest cold compile, A*'s).
BUDGET_S = 2.0

_ENV = "PATHFUSE_KERNELS"


class OverBudget(Exception):
    """Raised inside a plan that runs interpreted when the process has spent
    :data:`BUDGET_S` interpreting (under ``auto``): the plan is run again compiled."""


_state = {"on": True, "spent": 0.0}
_NOW: contextvars.ContextVar[bool] = contextvars.ContextVar("pathfuse_interpreting",
                                                            default=False)
_TWINS: dict[Any, Callable[..., Any]] = {}
_TIMED: dict[Any, Callable[..., Any]] = {}
_DEPTH: contextvars.ContextVar[bool] = contextvars.ContextVar("pathfuse_in_twin",
                                                              default=False)
_PYTHON: dict[Any, Callable[..., Any]] = {}


def mode() -> str:
    """The rule in force: ``PATHFUSE_KERNELS`` (``auto`` when unset).

    Raises
    ------
    ConfigError
        The variable names no rule of :data:`MODES`.
    """
    value = os.environ.get(_ENV, "auto").strip().lower() or "auto"
    if value not in MODES:
        raise ConfigError(f"{_ENV}: must be one of {', '.join(MODES)}, "
                          f"got {os.environ.get(_ENV)!r}")
    return value


def admit(cells: int, cold: Callable[[], bool], *, timed: bool = False) -> bool:
    """Whether the plan about to start, on a map of ``cells`` cells (with a time limit
    when ``timed``), runs its kernels interpreted.  ``cold()`` tells whether some kernel
    it runs still needs compiling (it is called only when the answer depends on it).  A
    plan that is not admitted under ``auto`` ends interpretation for the process
    (:func:`stop`), except for its time limit alone."""
    rule = mode()
    if _NUMBA_COMPILE is None:
        return False
    if rule == "interpreted":
        return True
    if rule == "compiled" or not _state["on"] or timed:
        return False
    if cells <= MAX_CELLS and _state["spent"] < BUDGET_S and cold():
        return True
    stop()
    return False


def stop() -> None:
    """End interpretation for this process (under ``auto``): the kernels are compiled
    from now on.  Called when a plan is not admitted and whenever kernels are compiled
    on purpose (:func:`pathfuse.planners.run.warm`)."""
    _state["on"] = False


@contextlib.contextmanager
def running(interpreting: bool) -> Iterator[None]:
    """The body of one plan: with ``interpreting`` (:func:`admit`'s answer), the call
    sites inside it (in this thread or task only) run the kernels interpreted."""
    token = _NOW.set(interpreting)
    try:
        yield
    finally:
        _NOW.reset(token)


def spent_s() -> float:
    """CPU seconds this process has spent in kernels run interpreted."""
    return _state["spent"]


def interpreting() -> bool:
    """Whether this thread (or task) is inside a plan that runs interpreted."""
    return _NOW.get()


def _timed(kernel: Any) -> Callable[..., Any]:
    """:func:`interpreted` ``kernel``, adding the CPU time of each outermost call (its
    thread's) to :func:`spent_s`."""
    timed = _TIMED.get(kernel)
    if timed is None:
        twin = interpreted(kernel)

        def timed(*args: Any, **kws: Any) -> Any:
            # numba's dispatcher hands an omitted default argument over wrapped
            args = tuple(a.value if type(a) is OmittedArg else a for a in args)
            if _DEPTH.get():  # called from an interpreted kernel: its caller counts the time
                return twin(*args, **kws)
            if _state["spent"] >= BUDGET_S and mode() == "auto":
                raise OverBudget(f"{_state['spent']:.2f} s spent interpreting")
            token = _DEPTH.set(True)
            t0 = time.thread_time()
            try:
                return twin(*args, **kws)
            finally:
                _DEPTH.reset(token)
                _state["spent"] += time.thread_time() - t0

        _TIMED[kernel] = timed
    return timed


def _compile_for_args(self: Any, *args: Any, **kws: Any) -> Any:
    """numba's dispatcher calls this when no compiled code of the kernel fits the
    arguments, and calls what it returns with them: inside a plan that runs interpreted,
    the kernel's twin instead of a compile.  A kernel without a twin (a plug-in's with
    an intrinsic of its own) compiles, as it always does."""
    if _NOW.get():
        try:
            return _timed(self)
        except TypeError:
            pass
    return _NUMBA_COMPILE(self, *args, **kws)  # type: ignore[misc]


def python_for(intrinsic: Any) -> Callable[[Callable[..., Any]], Callable[..., Any]]:
    """Register the decorated function as what ``intrinsic`` (a numba ``@intrinsic``)
    computes, for kernels run interpreted.  It must return the same value and type."""
    def register(fn: Callable[..., Any]) -> Callable[..., Any]:
        _PYTHON[intrinsic] = fn
        return fn

    return register


def _names(code: types.CodeType) -> set[str]:
    """The global names ``code`` and the code nested in it read."""
    out = set(code.co_names)
    for c in code.co_consts:
        if isinstance(c, types.CodeType):
            out |= _names(c)
    return out


def _twin_of(obj: Any) -> Any:
    """``obj`` as an interpreted kernel reads it: a kernel's twin, an intrinsic's Python
    function, anything else itself."""
    if isinstance(obj, Dispatcher):
        return interpreted(obj)
    if isinstance(obj, _Intrinsic):
        fn = _PYTHON.get(obj)
        if fn is None:
            raise TypeError(f"the intrinsic {obj._name!r} has no Python function "
                            "(register one with pathfuse.tier.python_for)")
        return fn
    return obj


def interpreted(kernel: Any) -> Callable[..., Any]:
    """The interpreted twin of ``kernel`` (an ``@njit`` function): its Python source
    as a function whose globals and closure name the twins of the kernels and the Python
    functions of the intrinsics it calls, so that calling it compiles nothing.  Built
    once per kernel; its globals are the kernel module's as they are at this first call.

    Examples
    --------
    >>> from pathfuse.search.kernel import _h
    >>> interpreted(_h)(3.0, 4.0, False)
    5.0
    """
    twin = _TWINS.get(kernel)
    if twin is not None:
        return twin
    if not isinstance(kernel, Dispatcher):
        raise TypeError(f"not a numba kernel: {kernel!r}")
    py = kernel.py_func
    glob = dict(py.__globals__)
    closure = py.__closure__
    if closure is not None:
        closure = tuple(c if not isinstance(c.cell_contents, (Dispatcher, _Intrinsic))
                        else types.CellType(_twin_of(c.cell_contents)) for c in closure)
    twin = types.FunctionType(py.__code__, glob, py.__name__, py.__defaults__, closure)
    twin.__kwdefaults__ = py.__kwdefaults__
    twin.__doc__ = py.__doc__
    twin.__qualname__ = py.__qualname__
    _TWINS[kernel] = twin  # before the callees: a kernel that calls itself finds it
    try:
        for name in _names(py.__code__):
            if name in glob:
                glob[name] = _twin_of(glob[name])
    except BaseException:
        del _TWINS[kernel]
        raise
    return twin


# the hook: numba's C dispatcher looks ``_compile_for_args`` up on the dispatcher each time
# it finds no compiled code for a call (numba 0.58-0.68); a numba without it runs every
# plan compiled (admit() says no)
_NUMBA_COMPILE = getattr(Dispatcher, "_compile_for_args", None)
if _NUMBA_COMPILE is not None:
    Dispatcher._compile_for_args = _compile_for_args  # type: ignore[attr-defined]
