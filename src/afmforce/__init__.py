"""afmforce: dynamic surface force measurement with the atomic force microscope.

Physics of Attard, Carambassis & Rutland, Langmuir 15, 553 (1999): surface
forces, cantilever statics and dynamics with friction, a virtual AFM and the
analysis of measured force curves. SI units throughout.

The names below are imported on first use (PEP 562), so that ``import
afmforce`` -- and ``afmforce --help`` -- does not load numpy.
"""

from __future__ import annotations

import importlib
import importlib.util
import sys
from typing import Any

from . import errors
from .errors import AfmforceError

__version__ = "0.1.0"

__all__ = [
    "AfmforceError",
    "InclinedCantilever",
    "SimpleSpring",
    "constants",
    "errors",
    "forces",
    "__version__",
]

#: Public name -> module that defines it (``None``: the name is the module).
_LAZY = {"InclinedCantilever": "cantilever", "SimpleSpring": "cantilever", "constants": None, "forces": None}


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        module = importlib.import_module(f".{_LAZY[name] or name}", __name__)
        value = module if _LAZY[name] is None else getattr(module, name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))


class _GuardNumbaCache:
    """Import hook: once numba's caching module is imported, and before any kernel is decorated,
    afmforce's kernels get cache locators whose stamp covers every source a kernel may reach
    (:mod:`afmforce._jitcache`: an edit of a callee's file never leaves the old code cached).
    Imports nothing until numba is imported."""

    NAME = "numba.core.caching"

    def find_spec(self, name, path=None, target=None):
        if name != self.NAME:
            return None
        sys.meta_path.remove(self)
        spec = importlib.util.find_spec(name)
        if spec is not None and spec.loader is not None and hasattr(spec.loader, "exec_module"):
            run = spec.loader.exec_module

            def exec_module(module):
                run(module)
                try:
                    importlib.import_module(f"{__name__}._jitcache").install()
                except Exception:       # noqa: BLE001 - never break numba's import: its own stamps then
                    pass

            spec.loader.exec_module = exec_module
        return spec


def _guard_numba_cache() -> None:
    if _GuardNumbaCache.NAME in sys.modules:
        importlib.import_module(f"{__name__}._jitcache").install()
    elif not any(isinstance(f, _GuardNumbaCache) for f in sys.meta_path):
        sys.meta_path.insert(0, _GuardNumbaCache())


_guard_numba_cache()
