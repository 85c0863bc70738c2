"""Compiled kernels of the modulus fit: the closed-form (E, b) and sum of squares of a power law
``F = E k (u - c)^p + b`` -- and (E, w, b) of DMT -- at many contact points c, in one pass over the
data per point (no temporary arrays: 100 contact points on 300 samples in tens of microseconds).
The adhesive laws' kernels: :mod:`._adhesive_kernels`."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["ramp_weight", "scan_power_law", "search_power_law", "scan_dmt", "power_law_terms", "COMPILED"]


@njit(cache=True)
def ramp_weight(d, width):  # pragma: no cover - compiled
    """The weight of a sample at indentation ``d`` [m]: ramped up linearly over ``width`` [m] from the
    contact point, 1 beyond (``width`` <= 0: 1) -- :func:`afmforce.contact._weights.weights`, one sample."""
    if width > 0:
        return min(abs(d) / width, 1.0)
    return 1.0


@njit(cache=True)
def scan_power_law(u, F, cands, k, p, width):  # pragma: no cover - compiled
    """For each contact point ``cands[j]`` [m]: (E [Pa], b [N], weighted sum of squares [N^2]) of the
    weighted least-squares fit of ``F = E k max(u - c, 0)^p + b`` (weights as in fit._weights;
    sum of squares inf where E <= 0 or the system is singular)."""
    m = cands.size
    E = np.empty(m)
    b = np.empty(m)
    ssr = np.empty(m)
    ascending = True
    for j in range(1, m):
        if not cands[j] > cands[j - 1]:
            ascending = False
    if width <= 0 and ascending:
        return _scan_unweighted(u, F, cands, k, p, E, b, ssr)
    for j in range(m):
        c = cands[j]
        s0 = s1 = s2 = sy = sxy = syy = 0.0
        for i in range(u.size):
            d = u[i] - c
            q = ramp_weight(d, width)
            q = q * q
            if d <= 0:
                phi = 0.0
            elif p == 1.5:  # a power is ten times the cost of a square root
                phi = k * d * math.sqrt(d)
            elif p == 2.0:
                phi = k * d * d
            else:
                phi = k * d ** p
            f = F[i]
            s0 += q
            s1 += q * phi
            s2 += q * phi * phi
            sy += q * f
            sxy += q * phi * f
            syy += q * f * f
        E[j], b[j], ssr[j] = _candidate_line(s0, s1, s2, sy, sxy, syy)
    return E, b, ssr


@njit(cache=True, inline="always")
def _candidate_line(s0, s1, s2, sy, sxy, syy):  # pragma: no cover - compiled
    """One candidate's weighted line ``F = E phi + b`` from its sums: (E, b, SSR); SSR inf where
    E <= 0 or the sums are degenerate (NaN E, b then)."""
    det = s0 * s2 - s1 * s1
    if det > 0:
        e = (s0 * sxy - s1 * sy) / det
        bb = (s2 * sy - s1 * sxy) / det
        r = syy - e * sxy - bb * sy
        return e, bb, (r if (e > 0 and math.isfinite(r)) else np.inf)
    return np.nan, np.nan, np.inf


@njit(cache=True)
def _scan_unweighted(u, F, cands, k, p, E, b, ssr):  # pragma: no cover - compiled
    """:func:`scan_power_law` with unit weights and strictly ascending candidates, the same sums: the
    weight, force and force-squared sums do not depend on the contact point (computed once, in the same
    order), and a sample before a contact point adds zeros to its other sums (left out). Each sample adds
    its terms to the candidates below it (a prefix of the grid: the inner loop), so every candidate's
    sums still run over the samples in their order."""
    m = cands.size
    n = u.size
    s0 = sy = syy = 0.0
    for i in range(n):
        f = F[i]
        s0 += 1.0
        sy += f
        syy += f * f
    s1 = np.zeros(m)
    s2 = np.zeros(m)
    sxy = np.zeros(m)
    for i in range(n):
        ui = u[i]
        f = F[i]
        top = np.searchsorted(cands, ui)  # the candidates c < u[i]: u[i] - c > 0
        if p == 1.5:
            for j in range(top):
                d = ui - cands[j]
                phi = k * d * math.sqrt(d)
                s1[j] += phi
                s2[j] += phi * phi
                sxy[j] += phi * f
        elif p == 2.0:
            for j in range(top):
                d = ui - cands[j]
                phi = k * d * d
                s1[j] += phi
                s2[j] += phi * phi
                sxy[j] += phi * f
        else:
            for j in range(top):
                d = ui - cands[j]
                phi = k * d ** p
                s1[j] += phi
                s2[j] += phi * phi
                sxy[j] += phi * f
    for j in range(m):
        E[j], b[j], ssr[j] = _candidate_line(s0, s1[j], s2[j], sy, sxy[j], syy)
    return E, b, ssr


@njit(cache=True)
def search_power_law(u, F, cands, k, p, width, stride):  # pragma: no cover - compiled
    """The contact-point search of :func:`afmforce.contact.fit._linear_fit` for a power law, in one call:
    four rounds of :func:`scan_power_law`, each on the candidates made unique and sorted (``np.unique``),
    the first three on every ``stride``-th sample, the last on all; after each round the grid is 17 points
    (``np.linspace``, bit for bit) between the best candidate's neighbours. Returns ``(ok, c, E, b, ssr)``
    of the last round's best candidate; ``ok`` False where no candidate gives a positive modulus."""
    if stride > 1:
        us = np.ascontiguousarray(u[::stride])
        fs = np.ascontiguousarray(F[::stride])
    else:
        us = u
        fs = F
    c0 = e0 = b0 = s0 = np.nan
    for rnd in range(4):
        cands = np.unique(cands)
        if rnd < 3:
            E, b, ssr = scan_power_law(us, fs, cands, k, p, width)
        else:
            E, b, ssr = scan_power_law(u, F, cands, k, p, width)
        i = 0
        for j in range(1, ssr.size):  # np.argmin: the first smallest (no NaN here)
            if ssr[j] < ssr[i]:
                i = j
        if not math.isfinite(ssr[i]):
            return False, np.nan, np.nan, np.nan, np.inf
        c0, e0, b0, s0 = cands[i], E[i], b[i], ssr[i]
        left, right = cands[max(i - 1, 0)], cands[min(i + 1, cands.size - 1)]
        step = (right - left) / 16.0  # np.linspace(left, right, 17): i * step + left, the last right
        cands = np.empty(17)
        for j in range(17):
            cands[j] = j * step + left
        cands[16] = right
    return True, c0, e0, b0, s0


