"""Compiled :func:`~afmforce.analysis.dynamic.dead_zone` for a run's speed (:meth:`.state.State.velocity`, issue 35).

The same operations as the numpy function (absolute first differences, second differences, three
medians, the first sample beyond the tolerance) in one call: medians select a sample (or average the
middle two, as numpy does), so the number is numpy's exactly. ``dynamic`` itself stays numpy: the
``fit`` command uses it and loads no numba.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["dead_zone"]


@njit(cache=True, nogil=True)
def dead_zone(zm):
    """:func:`afmforce.analysis.dynamic.dead_zone` of a finite 1-D float64 ``zm`` [-] (-1: a sample is not
    finite: the caller uses numpy's)."""
    n = zm.size
    for i in range(n):
        if not np.isfinite(zm[i]):
            return -1
    if n < 30:
        return 0
    d = np.empty(n - 1)  # np.diff(zm)
    pos = np.empty(n - 1)  # |d| > 0
    m = 0
    for i in range(n - 1):
        d[i] = zm[i + 1] - zm[i]
        a = abs(d[i])
        if a > 0:
            pos[m] = a
            m += 1
    step = np.median(pos[:m]) if m > 0 else 0.0
    d2 = np.empty(n - 2)  # np.diff(zm, 2)
    for i in range(n - 2):
        d2[i] = d[i + 1] - d[i]
    med = np.median(d2)
    for i in range(n - 2):
        d2[i] = abs(d2[i] - med)
    noise = np.median(d2) * 1.4826 / math.sqrt(6.0)
    tol = 0.5 * step + 4.0 * noise
    first = -1
    for i in range(n):
        if abs(zm[i] - zm[0]) > tol:
            first = i
            break
    if first < 0:
        return 0
    k = first - 1
    return k if k > 0 and n - k >= max(10, n // 3) else 0
