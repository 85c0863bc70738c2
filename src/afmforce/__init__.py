"""afmforce: dynamic surface force measurement with the atomic force microscope.

Physics of Attard, Carambassis & Rutland, Langmuir 15, 553 (1999): surface
forces, cantilever statics and dynamics with friction, a virtual AFM and the
analysis of measured force curves. SI units throughout.
"""

from __future__ import annotations

from . import constants, errors, forces
from .cantilever import InclinedCantilever, SimpleSpring
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
