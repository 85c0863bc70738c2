"""``np.median`` of a 1-D float64 array through one ``np.partition`` call: the same number, bit for bit.

``np.median`` spends ~15-20 us in its wrappers (``_ureduce``, ``mean`` of the middle pair, the NaN
check) on any array, where the partition itself of a curve's few hundred samples costs 2-5 us; the
pipeline's own checks (the orientation, the sign, the glitches, the position's trend) take a dozen
medians a curve (issue 35). :func:`median` partitions at numpy's own ``kth`` (the middle one or two
and the last, where a NaN goes), so the partitioned array is numpy's, and averages the middle pair
as ``np.mean`` does (their sum from the identity +0.0, over two: a median of -0.0 is +0.0).
"""

from __future__ import annotations

import numpy as np

__all__ = ["median"]


def median(a: np.ndarray) -> float:
    """``float(np.median(a))`` (the same number; NaN when ``a`` holds a NaN) without numpy's wrappers.

    Other than 1-D float64 arrays (and empty ones) go to ``np.median`` itself."""
    a = np.asarray(a)
    n = a.size
    if a.ndim != 1 or a.dtype != np.float64 or n == 0:
        return float(np.median(a))
    h = n // 2
    if n % 2:
        p = np.partition(a, [h, -1])
        m = p[h] + 0.0
    else:
        p = np.partition(a, [h - 1, h, -1])
        m = (p[h - 1] + p[h] + 0.0) / 2.0
    if p[-1] != p[-1]:  # numpy's NaN check: a NaN sorts last
        return float("nan")
    return float(m)
