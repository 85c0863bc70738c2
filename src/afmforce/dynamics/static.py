"""Quasi-static deflection curves, including the unstable branch (spec sections 2-3).

The static (infinitely slow, friction-free) measurement obeys Hooke's law
``k z2 = Fs(h)`` with ``h = z2 - z``. Parametrised by the separation it is
explicit: ``z2 = Fs(h)/k``, ``z = z2 - h = Fs(h)/k - h``. A branch point is stable
where ``Fs'(h) < k``; the static jump-in is the largest ``h`` where
``Fs'(h) = k`` (the paper's Fig 1 and Fig 6 show the unstable part dashed).

For the inclined cantilever without friction the same holds with the
force-measuring spring constant of eq 13.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numpy.typing import ArrayLike

from .._validate import positive
from ..constants import HAMAKER, Z0
from ..errors import ParameterError
from ..forces import static_jump_in_separation, vdw_force, vdw_force_gradient
from ..surface_laws import LAWS
from ..surface_laws import reach as law_reach
from ..surface_laws import total_force

__all__ = ["StaticCurve", "static_curve", "static_deflection", "static_jump_in", "surface_jump_in",
           "surface_static_deflection", "surface_static_force"]


@dataclass(frozen=True)
class StaticCurve:
    """A static deflection curve, parametrised by the separation.

    Attributes
    ----------
    separation : ndarray
        h [m], increasing.
    piezo_position : ndarray
        Drive position z = z2 - h = Fs(h)/k - h [m] (h = z2 - z, spec 1).
    deflection : ndarray
        z2 = Fs(h)/k [m].
    force : ndarray
        Fs(h) [N].
    stable : ndarray of bool
        ``Fs'(h) < k``: the branch a slow measurement follows.
    jump_in_separation, jump_in_position, jump_in_deflection : float
        The static jump-in point (largest h with Fs' = k) [m]; NaN when the
        spring is stiffer than the steepest attraction.
    spring_constant : float
        k [N/m].
    """

    separation: np.ndarray
    piezo_position: np.ndarray
    deflection: np.ndarray
    force: np.ndarray
    stable: np.ndarray
    jump_in_separation: float
    jump_in_position: float
    jump_in_deflection: float
    spring_constant: float


def static_jump_in(spring_constant: float, radius: float, hamaker: float = HAMAKER,
                   z0: float = Z0) -> tuple[float, float, float]:
    """Static jump-in point ``(h_J, z_J, z2_J)`` [m] (spec section 2).

    ``h_J`` is the largest separation with ``Fs'(h) = k``; the drive position
    there is ``z_J = Fs(h_J)/k - h_J`` and the deflection ``Fs(h_J)/k``.
    All NaN when there is no mechanical instability.
    """
    k = positive("spring_constant", spring_constant, "N/m")
    return _jump_in(k, float(radius), float(hamaker), float(z0))


@lru_cache(maxsize=1024)
def _jump_in(k: float, radius: float, hamaker: float, z0: float) -> tuple[float, float, float]:
    """:func:`static_jump_in` for validated scalars, solved once per parameter set."""
    hj = float(static_jump_in_separation(k, radius, hamaker, z0))
    if not math.isfinite(hj):
        return math.nan, math.nan, math.nan
    dj = float(vdw_force(hj, radius, hamaker, z0)) / k
    return hj, dj - hj, dj


def static_curve(spring_constant: float, radius: float, hamaker: float = HAMAKER, z0: float = Z0,
                 separation: ArrayLike | None = None, h_max: float = 60e-9,
                 n: int = 2000) -> StaticCurve:
    """The static deflection curve with both stable and unstable parts.

    Parameters
    ----------
    spring_constant : float
        k [N/m] (for the inclined beam: eq 13).
    radius, hamaker, z0 : float
        Surface-force parameters of eq 2 [m, J, m].
    separation : array_like, optional
        Separations to evaluate [m]; default ``n`` points from ``0.8 z0``
        (inside the contact branch) to ``h_max``, denser near contact.
    """
    k = positive("spring_constant", spring_constant, "N/m")
    positive("radius", radius, "m")
    if separation is None:
        h = np.geomspace(0.8 * z0, max(h_max, 2 * z0), n)
    else:
        h = np.sort(np.asarray(separation, dtype=float).ravel())
        if h.size == 0 or np.any(h <= 0):
            raise ParameterError("separation values must be positive [m]")
    f = np.asarray(vdw_force(h, radius, hamaker, z0))
    d = f / k
    stable = np.asarray(vdw_force_gradient(h, radius, hamaker, z0)) < k
    hj, zj, dj = static_jump_in(k, radius, hamaker, z0)
    return StaticCurve(h, d - h, d, f, stable, hj, zj, dj, k)


def static_deflection(piezo_position: ArrayLike, spring_constant: float, radius: float,
                      hamaker: float = HAMAKER, z0: float = Z0):
    """Deflection on the out-of-contact stable branch at drive position z [m].

    Solves ``h + z - Fs(h)/k = 0`` for the largest root (the branch an approach
    follows before it jumps in). NaN where that branch no longer exists
    (``z >= z_J``). Without an instability (spring stiffer than any attractive
    gradient) the curve is single-valued and defined everywhere.

    Returns
    -------
    numeric
        z2 [m] (negative: attraction), same shape as ``piezo_position``.
    """
    k = positive("spring_constant", spring_constant, "N/m")
    z = np.asarray(piezo_position, dtype=float)
    hj, zj, _ = static_jump_in(k, radius, hamaker, z0)
    lo_h = hj if math.isfinite(hj) else 0.5 * z0
    lo = np.full(z.shape, lo_h)
    hi = lo_h + np.abs(z) + (abs(zj) if math.isfinite(zj) else 0.0) + abs(
        float(vdw_force(z0, radius, hamaker, z0))) / k + 1e-9
    hi = np.broadcast_to(hi, z.shape).copy()

    def g(h):
        return h + z - np.asarray(vdw_force(h, radius, hamaker, z0)) / k

    if z.ndim == 0:  # scalar: Brent's method on the same bracket
        from scipy.optimize import brentq

        zs = float(z)

        def gs(h):
            r6 = (z0 / h) ** 6
            return h + zs + (hamaker * radius / (12.0 * h * h)) * (1.0 - 0.25 * r6) / k

        lo_s, hi_s = float(lo), float(hi)
        if gs(lo_s) >= 0.0:   # only possible at the fold itself
            h = lo_s
        else:
            h = brentq(gs, lo_s, hi_s, xtol=1e-24, rtol=4 * np.finfo(float).eps, maxiter=200)
        d = h + zs
        return d if not math.isfinite(zj) or zs < zj else math.nan

    for _ in range(200):
        mid = 0.5 * (lo + hi)
        pos = g(mid) > 0
        hi = np.where(pos, mid, hi)
        lo = np.where(pos, lo, mid)
        if np.all(hi - lo <= 4e-16 * hi):
            break
    h = 0.5 * (lo + hi)
    d = h + z
    if math.isfinite(zj):
        d = np.where(z < zj, d, np.nan)
    return d[()] if d.ndim == 0 else d


# --- any surface (issue 25): the paper's eq 2 on the geometry, plus the double layer ----------
def surface_static_force(surface, h: ArrayLike):
    """(F(h) [N], F'(h) [N/m]) of a :class:`~afmforce.dynamics.parts.Surface`: eq 2 with its
    geometry (:attr:`Surface.paper_radius`) plus its double layer and the surface force laws of
    :mod:`afmforce.surface_laws` (drainage and drag vanish at rest)."""
    from ..forces import double_layer_force, double_layer_force_gradient
    s = surface
    r = s.paper_radius
    f = np.asarray(vdw_force(h, r, s.hamaker, s.z0), dtype=float)
    df = np.asarray(vdw_force_gradient(h, r, s.hamaker, s.z0), dtype=float)
    if s.double_layer != "none":
        args = (s.radius, s.surface_potential, s.debye_length, s.surface_potential_2,
                s.permittivity, s.double_layer, s.geometry)
        f = f + double_layer_force(h, *args)
        df = df + double_layer_force_gradient(h, *args)
    if s.laws:
        fl, dfl = total_force(h, s.radius_eff, s.law_values)
        f, df = f + fl, df + dfl
    return f, df


def surface_jump_in(spring_constant: float, surface) -> tuple[float, float, float]:
    """Static jump-in ``(h_J, z_J, z2_J)`` [m] of any surface (largest h with F'(h) = k).

    Without a double layer this is :func:`static_jump_in` with the geometry's radius (closed
    form); with one, F' is scanned on a fine logarithmic grid from the outside in and the
    crossing refined by Brent's method. NaN when there is no instability.
    """
    s = surface
    if s.eq2_only:
        return static_jump_in(spring_constant, s.paper_radius, s.hamaker, s.z0)
    return _surface_jump_in(float(spring_constant), s)


@lru_cache(maxsize=1024)
def _surface_jump_in(k: float, s) -> tuple[float, float, float]:
    from scipy.optimize import brentq
    # out to where the model's own laws (eq 2, the double layer) and twice the others' reach
    model = (law.reach({p.name: getattr(s, p.name) for p in law.parameters})
             for law in LAWS.values() if not law.compiled)
    hi = max(*model, 2.0 * law_reach(s.law_values))
    h = np.geomspace(0.5 * s.z0, hi, 6000)[::-1]
    _, df = surface_static_force(s, h)
    above = np.nonzero(df >= k)[0]
    if above.size == 0:
        return math.nan, math.nan, math.nan
    i = above[0]
    if i == 0:
        raise ParameterError("the surface force is steeper than the spring out to "
                             f"{hi * 1e9:.3g} nm: no static branch to start on")
    hj = brentq(lambda x: float(surface_static_force(s, x)[1]) - k, h[i], h[i - 1], xtol=1e-22,
                rtol=4 * np.finfo(float).eps)
    dj = float(surface_static_force(s, hj)[0]) / k
    return hj, dj - hj, dj


def surface_static_deflection(start: float, spring_constant: float, surface) -> float:
    """Deflection [m] on the out-of-contact static branch at drive position ``start`` (any surface)."""
    s = surface
    if s.eq2_only:
        return float(static_deflection(start, spring_constant, s.paper_radius, s.hamaker, s.z0))
    return _surface_start(float(start), float(spring_constant), s)


@lru_cache(maxsize=1024)
def _surface_start(start: float, k: float, s) -> float:
    from scipy.optimize import brentq
    hj, zj, _ = _surface_jump_in(k, s)
    if math.isfinite(zj) and start >= zj:
        return math.nan
    lo = hj if math.isfinite(hj) else 0.5 * s.z0

    def g(h):
        return h + start - float(surface_static_force(s, h)[0]) / k

    hi = max(-start, lo) + 1e-9
    while g(hi) <= 0.0:
        hi *= 2.0
    if g(lo) >= 0.0:
        return lo + start
    h = brentq(g, lo, hi, xtol=1e-24, rtol=4 * np.finfo(float).eps, maxiter=200)
    return h + start
