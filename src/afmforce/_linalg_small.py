"""Small dense linear systems for the compiled fits (numba): Gaussian elimination with partial
pivoting, the one implementation shared by the layers (the contact fits below the analysis, the
analysis' drift and fringe fits above them; docs/architecture.md).

For a few unknowns (the normal equations of 2 to 5 parameters, solved once per Levenberg-Marquardt
or IRLS step) a loop in the kernel costs less than a call into LAPACK and allocates nothing.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["solve_small", "solve_small_in_place"]


@njit(cache=True)
def solve_small_in_place(M, y):  # pragma: no cover - compiled
    """``M z = y`` by Gaussian elimination with partial pivoting, in place: ``M`` is overwritten by
    its elimination and ``y`` by the solution z. Returns False, with ``M`` and ``y`` undefined, when
    a pivot is zero or NaN (singular)."""
    n = y.size
    for col in range(n):
        piv = col
        for i in range(col + 1, n):
            if abs(M[i, col]) > abs(M[piv, col]):
                piv = i
        if not abs(M[piv, col]) > 0.0:
            return False
        if piv != col:
            for k in range(n):
                M[col, k], M[piv, k] = M[piv, k], M[col, k]
            y[col], y[piv] = y[piv], y[col]
        for i in range(col + 1, n):
            f = M[i, col] / M[col, col]
            for k in range(col, n):
                M[i, k] -= f * M[col, k]
            y[i] -= f * y[col]
    for i in range(n - 1, -1, -1):
        acc = y[i]
        for k in range(i + 1, n):
            acc -= M[i, k] * y[k]
        y[i] = acc / M[i, i]
    return True


@njit(cache=True)
def solve_small(A, b):  # pragma: no cover - compiled
    """``A x = b`` by :func:`solve_small_in_place` on copies (``A`` and ``b`` are not changed): x, or
    NaN everywhere when a pivot is zero or NaN (singular)."""
    M = A.copy()
    v = b.copy()
    if not solve_small_in_place(M, v):
        return np.full(b.size, np.nan)
    return v
