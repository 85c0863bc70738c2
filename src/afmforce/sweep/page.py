"""A sweep's result as JSON rows and as one self-contained HTML page.

:func:`sweep_payload` is the JSON the web Sweep view draws (``afmforce serve``: the job's
result); :func:`write_page` writes the same payload into ``results.html``, a page with no
network access and no external script that plots any output column against the swept
parameters and lists the runs: the file to keep or mail once the server is gone.

>>> paths = result.write("sweeps/fig5", units)      # doctest: +SKIP
>>> paths["html"]                                    # doctest: +SKIP
PosixPath('sweeps/fig5/results.html')
"""

from __future__ import annotations

import html
import json
import math
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from .._files import atomic_write_text

__all__ = ["sweep_payload", "write_page", "PAGE_ROWS"]

#: The most runs embedded in the page (a larger sweep: the first ones; every run is in results.csv).
PAGE_ROWS = 20_000
_TEMPLATE = Path(__file__).with_name("page.html")


def _cell(v: Any) -> Any:
    """A table cell as JSON: finite floats, ints, text; NaN and infinities as null."""
    if isinstance(v, (float, np.floating)):
        return float(v) if math.isfinite(v) else None
    if isinstance(v, np.integer):
        return int(v)
    if isinstance(v, np.bool_):
        return bool(v)
    return v if v is None or isinstance(v, (int, str, bool)) else str(v)


def sweep_payload(result: Any, units: Mapping[str, str] | None = None, *,
                  max_rows: int | None = None) -> dict[str, Any]:
    """A :class:`~afmforce.sweep.results.SweepResult` as JSON-ready rows (SI values;
    ``units``: column -> unit).

    Returns ``{"n_runs", "n_failed", "chunks_run", "chunks_skipped", "parameters",
    "columns", "units", "rows"}``; ``rows`` holds the first ``max_rows`` runs (all when None).
    """
    units = dict(units or {})
    table = result.table if max_rows is None else result.table.head(int(max_rows))
    columns = [str(c) for c in table.columns]
    return {"n_runs": int(len(result.table)), "n_failed": int(result.n_failed),
            "chunks_run": int(result.chunks_run), "chunks_skipped": int(result.chunks_skipped),
            "parameters": [str(p) for p in result.parameter_names], "columns": columns,
            "units": {c: units.get(c, "") for c in columns},
            "rows": [[_cell(v) for v in row] for row in table.itertuples(index=False)]}


def _fixed(result: Any, units: Mapping[str, str]) -> list[list[str]]:
    spec = result.spec
    if spec is None:
        return []
    return [[str(k), str(v), units.get(k, "")] for k, v in spec.fixed]


def write_page(result: Any, path: str | Path, units: Mapping[str, str] | None = None, *,
               title: str = "afmforce sweep", max_rows: int = PAGE_ROWS) -> Path:
    """Write the sweep as one self-contained HTML page (atomically); returns its path.

    The page embeds :func:`sweep_payload` (at most ``max_rows`` runs) and the fixed settings;
    it draws the chosen output against the first swept parameter, one line per value of the
    second, and a table of the runs.
    """
    units = dict(units or {})
    data = {**sweep_payload(result, units, max_rows=max_rows), "fixed": _fixed(result, units)}
    text = json.dumps(data, allow_nan=False, separators=(",", ":")).replace("</", "<\\/")
    page = (_TEMPLATE.read_text(encoding="utf-8").replace("__TITLE__", html.escape(title))
            .replace("/*__DATA__*/null", text))
    return atomic_write_text(path, page, force=True)