@njit(cache=True)
def scan_dmt(u, F, cands, k, g, width):  # pragma: no cover - compiled
    """DMT at each contact point ``cands[j]`` [m]: the weighted least-squares (E [Pa], w [J/m^2], b [N])
    of ``F = E k max(u - c, 0)^1.5 - w g [u > c] + b`` (k = 4/3 sqrt(R)/(1 - nu^2), g = 2 pi R) and its
    sum of squares [N^2]; w >= 0 (on the bound: the Hertz fit, w = 0); inf where E <= 0 or singular."""
    m = cands.size
    E = np.full(m, np.nan)
    W = np.zeros(m)
    B = np.full(m, np.nan)
    ssr = np.full(m, np.inf)
    f0 = 0.0
    for i in range(F.size):
        f0 += F[i]
    f0 /= F.size  # the force centred: the sums of squares without cancellation
    plain = width <= 0  # unit weights: only the points in contact need a loop
    order = np.argsort(u)
    us = u[order]
    fs = F[order] - f0
    n = u.size
    sy = 0.0
    syy = 0.0
    for i in range(n):
        sy += fs[i]
        syy += fs[i] * fs[i]
    for j in range(m):
        c = cands[j]
        s00 = s01 = s02 = s11 = s12 = s22 = y0 = y1 = y2 = yy = 0.0
        if plain:
            s22, y2, yy = float(n), sy, syy
            for i in range(np.searchsorted(us, c, side="right"), n):
                d = us[i] - c
                phi = k * d * math.sqrt(d)
                f = fs[i]
                s00 += phi * phi
                s01 -= phi * g
                s02 += phi
                s11 += g * g
                s12 -= g
                y0 += phi * f
                y1 -= g * f
        else:
            for i in range(n):
                d = us[i] - c
                q = ramp_weight(d, width)
                q = q * q
                if d > 0:
                    phi = k * d * math.sqrt(d)
                    psi = -g
                else:
                    phi = 0.0
                    psi = 0.0
                f = fs[i]
                s00 += q * phi * phi
                s01 += q * phi * psi
                s02 += q * phi
                s11 += q * psi * psi
                s12 += q * psi
                s22 += q
                y0 += q * phi * f
                y1 += q * psi * f
                y2 += q * f
                yy += q * f * f
        if not (s00 > 0 and s11 > 0 and s22 > 0):
            continue
        # unit diagonal (the columns differ by ~1e13), then Cramer's rule on the 3 x 3 system
        n0, n1, n2 = math.sqrt(s00), math.sqrt(s11), math.sqrt(s22)
        a01, a02, a12 = s01 / (n0 * n1), s02 / (n0 * n2), s12 / (n1 * n2)
        r0, r1, r2 = y0 / n0, y1 / n1, y2 / n2
        det = 1 + 2 * a01 * a02 * a12 - a01 * a01 - a02 * a02 - a12 * a12
        e = w = bb = 0.0
        ok = False
        if det > 1e-13:
            x0 = (r0 * (1 - a12 * a12) - a01 * (r1 - a12 * r2) + a02 * (a12 * r1 - r2)) / det
            x1 = ((r1 - a12 * r2) - r0 * (a01 - a12 * a02) + a02 * (a01 * r2 - a02 * r1)) / det
            x2 = ((r2 - a12 * r1) - a01 * (a01 * r2 - a02 * r1) + r0 * (a01 * a12 - a02)) / det
            if x1 >= 0:
                e, w, bb = x0 / n0, x1 / n1, x2 / n2
                ok = True
        if not ok:  # w on its bound: E and b alone
            det2 = 1 - a02 * a02
            if det2 <= 1e-13:
                continue
            x0 = (r0 - a02 * r2) / det2
            x2 = (r2 - a02 * r0) / det2
            e, w, bb = x0 / n0, 0.0, x2 / n2
        r = yy - (e * y0 + w * y1 + bb * y2)  # the normal equations hold for the solved parameters
        if e > 0 and math.isfinite(r):
            E[j] = e
            W[j] = w
            B[j] = bb + f0
            ssr[j] = max(r, 0.0)
    return E, W, B, ssr


