"""Worm-like-chain fits of a tether's rise before its rupture (single-molecule force spectroscopy).

The force of a worm-like chain of contour length ``L`` and persistence length ``p`` held at extension
``x`` (:func:`wlc_force`), in the interpolation of Marko & Siggia (Macromolecules 28, 8759 (1995))

    F = kT / p (1 / (4 (1 - x/L)^2) - 1/4 + x/L)

or with the seven-term correction of Bouchiat et al. (Biophys. J. 76, 409 (1999), their eq 11, within
0.01 % of the exact chain): ``+ sum_{i=2..7} a_i (x/L)^i`` (:data:`BOUCHIAT`).

:func:`fit_rise` fits ``L`` and ``p`` to the samples of one rise (extension: the tip--sample separation of a
hard contact; force: the pull, > 0), with a force offset (the zero of force under the rise: the drift
line's error shifts it by about a pN, which, fixed at 0, put virtual tethers' L_c and l_p up to 3.8 standard
errors off; the curve's zero counts as one more sample, so a rise without a slack part, a sawtooth's, cannot
trade the offset freely against l_p), by least squares: ``kT/p`` and the offset enter linearly and are profiled out on a grid of
``L`` (no starting guess to give), the three are then refined jointly (:func:`scipy.optimize.least_squares`)
and the standard errors are those of the linearised fit with the residual variance (at least the
baseline noise). A parameter the rise cannot determine is NaN with the
reason (:attr:`WlcFit.reason`): too few samples, too short an extension relative to ``L``
(the entropic regime determines only ``p L``), a parameter at the bound of its search range, or a
standard error over :data:`MAX_RELATIVE_ERROR` of the value -- never a tight interval.

The temperature is the file's (``temperature`` in its metadata, or ``--meta temperature=...``), else
:data:`~afmforce.constants.DEFAULT_TEMPERATURE` (295 K, the one default of afmforce's kT, the thermal
calibration's too).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from ..constants import DEFAULT_TEMPERATURE
from ..errors import ParameterError
from ..forces import KB
from ._units import unit as _u
from .options import AdhesionOptions

__all__ = ["WLC_MODELS", "BOUCHIAT", "WlcFit", "wlc_force", "fit_rise", "loading_rate", "MIN_POINTS",
           "MIN_EXTENSION_RATIO", "MAX_RELATIVE_ERROR", "PERSISTENCE_RANGE", "DEFAULT_TEMPERATURE"]

#: The chain models: the choices of ``AdhesionOptions.wlc_model`` (declared there).
WLC_MODELS = tuple(next(f for f in dataclasses.fields(AdhesionOptions) if f.name == "wlc_model").metadata["choices"])
#: Bouchiat et al. (1999) eq 11: a_2 .. a_7 of the polynomial added to Marko--Siggia's interpolation [-].
BOUCHIAT = (-0.5164228, -2.737418, 16.07497, -38.87607, 39.49944, -14.17718)
#: A rise of fewer samples determines nothing [-].
MIN_POINTS = 10
#: The rise must reach this fraction of the contour length; below it the chain is in its entropic, linear
#: regime (F ~ 3 kT x / (2 p L)), which fixes only the product p L [-].
MIN_EXTENSION_RATIO = 0.5
#: A parameter whose standard error exceeds this fraction of its value is undetermined [-].
MAX_RELATIVE_ERROR = 1.0 / 3.0
#: Search range of the persistence length [m]: from under a chemical bond (C-C: 0.154 nm; a chain's l_p is at
#: least about one: polypeptides 0.3-0.4 nm, PEG 0.38 nm) to beyond double-stranded DNA's 50 nm.
PERSISTENCE_RANGE = (0.1e-9, 200e-9)
#: Search range of the contour length, in multiples of the largest extension fitted [-].
CONTOUR_RANGE = (1.0 + 1e-4, 20.0)


def _shape(r: np.ndarray, model: str) -> np.ndarray:
    """F p / kT at relative extension r = x / L (< 1)."""
    g = 0.25 / (1.0 - r) ** 2 - 0.25 + r
    if model == "bouchiat":
        g = g + sum(a * r ** (i + 2) for i, a in enumerate(BOUCHIAT))
    return g


def _dshape(r: np.ndarray, model: str) -> np.ndarray:
    """d(F p / kT)/dr."""
    d = 0.5 / (1.0 - r) ** 3 + 1.0
    if model == "bouchiat":
        d = d + sum((i + 2) * a * r ** (i + 1) for i, a in enumerate(BOUCHIAT))
    return d


def _d2shape(r: float, model: str) -> float:
    """d^2(F p / kT)/dr^2."""
    d = 1.5 / (1.0 - r) ** 4
    if model == "bouchiat":
        d = d + sum((i + 2) * (i + 1) * a * r ** i for i, a in enumerate(BOUCHIAT))
    return d


def wlc_force(extension: np.ndarray | float, contour_length: float, persistence_length: float,
              temperature: float = DEFAULT_TEMPERATURE, model: str = "marko-siggia") -> np.ndarray:
    """Worm-like-chain force [N]: Marko--Siggia's interpolation, or with Bouchiat's correction.

    ``F = kT / p (1 / (4 (1 - x/L)^2) - 1/4 + x/L [+ sum a_i (x/L)^i])`` for ``0 <= x < L``.

    Parameters
    ----------
    extension : float or ndarray  end-to-end distance x [m]
    contour_length : float  L [m]
    persistence_length : float  p [m]
    temperature : float  T [K]
    model : str  ``"marko-siggia"`` or ``"bouchiat"``
    """
    if model not in WLC_MODELS:
        raise ParameterError(f"wlc_model {model!r} is not a worm-like-chain model; choose one of {WLC_MODELS}")
    r = np.clip(np.asarray(extension, float) / contour_length, 0.0, None)
    if np.any(r >= 1.0):
        raise ParameterError("extension reaches the contour_length: the worm-like chain's force diverges there; "
                             "give extensions below the contour length")
    return KB * temperature / persistence_length * _shape(r, model)


@dataclass(frozen=True)
class WlcFit:
    """A worm-like-chain fit of one rise (NaN: undetermined, :attr:`reason` says why).

    Attributes
    ----------
    contour_length, contour_length_se : float  L_c and its standard error [m]
    persistence_length, persistence_length_se : float  l_p and its standard error [m]
    temperature : float  T of kT [K]
    model : str  the chain model (:data:`WLC_MODELS`)
    points : int  samples fitted [-]
    extension_max : float  largest extension fitted [m]
    rms : float  residual rms of the fit [N]
    reason : str  why L_c or l_p is undetermined ('' when both are determined)
    slope, slope_se : float  the fitted chain's stiffness dF/dx at the last sample given and its standard
        error [N/m] (NaN: undetermined)
    force_offset, force_offset_se : float  the zero of force fitted with the chain (the pull measured is the
        chain's plus this) and its standard error [N]
    parallel : int  later chains, pulled in parallel, whose fitted forces were taken out of this rise [-]
    """

    contour_length: float = _u("m")
    contour_length_se: float = _u("m")
    persistence_length: float = _u("m")
    persistence_length_se: float = _u("m")
    temperature: float = _u("K")
    model: str = "marko-siggia"
    points: int = _u("", 0)
    extension_max: float = _u("m", math.nan)
    rms: float = _u("N", math.nan)
    reason: str = ""
    slope: float = _u("N/m", math.nan)
    slope_se: float = _u("N/m", math.nan)
    force_offset: float = _u("N", math.nan)
    force_offset_se: float = _u("N", math.nan)
    parallel: int = _u("", 0)

    @property
    def determined(self) -> bool:
        """Both L_c and l_p determined."""
        return math.isfinite(self.contour_length) and math.isfinite(self.persistence_length)

    def chain(self, extension: np.ndarray) -> np.ndarray:
        """The fitted chain's own pull at ``extension`` [N] (no offset; NaN where undetermined or beyond L_c)."""
        x = np.asarray(extension, float)
        out = np.full(x.shape, math.nan)
        if not self.determined:
            return out
        r = np.clip(x / self.contour_length, 0.0, None)
        ok = r < 1.0
        out[ok] = KB * self.temperature / self.persistence_length * _shape(r[ok], self.model)
        return out

    def stiffness(self, extension: float) -> float:
        """dF/dx of the fitted chain at ``extension`` [N/m] (NaN where undetermined or beyond L_c)."""
        if not self.determined or not extension < self.contour_length:
            return math.nan
        r = np.array(max(extension, 0.0) / self.contour_length)
        return float(KB * self.temperature / self.persistence_length * _dshape(r, self.model) / self.contour_length)

    def force(self, extension: np.ndarray) -> np.ndarray:
        """The fitted pull at ``extension`` [N]: the chain's plus the offset (NaN where undetermined or beyond
        L_c; with ``parallel``, the later chains' forces come on top: :func:`~.tethers.fit_tethers`)."""
        return self.chain(extension) + (self.force_offset if math.isfinite(self.force_offset) else 0.0)


def _undetermined(reason: str, temperature: float, model: str, n: int, xmax: float = math.nan,
                  rms: float = math.nan) -> WlcFit:
    return WlcFit(math.nan, math.nan, math.nan, math.nan, temperature, model, n, xmax, rms, reason)


def fit_rise(x: np.ndarray, f: np.ndarray, temperature: float = DEFAULT_TEMPERATURE, model: str = "marko-siggia",
             noise: float = 0.0) -> WlcFit:
    """Contour and persistence lengths of one rise, with standard errors (NaN and a reason: undetermined).

    Parameters
    ----------
    x : ndarray  extension of the chain (tip--sample separation) [m]
    f : ndarray  its pull [N] (> 0 where taut)
    temperature : float  [K]
    model : str  :data:`WLC_MODELS`
    noise : float  force noise of one sample [N] (the residual's scale is at least this)
    """
    from scipy.optimize import least_squares

    if model not in WLC_MODELS:
        raise ParameterError(f"wlc_model {model!r} is not a worm-like-chain model; choose one of {WLC_MODELS}")
    x, f = np.asarray(x, float), np.asarray(f, float)
    keep = np.isfinite(x) & np.isfinite(f) & (x > 0)
    x, f = x[keep], f[keep]
    n = int(x.size)
    if n < MIN_POINTS:
        return _undetermined(f"too few samples in the rise ({n} < {MIN_POINTS})", temperature, model, n)
    xmax = float(x.max())
    kt = KB * temperature

    def shape(L: float) -> np.ndarray:
        return _shape(x / L, model)

    ones = np.ones_like(x)

    def profile(L: float) -> tuple[float, float, float]:   # best kT/p and offset for this L (linear), the residuals
        g = shape(L)
        (a, c), *_ = np.linalg.lstsq(np.column_stack([g, ones]), f, rcond=None)
        return float(a), float(c), float(np.sum((f - a * g - c) ** 2))

    grid = xmax * np.exp(np.linspace(math.log(CONTOUR_RANGE[0]), math.log(CONTOUR_RANGE[1]), 240))
    rss = [profile(L)[2] for L in grid]
    i = int(np.argmin(rss))
    L0 = float(grid[i])
    a0, c0, _ = profile(L0)
    p_lo, p_hi = PERSISTENCE_RANGE
    p0 = float(np.clip(kt / a0, p_lo * 1.01, p_hi / 1.01)) if a0 > 0 else p_hi / 1.01
    big = 1e3 * (float(np.ptp(f)) + noise) * 1e12   # the offset's range [pN]: free
    lo = np.array([xmax * CONTOUR_RANGE[0] * 1e9, p_lo * 1e9, -big])
    hi = np.array([xmax * CONTOUR_RANGE[1] * 1e9, p_hi * 1e9, big])

    def resid(q: np.ndarray) -> np.ndarray:   # q: L, p in nm, the offset in pN; the zero of force: one more sample
        return np.append((kt / (q[1] * 1e-9) * _shape(x / (q[0] * 1e-9), model) - f) * 1e12 + q[2], q[2])   # pN

    q0 = np.clip(np.array([L0 * 1e9, p0 * 1e9, c0 * 1e12]), lo + 1e-9 * np.abs(lo), hi - 1e-9 * np.abs(hi))
    sol = least_squares(resid, q0, bounds=(lo, hi), x_scale="jac", xtol=1e-12, ftol=1e-12, gtol=1e-12)
    L, p, c = float(sol.x[0]) * 1e-9, float(sol.x[1]) * 1e-9, float(sol.x[2]) * 1e-12
    r = x / L
    g = _shape(r, model)
    res = kt / p * g + c - f
    rms = float(math.sqrt(np.mean(res ** 2)))
    s2 = max(float(res @ res) / max(n - 3, 1), noise ** 2)
    # Jacobian of the model in (L, p, offset) [N/m, N/m, 1]
    jac = np.column_stack([kt / p * _dshape(r, model) * (-x / L ** 2), -kt / p ** 2 * g, ones])
    try:
        cov = s2 * np.linalg.inv(jac.T @ jac + np.diag([0.0, 0.0, 1.0]))   # the zero's sample: a row (0, 0, 1)
    except np.linalg.LinAlgError:
        cov = np.full((3, 3), math.inf)
    se = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    ratio = xmax / L
    at_bound = [name for name, v, a, b in (("L_c", sol.x[0], lo[0], hi[0]), ("l_p", sol.x[1], lo[1], hi[1]))
                if v <= a * (1 + 1e-3) or v >= b * (1 - 1e-3)]
    if at_bound == ["l_p"] and sol.x[1] <= lo[1] * (1 + 1e-3):
        return _undetermined(
            f"l_p falls to {p_lo * 1e9:g} nm, under a chemical bond's length: the rise is no single worm-like chain "
            "(several in parallel, or no chain)", temperature, model, n, xmax, rms)
    if at_bound:
        return _undetermined(
            f"{' and '.join(at_bound)} at the bound of the search range (L_c up to {CONTOUR_RANGE[1]:g} x the "
            f"largest extension, l_p {p_lo * 1e9:g} to {p_hi * 1e9:g} nm): the rise does not fix it",
            temperature, model, n, xmax, rms)
    if ratio < MIN_EXTENSION_RATIO:
        return _undetermined(
            f"too short an extension: the rise reaches {ratio:.2f} of the contour length (< {MIN_EXTENSION_RATIO:g}), "
            "where the chain's force fixes only l_p x L_c", temperature, model, n, xmax, rms)
    # the chain's stiffness at the last sample, with its error from the covariance of (L, p)
    xe, re_ = float(x[-1]), float(x[-1]) / L
    slope = kt / p * _dshape(np.array(re_), model) / L
    d2 = float(_d2shape(re_, model))
    grad = np.array([kt / p * (-d2 * xe / L ** 3 - float(_dshape(np.array(re_), model)) / L ** 2), -slope / p, 0.0])
    slope_se = float(math.sqrt(max(float(grad @ cov @ grad), 0.0))) if np.all(np.isfinite(cov)) else math.inf
    slope = float(slope)
    if not slope_se <= MAX_RELATIVE_ERROR * abs(slope):
        slope, slope_se = math.nan, math.nan
    loose = [(name, e / v) for name, v, e in (("L_c", L, se[0]), ("l_p", p, se[1]))
             if not (math.isfinite(e) and e <= MAX_RELATIVE_ERROR * v)]
    reason = ""
    if loose:
        reason = (" and ".join(f"{name} to +-{rel:.0%}" for name, rel in loose)
                  + f" only (more than {MAX_RELATIVE_ERROR:.0%}): undetermined ({n} samples reaching {ratio:.2f} of L_c)")
        reason = "the rise determines " + reason
    lc, lc_se = (math.nan, math.nan) if any(nm == "L_c" for nm, _ in loose) else (L, float(se[0]))
    lp, lp_se = (math.nan, math.nan) if any(nm == "l_p" for nm, _ in loose) else (p, float(se[1]))
    return WlcFit(lc, lc_se, lp, lp_se, temperature, model, n, xmax, rms, reason, slope, slope_se, c, float(se[2]))


def loading_rate(t: np.ndarray, f: np.ndarray, noise: float = 0.0) -> tuple[float, float, str]:
    """Slope of the pull against time at the last sample [N/s], its standard error, and why it is
    undetermined ('' when determined): a parabola through the samples (the chain's force steepens towards
    the rupture: a line reads the window's middle, 30 % low on a virtual tether), its derivative at the last.

    Parameters
    ----------
    t : ndarray  times [s] of the last attached samples before a rupture
    f : ndarray  the pull there [N] (> 0)
    noise : float  force noise of one sample [N] (the residual's scale is at least this)
    """
    t, f = np.asarray(t, float), np.asarray(f, float)
    ok = np.isfinite(t) & np.isfinite(f)
    t, f = t[ok], f[ok]
    if t.size < 5 or not np.ptp(t) > 0:
        return math.nan, math.nan, f"too few timed samples before the rupture ({t.size})"
    tc = t - t[-1]
    a = np.column_stack([tc ** 2, tc, np.ones_like(tc)])
    coef, *_ = np.linalg.lstsq(a, f, rcond=None)
    res = f - a @ coef
    s2 = max(float(res @ res) / max(t.size - 3, 1), noise ** 2)
    cov = s2 * np.linalg.inv(a.T @ a)
    slope, se = float(coef[1]), float(math.sqrt(max(cov[1, 1], 0.0)))
    if not slope > 2.0 * se:
        return math.nan, math.nan, (f"the pull does not rise significantly over the last {t.size} samples "
                                    f"({slope * 1e9:.3g} +- {se * 1e9:.2g} nN/s)")
    return slope, se, ""
