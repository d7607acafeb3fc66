"""The one YAML loader of pathfuse: safe, bounded, strict about keys, floats as users write them.

Every YAML file pathfuse reads (ROS map YAML, inline rows maps, scenarios,
experiments) and every YAML scalar typed on the command line
(``--param k=v``) goes through :func:`load_yaml`.  On top of PyYAML's
``SafeLoader`` (no Python objects are ever built) it

* refuses a document whose size *with aliases expanded* exceeds
  ``MAX_YAML_NODES`` (a "billion laughs" alias bomb is refused while it is
  parsed, before anything is expanded);
* refuses collections nested deeper than ``MAX_YAML_DEPTH`` (no
  ``RecursionError``);
* refuses files larger than ``MAX_YAML_BYTES`` (read with a cap, so a link
  to ``/dev/zero`` is refused too);
* refuses a repeated key and a key that is not a scalar (a list or a
  mapping used as a key);
* reads ``1e-2``, ``5E3`` and ``.5e-3`` as floats (YAML 1.1, which PyYAML
  implements, reads them as strings).

Every failure is one line naming the file (and line and column where YAML
knows them), raised as the exception class the caller passes.  The limits
are those of :mod:`pathfuse.limits`.

Examples
--------
>>> load_yaml("step_m: 1e-2\\nr1_m: [1, 2.5E1]", "x.yaml")
{'step_m': 0.01, 'r1_m': [1, 25.0]}
>>> load_yaml("a: 1\\na: 2", "x.yaml")
Traceback (most recent call last):
...
pathfuse.result.ConfigError: x.yaml: line 2, column 1: invalid YAML: duplicate key 'a'
>>> bomb = "a: &a [x, x, x, x, x, x, x, x, x, x]\\n" + "".join(
...     f"{c}: &{c} [{', '.join(['*' + p] * 10)}]\\n" for p, c in zip("abcdefgh", "bcdefghi"))
>>> load_yaml(bomb, "lol.yaml")                          # doctest: +ELLIPSIS
Traceback (most recent call last):
...
pathfuse.limits.LimitError: lol.yaml: line ...: too large with its aliases expanded: ...
"""

from __future__ import annotations

import os
import re
from pathlib import Path
from typing import Any

from pathfuse.limits import LimitError, env_name, limit, read_capped
from pathfuse.result import ConfigError, PathfuseError
from pathfuse.validate import short

__all__ = ["load_yaml", "read_yaml", "read_yaml_mapping", "FLOAT_RE"]

FLOAT_RE = re.compile(
    r"""^(?:[-+]?(?:[0-9][0-9_]*)\.[0-9_]*(?:[eE][-+]?[0-9]+)?
    |[-+]?(?:[0-9][0-9_]*)(?:[eE][-+]?[0-9]+)
    |\.[0-9_]+(?:[eE][-+]?[0-9]+)?
    |[-+]\.[0-9_]+(?:[eE][-+]?[0-9]+)?
    |[-+]?[0-9][0-9_]*(?::[0-5]?[0-9])+\.[0-9_]*
    |[-+]?\.(?:inf|Inf|INF)
    |\.(?:nan|NaN|NAN))$""",
    re.X,
)
"""Plain scalars read as floats: YAML 1.1's forms plus exponents without a dot or a sign
(``1e-2``, ``5E3``), which YAML 1.2 and every user read as numbers."""

_LOADER: Any = None


class _Refused(Exception):
    """Raised inside the loader; turned into the caller's error with the mark."""

    def __init__(self, problem: str, mark: Any, name: str | None = None):
        super().__init__(problem)
        self.problem = problem
        self.mark = mark
        self.name = name


