"""The modulus fit of one indentation curve: Young's modulus, contact point and baseline together.

The data are the tip's depth ``u`` [m] (piezo position minus deflection, growing as the tip
moves into the sample) and the force ``F`` [N] of one run. The model, as nanite's, is::

    F(u) = E * shape(u - c) + b        (shape = 0 before contact, u <= c)

with the Young's modulus E [Pa], the contact point c [m] (a depth) and the force baseline b [N]
fitted jointly, and residuals weighted down linearly within ``weight_width`` of the contact point
(nanite's ``weight_cp``; 0: unweighted). For a given c the model is linear in (E, b): the fit
solves it in closed form for a few dozen contact points at once (one array operation), refines
the best one twice, and ends with Gauss-Newton steps on (E, c, b), whose Jacobian gives the
standard errors. A fit range (``max_indentation``) is a fixed set of samples, ``u <= c_ref +
max_indentation`` for every contact point tried, with c_ref the whole run's contact point
(:func:`fit_indentation`). Adhesive laws (JKR, DMT, Maugis) add the work of adhesion w [J/m^2]: all four
parameters, the contact point included, are fitted together and get their covariance
(:mod:`afmforce.contact.adhesive_fit`).

>>> fit = fit_indentation(u, F, "hertz_paraboloid", {"radius": 5e-6}, nu=0.5)   # doctest: +SKIP
>>> fit.youngs_modulus, fit.youngs_modulus_se, fit.contact                     # doctest: +SKIP
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from ..errors import AnalysisError, ParameterError
from .adhesive import adhesive_force
from ._weights import t95 as _t95, weights as _weights
from .adhesive_fit import fit_adhesive
from .models import BILODEAU_FOUR_SIDED, BILODEAU_THREE_SIDED, _check_nu, shape_and_slope
from .registry import indentation_model

__all__ = ["IndentationFit", "FixedBaselineFit", "fit_indentation", "fit_fixed_baseline", "validity", "model_force"]

@dataclass(frozen=True)
class IndentationFit:
    """The fit of one curve (SI).

    Attributes
    ----------
    model : str  key of :data:`~afmforce.contact.registry.INDENTATION_MODELS`
    youngs_modulus, youngs_modulus_se : float  E and its standard error [Pa]
    youngs_modulus_low, youngs_modulus_high : float  95 % interval of E [Pa]
    contact, contact_se : float  contact point as a tip depth and its standard error [m]
    baseline : float  force before contact [N]
    work_of_adhesion, work_of_adhesion_se : float  w [J/m^2] (adhesive laws; NaN otherwise)
    work_of_adhesion_low, work_of_adhesion_high : float  95 % interval of w [J/m^2] (adhesive laws); when it
        reaches 0: [0, the profile likelihood's upper end], NaN upper end: open (the data do not bound w)
    max_indentation : float  deepest indentation fitted [m]
    max_force : float  force there above the baseline [N]
    n_points, n_contact : int  points fitted, of them in contact [-]
    rms : float  root-mean-square residual [N]
    residuals : ndarray  data minus model on the fitted points [N]
    fitted : ndarray of int  indices (into the arrays given) of the fitted points
    warnings : tuple of str  the validity check (:func:`validity`) and fit troubles
    range_reference : float  the contact point the fit range (``max_indentation``) is measured from: the
        whole run's, or the one given (``contact_point``) [m] (NaN: no range, the whole run fitted)
    """

    model: str
    youngs_modulus: float
    youngs_modulus_se: float
    youngs_modulus_low: float
    youngs_modulus_high: float
    contact: float
    contact_se: float
    baseline: float
    work_of_adhesion: float
    work_of_adhesion_se: float
    max_indentation: float
    max_force: float
    n_points: int
    n_contact: int
    rms: float
    residuals: np.ndarray = field(repr=False)
    fitted: np.ndarray = field(repr=False)
    warnings: tuple[str, ...] = ()
    work_of_adhesion_low: float = math.nan
    work_of_adhesion_high: float = math.nan
    range_reference: float = math.nan


def model_force(key: str, delta, E: float, geometry: dict, nu: float, w: float = 0.0, lam: float = 1.0,
                branch: str = "approach") -> np.ndarray:
    """Force [N] of model ``key`` at indentation ``delta`` [m] (baseline excluded)."""
    m = indentation_model(key)
    delta = np.asarray(delta, dtype=float)
    if m.linear:
        return E * shape_and_slope(key, delta, geometry, nu)[0]
    return np.asarray(adhesive_force(key, delta, E, w, geometry["radius"], nu, lam, branch))


#: Power laws F = E k delta^p: key -> (k(geometry, nu), p), scanned by the compiled kernel.
_POWER = {"hertz_paraboloid": (lambda g, c: 4.0 / 3.0 * c * math.sqrt(g["radius"]), 1.5),
          "hertz_cone": (lambda g, c: 2.0 / math.pi * math.tan(g["half_angle"]) * c, 2.0),
          "bilodeau_pyramid3": (lambda g, c: BILODEAU_THREE_SIDED * math.tan(g["half_angle"]) * c, 2.0),
          "bilodeau_pyramid4": (lambda g, c: BILODEAU_FOUR_SIDED * math.tan(g["half_angle"]) * c, 2.0)}


def _scan(u, F, cands, key, geom, nu, width):
    """Closed-form (E, b) and the weighted sum of squares for each candidate contact point (all samples
    given are fitted: a fit range is applied before, as a fixed set of samples)."""
    if key in _POWER:
        from ._kernels import scan_power_law

        kf, p = _POWER[key]
        return scan_power_law(u, F, np.ascontiguousarray(cands, dtype=float), kf(geom, 1.0 / (1.0 - nu * nu)), p,
                              float(width))
    d = u[None, :] - cands[:, None]
    phi = shape_and_slope(key, d, geom, nu)[0]
    q = _weights(d, width) ** 2
    s0, s1, s2 = q.sum(1), (q * phi).sum(1), (q * phi * phi).sum(1)
    qf = q * F
    sy, sxy, syy = qf.sum(1), (qf * phi).sum(1), (qf * F).sum(1)
    det = s0 * s2 - s1 * s1
    with np.errstate(divide="ignore", invalid="ignore"):
        E = (s0 * sxy - s1 * sy) / det
        b = (s2 * sy - s1 * sxy) / det
        ssr = syy - E * sxy - b * sy
    ssr = np.where((det > 0) & (E > 0) & np.isfinite(ssr), ssr, np.inf)
    return E, b, ssr


#: The fixed parts of the candidate grid of :func:`_linear_fit` (np.geomspace, np.linspace: computed once).
_GEO = np.geomspace(1e-3, 1.0, 64)
_AROUND = np.linspace(-0.02, 0.02, 9)
_EVEN = np.arange(1.0, 32.0)  # np.linspace(lo, hi, 33)[1:-1] is _EVEN * ((hi - lo) / 32) + lo


#: Gauss-Newton steps of :func:`_linear_fit` at most (each while the sum of squares falls; most fits converge in
#: one or two, a contact point far before the first sample in ~10). A fit that uses them all without converging
#: says so in its warnings (never a silent non-converged number).
_GN_MAX_STEPS = 50
#: Halvings of a Gauss-Newton step that does not lower the sum of squares, before the polish stops.
_GN_HALVINGS = 8


def _linear_fit(u, F, key, geom, nu, width, guess):
    lo, hi = float(np.min(u)), float(np.max(u))
    span = hi - lo
    if not span > 0:
        raise AnalysisError("the tip does not move: no indentation to fit")
    # indentations from 0.1 % of the travel to all of it, on a log scale (the contact is near the top
    # on most curves), and evenly over the travel
    step = (hi - lo) / 32
    even = _EVEN * step + lo if step != 0 else np.linspace(lo, hi, 33)[1:-1]
    parts = (hi - span * _GEO, even)
    if guess is not None and math.isfinite(guess):
        parts += (guess + span * _AROUND,)
    cands = np.concatenate(parts)
    stride = max(1, u.size // 2000)  # long runs: the first rounds on every stride-th sample, the last on all
    if key in _POWER:  # the four rounds in one compiled call (the same numbers)
        from ._kernels import search_power_law

        kf, p = _POWER[key]
        ok, c, E0, b0, best = search_power_law(u, F, cands, kf(geom, 1.0 / (1.0 - nu * nu)), p, float(width),
                                               stride)
        if not ok:
            raise AnalysisError("no contact point gives a positive modulus: the curve does not rise into contact")
        c, E0, b0 = float(c), float(E0), float(b0)
    else:
        for rnd in range(4):
            cands = np.unique(cands)
            us, Fs = (u[::stride], F[::stride]) if rnd < 3 else (u, F)
            E, b, ssr = _scan(us, Fs, cands, key, geom, nu, width)
            i = int(np.argmin(ssr))
            if not math.isfinite(ssr[i]):
                raise AnalysisError("no contact point gives a positive modulus: the curve does not rise into "
                                    "contact")
            c0 = float(cands[i])
            left, right = cands[max(i - 1, 0)], cands[min(i + 1, cands.size - 1)]
            cands = np.linspace(left, right, 17)
        c, E0, b0, best = c0, float(E[i]), float(b[i]), ssr[i]
    # Gauss-Newton on (E, c, b): the weights at the current c
    p = np.array([E0, c, b0])
    power = _power_terms(key, geom, nu, u, F)
    # the scan has the contact point to ~1e-4 of a grid step: a polish, continued while the sum of squares
    # falls until the step is below 1e-6 of the travel: the scan's first rounds on every stride-th sample can
    # bracket another point than all samples' optimum (the JPK map curve 1: 12,030 samples, stride 6, 103.5 nm
    # against 106.7 nm; two steps stopped at 106.34 nm, E 6679 Pa, nanite 6710 Pa). Also where the contact point
    # leaves the samples (the whole record in contact: optics11-piuma test2, cone 1637 Pa as nanite's, where
    # stopping two steps after leaving gave 3301 Pa): the caller warns that it is extrapolated
    # (:func:`_fit_samples`), and the indentation step's baseline checks judge the converged fit
    converged = False
    for _it in range(_GN_MAX_STEPS):
        if power is not None:  # compiled, the same numbers
            r, J, _ = power(p, width, True)
        else:
            d = u - p[1]
            phi, dphi = shape_and_slope(key, d, geom, nu)
            q = _weights(d, width)
            r = q * (F - p[0] * phi - p[2])
            J = q[:, None] * np.column_stack((phi, -p[0] * dphi, np.ones_like(phi)))
        try:
            dp = _normal_solve(J, r)
        except np.linalg.LinAlgError:
            converged = True  # singular at p: no descent direction to take
            break
        for _h in range(_GN_HALVINGS):  # a step that overshoots (the law's curvature jumps at each sample
            trial = p + dp               # passed) is halved: the nsfopen curve stopped 0.5 nm off, 0.8 % in E
            s = math.inf
            if trial[0] > 0:
                if power is not None:
                    rt = power(trial, width, False)[0]
                else:
                    dt = u - trial[1]
                    rt = _weights(dt, width) * (F - trial[0] * shape_and_slope(key, dt, geom, nu)[0] - trial[2])
                s = float(rt @ rt)
            if s <= best:
                break
            dp = 0.5 * dp
        if s > best:
            converged = True  # no step along the Gauss-Newton direction lowers the sum of squares: its minimum
            break
        p, best = trial, s
        if abs(dp[1]) < 1e-6 * span and abs(dp[0]) < 1e-9 * abs(p[0]):
            converged = True
            break
    return p, converged


def _power_terms(key, geom, nu, u, F):
    """``terms(p, width, jacobian) -> (r, J, phi)`` of the power law ``key`` on the samples ``u, F`` by the compiled
    :func:`._kernels.power_law_terms` (the numbers of the numpy expressions it replaces); None where the law is
    no power law, the samples are not contiguous float64 or numba's JIT is off (the numpy path)."""
    from ._kernels import COMPILED, power_law_terms

    if key not in _POWER or not COMPILED:
        return None
    if not all(isinstance(a, np.ndarray) and a.dtype == np.float64 and a.ndim == 1 and a.flags.c_contiguous
               for a in (u, F)):
        return None
    c = _check_nu(nu)    # shape_and_slope's check (a Poisson ratio out of range is refused there too)
    kf, pw = _POWER[key]
    k = kf(geom, c)

    def terms(p, width, jacobian):  # (r, J, phi)
        return power_law_terms(u, F, float(p[0]), float(p[1]), float(p[2]), k, pw, float(width), jacobian)
    return terms


def _normal_solve(J: np.ndarray, r: np.ndarray) -> np.ndarray:
    """The Gauss-Newton step (J^T J)^-1 J^T r, with J's columns scaled (they differ by ~1e13)."""
    A = J.T @ J
    n = np.sqrt(np.diag(A))
    n[n == 0] = 1.0
    return np.linalg.solve(A / np.outer(n, n), (J.T @ r) / n) / n


def _covariance(J: np.ndarray, s2: float) -> np.ndarray:
    """s^2 (J^T J)^-1, inverted with the columns scaled."""
    A = J.T @ J
    n = np.sqrt(np.diag(A))
    n[n == 0] = 1.0
    return np.linalg.inv(A / np.outer(n, n)) / np.outer(n, n) * s2


def extrapolated_contact_note(before: float, travel: float) -> str:
    """The warning of a fitted contact point ``before`` [m] ahead of the first sample of a run whose tip travels
    ``travel`` [m]: the whole record is in contact and the contact point is extrapolated."""
    return (f"the contact point lies {before * 1e9:.4g} nm ({before / travel:.2g} x the travel) before the first "
            "sample: the curve starts in contact, the contact point is extrapolated beyond the data and the "
            "modulus rests on the law's shape there (uncertain); record the approach from further away")


def validity(key: str, geometry: dict, max_indentation: float, thickness: float | None = None,
             n_contact: int = 0) -> tuple[str, ...]:
    """Where the law is used outside its range, in words (empty: within it).

    Checks: the indentation against the tip radius (sphere laws), against a tenth of the
    sample's ``thickness`` [m] (half-space laws; for ``hertz_thin_layer``: chi = sqrt(R delta)/h < 1),
    and the number of points in contact.
    """
    out = list(out_of_range(key, geometry, max_indentation, thickness))
    if n_contact < 10:
        out.append(f"only {n_contact} points in contact: the modulus is poorly determined")
    return tuple(out)


def out_of_range(key: str, geometry: dict, max_indentation: float, thickness: float | None = None) -> tuple[str, ...]:
    """Where the law ``key`` is used outside the range it holds in, in words (empty: within it): the part of
    :func:`validity` that says the law does not describe the fitted indentation. A fit beyond it has a modulus
    that is the law's best match, not the sample's, and no interval (:func:`fit_indentation`)."""
    m = indentation_model(key)
    out = []
    R = geometry.get("radius")
    d = max_indentation
    if R and math.isfinite(m.max_depth_over_radius) and d > m.max_depth_over_radius * R:
        out.append(f"indentation {d * 1e9:.4g} nm exceeds {m.max_depth_over_radius:g} x the tip radius "
                   f"({R * 1e9:.4g} nm): the {m.name} law does not hold there (fit a smaller range with "
                   "indentation.max_indentation, or use a cone or pyramid model)")
    h = thickness if thickness is not None else geometry.get("thickness")
    if h:
        if key == "hertz_thin_layer":
            chi = math.sqrt(R * d) / h
            if chi > 1:
                out.append(f"thin-layer parameter sqrt(R delta)/h = {chi:.3g} > 1: beyond the range of "
                           "Dimitriadis's series")
        elif d > 0.1 * h:
            out.append(f"indentation {d * 1e9:.4g} nm is more than a tenth of the sample thickness "
                       f"({h * 1e9:.4g} nm): the substrate stiffens the response (use hertz_thin_layer)")
    return tuple(out)


def fit_indentation(depth, force, model: str = "hertz_paraboloid", geometry: dict | None = None, *,
                    nu: float = 0.5, weight_width: float = 0.0, max_indentation: float = math.inf,
                    contact_guess: float | None = None, thickness: float | None = None,
                    transition: float = 1.0, branch: str = "approach",
                    contact_point: float | None = None) -> IndentationFit:
    """Fit the law ``model`` to one run: E, contact point and baseline jointly (and w for adhesive laws).

    Parameters
    ----------
    depth : array_like
        Tip depth u [m]: position minus deflection, growing into the sample.
    force : array_like
        Force [N], positive pushing.
    model : str
        Key of :data:`~afmforce.contact.registry.INDENTATION_MODELS`.
    geometry : dict
        ``radius`` [m], ``half_angle`` [rad], ``thickness`` [m] as the model needs.
    nu : float
        Poisson ratio of the sample [-].
    weight_width : float
        Residuals within this distance of the contact point are weighted down linearly [m] (0: none).
    max_indentation : float
        Fit only up to this indentation beyond the contact point [m] (inf: the whole run). The range
        is a fixed set of samples, ``u <= c_ref + max_indentation``, the same for every contact point
        tried, with ``c_ref`` the whole run's contact point (the first pass of nanite's
        ``range_type="relative cp"``; :attr:`IndentationFit.range_reference`); E, the contact point
        and the baseline are then fitted on those samples. A range that moved with each tried contact
        point would let contact points early in the baseline win by fitting fewer samples; further
        passes (c_ref from the range's own fit) do not settle on curves whose onset is not the law's.
    contact_guess : float, optional
        A contact point (tip depth [m]) the search also looks around.
    thickness : float, optional
        Sample thickness [m], for the validity check.
    transition : float
        Maugis-Dugdale transition parameter lambda [-].
    branch : str
        Adhesive laws: ``"approach"`` (no force before contact) or ``"retract"`` (the neck before
        the pull-off: negative indentations; the data read backwards, into the sample).

    contact_point : float, optional
        The contact point, fixed, as a tip depth [m] (None: fitted). Then only E and the baseline are
        fitted (linear least squares), the contact point's standard error is 0 and a note in
        ``warnings`` says it was given; a fit range is measured from it. Linear laws only.

    Returns
    -------
    IndentationFit

    Raises
    ------
    ParameterError
        Unknown model or a missing geometry parameter.
    AnalysisError
        Too few points, or no contact point gives a positive modulus.
    """
    m = indentation_model(model)
    geom = dict(geometry or {})
    for g in m.geometry:
        v = geom.get(g)
        if v is None or not (float(v) > 0):
            key = {"radius": "tip_radius", "thickness": "indentation.thickness"}.get(g, g)     # the quantity the user gives (`key`: each face's flag)
            raise ParameterError(f"indentation model {model!r} needs the {g.replace('_', ' ')} (`{key}`)")
    if not (max_indentation > 0):
        raise ParameterError(f"max_indentation must be positive (got {max_indentation!r} m)")
    u = np.asarray(depth, dtype=float)
    F = np.asarray(force, dtype=float)
    ok = np.isfinite(u) & np.isfinite(F)
    idx = np.flatnonzero(ok)
    u, F = u[ok], F[ok]
    if u.size < 8:
        raise AnalysisError(f"only {u.size} points to fit the indentation model (at least 8 are needed)")
    args = (model, geom, nu, weight_width, thickness, transition, branch)
    if contact_point is not None:
        return _fit_fixed(u, F, idx, args, m, float(contact_point), max_indentation)
    fit = _fit_samples(u, F, idx, *args, contact_guess)
    if not math.isfinite(max_indentation):
        return fit
    # the fit range: a fixed set of samples, u <= c_ref + max_indentation, the same for every contact
    # point tried, c_ref the whole run's contact point (nanite's first pass of its "relative cp" range).
    # Not iterated: on real curves whose onset is not the law's, each pass moves the contact point
    # earlier and the range with it (the shipped cell, 30 nm: 7 kPa, 0.9 kPa, then 1 Pa at 1.7 um of
    # "indentation" in the baseline), so the passes never settle
    keep = u <= fit.contact + max_indentation
    if int(keep.sum()) < 8:
        raise AnalysisError(f"only {int(keep.sum())} points within max_indentation = "
                            f"{max_indentation * 1e9:.4g} nm of the contact point (at least 8 are "
                            "needed): fit a larger range")
    ref = fit.contact
    if keep.all():  # the range holds the whole run: its fit
        return replace(fit, range_reference=float(ref))
    fit = _fit_samples(u[keep], F[keep], idx[keep], *args, ref)
    shift = ref - fit.contact
    extra = ()
    if abs(shift) > 0.5 * max_indentation:
        extra = (f"the contact point of the fit range lies {abs(shift) * 1e9:.3g} nm "
                 f"{'before' if shift > 0 else 'beyond'} the whole run's (the range's reference), more than "
                 f"half the range: the curve near contact is not of the {m.name} law's shape, and the "
                 "modulus depends on the range",)
    return replace(fit, range_reference=float(ref), warnings=fit.warnings + extra)


def _fit_fixed(u, F, idx, args, m, c: float, max_indentation: float) -> IndentationFit:
    """The fit with the contact point ``c`` [m] given: E and b on the samples within the range of c."""
    if not m.linear:
        raise ParameterError(f"a fixed contact point is supported for the laws without adhesion, not {m.name} "
                             "(give no contact_point: it is fitted with E and w)")
    if not math.isfinite(c):
        raise ParameterError(f"contact_point must be a finite tip depth (got {c!r} m)")
    keep = u <= c + max_indentation
    if int(keep.sum()) < 8:
        raise AnalysisError(f"only {int(keep.sum())} points within max_indentation = {max_indentation * 1e9:.4g} nm "
                            "of the contact point (at least 8 are needed): fit a larger range")
    fit = _fit_samples(u[keep], F[keep], idx[keep], *args, None, fixed=c)
    note = (f"the contact point is fixed (given) at a tip depth of {c * 1e9:.6g} nm: not fitted, its standard "
            "error is 0",)
    return replace(fit, range_reference=c if math.isfinite(max_indentation) else math.nan,
                   warnings=note + fit.warnings)


def _fit_samples(u, F, idx, model, geom, nu, weight_width, thickness, transition, branch,
                 contact_guess, fixed: float | None = None) -> IndentationFit:
    """The fit on the finite samples (u, F) (all of them: the fit range is applied before); ``idx``:
    their indices into the arrays the caller gave; ``fixed``: the contact point, held (linear laws)."""
    m = indentation_model(model)
    w = w_se = w_low = w_high = math.nan
    converged = True
    if fixed is not None:  # E and b alone: linear least squares at the given contact point
        c = float(fixed)
        d = u - c
        phi = shape_and_slope(model, d, geom, nu)[0]
        q = _weights(d, weight_width)
        J = q[:, None] * np.column_stack((phi, np.ones_like(phi)))
        try:
            E, b = _normal_solve(J, q * F)
        except np.linalg.LinAlgError:
            E = math.nan
        if not (E > 0):
            raise AnalysisError(f"with the contact point fixed at a tip depth of {c * 1e9:.6g} nm, no positive "
                                "modulus fits: the curve does not rise into contact past it (give another "
                                "contact_point, or none to fit it)")
        r = q * (F - E * phi - b)
        names = 2
    elif m.linear:
        (E, c, b), converged = _linear_fit(u, F, model, geom, nu, weight_width, contact_guess)
        d = u - c
        q = _weights(d, weight_width)
        power = _power_terms(model, geom, nu, u, F)
        if power is not None:  # compiled, the same numbers
            r, J, phi = power((E, c, b), weight_width, True)
        else:
            phi, dphi = shape_and_slope(model, d, geom, nu)
            r = q * (F - E * phi - b)
            J = q[:, None] * np.column_stack((phi, -E * dphi, np.ones_like(phi)))
        names = 3
    else:
        a = fit_adhesive(u, F, model, geom["radius"], nu, transition, branch, weight_width)
        E, w, c, b = a.E, a.w, a.c, a.b
        d = u - c
        q = a.weights
        se_a = np.sqrt(np.clip(np.diag(a.cov), 0, None))
        w_low, w_high = a.w_low, a.w_high
        names = 4
    used = q > 0
    n = int(used.sum())
    dof = n - names
    if m.linear or fixed is not None:
        s2 = float(r @ r) / dof if dof > 0 else math.nan
        try:
            se = np.sqrt(np.clip(np.diag(_covariance(J, s2)), 0, None))
        except np.linalg.LinAlgError:
            se = np.full(names, math.nan)
        E_se, c_se = float(se[0]), (float(se[1]) if fixed is None else 0.0)
    else:
        E_se, w_se, c_se = float(se_a[0]), float(se_a[1]), float(se_a[2])
    t = _t95(dof)
    E_low, E_high = (E - t * E_se, E + t * E_se) if m.linear else (a.E_low, a.E_high)
    undetermined = m.linear and (not (E_low > 0) or not converged)
    if undetermined:
        # E > 0: an interval reaching 0 says the data do not bound E (a few points of indentation, the
        # contact point trades against E): [0, open], not a negative end nor a finite upper one (the
        # covariance's missed the truth in 21 of 30 seeds with 3 points in contact, 9 of 30 with 5)
        E_low, E_high = 0.0, math.nan
    in_contact = used & (d > 0)
    dmax = float(d[in_contact].max()) if in_contact.any() else 0.0
    fmodel = E * phi if m.linear else a.model  # model_force(model, d, E, ...): E times the shape at d
    resid = (F - fmodel - b)[used]
    warn = list(validity(model, geom, dmax, thickness, int(in_contact.sum())))
    first = float(u.min())
    if fixed is None and m.linear and c < first:
        warn.append(extrapolated_contact_note(first - c, float(u.max()) - first))
    # the adhesive sphere laws (JKR, DMT, Maugis) assume a contact radius small against R: beyond their range
    # the law is not the curve's; a paraboloid is exact for a paraboloidal tip at any depth (only a sphere's
    # approximation, as nanite fits it): its range stays a warning
    invalid = out_of_range(model, geom, dmax, thickness) if m.adhesive else ()
    if not converged:
        warn.append(f"the fit did not converge in {_GN_MAX_STEPS} Gauss-Newton steps (the contact point still "
                    f"moving): E = {E:.4g} Pa is no least-squares optimum, its interval is left open "
                    "(undetermined); fit a smaller range (indentation.max_indentation) or another law")
    elif invalid and not undetermined:
        # the law does not describe the curve over the fitted indentation: its covariance's interval is the
        # noise's alone about the law's best match, a precision the model does not have: E undetermined
        # ([0, open]), as where the data do not bound it (docs/contact.md, "A law beyond its range")
        warn.append(f"the modulus is undetermined: the {m.name} law does not hold over the fitted indentation "
                    f"(above), so its 95 % interval [{E_low:.3g}, {E_high:.3g}] Pa would be the noise's alone about "
                    f"the law's best match ({E:.3g} Pa), not the sample's modulus; fit within the law's range "
                    "(indentation.max_indentation) or choose a law that holds there")
        E_low, E_high = 0.0, math.nan
        if m.adhesive:
            w_low, w_high = 0.0, math.nan
        undetermined = True
    elif undetermined:
        warn.append(f"the modulus is undetermined: its 95 % interval reaches 0 (standard error "
                    f"{E_se / E:.0%} of the value, {int(in_contact.sum())} points in contact); the data do "
                    "not bound it: indent deeper or fit more of the curve")
    elif math.isfinite(E_se) and E_se > 0.5 * E:
        warn.append(f"the modulus is poorly determined: standard error {E_se / E:.0%} of the value")
    if m.adhesive and w_low == 0.0 and not invalid:
        bound = "no upper bound" if math.isnan(w_high) else f"95 % upper bound {w_high:.3g} J/m^2"
        warn.append(f"the work of adhesion is not distinguishable from 0 ({bound})")
    return IndentationFit(
        model=model, youngs_modulus=float(E), youngs_modulus_se=E_se, youngs_modulus_low=float(E_low),
        youngs_modulus_high=float(E_high), contact=float(c), contact_se=c_se, baseline=float(b),
        work_of_adhesion=float(w), work_of_adhesion_se=w_se, max_indentation=dmax,
        max_force=float(F[in_contact].max() - b) if in_contact.any() else math.nan, n_points=n,
        n_contact=int(in_contact.sum()), rms=float(np.sqrt(np.mean(resid ** 2))) if resid.size else math.nan,
        residuals=resid, fitted=idx[used], warnings=tuple(warn), work_of_adhesion_low=float(w_low),
        work_of_adhesion_high=float(w_high))


@dataclass(frozen=True)
class FixedBaselineFit:
    """The fit of a law without adhesion with the force baseline held at a measured level (SI).

    Attributes
    ----------
    youngs_modulus, youngs_modulus_se : float  E and its standard error [Pa]
    youngs_modulus_low, youngs_modulus_high : float  95 % interval of E [Pa] ([0, NaN]: undetermined)
    contact : float  contact point as a tip depth [m]
    baseline : float  the force baseline held [N]
    rms : float  root-mean-square residual [N]
    """

    youngs_modulus: float
    youngs_modulus_se: float
    youngs_modulus_low: float
    youngs_modulus_high: float
    contact: float
    baseline: float
    rms: float


def fit_fixed_baseline(depth, force, model: str, geometry: dict, baseline: float, *, nu: float = 0.5,
                       weight_width: float = 0.0, contact_guess: float | None = None) -> FixedBaselineFit:
    """Fit E and the contact point of the law ``model`` (no adhesion) with the force baseline held at
    ``baseline`` [N]: ``F(u) = E shape(u - c) + baseline``.

    The check of the free fit's baseline (:func:`afmforce.analysis.indentation.indentation`, docs/contact.md):
    for a given c, E is linear (closed form); c is scanned over the same grid as :func:`fit_indentation`'s
    (plus ``contact_guess``), refined by a bounded 1-D minimisation between the best candidate's neighbours,
    and the standard error of E comes from the (E, c) Jacobian. All samples given are fitted.

    Parameters
    ----------
    depth, force : array_like  tip depth u [m] and force [N] of the samples to fit
    model : str  a law without adhesion (key of :data:`~afmforce.contact.registry.INDENTATION_MODELS`)
    geometry : dict  as :func:`fit_indentation`'s
    baseline : float  the force before contact, held [N]
    nu : float  Poisson ratio [-]
    weight_width : float  as :func:`fit_indentation`'s [m]
    contact_guess : float, optional  a contact point (tip depth [m]) the scan also looks around

    Raises
    ------
    ParameterError
        An adhesive law.
    AnalysisError
        Too few points, or no contact point gives a positive modulus.
    """
    from scipy.optimize import minimize_scalar

    m = indentation_model(model)
    if not m.linear:
        raise ParameterError(f"a fixed baseline is supported for the laws without adhesion, not {m.name}")
    u = np.asarray(depth, dtype=float)
    F = np.asarray(force, dtype=float) - float(baseline)
    ok = np.isfinite(u) & np.isfinite(F)
    u, F = u[ok], F[ok]
    if u.size < 8:
        raise AnalysisError(f"only {u.size} points to fit the indentation model (at least 8 are needed)")
    lo, hi = float(u.min()), float(u.max())
    span = hi - lo
    if not span > 0:
        raise AnalysisError("the tip does not move: no indentation to fit")

    def ssr_at(c: float) -> tuple[float, float]:
        d = u - c
        phi = shape_and_slope(model, d, geometry, nu)[0]
        q2 = _weights(d, weight_width) ** 2
        den = float((q2 * phi * phi).sum())
        if not den > 0:
            return math.inf, math.nan
        E = float((q2 * phi * F).sum()) / den
        if not E > 0:
            return math.inf, math.nan
        r = F - E * phi
        return float((q2 * r * r).sum()), E

    parts = [hi - span * _GEO, _EVEN * (span / 32) + lo]
    if contact_guess is not None and math.isfinite(contact_guess):
        parts.append(contact_guess + span * _AROUND)
    cands = np.unique(np.concatenate(parts))
    ss = np.array([ssr_at(float(c))[0] for c in cands])
    i = int(np.argmin(ss))
    if not math.isfinite(ss[i]):
        raise AnalysisError("with the baseline held, no contact point gives a positive modulus")
    a, b = float(cands[max(i - 1, 0)]), float(cands[min(i + 1, cands.size - 1)])
    c = float(cands[i])
    if b > a:
        opt = minimize_scalar(lambda x: ssr_at(x)[0], bounds=(a, b), method="bounded",
                              options={"xatol": 1e-6 * span})
        if opt.fun <= ss[i]:
            c = float(opt.x)
    best, E = ssr_at(c)
    d = u - c
    phi, dphi = shape_and_slope(model, d, geometry, nu)
    q = _weights(d, weight_width)
    n = int((q > 0).sum())
    dof = n - 2
    s2 = best / dof if dof > 0 else math.nan
    J = q[:, None] * np.column_stack((phi, -E * dphi))
    try:
        E_se = float(math.sqrt(max(_covariance(J, s2)[0, 0], 0.0)))
    except np.linalg.LinAlgError:
        E_se = math.nan
    t = _t95(dof)
    low, high = E - t * E_se, E + t * E_se
    if not low > 0:
        low, high = 0.0, math.nan
    return FixedBaselineFit(youngs_modulus=E, youngs_modulus_se=E_se, youngs_modulus_low=float(low),
                            youngs_modulus_high=float(high), contact=c, baseline=float(baseline),
                            rms=math.sqrt(best / max(n, 1)))
