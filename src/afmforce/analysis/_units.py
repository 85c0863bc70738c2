"""Units of the step results (``AnalysisResult.details``), declared once as field metadata.

A numeric field of a step's result dataclass is declared ``name: float = unit("m")``
(``unit("m", default)`` with a default); ``{signal}`` stands for the unit of the
raw deflection signal (``V``, ``m`` or ``N``), known only with the curve.
:func:`units_of` reads them back, recursively, for the JSON output.
"""

from __future__ import annotations

import dataclasses
from typing import Any

__all__ = ["unit", "units_of"]


def unit(symbol: str, default: Any = dataclasses.MISSING) -> Any:
    """A dataclass field whose metadata states its SI unit (``""``: a plain number or a count)."""
    return dataclasses.field(default=default, metadata={"unit": symbol})


def units_of(obj: Any, signal: str = "") -> Any:
    """Field -> unit of a result dataclass (nested records give nested dicts; ``{signal}`` filled in).

    Fields without a unit (words, flags) are left out.
    """
    if isinstance(obj, (list, tuple)):
        return units_of(obj[0], signal) if obj and dataclasses.is_dataclass(obj[0]) else None
    if not (dataclasses.is_dataclass(obj) and not isinstance(obj, type)):
        return None
    out: dict[str, Any] = {}
    for f in dataclasses.fields(obj):
        if "unit" in f.metadata:
            out[f.name] = f.metadata["unit"].replace("{signal}", signal or "signal unit")
        else:
            nested = units_of(getattr(obj, f.name), signal)
            if nested:
                out[f.name] = nested
    return out
