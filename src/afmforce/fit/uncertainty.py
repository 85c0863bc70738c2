"""Profile-likelihood intervals and the model comparison (friction detected or not).

With Gaussian noise of known rms the log-likelihood is ``-chi2/2``, so the
profile-likelihood interval at level ``1 - alpha`` holds the values where the
re-minimised chi-square exceeds the minimum by less than
``chi2_1^-1(1 - alpha)`` (3.84 at 95 %), and the likelihood-ratio statistic of
two nested fits is their chi-square difference. When the fit's reduced
chi-square ``s2`` exceeds 1 the noise was underestimated and every difference
is divided by ``s2``. Friction ``xi >= 0`` is tested on the boundary of its
range: the null distribution of the statistic is an equal mixture of 0 and
chi-square with one degree of freedom (Self & Liang, JASA 82, 605 (1987)), so
``p = chi2_1.sf(LR) / 2``.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.stats import chi2 as chi2_dist

from .model import Evaluator
from .params import PARAMETERS
from .problem import Problem
from .result import ModelComparison

__all__ = ["profile_interval", "fit_nested", "compare_models", "PROFILE_STEPS", "PROFILE_STEPS_FAR",
           "PROFILE_NOISE"]

#: Profile points at these multiples of the standard error on each side (until the threshold).
PROFILE_STEPS = (1.0, 2.0, 3.0, 4.5, 6.5, 9.0, 13.0)
#: Further profile points [standard errors] where the profile's refits scatter (a curvature at the
#: optimum that the profile does not follow: its standard error is then no measure of the width).
PROFILE_STEPS_FAR = (18.0, 25.0, 35.0, 50.0)
#: A fall of the profile away from its minimum larger than this [chi-square] is taken as the refits'
#: error, and the interval's ends must clear the threshold by it (:func:`profile_interval`).
PROFILE_NOISE = 0.01


def _sub_problem(prob: Problem, name: str, value: float) -> Problem:
    free = tuple(n for n in prob.free if n != name)
    return Problem(prob.ev, free, {**prob.fixed, name: value})


def _drop(x: np.ndarray, j: int) -> np.ndarray:
    return np.delete(np.asarray(x, float), j)


def _refit(sub: Problem, x0: np.ndarray, max_nfev: int) -> tuple[float, np.ndarray]:
    from .problem import local_fit

    if len(x0) == 0:
        return sub.chi2(x0), x0
    x, _ = local_fit(sub, x0, max_nfev)
    return sub.chi2(x), x


def _crossing(v0: float, d0: float, v1: float, d1: float, need: float) -> float:
    """Where the profile reaches ``need`` between ``(v0, d0)`` (below) and ``(v1, d1)`` (at or above):
    the signed root ``sqrt(delta chi2)`` interpolated, ~linear in the parameter."""
    a, b = math.sqrt(min(d0, need)), math.sqrt(d1)
    return v0 + (v1 - v0) * (math.sqrt(need) - a) / max(b - a, 1e-300)


def profile_interval(prob: Problem, x: np.ndarray, chi2_min: float, name: str, stderr: float,
                     s2: float, level: float, max_nfev: int = 15, cov: np.ndarray | None = None):
    """Profile-likelihood interval of ``name`` at ``level``.

    Each profile point is refitted from the point the covariance ``cov`` (of the scaled
    vector) predicts, ``x + cov[:, j] / cov[j, j] (v - best)``: along the valley of
    strongly correlated parameters (A and xi correlate at 0.7-0.98), where a start from
    the previous profile point keeps the others at the wrong place and a short refit
    stops on the valley's wall (the profile then rises too early and the interval is too
    short: the truth of seed 6 of the ``typical`` set lay outside such an end). When a point
    would end the interval, the previous point's optimum is tried
    too and the lower chi-square kept.

    Returns ``(lower, upper, points, note)``; ``points`` holds the profiled values
    (``value`` [unit]) and ``delta_chi2`` (already divided by ``s2``). A side
    that does not cross the threshold is open: ``None`` (one-sided interval, with
    ``note`` saying how far the profile went), except at a physical lower bound
    (``FitParameter.physical_lower``, e.g. xi = 0), where the interval is an upper
    bound ``[lower, hi]``. A search bound's value is never reported as an end. Where the
    refits scatter (the profile falls away from its minimum by more than
    :data:`PROFILE_NOISE`), an end must clear the threshold by the largest such fall, and the
    profile goes on out to :data:`PROFILE_STEPS_FAR` to find it.
    """
    p = PARAMETERS[name]
    j = prob.free.index(name)
    best = float(prob.unpack(x)[0][name])
    thr = float(chi2_dist.ppf(level, 1))
    step = stderr if math.isfinite(stderr) and stderr > 0 else 0.2 * max(abs(best), p.abs_step)
    pts = {best: 0.0}
    ends, notes = [], []
    x = np.asarray(x, float)
    slope = (np.asarray(cov, float)[:, j] / cov[j, j] if cov is not None and cov[j, j] > 0
             else np.eye(len(x))[j])

    def side(sign: float, state: dict, need: float) -> None:
        """Profile one side from ``state`` on until a point reaches ``need`` (the end, interpolated
        at ``need``) or the steps or a search bound run out (``end`` None, or the physical bound)."""
        steps = PROFILE_STEPS + (PROFILE_STEPS_FAR if need > thr else ())
        while state["k"] < len(steps) and not state["bound"]:
            v = best + sign * steps[state["k"]] * step
            state["k"] += 1
            at_bound = (v <= p.lower) if sign < 0 else (v >= p.upper)
            v = min(max(v, p.lower), p.upper)
            sub = _sub_problem(prob, name, v)
            pred = _drop(x + slope * (v - best) / p.scale, j)
            c2, x_new = _refit(sub, pred, max_nfev)
            if (c2 - chi2_min) / s2 >= need:     # would end the interval: the other start too
                c2b, xb = _refit(sub, state["xs"], max_nfev)
                if c2b < c2:
                    c2, x_new = c2b, xb
            state["xs"] = x_new
            d = max((c2 - chi2_min) / s2, 0.0)
            pts[v] = d
            state["seq"].append(d)
            state["last_v"] = v
            if d >= need:
                state["cross"] = (state["prev_v"], state["prev_d"], v, d)
                state["end"] = _crossing(*state["cross"], need)
                return
            state["prev_v"], state["prev_d"] = v, max(d, state["prev_d"])
            if at_bound:
                state["bound"] = True
                return

    states = {}
    for sign in (-1.0, 1.0):
        states[sign] = {"k": 0, "xs": _drop(x, j), "prev_v": best, "prev_d": 0.0, "seq": [0.0], "end": None,
                        "bound": False}
        side(sign, states[sign], thr)
    # A profile cannot fall away from its minimum: a drop between consecutive points outward is the
    # refits' error (short local fits in a curved valley), at least that large everywhere. A crossing
    # that error could make is no end: such a side goes on until the profile clears the threshold
    # by it (on the `typical` preset in a vendor file, seed 3 at 0.5, 2, 8 um/s, the Hamaker profile
    # went 1.31, 0.61, 3.24, 4.90 on one side, 1.85, 0.66, 3.39, 0.88, ... 1.19 on the other: a
    # lower end 2 % below the value on a drop of 2.5, the truth 6 % below it).
    noise = max((max(0.0, a - b) for st in states.values() for a, b in zip(st["seq"][:-1], st["seq"][1:])
                 ), default=0.0)
    if noise > PROFILE_NOISE:
        for sign, st in states.items():
            if st["end"] is not None and st["seq"][-1] >= thr + noise:   # it clears it: the end there
                st["end"] = _crossing(*st["cross"], thr + noise)
                continue
            if st["end"] is not None:
                st["end"] = None
                st["prev_v"], st["prev_d"] = st["last_v"], st["seq"][-1]
            side(sign, st, thr + noise)            # on, out to PROFILE_STEPS_FAR
        notes.append(f"{name}: the profile's refits scatter by {noise:.3g} in chi-square (the profile "
                     f"falls by that much away from its minimum): its ends are where it exceeds the "
                     f"{level:.0%} threshold by that much")
    for sign in (-1.0, 1.0):
        st = states[sign]
        end = st["end"]
        if end is None and sign < 0 and p.physical_lower:
            end = p.lower
        if end is None:
            prev_v = st["prev_v"]
            side_name = "lower" if sign < 0 else "upper"
            where = (f"the search bound {prev_v:.3g} {p.unit}" if prev_v in (p.lower, p.upper)
                     else f"{prev_v:.3g} {p.unit} (the last profiled value)")
            notes.append(f"{name}: one-sided interval, no {side_name} end: the profile stays below the "
                         f"{level:.0%} threshold out to {where}")
        ends.append(end)
    keys = sorted(pts)
    return (ends[0], ends[1], {"value": keys, "delta_chi2": [pts[k] for k in keys]},
            "; ".join(notes))


def profiled_estimate(name: str, lo, hi, note: str, stderr: float, unit: str) -> tuple[str, float, str]:
    """``(interval_method, stderr, note)`` of a profiled parameter.

    A profile that stays below the threshold on both sides (``lo`` and ``hi`` None) means the data
    do not determine the parameter: it is reported ``"undetermined"`` with no standard error,
    because the Jacobian's one is the curvature at the optimum only, and a valley that stays flat
    for many of those widths makes it a tight number the data do not support (seen: a Hamaker
    constant at 0.2 % whose profile stayed flat beyond +-13 of them, the truth 44 of them away).
    """
    if lo is None and hi is None:
        return ("undetermined", math.nan,
                f"{name}: undetermined: the profile stays below the threshold on both sides; the data "
                f"cannot determine it (the curvature at the optimum alone would say +-{stderr:.3g} {unit}, "
                f"a width the profile does not confirm); {note}")
    return "profile", stderr, note


def fit_nested(prob: Problem, x: np.ndarray, curves, base, drift: bool, max_nfev: int,
               starts=()) -> dict:
    """The static and the friction-free dynamic fits nested in the full fit at ``x``.

    Returns ``{"static": (chi2, n_par) or None, "no_friction": (chi2, x_full, n_par) or
    None}``; ``x_full`` is the friction-free optimum as a vector of the full problem
    (friction parameters at 0), from which the full model can be restarted. The
    friction-free model is fitted from the full optimum with friction set to 0, from
    the static optimum and from each of ``starts`` (full vectors, e.g. the xi = 0 point
    of the ridge), and keeps the best.
    """
    from .params import SPEED_DEPENDENT
    from .problem import local_fit

    n_lin = prob.ev.n_linear()
    values, shifts = prob.unpack(x)
    out: dict = {"static": None, "no_friction": None}
    free_s = tuple(f for f in prob.free if f not in SPEED_DEPENDENT)
    static_start = None
    if free_s:   # static: no inertia, drainage or friction; only the speed-independent parameters
        ev_s = Evaluator(curves, base.replace(**{k: v for k, v in values.items()
                                                 if k not in SPEED_DEPENDENT}), "static", drift,
                         prob.ev.fringes, prob.ev.fringe_period, prob.ev.curvature)
        ps = Problem(ev_s, free_s)
        xs, _ = local_fit(ps, ps.pack(values, shifts), max_nfev)
        out["static"] = (ps.chi2(xs), len(xs) + n_lin)
        prob.ev.simulations += ev_s.simulations
        static_start = ps.unpack(xs)
    fric = [f for f in ("xi", "zeta") if f in prob.free]
    if not fric:
        return out
    keep = [k for k, nm in enumerate(prob.names) if nm not in fric]
    sub = Problem(prob.ev, tuple(f for f in prob.free if f not in fric),
                  {**prob.fixed, **{f: 0.0 for f in fric}})
    cands = [np.asarray(x, float)[keep]] + [np.asarray(st, float)[keep] for st in starts]
    if static_start is not None:   # without friction the jump moves out: the static fit
        cands.append(sub.pack({**values, **static_start[0]}, static_start[1]))
    best = None
    for x0 in cands:
        c2, xs = _refit(sub, x0, max_nfev)
        if best is None or c2 < best[0]:
            best = (c2, xs)
    x_full = np.asarray(x, float).copy()
    x_full[keep] = best[1]
    for f in fric:
        x_full[prob.names.index(f)] = 0.0
    out["no_friction"] = (best[0], x_full, len(best[1]) + n_lin)
    return out


def compare_models(prob: Problem, x: np.ndarray, chi2_full: float, curves, base, drift: bool,
                   level: float, s2: float, nested: dict,
                   verdict_override: str | None = None, max_nfev: int = 40) -> ModelComparison:
    """Compare the static, friction-free and full fits (:func:`fit_nested`).

    ``verdict_override``: the words when no verdict can be given (the model does
    not describe the data); ``friction_detected`` is then None.
    """
    n = sum(int(c.mask.sum()) for c in curves)
    n_lin = prob.ev.n_linear()
    chi2, npar = {}, {}
    if nested["static"] is not None:
        chi2["static"], npar["static"] = nested["static"]
    if nested["no_friction"] is not None:
        c2, _, n_nf = nested["no_friction"]
        chi2["dynamic, no friction"], npar["dynamic, no friction"] = c2, n_nf
        chi2["dynamic, friction"], npar["dynamic, friction"] = chi2_full, len(x) + n_lin
        lr = max((c2 - chi2_full) / s2, 0.0)
        p = 1.0 if lr <= 0 else 0.5 * float(chi2_dist.sf(lr, 1))
        detected = p < 1.0 - level
        verdict = (f"friction {'detected' if detected else 'not detected'} at the "
                   f"{level:.0%} level")
    else:
        chi2["dynamic"], npar["dynamic"] = chi2_full, len(x) + n_lin
        lr, p, detected = math.nan, math.nan, False
        verdict = "friction not tested (xi is not free" + (
            "; the spring model has no friction)" if base.model == "spring" else ")")
    if verdict_override is not None:
        detected, verdict = None, verdict_override
    slip = _compare_slip(prob, x, chi2_full, n_lin, level, max_nfev, s2, chi2, npar)
    if slip and verdict_override is not None:    # no verdict without a model that fits
        slip.update(slip_detected=None, slip_verdict=verdict_override)
    aic = {m: chi2[m] / s2 + 2 * npar[m] for m in chi2}
    bic = {m: chi2[m] / s2 + npar[m] * math.log(n) for m in chi2}
    return ModelComparison(chi2=chi2, n_parameters=npar, aic=aic, bic=bic, lr=lr, p_value=p,
                           level=level, friction_detected=None if detected is None
                           else bool(detected), verdict=verdict,
                           best_by_aic=min(aic, key=aic.get), best_by_bic=min(bic, key=bic.get),
                           **slip)


def _compare_slip(prob: Problem, x: np.ndarray, chi2_full: float, n_lin: int, level: float,
                  max_nfev: int, s2: float, chi2: dict, npar: dict) -> dict:
    """Slip (b free) against no slip (b = 0), issue 25: the boundary likelihood-ratio test of
    friction (b >= 0; ``p = chi2_1.sf(LR) / 2``). Adds the no-slip fit to ``chi2``/``npar``."""
    if "slip_length" not in prob.free:
        return {}
    sub = Problem(prob.ev, tuple(f for f in prob.free if f != "slip_length"),
                  {**prob.fixed, "slip_length": 0.0})
    x0 = np.array([xx for nm, xx in zip(prob.names, x) if nm != "slip_length"])
    c0, _ = _refit(sub, x0, max_nfev)
    chi2["dynamic, no slip"], npar["dynamic, no slip"] = c0, len(x0) + n_lin
    chi2.setdefault("dynamic", chi2_full)
    npar.setdefault("dynamic", len(x) + n_lin)
    lr = max((c0 - chi2_full) / s2, 0.0)
    p = 1.0 if lr <= 0 else 0.5 * float(chi2_dist.sf(lr, 1))
    detected = p < 1.0 - level
    return dict(slip_detected=bool(detected), slip_lr=lr, slip_p_value=p,
                slip_verdict=f"slip {'detected' if detected else 'not detected'} at the {level:.0%} level")