def _loader_class() -> Any:
    """The loader class, built on first use (``yaml`` is imported lazily)."""
    global _LOADER
    if _LOADER is not None:
        return _LOADER
    import yaml

    class Loader(yaml.SafeLoader):
        max_nodes = 0
        max_depth = 0

        def __init__(self, stream: str) -> None:
            super().__init__(stream)
            self._sizes: dict[int, int] = {}
            self._depth = 0

        def compose_node(self, parent: Any, index: Any) -> Any:
            mark = self.peek_event().start_mark
            self._depth += 1
            if self._depth > self.max_depth:
                raise _Refused(f"nested deeper than {self.max_depth} levels", mark,
                               "MAX_YAML_DEPTH")
            try:
                node = super().compose_node(parent, index)
            finally:
                self._depth -= 1
            key = id(node)
            if key not in self._sizes:  # an alias returns a node already sized
                if isinstance(node, yaml.SequenceNode):
                    size = 1 + sum(self._sizes.get(id(c), 1) for c in node.value)
                elif isinstance(node, yaml.MappingNode):
                    size = 1 + sum(self._sizes.get(id(k), 1) + self._sizes.get(id(v), 1)
                                   for k, v in node.value)
                else:
                    size = 1
                if size > self.max_nodes:
                    raise _Refused(f"too large with its aliases expanded: more than "
                                   f"{self.max_nodes} nodes", mark, "MAX_YAML_NODES")
                self._sizes[key] = size
            return node

        def construct_mapping(self, node: Any, deep: bool = False) -> dict[Any, Any]:
            if not isinstance(node, yaml.MappingNode):
                return super().construct_mapping(node, deep=deep)  # raises the usual error
            # keys written in this mapping must be unique; keys brought in by a merge
            # ("<<: *base") come first and may be overridden by them
            merge = "tag:yaml.org,2002:merge"
            n_own = sum(1 for k, _ in node.value if k.tag != merge)
            self.flatten_mapping(node)
            n_merged = len(node.value) - n_own
            out: dict[Any, Any] = {}
            own: set[Any] = set()
            for i, (knode, vnode) in enumerate(node.value):
                if not isinstance(knode, yaml.ScalarNode):
                    kind = "a list" if isinstance(knode, yaml.SequenceNode) else "a mapping"
                    raise _Refused(f"a mapping key must be text or a number, got {kind}",
                                   knode.start_mark)
                k = self.construct_object(knode, deep=deep)
                if i >= n_merged:
                    if k in own:
                        raise _Refused(f"duplicate key {short(k)}", knode.start_mark)
                    own.add(k)
                out[k] = self.construct_object(vnode, deep=deep)
            return out

    Loader.add_implicit_resolver("tag:yaml.org,2002:float", FLOAT_RE,
                                 list("-+0123456789."))
    _LOADER = Loader
    return Loader


def _where(where: str, mark: Any) -> str:
    if mark is None:
        return f"{where}: "
    return f"{where}: line {mark.line + 1}, column {mark.column + 1}: "


def load_yaml(text: str | bytes, where: str,
              error: type[PathfuseError] = ConfigError) -> Any:
    """Parse one YAML document safely (see the module docstring).

    Parameters
    ----------
    text : str or bytes
        The document (bytes must be UTF-8).
    where : str
        What to name in messages (a file path, ``--param step_m``).
    error : PathfuseError subclass
        The class of the error raised for malformed YAML; exceeded limits
        raise :class:`~pathfuse.limits.LimitError` (a ``ConfigError``).
    """
    import yaml

    if isinstance(text, bytes):
        try:
            text = text.decode("utf-8")
        except UnicodeDecodeError as exc:
            raise error(f"{where}: not a UTF-8 text file ({exc.reason} at byte "
                        f"{exc.start})") from None
    cls = _loader_class()
    cls.max_nodes = limit("MAX_YAML_NODES")
    cls.max_depth = limit("MAX_YAML_DEPTH")
    loader = None
    try:
        loader = cls(text)  # reads the stream: may raise a ReaderError
        return loader.get_single_data()
    except _Refused as exc:
        if exc.name is not None:
            raise LimitError(f"{_where(where, exc.mark)}{exc.problem} ({exc.name}; set the "
                             f"environment variable {env_name(exc.name)} to raise it)") \
                from None
        raise error(f"{_where(where, exc.mark)}invalid YAML: {exc.problem}") from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        raise error(f"{_where(where, mark)}invalid YAML: {short(problem, 120)[1:-1]}") \
            from None
    except RecursionError:  # pragma: no cover - the depth limit comes first
        raise LimitError(f"{where}: nested too deeply") from None
    finally:
        if loader is not None:
            loader.dispose()


def read_yaml(path: str | os.PathLike[str], what: str = "YAML",
              error: type[PathfuseError] = ConfigError) -> Any:
    """Read and parse a YAML file, its size capped by ``MAX_YAML_BYTES``.

    A missing file, a folder, an unreadable file and bad YAML are ``error``s
    naming the path.
    """
    p = Path(path)
    try:
        data = read_capped(p, f"the {what} file", "MAX_YAML_BYTES")
    except FileNotFoundError:
        raise error(f"{what} file not found: {p}") from None
    except IsADirectoryError:
        raise error(f"{what} path is a directory, not a file: {p}") from None
    except OSError as exc:
        raise error(f"{p}: cannot read the {what} file ({exc.strerror or exc})") from None
    return load_yaml(data, str(p), error)


def read_yaml_mapping(path: str | os.PathLike[str], what: str = "YAML",
                      error: type[PathfuseError] = ConfigError) -> dict[str, Any]:
    """:func:`read_yaml` of a file that must hold a mapping."""
    doc = read_yaml(path, what, error)
    if not isinstance(doc, dict):
        kind = "empty" if doc is None else f"a {type(doc).__name__}"
        raise error(f"{path}: {what} must be a mapping of keys to values, got {kind}")
    return doc
