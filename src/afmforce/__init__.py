"""afmforce: dynamic surface force measurement with the atomic force microscope.

Physics of Attard, Carambassis & Rutland, Langmuir 15, 553 (1999): surface
forces, cantilever statics and dynamics with friction, a virtual AFM and the
analysis of measured force curves. SI units throughout.

The names below are imported on first use (PEP 562), so that ``import
afmforce`` -- and ``afmforce --help`` -- does not load numpy.
"""

from __future__ import annotations

import importlib
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
