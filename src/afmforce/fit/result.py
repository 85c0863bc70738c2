"""Results of a dynamic fit: dataclasses with units, JSON and a Markdown summary."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

import numpy as np

__all__ = ["Estimate", "CurveFit", "ModelComparison", "FitResult"]


def contain_value(name: str, e: "Estimate") -> str:
    """Make ``e``'s interval contain its value (in place; issue 34: a reported value is always
    inside its own interval); returns a note when it had to be extended ("" otherwise).

    A profile refit that finds a lower chi-square than the optimum's moves the threshold's
    crossing past the estimate; the interval then reaches the estimate (and the note says
    that the optimum may not be the global one)."""
    lo, hi = e.interval
    v = float(e.value)
    if not math.isfinite(v):
        return ""
    new = (v if lo is not None and v < lo else lo, v if hi is not None and v > hi else hi)
    if new == (lo, hi):
        return ""
    e.interval = new
    fmt = (lambda t: "open" if t is None else f"{t:.4g}")
    return (f"{name}: the estimate {v:.4g} {e.unit} lay outside its {e.interval_method} interval "
            f"[{fmt(lo)}, {fmt(hi)}]; extended to it (the profile found a lower chi-square "
            "elsewhere: the optimum may not be the global one)")


@dataclass
class Estimate:
    """One fitted parameter.

    Attributes
    ----------
    value, stderr : float
        Best estimate and standard error from the Jacobian (scaled by the
        reduced chi-square when it exceeds 1) [unit].
    interval : (float or None, float or None)
        Profile-likelihood interval at ``level`` where computed, else
        ``value +- z stderr`` [unit]. A side the data do not bound (the profile
        reaches a search bound, or stays below the threshold as far as it goes)
        is ``None`` (one-sided interval, see ``note``); at a physical lower bound
        (xi = 0) the interval is an upper bound ``[0, hi]``.
    interval_method : str
        ``"profile"``, ``"wald"`` or ``"undetermined"`` (both ends open: the data cannot
        determine it, see ``note``).
    unit : str
    note : str
        Why an interval is one-sided ("" when it is two-sided).
    """

    value: float
    stderr: float
    interval: tuple[float | None, float | None]
    interval_method: str
    unit: str
    note: str = ""


@dataclass
class CurveFit:
    """Per-curve result: nuisance parameters and goodness of fit (SI)."""

    name: str
    velocity: float
    sample_rate: float
    n_points: int
    n_used: int
    sigma: float
    shift: float
    shift_stderr: float
    offset: float
    drift: float
    chi2: float
    rms_residual: float
    retract: bool = False       # the retract run was fitted too
    pink: float = 0.0           # rms of the 1/f noise in the noise model [m] (0: white only)


@dataclass
class ModelComparison:
    """Static vs dynamic without friction vs dynamic with friction.

    ``chi2``, ``n_parameters``, ``aic``, ``bic`` per model name; the
    likelihood-ratio statistic of friction (``lr``) and its p-value (boundary
    case xi >= 0: half a chi-square with one degree of freedom).
    ``friction_detected`` is None (and ``verdict`` says "undetermined: ...") when the
    best model does not describe the data (:mod:`afmforce.fit.adequacy`).
    """

    chi2: dict
    n_parameters: dict
    aic: dict
    bic: dict
    lr: float
    p_value: float
    level: float
    friction_detected: bool | None
    verdict: str
    best_by_aic: str
    best_by_bic: str
    #: issue 25: slip (``slip_length`` free) against no slip (b = 0), the same boundary test;
    #: None when slip_length is not free
    slip_detected: bool | None = None
    slip_lr: float = math.nan
    slip_p_value: float = math.nan
    slip_verdict: str = ""
    #: issue 23: friction against no friction with the lever damped at Q = 30 (None: not run,
    #: i.e. friction not detected or the model has a quality factor; afmforce.fit.damping_check)
    damping_check: dict | None = None


@dataclass
class FitResult:
    """Everything a joint dynamic fit found (SI units; see :meth:`to_dict`)."""

    model: str
    free: tuple
    parameters: dict
    derived: dict
    correlations: dict
    curves: list
    chi2: float
    dof: int
    redchi: float
    n_data: int
    level: float
    comparison: ModelComparison | None
    profiles: dict
    warnings: list
    model_evaluations: int
    wall_time: float
    success: bool
    message: str
    config: dict = field(default_factory=dict)
    #: goodness of fit: ``redchi``, ``threshold``, ``adequate``, ``worst`` (see fit.adequacy)
    adequacy: dict = field(default_factory=dict)
    #: interference fringes in the baseline: ``mode`` used, ``period`` [m], ``amplitude`` and
    #: ``amplitude_stderr`` [m] of the shared periodic fringes (issue 23; fit.model.Evaluator)
    fringes: dict = field(default_factory=dict)
    #: the photodiode's curved response ``d + q d^2``: ``curvature`` q [1/m] and
    #: ``curvature_stderr`` (None: not fitted; fit.model.Evaluator ``curvature``)
    photodiode: dict = field(default_factory=dict)
    _problem: object = field(default=None, repr=False, compare=False)
    _x: object = field(default=None, repr=False, compare=False)

    @property
    def friction_detected(self) -> bool | None:
        return None if self.comparison is None else self.comparison.friction_detected

    @property
    def p_value(self) -> float:
        return math.nan if self.comparison is None else self.comparison.p_value

    @property
    def slip_detected(self) -> bool | None:
        """Slip against no slip (issue 25): True/False, None when slip_length is not free."""
        return None if self.comparison is None else self.comparison.slip_detected

    @property
    def slip_p_value(self) -> float:
        return math.nan if self.comparison is None else self.comparison.slip_p_value

    def predictions(self) -> list:
        """Best-fit model deflection of every curve incl. offset and drift [m]."""
        return self._problem.predictions(self._x)

    def to_dict(self) -> dict:
        """JSON-able dictionary (SI values, units given next to them)."""
        d = {
            "model": self.model,
            "free": list(self.free),
            "parameters": {k: {**asdict(v), "interval": list(v.interval)}
                           for k, v in self.parameters.items()},
            "derived": {k: {**asdict(v), "interval": list(v.interval)}
                        for k, v in self.derived.items()},
            "friction_detected": self.friction_detected,
            "p_value": self.p_value,
            "slip_detected": self.slip_detected,
            "slip_p_value": self.slip_p_value,
            "comparison": None if self.comparison is None else asdict(self.comparison),
            "correlations": self.correlations,
            "curves": [asdict(c) for c in self.curves],
            "units": {"shift": "m", "offset": "m", "drift": "m/s", "sigma": "m", "velocity": "m/s",
                      "sample_rate": "Hz", "rms_residual": "m", "pink": "m"},
            "chi2": self.chi2, "dof": self.dof, "redchi": self.redchi, "n_data": self.n_data,
            "level": self.level,
            "profiles": {k: {kk: list(map(float, vv)) for kk, vv in p.items()}
                         for k, p in self.profiles.items()},
            "warnings": list(self.warnings),
            "model_evaluations": self.model_evaluations,
            "wall_time": self.wall_time, "success": self.success, "message": self.message,
            "config": self.config,
            "adequacy": dict(self.adequacy),
            "fringes": dict(self.fringes),
            "photodiode": dict(self.photodiode),
            "verdict": None if self.comparison is None else self.comparison.verdict,
        }
        return d

    def markdown(self) -> str:
        """A Markdown summary: parameters, verdict, model comparison, curves."""
        from ..units import format_quantity

        def fq(value, unit):     # a value that is no number (a failed run's offset, an undefined
            # std. error) is printed as "-", never as "nan" beside a unit
            return format_quantity(value, unit) if value is not None and math.isfinite(value) else "-"

        def g(value, spec=".3g"):
            return format(value, spec) if value is not None and math.isfinite(value) else "-"

        L = [f"# Dynamic fit ({self.model} model, {len(self.curves)} curves)", ""]
        L += [f"| parameter | value | std. error | {self.level:.0%} interval |", "|---|---|---|---|"]
        def end(v, unit):
            return "open" if v is None else fq(v, unit)

        for name, e in {**self.parameters, **self.derived}.items():
            L.append(f"| {name} | {fq(e.value, e.unit)} | {fq(e.stderr, e.unit)} | "
                     f"[{end(e.interval[0], e.unit)}, {end(e.interval[1], e.unit)}] "
                     f"({e.interval_method}{', one-sided' if (e.interval[0] is None) != (e.interval[1] is None) else ''}) |")
        L.append("")
        if self.adequacy and not self.adequacy.get("adequate", True):
            L += ["**The model does not describe the data**: " + (self.adequacy.get("reason") or (
                  f"reduced chi-square {self.redchi:.3g} > {self.adequacy['threshold']:.3g}")) + ".", ""]
            L += [f"- {w}" for w in self.adequacy.get("worst", [])]
            L += ([f"- what to check: {self.adequacy['advice']}"] if self.adequacy.get("advice")
                  else []) + [""]
        if self.comparison is not None:
            c = self.comparison
            L += [f"**{c.verdict}** (likelihood ratio {g(c.lr)}, p = {g(c.p_value)})", ""]
            if c.slip_detected is not None:
                L += [f"**{c.slip_verdict}** (likelihood ratio {g(c.slip_lr)}, p = "
                      f"{g(c.slip_p_value)})", ""]
            L += ["| model | chi2 | parameters | AIC | BIC |", "|---|---|---|---|---|"]
            for m in c.chi2:
                L.append(f"| {m} | {c.chi2[m]:.1f} | {c.n_parameters[m]} | {c.aic[m]:.1f} | "
                         f"{c.bic[m]:.1f} |")
            L += ["", f"Best by AIC: {c.best_by_aic}; by BIC: {c.best_by_bic}.", ""]
        L += [f"chi2 = {self.chi2:.1f} for {self.dof} degrees of freedom (reduced "
              f"{self.redchi:.3g}); {self.model_evaluations} model evaluations, "
              f"{self.wall_time:.1f} s.", ""]
        if self.fringes.get("mode") == "periodic":
            L += [f"Interference fringes (shared by the curves, period "
                  f"{fq(self.fringes['period'], 'm')}): amplitude "
                  f"{fq(self.fringes['amplitude'], 'm')} ± "
                  f"{fq(self.fringes['amplitude_stderr'], 'm')}.", ""]
        L += [
              "| curve | speed | sample rate | points used | noise | shift | offset | drift | rms residual |",
              "|---|---|---|---|---|---|---|---|---|"]
        for c in self.curves:
            L.append(f"| {c.name} | {fq(c.velocity, 'm/s')} | {fq(c.sample_rate, 'Hz')} | "
                     f"{c.n_used}/{c.n_points} | {fq(c.sigma, 'm')} | {fq(c.shift, 'm')} | "
                     f"{fq(c.offset, 'm')} | {fq(c.drift, 'm/s')} | {fq(c.rms_residual, 'm')} |")
        if self.warnings:
            L += ["", "Warnings:", ""] + [f"- {w}" for w in self.warnings]
        return "\n".join(L) + "\n"


def wald_interval(value: float, stderr: float, level: float, lower: float,
                  upper: float, physical_lower: bool = False) -> tuple[tuple, str]:
    """``value +- z stderr`` and a note; a side beyond a search bound is None (one-sided).

    A side below a physical lower bound (``physical_lower``, e.g. xi >= 0) ends at it.
    """
    from scipy.stats import norm

    z = float(norm.ppf(0.5 + level / 2))
    lo = value - z * stderr if math.isfinite(stderr) else -math.inf
    hi = value + z * stderr if math.isfinite(stderr) else math.inf
    notes = []
    if lo <= lower:
        lo = lower if physical_lower else None
        if lo is None:
            notes.append(f"no lower end above the search bound {lower:.3g}")
    if hi >= upper:
        hi = None
        notes.append(f"no upper end below the search bound {upper:.3g}")
    return (None if lo is None else float(lo), None if hi is None else float(hi)), \
        ("one-sided Wald interval: " + "; ".join(notes) if notes else "")
