"""What a command compiles or loads from numba's cache, and the CPU time of each compilation.

Runs a pathfuse command line in this process with numba's compile events
recorded: every function numba compiles (a dispatcher's own compilation; a
callee's inside its caller's is counted apart, so the times are *exclusive*),
split into type inference, lowering (numba writing LLVM IR, and linking), LLVM's
own work (its optimisation passes and its machine code: the part ``NUMBA_OPT``
sets) and the rest of numba's pipeline, and every overload looked up in the on-disk cache
(hit or miss). numba's own start-up (its first compilation in a process, of a
one-line function) runs first and is left out of the figures. The pathfuse
modules imported are listed at the end.

Usage (an empty cache shows a cold start, the same folder again a warm one)::

    NUMBA_CACHE_DIR=$(mktemp -d) python benchmarks/compile_trace.py \\
        plan --map paper --planner fusion
"""

from __future__ import annotations

import collections
import contextlib
import io
import sys
import time
from typing import Any


def main(argv: list[str]) -> None:
    import numba
    from numba.core import caching, event, typed_passes

    t0 = time.process_time()
    numba.njit(lambda a: a + 1)(1)  # numba's own first-compilation set-up
    setup = time.process_time() - t0
    stack: list[list[Any]] = []  # [function, phase, start, time of nested frames]
    excl: collections.Counter[tuple[str, str]] = collections.Counter()
    loads: list[tuple[str, bool]] = []

    def push(name: str, phase: str) -> None:
        stack.append([name, phase, time.process_time(), 0.0])

    def pop() -> None:
        name, phase, start, nested = stack.pop()
        dt = time.process_time() - start
        if stack:
            stack[-1][3] += dt
        excl[(name, phase)] += dt - nested

    class Listener(event.Listener):
        def on_start(self, ev: Any) -> None:
            f = ev.data["dispatcher"].py_func
            push(f"{f.__module__}.{f.__qualname__}", "other")

        def on_end(self, ev: Any) -> None:
            pop()

    def timed(cls: Any, phase: str) -> None:
        run_pass = cls.run_pass

        def wrapper(self: Any, state: Any) -> Any:
            push(stack[-1][0] if stack else "?", phase)
            try:
                return run_pass(self, state)
            finally:
                pop()

        cls.run_pass = wrapper

    timed(typed_passes.NopythonTypeInference, "typing")
    timed(typed_passes.NativeLowering, "lowering")
    from llvmlite.binding import executionengine, newpassmanagers

    def llvm(cls: Any, method: str) -> None:
        run = getattr(cls, method)

        def wrapper(self: Any, *args: Any) -> Any:
            push(stack[-1][0] if stack else "?", "llvm")
            try:
                return run(self, *args)
            finally:
                pop()

        setattr(cls, method, wrapper)

    llvm(newpassmanagers.ModulePassManager, "run")
    llvm(newpassmanagers.FunctionPassManager, "run")
    llvm(executionengine.ExecutionEngine, "finalize_object")
    event.register("numba:compile", Listener())
    load_overload = caching.Cache.load_overload

    def traced_load(self: Any, sig: Any, target_context: Any) -> Any:
        got = load_overload(self, sig, target_context)
        loads.append((getattr(self._py_func, "__qualname__", self._name), got is not None))
        return got

    caching.Cache.load_overload = traced_load  # type: ignore[method-assign]

    from pathfuse.cli.parser import main as cli

    t1 = time.process_time()
    with contextlib.redirect_stdout(io.StringIO()):
        cli(argv)
    total = time.process_time() - t1
    per: dict[str, dict[str, float]] = collections.defaultdict(dict)
    for (name, phase), dt in excl.items():
        per[name][phase] = dt
    print(f"numba's own set-up {setup:.2f} s; the command {total:.2f} s of CPU, of which "
          f"compiling {sum(excl.values()):.2f} s ({len(per)} functions)")
    print("   CPU s  typing lowering  llvm   other  function")
    for name, d in sorted(per.items(), key=lambda kv: -sum(kv[1].values())):
        print(f"  {sum(d.values()):6.2f}  {d.get('typing', 0):6.2f}  {d.get('lowering', 0):6.2f} "
              f"{d.get('llvm', 0):6.2f} {d.get('other', 0):6.2f}  {name}")
    tot = {ph: sum(d.get(ph, 0.0) for d in per.values())
           for ph in ("typing", "lowering", "llvm", "other")}
    print(f"  {sum(tot.values()):6.2f}  {tot['typing']:6.2f}  {tot['lowering']:6.2f} "
          f"{tot['llvm']:6.2f} {tot['other']:6.2f}  (all)")
    hits = [n for n, hit in loads if hit]
    print(f"cache: {len(hits)} loaded ({', '.join(hits)}), {len(loads) - len(hits)} missed")
    mods = sorted(m for m in sys.modules if m.startswith("pathfuse"))
    print(f"{len(mods)} pathfuse modules imported: {' '.join(m[9:] or 'pathfuse' for m in mods)}")


if __name__ == "__main__":
    main(sys.argv[1:])
