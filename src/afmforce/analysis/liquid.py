"""Analysis of colloid-probe curves measured in a liquid (issue 25; docs/liquid.md).

The steps a colloid scientist applies to one approach-retract cycle before fitting forces,
after P. Attard, "How to measure forces when the AFM shows non-linear compliance"
(arXiv 1212.3019, 2012) and Zhu, Attard & Neto, Langmuir 27, 6701 (2011):

1. :func:`quadratic_compliance` -- the constant-compliance region calibrates the photodiode
   with a quadratic, ``d = a (V - V0) + c (V - V0)^2`` (a curved compliance from a
   non-linear photodiode response), and fixes the zero of separation (h = 0 on the
   compliance line) without a human.
2. :func:`drag_baselines` -- far from the surface the approach and the retract deflections
   are offset from each other by the drag on the lever ("virtual deflection",
   Vinogradova et al. 2001): ``k (d_app - d_ret) = c (v_app + v_ret)`` gives the lever drag c.
3. :func:`split_drainage` -- at equal separation the static force is the mean of the
   approach and retract forces and the velocity-dependent part (drainage and lever drag)
   half their difference.
4. :func:`fit_dlvo` -- the static force fitted with eq 2 on the geometry plus a double layer:
   surface potential, Debye length and Hamaker constant with standard errors.

Everything is SI; the functions take arrays (one run each) and return small records.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import AnalysisError

__all__ = ["ComplianceCalibration", "quadratic_compliance", "DragBaselines", "drag_baselines",
           "split_drainage", "velocity_force_fit", "VelocityForceFit", "VELOCITY_FIT_MIN_POINTS", "DLVOFit", "fit_dlvo", "calibrate_liquid_curve",
           "retract_free_mask", "FAR_MIN_POINTS"]

#: Fewest free samples a run must have in the far region for its baseline [-].
FAR_MIN_POINTS = 20


@dataclass(frozen=True)
class ComplianceCalibration:
    """Quadratic calibration of the photodiode on the compliance region.

    ``deflection(V) = a (V - V0) + c (V - V0)^2`` [m] (V0: the signal at zero force, from
    the far baseline), and the separation ``h = z + deflection - z_c`` is zero on the
    compliance line.

    Attributes
    ----------
    a : float
        Linear sensitivity [m/V].
    c : float
        Quadratic term [m/V^2].
    v0 : float
        Signal at zero deflection [V].
    z_contact : float
        Piezo position offset z_c [m] that puts the compliance line at h = 0.
    rms : float
        rms residual of the compliance fit [m].
    n : int
        Samples in the compliance region.
    """

    a: float
    c: float
    v0: float
    z_contact: float
    rms: float
    n: int

    def deflection(self, signal) -> np.ndarray:
        """Deflection [m] of photodiode signals [V]."""
        u = np.asarray(signal, float) - self.v0
        return self.a * u + self.c * u * u

    def separation(self, piezo, signal, h_contact: float = 0.0) -> np.ndarray:
        """Separation h [m]: substrate up is ``z`` increasing (spec section 1),
        ``h = d - z + z_c + h_contact`` (``h_contact``: the separation given to the compliance
        line, e.g. the soft-wall equilibrium ``z0 / 2^(1/3)``; the paper puts it at z0)."""
        return self.deflection(signal) - np.asarray(piezo, float) + self.z_contact + h_contact


def quadratic_compliance(piezo, signal, v0: float, min_span: float = 20e-9,
                         slope_tolerance: float = 0.3) -> ComplianceCalibration:
    """Calibrate a curved compliance region with a quadratic (Attard 2012).

    The compliance region is found without a human: the samples of the approach (``piezo``
    increasing) after the last point where the local slope ``dV/dz`` falls below
    ``(1 - slope_tolerance)`` of its final value; there ``z = d(V) + const`` and
    ``d(V) = a u + c u^2``, ``u = V - v0``, so ``z = a u + c u^2 + const`` is linear least squares.

    Parameters
    ----------
    piezo, signal : array_like
        Approach run: piezo position [m] (increasing) and photodiode signal [V].
    v0 : float
        Signal at zero deflection [V] (the far-field baseline, corrected for drag if known).
    min_span : float
        Smallest piezo travel the compliance region must span [m].
    """
    z = np.asarray(piezo, float)
    v = np.asarray(signal, float)
    if z.size < 20:
        raise AnalysisError("quadratic_compliance: give at least 20 approach samples")
    n = z.size
    w = max(5, n // 50)
    dz = z[w:] - z[:-w]
    dv = v[w:] - v[:-w]
    slope = np.where(dz != 0, dv / np.where(dz != 0, dz, 1.0), 0.0)
    final = np.median(slope[-max(3, slope.size // 20):])
    if not final > 0:
        raise AnalysisError("quadratic_compliance: the signal does not rise at the end of the "
                            "approach: no constant-compliance region")
    low = np.flatnonzero(slope < (1.0 - slope_tolerance) * final)
    i0 = int(low[-1]) + w + 1 if low.size else 0
    if z[-1] - z[min(i0, n - 1)] < min_span or n - i0 < 10:
        raise AnalysisError(f"quadratic_compliance: the compliance region spans "
                            f"{(z[-1] - z[min(i0, n - 1)]) * 1e9:.3g} nm (< {min_span * 1e9:.3g} nm); "
                            "drive further into contact")
    u = v[i0:] - v0
    X = np.column_stack([u, u * u, np.ones_like(u)])
    coef, *_ = np.linalg.lstsq(X, z[i0:], rcond=None)
    rms = float(np.sqrt(np.mean((X @ coef - z[i0:]) ** 2)))
    return ComplianceCalibration(a=float(coef[0]), c=float(coef[1]), v0=float(v0),
                                 z_contact=float(coef[2]), rms=rms, n=int(n - i0))


@dataclass(frozen=True)
class DragBaselines:
    """Far-field baselines of the approach and the retract and the lever drag they give.

    Attributes
    ----------
    approach, retract : tuple of float
        (offset [m], slope [-]) of ``d = offset + slope z`` on the far part of each run.
    gap : float
        ``d_app - d_ret`` at the middle of the far region [m] (drag: positive).
    lever_drag : float
        ``k gap / (v_app + v_ret)`` [N s/m] (NaN without k).
    gap_se, lever_drag_se : float
        Their standard errors [m], [N s/m]: the two lines' covariances at that point, widened by the
        residuals' correlation time (1/f noise), and the drift between the runs (the lines' slope
        difference times the distance to the turning point, added in quadrature).
    """

    approach: tuple
    retract: tuple
    gap: float
    lever_drag: float
    gap_se: float = math.nan
    lever_drag_se: float = math.nan


def drag_baselines(piezo_app, defl_app, piezo_ret, defl_ret, far: float, *,
                   spring_constant: float = math.nan, v_app: float = math.nan,
                   v_ret: float = math.nan) -> DragBaselines:
    """Lines through the far-field deflection of both runs (positions below ``far`` [m]).

    The far region must be out of reach of the surface forces (several Debye lengths); the
    lever drag offsets the runs in opposite directions. The drainage of a colloid probe
    reaches far (``6 pi eta R^2 v / h``): the gap holds it at the far region's separation too;
    :func:`velocity_force_fit` separates the two.
    """
    za, da = np.asarray(piezo_app, float), np.asarray(defl_app, float)
    zr, dr = np.asarray(piezo_ret, float), np.asarray(defl_ret, float)
    ma, mr = za < far, zr < far
    if ma.sum() < 5 or mr.sum() < 5:
        raise AnalysisError("drag_baselines: fewer than 5 samples of a run lie in the far region")
    pa = np.polyfit(za[ma], da[ma], 1)
    pr = np.polyfit(zr[mr], dr[mr], 1)
    zm = 0.5 * (max(za[ma].min(), zr[mr].min()) + far)
    gap = float(np.polyval(pa, zm) - np.polyval(pr, zm))
    var = 0.0
    for z, d, p in ((za[ma], da[ma], pa), (zr[mr], dr[mr], pr)):
        r = d - np.polyval(p, z)
        s2 = float(r @ r) / max(r.size - 2, 1) * _correlation_time(r)
        X = np.column_stack([z - zm, np.ones_like(z)])
        var += s2 * float(np.linalg.pinv(X.T @ X)[1, 1])      # the line's variance at zm
    # drift between the runs: a drift rate r tilts the approach's line by +r/v_app and the retract's by
    # -r/v_ret, and offsets them at zm by r times the time between passing zm on the way in and out, i.e.
    # by (slope_app - slope_ret) (z_turn - zm) whatever the speeds: not separable from the drag offset on
    # one curve (drift is not linear in time), so its size counts as an error of the gap
    z_turn = max(float(za.max()), float(zr.max()))
    var += (float(pa[0] - pr[0]) * (z_turn - zm)) ** 2
    gap_se = math.sqrt(var)
    drag = spring_constant * gap / (v_app + v_ret)
    return DragBaselines((float(pa[1]), float(pa[0])), (float(pr[1]), float(pr[0])), gap, float(drag),
                         gap_se, float(spring_constant * gap_se / (v_app + v_ret)))


def split_drainage(h_app, f_app, h_ret, f_ret, h=None):
    """Static force and velocity-dependent force at equal separation [N].

    On approach the drainage and drag push (``+F_v``), on the retract they pull (``-F_v``)
    at equal speeds, so ``F_static = (F_app + F_ret) / 2`` and ``F_v = (F_app - F_ret) / 2``.
    Returns ``(h, F_static, F_v)`` on ``h`` (default: the approach separations within the
    retract's range); both runs are interpolated in h (sorted), and separations where a run
    has no sample within 3 median spacings (a jump) are left out.
    """
    ha, fa = np.asarray(h_app, float), np.asarray(f_app, float)
    hr, fr = np.asarray(h_ret, float), np.asarray(f_ret, float)
    oa, orr = np.argsort(ha), np.argsort(hr)
    if h is None:
        h = ha[oa][(ha[oa] >= hr.min()) & (ha[oa] <= hr.max())]
    h = np.asarray(h, float)
    keep = np.ones(h.size, bool)
    for hh in (ha[oa], hr[orr]):
        gaps = np.diff(hh)
        big = np.flatnonzero(gaps > 3.0 * np.median(gaps))
        for i in big:
            keep &= ~((h > hh[i]) & (h < hh[i + 1]))
    h = h[keep]
    a = np.interp(h, ha[oa], fa[oa])
    r = np.interp(h, hr[orr], fr[orr])
    return h, 0.5 * (a + r), 0.5 * (a - r)


@dataclass(frozen=True)
class VelocityForceFit:
    """``F_v = v (c + beta / h)`` fitted far out: values, standard errors, and why not when undetermined.

    Attributes
    ----------
    lever_drag, drainage_coefficient : float
        c [N s/m] and ``beta = 6 pi eta R_eff^2`` [N s] (NaN when undetermined).
    lever_drag_se, drainage_coefficient_se : float
        Their standard errors [N s/m], [N s]: the least-squares covariance with the residuals'
        variance, widened by their correlation time (NaN when undetermined).
    n : int
        Samples in the separation range [-].
    correlation_time : float
        The residuals' integrated correlation time [samples] (1: white).
    undetermined : str
        Why the data cannot determine c and beta ("" when they do): too few samples, a speed that is
        not a positive number, or no spread of 1/h (c and beta collinear).
    """

    lever_drag: float
    drainage_coefficient: float
    lever_drag_se: float = math.nan
    drainage_coefficient_se: float = math.nan
    n: int = 0
    correlation_time: float = 1.0
    undetermined: str = ""


#: Fewest samples a velocity-force fit takes (two parameters and a variance from the rest).
VELOCITY_FIT_MIN_POINTS = 5


def velocity_force_fit(h, f_v, velocity: float, h_min: float, h_max: float) -> VelocityForceFit:
    """Separate the lever drag from the drainage in the velocity-dependent force.

    Far out (h >> slip length) ``F_v = v (c + beta / h)`` with c the lever drag and
    ``beta = 6 pi eta R_eff^2`` (Reynolds); a linear least-squares fit of ``F_v / v`` in 1/h over
    ``[h_min, h_max]`` [m]: beta checks eta R^2 in situ. The standard errors are those of ordinary
    least squares (``s^2 (X'X)^-1``, s^2 the residual variance with n - 2 degrees of freedom) times
    the square root of the residuals' correlation time (the velocity force is a difference of two
    runs interpolated on one grid, with drift and 1/f noise: neighbouring samples are not
    independent). Undetermined (NaN, and the reason) with fewer than
    :data:`VELOCITY_FIT_MIN_POINTS` samples in the range, a speed that is not positive, or no
    spread of 1/h.

    Parameters
    ----------
    h, f_v : array_like
        Separation [m] and velocity-dependent force [N] (:func:`split_drainage`).
    velocity : float
        Mean speed of the two runs [m/s].
    h_min, h_max : float
        Separation range fitted [m].
    """
    h, f_v = np.asarray(h, float), np.asarray(f_v, float)
    m = (h >= h_min) & (h <= h_max) & np.isfinite(h) & np.isfinite(f_v) & (h > 0)
    n = int(m.sum())
    why = ""
    if n < VELOCITY_FIT_MIN_POINTS:
        why = (f"{n} samples between {h_min * 1e9:.3g} and {h_max * 1e9:.3g} nm (fewer than "
               f"{VELOCITY_FIT_MIN_POINTS})")
    elif not (math.isfinite(velocity) and velocity > 0):
        why = f"the speed is {velocity!r} m/s (not positive): no velocity force to divide"
    else:
        x = 1.0 / h[m]
        if not np.ptp(x) > 1e-9 * float(np.max(np.abs(x))):
            why = "all samples at one separation: 1/h has no spread, c and beta are collinear"
    if why:
        return VelocityForceFit(math.nan, math.nan, n=n, undetermined=why)
    y = f_v[m] / velocity
    X = np.column_stack([np.ones_like(x), x - x.mean()])     # centred: the two columns orthogonal
    coef, *_ = np.linalg.lstsq(X, y, rcond=None)
    r = y - X @ coef
    tau = _correlation_time(r)
    s2 = float(r @ r) / (n - 2) * tau
    cov = s2 * np.linalg.inv(X.T @ X)
    beta = float(coef[1])
    c = float(coef[0] - beta * x.mean())
    var_c = cov[0, 0] + x.mean() ** 2 * cov[1, 1] - 2.0 * x.mean() * cov[0, 1]
    return VelocityForceFit(c, beta, math.sqrt(max(var_c, 0.0)), math.sqrt(max(cov[1, 1], 0.0)), n, tau)


@dataclass(frozen=True)
class DLVOFit:
    """Least-squares DLVO fit: values, standard errors [SI], reduced chi-square, and the residuals'
    correlation time [samples] the standard errors are widened by (its square root; 1: white),
    each parameter's 95 % profile-likelihood interval (``interval``: (low, high) [SI], None for an
    end the data leave open) and ``note``: why a value or a standard error is NaN."""

    surface_potential: float
    debye_length: float
    hamaker: float
    stderr: dict
    redchi: float
    correlation_time: float = 1.0
    interval: dict = field(default_factory=dict)
    note: str = ""


def fit_dlvo(h, force, radius: float, *, sigma: float, geometry: str = "sphere-flat",
             law: str = "constant_potential", permittivity: float = 78.4, z0: float = 0.35e-9,
             guess=(-0.03, 10e-9, 1e-20), h_dot=None, viscosity: float = 0.0,
             slip_length: float = 0.0) -> DLVOFit:
    """Fit ``F(h) = vdW(h) + 2 pi R_eff W_dl(h) [+ drainage]`` to a force curve.

    Free: psi (symmetric surfaces, so its sign is that of the guess), the Debye length and
    the Hamaker constant; ``sigma`` [N] the force noise. With ``h_dot`` [m/s] and
    ``viscosity`` [Pa s] the drainage with slip (:func:`afmforce.forces.slip_drainage_force`,
    known) is part of the model, so an approach at finite speed gives the static force.
    Standard errors from the covariance, scaled by the reduced chi-square when it exceeds 1.

    The covariance is local: each parameter's profile likelihood (the others re-fitted,
    :func:`~.surface_law_fit.profile_interval`, chi-square in the same noise units) gives its 95 %
    interval. Open to a bound (a Debye length beyond the data range: only psi^2 / lambda is seen,
    the fit had psi = -0.0027 +- 0.0011 V for a true -0.03 V at lambda = 3 um over 2-30 nm), or a
    better fit elsewhere: the value and its error are NaN; an interval more than twice as wide as
    the error says on a side: the error is NaN (the value and its interval stay).
    """
    from scipy.optimize import least_squares

    from ..forces import double_layer_force, paper_radius, slip_drainage_force, vdw_force

    hh, ff = np.asarray(h, float), np.asarray(force, float)
    rp = float(paper_radius(radius, geometry))
    scale = np.array([0.01, 1e-8, 1e-20])
    drain = 0.0 if h_dot is None or viscosity <= 0 else np.asarray(
        slip_drainage_force(hh, h_dot, radius, viscosity, slip_length, geometry))

    def model(p):
        psi, lam, a = p * scale
        return np.asarray(vdw_force(hh, rp, a, z0)) + np.asarray(
            double_layer_force(hh, radius, psi, lam, None, permittivity, law, geometry)) + drain

    res = least_squares(lambda p: (model(p) - ff) / sigma, np.asarray(guess) / scale,
                        bounds=([-100, 1e-3, 1e-3], [100, 1e3, 1e4]), x_scale="jac")
    dof = max(hh.size - 3, 1)
    redchi = float(res.fun @ res.fun / dof)
    tau = _correlation_time(res.fun)
    cov = np.linalg.pinv(res.jac.T @ res.jac) * max(redchi, 1.0) * tau
    se = np.sqrt(np.clip(np.diag(cov), 0, None)) * scale
    from .surface_law_fit import profile_interval

    names = ("surface_potential", "debye_length", "hamaker")
    values = dict(zip(names, (float(v) for v in res.x * scale)))
    stderr = dict(zip(names, (float(v) for v in se)))
    lo, hi = np.array([-100, 1e-3, 1e-3]), np.array([100, 1e3, 1e4])
    interval, why = {}, []
    for i, n in enumerate(names):
        if not (math.isfinite(se[i]) and se[i] > 0):
            values[n], stderr[n] = math.nan, math.nan
            why.append(f"{n}: no standard error (the data do not move the model along it)")
            continue
        low, high, better = profile_interval(res, i, lambda p: model(p) / sigma, ff / sigma, 1.0, lo, hi,
                                             se[i] / scale[i], max(redchi, 1.0) * tau)
        low, high = (None if e is None else float(e * scale[i]) for e in (low, high))
        interval[n] = (low, high)
        shown = f"[{'-' if low is None else f'{low:.3g}'}, {'-' if high is None else f'{high:.3g}'}]"
        at = [b for b in (lo[i], hi[i]) if abs(float(res.x[i]) - b) <= 1e-6 * max(abs(b), 1e-3)]
        if at:   # a value the fit pushed to the edge of its range is no estimate (not 0.0 as a number)
            other = high if at[0] == lo[i] else low
            side = "at most" if at[0] == lo[i] else "at least"
            why.append(f"{n} undetermined: the fit runs to the {'lower' if at[0] == lo[i] else 'upper'} bound of its "
                       f"range ({at[0] * scale[i]:.3g})" + ("" if other is None else
                                                             f"; 95 % profile: {side} {other:.3g}"))
            values[n], stderr[n] = math.nan, math.nan
        elif better is not None or low is None or high is None:
            why.append(f"{n} undetermined: " + (f"a better fit lies at {better * scale[i]:.3g}" if better is not None
                                                  else f"its 95 % profile interval {shown} is open"))
            values[n], stderr[n] = math.nan, math.nan
        elif max(values[n] - low, high - values[n]) > 2 * 1.96 * se[i]:
            why.append(f"{n} = {values[n]:.3g}: its 95 % profile interval {shown} is far wider than the "
                       f"standard error {se[i]:.2g} says (no standard error given)")
            stderr[n] = math.nan
    return DLVOFit(values["surface_potential"], values["debye_length"], values["hamaker"], stderr, redchi, tau,
                   interval, "; ".join(why))


def _correlation_time(r) -> float:
    """Integrated autocorrelation time ``1 + 2 sum rho_k`` of residuals in sample order [samples].

    The sum runs while the autocorrelation stays positive (the initial positive sequence). White
    noise gives about 1; drift and 1/f noise, which a smooth force law follows over many samples,
    more: each independent piece of information is then spread over that many samples, and the
    covariance of a least-squares fit grows by that factor (its standard errors by the square root).
    """
    r = np.asarray(r, float)
    r = r - r.mean()
    n = r.size
    if n < 8 or not np.any(r):
        return 1.0
    spec = np.fft.rfft(r, 2 * n)
    acf = np.fft.irfft(spec * np.conj(spec))[:n]
    rho = acf / acf[0]
    stop = np.flatnonzero(rho[1:] <= 0)
    m = int(stop[0]) if stop.size else n - 1
    return float(min(max(1.0 + 2.0 * float(np.sum(rho[1:m + 1])), 1.0), n))


def retract_free_mask(piezo_app, signal_app, piezo_ret, signal_ret, far: float) -> np.ndarray:
    """The retract's samples after the pull-off (free lever) [bool, one per retract sample].

    In contact the signal follows the piezo with the compliance slope (the approach's final
    ``dV/dz``), and a clipped photodiode (:func:`~afmforce.analysis.regions.saturated_mask`) says
    nothing about the lever: the pull-off is after the last retract sample (time order) whose local
    slope exceeds half the compliance slope or whose signal is clipped, and a window of samples more
    (the jump and the relaxation after it). All False when the lever never pulls off. Raises
    :class:`~afmforce.errors.AnalysisError`, saying what happened, when fewer than
    :data:`FAR_MIN_POINTS` free retract samples lie in the far region (piezo below ``far`` [m]).
    """
    from .regions import saturated_mask

    za, va = np.asarray(piezo_app, float), np.asarray(signal_app, float)
    zr, vr = np.asarray(piezo_ret, float), np.asarray(signal_ret, float)
    w = max(3, za.size // 100)
    tail = slice(max(0, za.size - max(4 * w, za.size // 20)), za.size)
    comp = np.polyfit(za[tail], va[tail], 1)[0] if za[tail].size >= 3 else math.nan   # [V/m] in contact
    n = zr.size
    contact = np.zeros(n, bool)
    if math.isfinite(comp) and comp > 0 and n > w:
        dz, dv = zr[w:] - zr[:-w], vr[w:] - vr[:-w]
        slope = np.where(dz != 0, dv / np.where(dz != 0, dz, 1.0), np.inf)
        steep = np.abs(slope) > 0.5 * comp
        contact[:-w] |= steep
        contact[w:] |= steep
    clipped = saturated_mask(np.ascontiguousarray(np.concatenate([va, vr])))[za.size:]
    contact |= clipped
    free = np.ones(n, bool)
    last = np.flatnonzero(contact)
    if last.size:
        free[:min(n, int(last[-1]) + 1 + w)] = False
    nfar = int((free & (zr < far)).sum())
    if nfar < FAR_MIN_POINTS:
        what = "the photodiode clipped" if clipped.any() else "the deflection following the piezo"
        if not free.any():
            raise AnalysisError(f"the retract never pulls off: in contact ({what}) down to its end at z = "
                                f"{zr[-1] * 1e9:.4g} nm, so the retract has no free far baseline; retract further "
                                "(a larger `end`) or lower the adhesion")
        zp = float(zr[int(last[-1])])
        raise AnalysisError(f"the retract pulls off at z = {zp * 1e9:.4g} nm, inside the far region (below "
                            f"{far * 1e9:.4g} nm), leaving {nfar} free samples there (fewer than {FAR_MIN_POINTS}) "
                            "for its far baseline: retract further (a larger `end`)")
    return free


def calibrate_liquid_curve(curve, far: float | None = None):
    """A raw curve in volts -> the same curve with the deflection in metres (for ``afmforce fit``).

    The zero-deflection signal is the mean of the approach and retract far-field lines at the
    far region's middle (the lever drag cancels; the retract's after its pull-off, :func:`retract_free_mask`), ``far`` [m] the upper end of the far region
    in piezo position (default: the first 30 % of the approach travel); the deflection is the
    quadratic compliance calibration (:func:`quadratic_compliance`). The calibration is in
    ``metadata["liquid_calibration"]``. The piezo position read by the position sensor is
    used when there is one.
    """
    import dataclasses

    z = np.asarray(curve.position("auto"), float)
    v = np.asarray(curve.deflection_signal, float)
    seg = np.asarray(curve.segment)
    a, r = seg == 0, seg == 1
    if a.sum() < 20 or r.sum() < 20:
        raise AnalysisError("calibrate_liquid_curve: needs an approach and a retract run "
                            "(>= 20 samples each)")
    if far is None:
        far = z[a].min() + 0.3 * (z[a].max() - z[a].min())
    free = np.zeros(z.size, bool)
    free[r] = retract_free_mask(z[a], v[a], z[r], v[r], far)   # only the lever off the surface is a baseline
    ma, mr = a & (z < far), free & (z < far)
    if ma.sum() < 5 or mr.sum() < 5:
        raise AnalysisError("calibrate_liquid_curve: fewer than 5 samples of a run in the far region")
    mid = 0.5 * (max(z[ma].min(), z[mr].min()) + far)
    v0 = 0.5 * (np.polyval(np.polyfit(z[ma], v[ma], 1), mid) + np.polyval(np.polyfit(z[mr], v[mr], 1), mid))
    cal = quadratic_compliance(z[a], v[a], v0)
    meta = dict(curve.metadata or {})
    meta["liquid_calibration"] = dataclasses.asdict(cal)
    return dataclasses.replace(curve, deflection_signal=cal.deflection(v), deflection_unit="m",
                               metadata=meta)
