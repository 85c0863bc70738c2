"""What the analyse view's plots need, and no more: per-sample arrays thinned to the screen.

A plot is at most a thousand or two pixels wide, so a curve of 10,000 samples (or a million)
is sent as at most ``max_points`` samples chosen per screen column: in each of ``max_points / 2``
equal runs of samples, the one of lowest and the one of highest signal (a jump-in or a spike
between two evenly spread samples is kept, as a min/max envelope draws it), plus the first and
last sample of every segment (approach, retract, dwell). The statistics (fits, adhesion, the
modulus) are computed by the analysis from every sample; only the drawing is thinned. Every
array of one curve is thinned with the same indices, so the rows of the page's CSV stay rows.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["screen_indices", "result_arrays", "raw_arrays"]


def screen_indices(signal, segment, max_points: int | None) -> np.ndarray:
    """Indices (sorted, unique) of at most about ``max_points`` samples of ``signal`` [any unit]
    that draw it as every sample would at ``max_points / 2`` screen columns: each column's lowest
    and highest sample, and the first and last sample of each run of ``segment`` (all samples
    when ``max_points`` is None or not smaller than the length). Non-finite values never win."""
    y = np.asarray(signal, dtype=float)
    n = y.size
    if not max_points or n <= max_points:
        return np.arange(n)
    columns = max(1, int(max_points) // 2 - 2)
    ok = np.isfinite(y)
    lo_y = np.where(ok, y, np.inf)
    hi_y = np.where(ok, y, -np.inf)
    column = (np.arange(n) * columns) // n               # the screen column of each sample
    starts = np.flatnonzero(np.r_[True, column[1:] != column[:-1]])
    # lowest and highest per column: argmin/argmax inside each equal run of samples
    order_lo = np.lexsort((lo_y, column))
    order_hi = np.lexsort((-hi_y, column))
    keep = [order_lo[starts], order_hi[starts]]
    seg = np.asarray(segment) if segment is not None and len(segment) == n else None
    if seg is not None:
        edges = np.flatnonzero(seg[1:] != seg[:-1])
        keep += [edges, edges + 1]
    keep.append(np.array([0, n - 1]))
    return np.unique(np.concatenate(keep))


def _listed(arr, idx) -> list:
    """``arr[idx]`` as a JSON-ready list (NaN and infinities -> None)."""
    a = np.asarray(arr)[idx]
    if a.dtype.kind == "f":
        out = a.astype(object)
        out[~np.isfinite(a)] = None
        return out.tolist()
    return a.tolist()


def result_arrays(res, max_points: int | None) -> dict[str, Any]:
    """The per-sample arrays of an :class:`~afmforce.analysis.pipeline.AnalysisResult`
    (``time``, ``position``, ``separation``, ``deflection``, ``force``, ``segment``), thinned
    with :func:`screen_indices` of the force (the deflection where the force is not known)."""
    force = np.asarray(res.force, dtype=float)
    signal = force if np.isfinite(force).any() else np.asarray(res.deflection, dtype=float)
    idx = screen_indices(signal, res.segment, max_points)
    return {name: _listed(getattr(res, name), idx) for name in res.ARRAYS}


def raw_arrays(curve, max_points: int | None) -> dict[str, Any]:
    """The raw signal of a :class:`~afmforce.io.RawCurve` against time and the piezo position,
    thinned with :func:`screen_indices` of the signal; ``unit`` the signal's, ``time_base``
    False when ``time`` is the sample index, ``position`` the stage position of a map's curve [m] (None when not given)."""
    piezo = curve.position()
    idx = screen_indices(curve.deflection_signal, curve.segment, max_points)
    return {"time": _listed(curve.time, idx), "piezo": _listed(piezo, idx),
            "signal": _listed(curve.deflection_signal, idx), "segment": _listed(curve.segment, idx),
            "unit": curve.deflection_unit,
            # False: the file has no time base, "time" is the sample index (the page says so)
            "time_base": not curve.metadata.get("time_is_sample_index", False),
            "position": [curve.metadata.get("position_x"), curve.metadata.get("position_y")]}
