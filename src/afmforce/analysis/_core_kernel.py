"""Compiled kernels of the pipeline's core steps (issue 35 item 2): one call for what took a dozen numpy calls.

:func:`dead_zone_kernel` is :func:`afmforce.analysis.dynamic.dead_zone` (a run's speed reads it on every
measured channel). Medians and differences are exact whatever the order of the pass, and the arithmetic
is numpy's in the same order, so the numbers are those of the numpy code, which stays the reference
(tests/analysis/test_core_kernels.py) and the path where numba's JIT is off (:data:`COMPILED`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["dead_zone_kernel", "COMPILED"]


@njit(cache=True, nogil=True)
def dead_zone_kernel(zm: np.ndarray) -> int:
    """:func:`~afmforce.analysis.dynamic.dead_zone` of a float64 array of 30 samples or more [-]."""
    n = zm.size
    d = np.empty(n - 1)
    m = 0
    for i in range(n - 1):
        v = abs(zm[i + 1] - zm[i])
        d[i] = v
        if v > 0:
            m += 1
    step = 0.0
    if m:
        pos = np.empty(m)
        m = 0
        for i in range(n - 1):
            if d[i] > 0:
                pos[m] = d[i]
                m += 1
        step = np.median(pos)
    d2 = np.empty(n - 2)
    for i in range(n - 2):
        d2[i] = (zm[i + 2] - zm[i + 1]) - (zm[i + 1] - zm[i])
    mid = np.median(d2)
    for i in range(n - 2):
        d2[i] = abs(d2[i] - mid)
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


#: The kernels run compiled (False under ``NUMBA_DISABLE_JIT``, where they are plain Python).
COMPILED = hasattr(dead_zone_kernel, "py_func")