@njit(cache=True)
def power_law_terms(u, F, E, c, b, k, p, width, jacobian):  # pragma: no cover - compiled
    """The shape ``phi``, the weighted residuals ``r = q (F - E phi - b)`` of the power law ``phi = k d^p`` (``p`` 1.5: ``k d
    sqrt(d)``, slope ``1.5 k sqrt(d)``; else ``k d d``, slope ``2 k d``; ``d = max(u - c, 0)``) and, with
    ``jacobian``, ``J = q [phi, -E dphi, 1]`` (n x 3), the weights ``q`` those of ``fit._weights(u - c, width)``:
    the modulus fit's Gauss-Newton terms in one pass, each sample's operations those of the numpy expressions in
    :func:`afmforce.contact.fit._linear_fit` (``models.shape_and_slope``) in their order, so the same numbers.
    Returns ``(r, J, phi)`` (``J`` empty without ``jacobian``)."""
    n = u.size
    r = np.empty(n)
    shape = np.empty(n)
    J = np.empty((n if jacobian else 0, 3))
    ne = -E
    for i in range(n):
        d = u[i] - c
        dd = d if (d >= 0.0 or d != d) else 0.0     # np.maximum(d, 0.0)
        if p == 1.5:
            sq = math.sqrt(dd)
            phi = k * dd * sq
            dphi = 1.5 * k * sq
        else:
            phi = k * dd * dd
            dphi = 2 * k * dd
        if width <= 0:
            q = 1.0
        else:
            a = abs(d) / width
            q = a if (a <= 1.0 or a != a) else 1.0  # np.minimum(a, 1.0)
        shape[i] = phi
        r[i] = q * (F[i] - E * phi - b)
        if jacobian:
            J[i, 0] = q * phi
            J[i, 1] = q * (ne * dphi)
            J[i, 2] = q * 1.0
    return r, J, shape


#: The kernels run compiled (False under ``NUMBA_DISABLE_JIT``: the callers keep their numpy path there).
COMPILED = hasattr(power_law_terms, "py_func")
