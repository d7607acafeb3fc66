"""Plug-in modules of an experiment (``imports:``): imported once per process.

An experiment file's ``imports:`` names modules or ``.py`` files that
register extra planners.  They are ordinary Python code that runs in the
client and in every worker: an experiment file with ``imports:`` is code.
"""

from __future__ import annotations

import hashlib
import importlib
import importlib.util
import sys
from collections.abc import Sequence
from pathlib import Path

__all__ = ["ensure_imports"]

_IMPORTED: set[str] = set()


def ensure_imports(imports: Sequence[str]) -> None:
    """Import plug-in modules (names or ``.py`` paths) once per process."""
    for imp in imports:
        if imp in _IMPORTED:
            continue
        if imp.endswith(".py") and not Path(imp).is_file():
            # a Dask worker on another machine: the client uploaded the file
            importlib.import_module(Path(imp).stem)
        elif imp.endswith(".py"):
            path = Path(imp).resolve()
            digest = hashlib.sha1(str(path).encode()).hexdigest()[:10]
            mod_name = "pathfuse_plugin_" + "".join(
                c if c.isalnum() else "_" for c in path.stem) + f"_{digest}"
            if mod_name not in sys.modules:
                spec = importlib.util.spec_from_file_location(mod_name, path)
                if spec is None or spec.loader is None:
                    raise ImportError(f"cannot import {path}")
                mod = importlib.util.module_from_spec(spec)
                sys.modules[mod_name] = mod
                try:
                    spec.loader.exec_module(mod)
                except BaseException:
                    del sys.modules[mod_name]
                    raise
        else:
            importlib.import_module(imp)
        _IMPORTED.add(imp)
