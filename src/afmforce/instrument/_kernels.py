"""Compiled time loops of the virtual AFM (numba, ``cache=True``).

Hysteresis and relaxation operators carry a state from sample to sample, so
they are loops over time; everything else in :mod:`afmforce.instrument` is
vectorised numpy.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["play_superposition", "variable_play", "relaxation_forward", "relaxation_inverse"]


@njit(cache=True)
def play_superposition(x, thresholds, weights, linear_weight, state0):  # pragma: no cover - compiled
    """Prandtl-Ishlinskii operator ``y = p0 x + sum_i p_i F_{r_i}[x]``.

    ``F_r`` is the play (backlash) operator
    ``F_r[x](t_k) = min(x_k + r, max(x_k - r, F_r[x](t_{k-1})))`` whose
    initial outputs are ``state0``. Exact at the samples for inputs monotone
    between samples.
    """
    n = x.size
    m = thresholds.size
    state = state0.copy()
    out = np.empty(n)
    for k in range(n):
        xk = x[k]
        acc = linear_weight * xk
        for i in range(m):
            lo = xk - thresholds[i]
            hi = xk + thresholds[i]
            s = state[i]
            if s < lo:
                s = lo
            elif s > hi:
                s = hi
            state[i] = s
            acc += weights[i] * s
        out[k] = acc
    return out


@njit(cache=True)
def variable_play(x, half_width, y0):  # pragma: no cover - compiled
    """Play operator with a time-dependent half width ``r_k >= 0`` (backlash)."""
    n = x.size
    out = np.empty(n)
    s = y0
    for k in range(n):
        lo = x[k] - half_width[k]
        hi = x[k] + half_width[k]
        if s < lo:
            s = lo
        elif s > hi:
            s = hi
        out[k] = s
    return out


@njit(cache=True)
def _step_coefficients(h, tau):  # pragma: no cover - compiled
    """Exact first-order-hold update of ``tau dL/dt = x - L`` over a step h.

    ``L_k = e L_{k-1} + (1 - g) x_k + (g - e) x_{k-1}`` with ``e = exp(-h/tau)``
    and ``g = tau (1 - e) / h`` (x linear between samples).
    """
    if h <= 0.0:
        return 1.0, 1.0
    a = h / tau
    e = math.exp(-a)
    g = -math.expm1(-a) / a
    return e, g


@njit(cache=True)
def relaxation_forward(t, x, direct, weights, times):  # pragma: no cover - compiled
    """Linear relaxation (creep) operator, from rest at ``x[0]``.

    ``y = c0 x + sum_j c_j L_j[x]``, ``tau_j dL_j/dt = x - L_j``, ``L_j(t_0) = x(t_0)``.
    """
    n = x.size
    m = weights.size
    L = np.full(m, x[0])
    y = np.empty(n)
    acc = direct * x[0]
    for j in range(m):
        acc += weights[j] * L[j]
    y[0] = acc
    for k in range(1, n):
        h = t[k] - t[k - 1]
        acc = direct * x[k]
        for j in range(m):
            e, g = _step_coefficients(h, times[j])
            L[j] = e * L[j] + (1.0 - g) * x[k] + (g - e) * x[k - 1]
            acc += weights[j] * L[j]
        y[k] = acc
    return y


@njit(cache=True)
def relaxation_inverse(t, y, direct, weights, times):  # pragma: no cover - compiled
    """Exact inverse of :func:`relaxation_forward` on the same time grid."""
    n = y.size
    m = weights.size
    total = direct
    for j in range(m):
        total += weights[j]
    x = np.empty(n)
    x[0] = y[0] / total
    L = np.full(m, x[0])
    for k in range(1, n):
        h = t[k] - t[k - 1]
        known = 0.0
        gain = direct
        for j in range(m):
            e, g = _step_coefficients(h, times[j])
            known += weights[j] * (e * L[j] + (g - e) * x[k - 1])
            gain += weights[j] * (1.0 - g)
        xk = (y[k] - known) / gain
        for j in range(m):
            e, g = _step_coefficients(h, times[j])
            L[j] = e * L[j] + (1.0 - g) * xk + (g - e) * x[k - 1]
        x[k] = xk
    return x
