"""Names imported on first use: one helper for the packages' ``__init__`` modules (PEP 562).

A package re-exports its public names (``from zrp.gap import diagnose``) without importing the
modules that define them until a name is first used, so that ``import zrp`` and the command
line's ``zrp --help`` do not load SciPy, numba, MuJoCo or Dask for commands that do not run::

    _LAZY = {"diagnose": "zrp.gap.pipeline", "Foo": ("zrp.x", "Bar")}
    __getattr__, __dir__ = lazy_names(__name__, _LAZY)

An attribute that is not in the table but is a subpackage or submodule (``zrp.gap.report``)
is imported too, as ``import zrp.gap.report`` would.
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable, Mapping
from typing import Any

__all__ = ["lazy_names"]


def lazy_names(package: str, table: Mapping[str, str | tuple[str, str]]
               ) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """``(__getattr__, __dir__)`` for the module ``package`` serving the names of ``table``
    (name -> defining module, or (module, name there)); each is cached in the module once
    imported."""

    def getattr_(name: str) -> Any:
        entry = table.get(name)
        module = sys.modules[package]
        if entry is not None:
            mod, attr = (entry, name) if isinstance(entry, str) else entry
            value = getattr(importlib.import_module(mod), attr)
            setattr(module, name, value)
            return value
        if not name.startswith("__"):
            try:
                return importlib.import_module(f"{package}.{name}")
            except ModuleNotFoundError as exc:
                if exc.name != f"{package}.{name}":
                    raise
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    def dir_() -> list[str]:
        return sorted(set(vars(sys.modules[package])) | set(table))

    return getattr_, dir_
