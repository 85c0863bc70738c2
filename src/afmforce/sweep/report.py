"""The JSON report of an analysis of files: what ``afmforce analyze --json`` prints and
``POST /api/analyze`` (afmforce.web) returns, built once here for both.

>>> payload = analysis_json(result)          # doctest: +SKIP
>>> sorted(payload)                          # doctest: +SKIP
['failed', 'oscillation_origin', 'results']
"""

from __future__ import annotations

import json
import math
import re
from typing import Any

from .. import errors as _errors
from .results import BatchResult
from .summary import failures, summary_table

__all__ = ["analysis_json", "clean_error", "oscillation_origin_of"]


def _afmforce_errors() -> set[str]:
    """The names of every :class:`~afmforce.errors.AfmforceError` subclass, those outside
    :mod:`afmforce.errors` too (``io._guard.FileTimeoutError``, a reader's past its
    ``--file-timeout``: it was shown as "unexpected FileTimeoutError")."""
    names, todo = set(), [_errors.AfmforceError]
    while todo:
        cls = todo.pop()
        names.add(cls.__name__)
        todo.extend(cls.__subclasses__())
    return names


def clean_error(error: str) -> str:
    """``FileFormatError: msg`` -> ``msg``; other exception types are marked unexpected."""
    name, sep, rest = error.partition(": ")
    if sep and name in _afmforce_errors():
        return rest
    if sep and re.fullmatch(r"\w+(Error|Exception)", name):
        return f"unexpected {error}"
    return error


def oscillation_origin_of(ok) -> tuple[str, str] | None:
    """``(origin, verdict)`` of the oscillations across the curves of a summary table (None: < 2 curves)."""
    from ..analysis.oscillation import oscillation_origin

    if len(ok) < 2:
        return None
    freqs, vels = [], []
    for run in ("approach", "retract"):
        f, v = ok[f"oscillation_{run}_frequency"].to_numpy(float), ok[f"oscillation_{run}_velocity"].to_numpy(float)
        found = [i for i in range(len(f)) if math.isfinite(f[i])]
        freqs += [f[i] for i in found]
        vels += [v[i] for i in found]
    return oscillation_origin(freqs, vels)


def analysis_json(result: BatchResult, table=None) -> dict[str, Any]:
    """``{"results": {name: result JSON}, "failed": [{file, curve?, error}], "oscillation_origin"?}``.

    ``result`` is an :func:`~afmforce.sweep.files.analyze_files` batch run with
    ``keep_json=True``; values are SI (units under each result's ``units``). ``table``: its
    ``summary_table(result, with_json=True)`` when the caller has it already.
    """
    table = summary_table(result, with_json=True) if table is None else table
    ok = table[table["error"].isna()]
    payload: dict[str, Any] = {"results": {row["name"]: json.loads(row["json"]) for _, row in ok.iterrows()},
                               "failed": []}
    for name, error in failures(result):
        file, _, curve = name.rpartition("#") if re.search(r"#\d+$", name) else (name, "", "")
        entry: dict[str, Any] = {"file": file}
        if curve:
            entry["curve"] = int(curve)
        payload["failed"].append({**entry, "error": clean_error(error)})
    origin = oscillation_origin_of(ok)
    if origin is not None:
        payload["oscillation_origin"] = {"origin": origin[0], "verdict": origin[1]}
    return payload
