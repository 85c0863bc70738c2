"""``fit_dynamic``: fit the dynamic model jointly to curves measured at several speeds."""

from __future__ import annotations

import math
import time
from typing import Mapping, Sequence

import numpy as np

from ..errors import ParameterError
from ..limits import MAX_STARTS, check_count
from ..progress import Progress
from .data import FitCurve, prepare_curves
from .memory import check_fit_memory
from .model import DEFAULT_FRINGE_PERIOD, Evaluator
from .preprocess import preparation_warnings, result_warnings
from .._fields import check as check_value
from .params import LAW_PARAMETERS, PARAMETERS, SPEED_DEPENDENT, check_free
from .problem import Problem, local_fit
from .search import _refit_all, _search
from .result import CurveFit, Estimate, FitResult, contain_value, wald_interval

__all__ = ["fit_dynamic", "IdentifiabilityError", "base_config", "local_fit", "SPEED_DEPENDENT", "check_speeds",
           "check_curve_count", "MAX_CURVES"]

#: Above this viscosity [Pa s] the medium is a liquid (air 1.8e-5, hexane 3e-4, water 8.9e-4):
#: drainage and double-layer forces then bend the approach like an indentation does, so a curve
#: the analysis calls a soft contact is fitted (with a warning) rather than refused.
LIQUID_VISCOSITY = 1e-4
#: Largest amplitude of fitted ``periodic`` fringes taken as fringes [m]: the paper's Park
#: instrument showed 1.5 nm (section 3.1), present-day ones less; a larger fitted amplitude
#: means the fringe terms took up something else (docs/fit.md).
FRINGE_AMPLITUDE_MAX = 3e-9


#: Free parameters the approach alone cannot determine: the retract is fitted with them when
#: the curves have it (``retract=None``), otherwise they are reported undetermined. A constant
#: lever drag (``lever_height`` 0) is an offset ``c v / k`` of the free approach, absorbed by
#: each curve's baseline offset; the retract's offset has the opposite sign.
NEEDS_RETRACT = ("lever_drag",)
#: Curves one joint fit takes at most: the model is integrated for every curve at every step of
#: the search, the profiles and the comparison, and each curve adds its own shift, offset and
#: drift, so a force map's 100 curves would run for hours in a GB (the audit: past 15 minutes);
#: the fit is for a few curves at several speeds (a map's pixels are analysed one by one).
MAX_CURVES = 32

#: Trial runs the search may lose quietly, as a share of all: a step into a region where the model
#: cannot run (a start already in contact) is refused and the search goes on; the best point's own runs
#: are checked apart (``_failed_runs``). ``afmforce fit --example speeds`` (the README's) lost 1 of
#: 2717 and said so as a warning the user could not act on ("start 28.43 nm is already in contact").
TRIAL_FAILURES_QUIET = 0.01


def retract_follows(curve) -> bool:
    """Whether ``curve`` (a RawCurve) has a retract run directly after its approach."""
    seg = np.asarray(getattr(curve, "segment", ()))
    app = np.flatnonzero(seg == 0)
    if app.size < 30:
        return False
    run = app[: np.flatnonzero(np.diff(app) != 1)[0] + 1] if np.any(np.diff(app) != 1) else app
    nxt = int(run[-1]) + 1
    return nxt < seg.size and seg[nxt] == 1 and int(np.sum(seg[nxt:] == 1)) >= 30


class IdentifiabilityError(ParameterError):
    """The data cannot determine a free parameter (e.g. friction from one speed)."""


def check_curve_count(n: int) -> None:
    """Refuse a joint fit of more than :data:`MAX_CURVES` curves (``n``). Cheap: the web checks the
    curves its uploads hold before a job starts.

    Raises
    ------
    ParameterError
    """
    if n > MAX_CURVES:
        raise ParameterError(
            f"a joint fit of {n} curves: the dynamic fit takes at most {MAX_CURVES} (the model is "
            "integrated for every curve at every step; a force map's curves would take hours): give a few "
            "curves at several speeds, and analyse a map's curves one by one with `afmforce analyze` (its vdw "
            "step fits each curve's A R)")


def _failed_runs(prob, x, curves) -> str | None:
    """Say so when the model of a curve could not be integrated at the best point: its residual is
    the search's penalty (:data:`~afmforce.fit.model.FAILED_RESIDUAL` a sample), its offset and drift
    NaN, and the fit's numbers (chi2 504,000,000 on a 504-point sapphire curve, A at its search bound)
    are of no run of the model. None when every curve's run succeeded."""
    values, shifts = prob.unpack(x)
    failed = [c.name for c, (_, coef) in zip(curves, prob.projections(values, shifts)[0])
              if np.all(np.isnan(coef))]
    if not failed:
        return None
    ev = prob.ev
    return (f"the model could not be integrated at the fit's best parameters for {', '.join(failed[:3])}"
            f"{' ...' if len(failed) > 3 else ''} ({ev.failures} trial runs failed; last: {ev.last_error}): "
            "the values reported are of no run of the model, not a fit; the data are far from any run of "
            "it (check the curves' calibration, their spring constant against the model's lever, and the "
            "drive range)")


def check_speeds(free: Sequence[str], velocities: Sequence[float]) -> None:
    """Refuse a speed-dependent free parameter (:data:`SPEED_DEPENDENT`) with curves at one
    driving speed (less than 1.2x apart): friction lowers the apparent attraction like a smaller
    A*R does, and one speed cannot tell them apart. Cheap: the web checks it before a job starts.

    Raises
    ------
    IdentifiabilityError
    """
    speeds = sorted({round(float(v), 15) for v in velocities})
    dep = [n for n in free if n in SPEED_DEPENDENT]
    if dep and speeds and (len(speeds) < 2 or speeds[-1] / speeds[0] < 1.2):
        raise IdentifiabilityError(
            f"{', '.join(dep)} cannot be determined from curves at one driving speed "
            f"({speeds[0] * 1e6:.3g} um/s): friction (and inertia, drainage) lowers the "
            "apparent attraction like a smaller A*R would; give curves at >= 2 speeds "
            "(ideally a factor >= 4 apart) or fix " + ", ".join(dep)
            + " (e.g. `free` hamaker and `xi` 0: A*R alone, without friction)")


def base_config(model="beam", **fields):
    """A :class:`~afmforce.dynamics.SimulationConfig` from a model name, a config or a dict."""
    from ..dynamics import SimulationConfig

    if isinstance(model, SimulationConfig):
        return model.replace(**fields) if fields else model
    if isinstance(model, Mapping):
        return SimulationConfig(**{**dict(model), **fields})
    return SimulationConfig(model=str(model), **fields)


def _guess_globals(curves: list[FitCurve], base, free: tuple[str, ...]) -> dict:
    """Static first guesses: A (or R) from the static jump-in deflection of the slowest curve."""
    from ..dynamics.static import surface_jump_in

    g = {n: float(getattr(base, n)) for n in free}
    slow = min(curves, key=lambda c: c.velocity)
    target = slow.guess["min_deflection"]
    k = base.force_constant
    for name in ("hamaker", "radius"):
        if name not in free or not (target < 0):
            continue
        p = PARAMETERS[name]

        def inside(log_value: float) -> float:   # exp(log(1e-22)) is 9.99...e-23: keep the bounds
            return min(max(math.exp(log_value), p.lower), p.upper)

        lo, hi = math.log(p.lower), math.log(p.upper)
        for _ in range(60):   # |static jump deflection| grows with A*R
            mid = 0.5 * (lo + hi)
            dj = surface_jump_in(k, base.surface.replace(**{name: inside(mid)}))[2]
            lo, hi = (mid, hi) if dj > target else (lo, mid)
        g[name] = inside(0.5 * (lo + hi))
    for name in ("xi", "zeta", "slip_length", *LAW_PARAMETERS):
        if name in free:
            g[name] = max(g[name], PARAMETERS[name].abs_step)
    return g


def files_spring_constant(curves: list[FitCurve]) -> float | None:
    """The curves' spring constant [N/m]: the analysis's (the file's, rescaled with a refitted
    sensitivity, or a force's compliance slope), median over the curves; None without one."""
    ks = [(c.metadata.get("calibration") or {}).get("spring_constant")
          or (c.metadata or {}).get("spring_constant") for c in curves]
    ks = [float(k) for k in ks if k and math.isfinite(float(k)) and float(k) > 0]
    return float(np.median(ks)) if ks else None


def lever_from_files(base, curves: list[FitCurve], lever: str = "file"):
    """The model's lever calibrated as the files are (issue 34: defaults right as typed).

    ``lever="file"``: the spring model takes the curves' spring constant, the beam its
    rigidity scaled so that its spring constant (eq 13) is the curves' (``k0 * k_file / k``);
    ``"model"``: the lever as ``base`` has it (the user gave one). A free spring constant
    starts from the files' in either case. Curves without a spring constant leave ``base``.
    """
    k_file = files_spring_constant(curves)
    if k_file is None or lever == "model":
        return base
    if base.model == "spring":
        return base.replace(spring_constant=k_file)
    return base.replace(k0=base.cantilever.k0 * k_file / base.force_constant)


def lever_warnings(curves: list[FitCurve], base, lever: str = "file") -> list[str]:
    """Say which spring constant the model's lever took where a file gives none (the walk of
    2026-11-29: curves in volts with their sensitivity but no spring constant were fitted with the
    beam's default 0.139 N/m in silence; simulated with 0.277 N/m, A = 2.76e-19 J [2.34, 3.18]e-19
    and xi = 0.049 [0.043, 0.054] kg/s for 5e-19 J and 0.1 kg/s, "adequate").

    ``lever="model"`` (the user gave the lever): nothing to say. Otherwise, with no curve's spring
    constant the model's default lever is named (A*R and friction scale with k); with some
    curves' only, those without are named (one probe: the others' is taken).
    """
    if lever == "model":
        return []
    has = [files_spring_constant([c]) is not None for c in curves]
    if all(has):
        return []
    k = float(base.force_constant)
    if not any(has):
        return [f"no curve's file gives the lever's spring constant: the model's default lever "
                f"({base.model} model, {k:.4g} N/m) was taken, and the fitted A*R and friction scale "
                "with k; give the files' (`spring_constant`) or the model's lever (`k0`)"]
    names = [c.name for c, h in zip(curves, has) if not h]
    return [f"{', '.join(names[:3])}{' ...' if len(names) > 3 else ''}: no spring constant in the "
            f"file; taken as the other curves' {k:.4g} N/m (a joint fit assumes one lever)"]


#: A lever's spring constant fitted in situ (``spring_constant``, ``k0`` free) beyond this factor of
#: the files' is no result: a calibrated k is good to 10-20 %, a nominal one to about x2, so a k the
#: drainage puts 5x away is the model's misfit (radius, viscosity, a force it lacks) or a wrong file.
K_FILE_FACTOR = 5.0


def lever_off_files(params: Mapping, base, curves: list[FitCurve]) -> str | None:
    """Why a fitted in-situ spring constant is no result (None when it is one, or none is fitted).

    The fitted lever's spring constant [N/m]: ``spring_constant`` itself (spring model) or the
    beam's eq-13 constant scaled by the fitted ``k0`` (``force_constant * k0_fit / k0``); compared
    with the curves' (:func:`files_spring_constant`) against :data:`K_FILE_FACTOR`.
    """
    k_file = files_spring_constant(curves)
    if k_file is None:
        return None
    if "spring_constant" in params:
        name, k_fit = "spring_constant", float(params["spring_constant"].value)
    elif "k0" in params:
        name = "k0"
        k_fit = float(base.force_constant) * float(params["k0"].value) / float(base.cantilever.k0)
    else:
        return None
    ratio = k_fit / k_file
    if 1.0 / K_FILE_FACTOR <= ratio <= K_FILE_FACTOR:
        return None
    return (f"{name}: not a result: the lever's spring constant fitted in situ, {k_fit:.4g} N/m, is "
            f"{ratio:.3g} x the files' {k_file:.4g} N/m (beyond x{K_FILE_FACTOR:g}: no lever's "
            "calibration is that far off); the drainage force the model ascribes to k is another "
            "force, radius or viscosity, or the files' calibration is wrong: check them (`afmforce "
            "calibrate thermal`) before reading k, A*R or the slip length")


def files_resonance(curves: list[FitCurve]) -> float | None:
    """The curves' lever resonance [Hz]: their files' (a thermal tune's ``resonance_frequency``),
    median over the curves; None where no file gives one."""
    fs = [(c.metadata or {}).get("resonance_frequency") for c in curves]
    fs = [float(f) for f in fs if isinstance(f, (int, float)) and math.isfinite(float(f)) and float(f) > 0]
    return float(np.median(fs)) if fs else None


#: The model fields that, when the user gives one, make the model's lever (``LEVER_FIELDS``) or its
#: mass (``MASS_FIELDS``) win over the files' calibration and resonance (issue 34): one declaration
#: for the CLI's ``fit`` and the web's fit (:func:`lever_sources`).
LEVER_FIELDS = ("spring_constant", "k0", "B")
MASS_FIELDS = ("mass", "m_joint", "m_base")


def lever_sources(given) -> dict[str, str]:
    """``fit_dynamic``'s ``lever`` and ``mass`` arguments for the model fields the user gave
    (names in ``given``): ``"model"`` where one of :data:`LEVER_FIELDS` / :data:`MASS_FIELDS` is
    given, else ``"file"``."""
    given = set(given)
    return {"lever": "model" if given & set(LEVER_FIELDS) else "file",
            "mass": "model" if given & set(MASS_FIELDS) else "file"}


def mass_from_files(base, curves: list[FitCurve], mass: str = "file"):
    """The model's lever mass set so that its first free resonance is the files' (issue 34:
    defaults right as typed; the model's default lever rings at 4-6 kHz for the beam, 0.7 kHz for
    the spring, a real lever's thermal tune at 10-300 kHz, so its inertia was off by 10-10^4 x).

    ``mass="file"``: the spring's ``mass`` becomes ``k / (2 pi f)^2``, the beam's ``m_joint`` and
    ``m_base`` are scaled together by ``(f_model / f)^2`` (every mode of the beam scales as
    ``1/sqrt(mass)``); ``"model"``: the masses as ``base`` has them (the user gave one). Curves
    without a resonance leave ``base``.
    """
    f_file = files_resonance(curves)
    if f_file is None or mass == "model":
        return base
    from ..dynamics.thermal import free_resonance

    scale = (free_resonance(base.probe)[0] / f_file) ** 2
    if base.model == "spring":
        return base.replace(mass=base.probe.mass * scale)
    return base.replace(m_joint=base.probe.m_joint * scale, m_base=base.probe.m_base * scale)


#: Slope of the deflection against the piezo (dy/dz) above which a noise-free fit leaves an
#: approach sample before the jump-in out: there the lever's stiffness less the force gradient
#: is below half the lever's (dy/dz = F'/(k - F')), and the model's integration error is
#: amplified more than twofold (a saddle-node: the ``ideal`` preset's truth misfits there by
#: 25-150 integration tolerances, 5 samples at 0.5 um/s, 1 at 2 um/s).
JUMP_APPROACH_SLOPE = 1.0
#: Piezo travel before the jump-in within which :data:`JUMP_APPROACH_SLOPE` may leave samples
#: out [m] (the steep run spans 0.25 nm on the ``ideal`` preset; a jump index misplaced into a
#: hard contact, slope ~1, loses no more than this).
JUMP_APPROACH_RANGE = 1e-9


def _jump_approach(c) -> np.ndarray:
    """Indices of the approach samples just before the jump-in of curve ``c`` whose deflection
    rises faster than the piezo moves (:data:`JUMP_APPROACH_SLOPE`)."""
    j = int(c.jump_index)
    if j < 3:
        return np.zeros(0, int)
    z, y = np.asarray(c.position[:j], float), np.asarray(c.deflection[:j], float)
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.abs(np.gradient(y, z))
    k = j - 1
    while k > 0 and (not np.isfinite(s[k]) or s[k] > JUMP_APPROACH_SLOPE) \
            and abs(z[j - 1] - z[k]) < JUMP_APPROACH_RANGE:
        k -= 1
    return np.arange(k + 1, j)


def noise_floor(fc: list, atol: float) -> str | None:
    """Raise each curve's noise estimate [m] to the model's absolute tolerance ``atol`` [m].

    Noise-free curves (the ``ideal`` virtual AFM; a simulation written to a file) have a noise
    estimate of zero (second differences of a smooth baseline: 1e-15 m), and a chi-square in
    units of it measures the integrator's error, not the data's: the ``ideal`` preset's fit
    ended at reduced chi-square 1e8, on a wrong optimum (the 8 um/s curve's zero 20 nm off,
    A +15 %, xi -7 %, a 0.38 nm fringe fitted where there is none). Below ``atol`` (the model's
    own precision, :class:`afmforce.dynamics.parts.Numerics` ``atol``) the noise is taken as
    ``atol``: an absolute tolerance. The approach's last samples before the jump-in, where the
    model's error is amplified far above ``atol`` (:func:`_jump_approach`), are left out of
    such curves' masks: with them the truth itself misfit (reduced chi-square 28, 25-150 pm
    there), and which optimum the fit ended on turned on the data's last ulp (reduced
    chi-square 47 or 0.96 after a change of 3e-23 m); without them the truth fits to 0.1 pm.
    Returns the warning, or None when no curve was raised.
    """
    low = [c for c in fc if c.sigma < atol]
    if not low:
        return None
    for c in low:
        c.sigma = float(atol)
        c.mask = np.array(c.mask, bool)
        c.mask[_jump_approach(c)] = False
    names = ", ".join(c.name for c in low)
    return (f"{names}: no noise in the data (estimate below the model's absolute tolerance "
            f"{atol * 1e9:.3g} nm): noise-free curves, e.g. a simulation; the fit takes that "
            "tolerance as the noise (an absolute tolerance) and leaves out the approach's last "
            "samples before the jump-in (where the model's error is amplified), so its "
            "chi-square measures the misfit in units of the model's precision, not of the "
            "data's noise")


def _covariance(J: np.ndarray, scale: float) -> np.ndarray:
    JTJ = J.T @ J
    try:
        return np.linalg.pinv(JTJ, rcond=1e-12) * scale
    except np.linalg.LinAlgError:
        return np.full(JTJ.shape, np.nan)


def slip_wald_unreliable(e, curves, level: float) -> str:
    """Why the Wald interval of a fitted slip length cannot be trusted ("" when it can).

    Far from the surface (h >> b) Vinogradova's factor is ``f* ~ 1 - 2b/h``: the slip shifts the
    drainage like a change of separation, and the fit's likelihood is quadratic in b. Where b reaches
    a sixth of the separations fitted, ``6b/h ~ 1``, the drainage depends on b only through
    ``f* ~ (h/3b) ln(6b/h)``: a slow logarithm, traded against the spring constant's scale, and the
    likelihood is far from quadratic (on virtual curves with b = 1 um, 140 nm of approach, k free,
    the Wald interval was [0, 0.90 um], without the truth; the profile [0.20 um, open]). Then only a
    profile interval says what the data bound.
    """
    from scipy.stats import norm

    h_max = max((float(np.ptp(np.asarray(c.position)[: max(int(c.jump_index), 1)])) for c in curves),
                default=0.0)
    top = e.value + float(norm.ppf(0.5 + level / 2)) * e.stderr if math.isfinite(e.stderr) else math.inf
    if not h_max > 0 or top * 6.0 >= h_max:
        return (f"the slip length ({e.value * 1e9:.3g} nm, Wald upper end {top * 1e9:.3g} nm) is not small "
                f"against the separations fitted (up to {h_max * 1e9:.3g} nm): the drainage there depends on "
                "it too weakly for a standard error; profile it (`profile` slip_length, the default) for "
                "what the data bound")
    return ""


def check_starts(starts: int) -> None:
    """Refuse a number of local fits outside ``[1, MAX_STARTS]`` (:data:`afmforce.limits.MAX_STARTS`).

    Raises
    ------
    ParameterError
        Naming `` `starts` ``.
    """
    if isinstance(starts, bool) or not isinstance(starts, (int, np.integer)) or starts < 1:
        raise ParameterError(f"`starts` must be a whole number of local fits, at least 1, got {starts!r}")
    check_count("`starts`", starts, MAX_STARTS, "local fits")


def _curvature_report(prob, x, redchi: float) -> dict:
    """The fitted photodiode curvature ``q`` [1/m] and its standard error (scaled like the
    parameters' by the reduced chi-square where above 1); None where it is not fitted."""
    if not prob.ev.curvature:
        return {"curvature": None, "curvature_stderr": None}
    prob.fringe_amplitude(x)             # sets ev.curvature_fit at x
    q, se = prob.ev.curvature_fit
    return {"curvature": q, "curvature_stderr": se * math.sqrt(max(redchi, 1.0))}


def fit_dynamic(curves: Sequence, model="beam", free: Sequence[str] = ("hamaker", "xi"),
                fixed: Mapping[str, float] | None = None, *, names: Sequence[str] | None = None,
                velocities: Sequence[float] | None = None,
                sample_rates: Sequence[float] | None = None, drift: bool = True,
                starts: int = 2, level: float = 0.95, profile: Sequence[str] | None = None,
                compare: bool = True, jump_window: float | None = None,
                max_nfev: int = 40, sampling: str | None = "average",
                retract: bool | None = None, noise: str = "auto", fringes: str | bool = "periodic",
                fringe_period: float = DEFAULT_FRINGE_PERIOD, calibration: str = "auto",
                lever: str = "file", mass: str = "file", curvature: bool = False,
                progress=None) -> FitResult:
    """Fit the dynamic model jointly to approach curves measured at several speeds.

    Parameters
    ----------
    curves : sequence of RawCurve or FitCurve
        Calibrated curves (deflection in metres) with ``velocity`` [m/s] and
        ``sample_rate`` [Hz] in their metadata (or given here).
    model : str, SimulationConfig or dict
        ``"beam"`` / ``"spring"`` with the defaults of ``afmforce simulate``,
        or a configuration holding every fixed parameter.
    free : sequence of str
        Global parameters to fit (:data:`afmforce.fit.PARAMETERS`). The zero
        of position, baseline offset and drift of every curve are always fitted.
    fixed : mapping, optional
        Values [SI] of global parameters held fixed (override ``model``).
    names : sequence of str, optional
        Curve labels.
    velocities, sample_rates : sequence of float, optional
        Override the metadata [m/s], [Hz].
    drift : bool
        Fit a linear drift per curve.
    starts : int
        Local fits started from the best points of a scan in xi and A*R
        (multi-start); up to ``2 starts + 2`` while the best fit looks stuck
        (reduced chi-square > 1.5).
    level : float
        Confidence level of the intervals and of the friction test.
    profile : sequence of str, optional
        Parameters with profile-likelihood intervals; default: the free ones
        among ``hamaker``, ``radius``, ``xi``, ``slip_length``, ``lever_drag``,
        ``surface_potential`` and ``debye_length``.
    compare : bool
        Fit the static and the friction-free model too (model comparison).
    jump_window : float, optional
        Samples this long after the jump-in are left out [s] (the jump and the
        landing transient are timing, not shape; see docs/fit.md). None (default):
        chosen from each curve, until its deflection has landed on the contact line
        (:func:`afmforce.fit.data.landing_samples`, at most 2 ms).
    max_nfev : int
        Iteration budget of each local fit.
    sampling : {"average", "point"} or None
        What a recorded sample is in the model (``SimulationConfig.sampling``):
        ``average`` (default) the deflection averaged over each sample
        interval, as instruments that oversample and average their detector
        record it; this also removes the aliased MHz contact ringing that a
        nearly frictionless beam keeps and that no fit can match in phase.
        None: as ``model`` says.
    progress : callable, optional
        Called with a :class:`~afmforce.progress.Progress` (unit ``"stage"``: the
        local fits, each profile, the model comparison) after each stage; may raise
        to stop the fit (the web server's cancel).
    retract : bool, optional
        Fit the retract run of each curve too (it must follow the approach
        without a pause): the outward compliance line and its hysteresis carry
        friction, the pull-off (and ``jump_window`` after it) is left out. None
        (default): when a free parameter needs it (:data:`NEEDS_RETRACT`: a constant
        lever drag is a baseline offset on the approach alone) and every curve has one;
        otherwise such a parameter is reported undetermined (open interval).

    noise : {"auto", "white"}
        ``auto``: after a first fit, estimate 1/f detector noise from the residuals of
        the free approach and, where it is significant, refit with the whitened
        residuals (generalised least squares; :mod:`afmforce.fit.noise`).
        ``white``: white noise only (the noise rms of each curve from second differences).

    fringes : {"off", "periodic", "parabola"} or bool
        Interference fringes in the baseline (they run with the separation and stop in
        contact; :class:`~afmforce.fit.model.Evaluator`): ``periodic`` (default, True)
        two linear nuisances shared by all curves, ``cos`` and ``sin`` of ``2 pi h /
        fringe_period`` (curves taken at one spot); ``parabola`` a line and a parabola
        before contact per curve (curves whose fringes differ); ``off``.
    fringe_period : float
        Period of the ``periodic`` fringes in the separation [m]: half the laser
        wavelength at normal incidence (default 335 nm, a 670 nm laser diode).
    curvature : bool
        Fit the photodiode's curved response ``d + q d^2`` (default False): ``q`` [1/m], one
        linear nuisance shared by the curves (:class:`~afmforce.fit.model.Evaluator`), reported
        in ``photodiode``. Off by default: in contact it cannot be told from a piezo's bend (the
        ``paper`` preset, seed 2: q = -1.5e6 /m +- 0.4e6 fitted for none, A 3.3e-18 J, not
        adequate), and on the ``liquid`` preset (L = 3 um) the intervals cover without it.
    calibration : {"auto", "fit", "metadata"}
        The analysis's ``calibration.source``, one rule with ``afmforce analyze``
        (:class:`~afmforce.analysis.options.CalibrationOptions`): ``auto`` the files'
        sensitivities wherever they have one (the compliance slope without one, or where a hard
        contact's straight line makes the file's impossible); ``fit`` the compliance slope (a
        file's thermal k rescaled); ``metadata`` the files' always. ``file``: the former word
        for ``metadata``.
    lever : {"file", "model"}
        ``file`` (default): the model's lever calibrated as the curves are: the spring
        model's ``spring_constant`` is the curves' (the analysis's k), the beam's rigidity
        is scaled to give it (:func:`lever_from_files`); ``model``: the lever of ``model``
        as given (a spring constant in ``fixed`` counts as given too). Curves without a
        spring constant keep the model's.
    mass : {"file", "model"}
        ``file`` (default): the model lever's mass set so that its first free resonance is the
        files' ``resonance_frequency`` (:func:`mass_from_files`); ``model``: the masses of
        ``model`` as given (a mass in ``fixed`` or ``free`` counts as given too). Curves without
        a resonance keep the model's.

    Returns
    -------
    FitResult

    Raises
    ------
    ParameterError, IdentifiabilityError, FileFormatError, AnalysisError
        Bad parameters, a speed-dependent parameter with all curves at one
        speed, uncalibrated or inconsistent curves, a curve without contact.
    """
    check_starts(starts)
    t0 = time.perf_counter()
    check_value("jump_window", jump_window)        # the declared ranges (afmforce._fields.QUANTITIES)
    check_value("fringe_period", fringe_period)
    from .adequacy import adequacy, undetermined_verdict
    from .damping_check import damping_check, undamped_verdict
    from .noise import (PINK_SIGNIFICANCE, baseline_pink, baseline_refusal, estimate_pink,
                        pink_refusal, set_noise_model)
    from .uncertainty import compare_models, fit_nested, profile_interval, profiled_estimate

    from .preprocess import calibration_source
    calibration = calibration_source(calibration)   # the analysis's words (calibration.source); "file": metadata
    if noise not in ("auto", "white"):
        raise ParameterError(f"noise must be 'auto' or 'white', got {noise!r}")
    if not 0.5 < level < 1.0:
        raise ParameterError(f"level must lie between 0.5 and 1, got {level!r}")
    base = base_config(model, **dict(fixed or {}))
    if sampling is not None:
        base = base.replace(sampling=sampling)
    free = check_free(free, base.model, base.friction.law if base.model == "beam" else None)
    check_curve_count(len(curves))
    need = [n for n in free if n in NEEDS_RETRACT]
    if retract is None:
        retract = bool(need) and all(not isinstance(c, FitCurve) and retract_follows(c)
                                     for c in curves)
    fc = prepare_curves(curves, names, velocities=velocities, sample_rates=sample_rates,
                        jump_window=jump_window, retract=retract,
                        soft="warn" if base.viscosity > LIQUID_VISCOSITY else "refuse",
                        calibration=calibration)
    check_fit_memory(sum(c.n for c in fc), len(free), len(fc))   # before the large arrays
    if lever not in ("file", "model"):
        raise ParameterError(f"lever must be 'file' or 'model', got {lever!r}")
    if {"spring_constant", "k0"} & set(fixed or {}):
        lever = "model"                      # given by the caller
    base = lever_from_files(base, fc, lever)
    if lever == "model" and {"spring_constant", "k0"} & set(free):
        base = lever_from_files(base, fc, "file")   # a free k starts from the files' (issue 25)
    if mass not in ("file", "model"):
        raise ParameterError(f"mass must be 'file' or 'model', got {mass!r}")
    if {"mass", "m_joint", "m_base"} & (set(fixed or {}) | set(free)):
        mass = "model"                       # given (or fitted) by the caller
    base = mass_from_files(base, fc, mass)   # after k: the files' resonance with the files' k
    check_speeds(free, [c.velocity for c in fc])
    nominal = [(c.metadata or {}).get("velocity") for c in fc]
    if velocities is None and all(nominal):   # the files' set speeds: a map recorded at one speed is one
        check_speeds(free, nominal)           # speed, whatever its measured speeds' scatter (a 1.26x outlier)
    undetermined = [] if any(c.retract_start is not None for c in fc) else need
    floor_note = noise_floor(fc, base.atol)      # noise-free data: chi2 in the model's precision
    ev = Evaluator(fc, base, "dynamic", drift, fringes, fringe_period, curvature)
    prob = Problem(ev, free)
    guess = _guess_globals(fc, base, free)
    shifts0 = [c.guess["shift"] for c in fc]
    n_data = sum(int(c.mask.sum()) for c in fc)
    n_par = len(shifts0) + len(free) + ev.n_linear()
    dof = max(n_data - n_par, 1)
    todo = [n for n in (profile if profile is not None else (
        "hamaker", "radius", "xi", "z0", "mass", "m_joint", "slip_length", "lever_drag",
        "surface_potential", "debye_length")) if n in free and n not in undetermined]
    # z0, mass, m_joint: barely determined, their Wald intervals missed the truth (tests/fit/test_fit_extra_free_params.py)
    if floor_note:      # no noise: no statistical interval to profile (see noise_floor)
        todo = []
    stages = {"done": 0, "total": 2 + len(todo) + 2 * int(compare)}

    def report(what: str) -> None:
        if progress is not None:
            stages["done"] += 1
            stages["total"] = max(stages["total"], stages["done"])
            progress(Progress(stages["done"], stages["total"], "stage", what))

    chi2, x, res, nested, first = _search(prob, guess, shifts0, starts, max_nfev, dof)
    report("search")
    pre_warns = [floor_note] if floor_note else []
    fringe_amp = prob.fringe_amplitude(x)[0]
    if fringe_amp > FRINGE_AMPLITUDE_MAX:
        # with each curve's drift, the fringe's kink at contact can take up a tilted contact
        # line (a soft sample) or a bent baseline: more than fringes are. Fit without them.
        pre_warns.append(
            f"the fitted interference fringes ({fringe_amp * 1e9:.3g} nm, period "
            f"{fringe_period * 1e9:.3g} nm) exceed the {FRINGE_AMPLITUDE_MAX * 1e9:g} nm that "
            "fringes reach: they took up a misfit (a soft contact? a bent baseline?); fitted "
            "without fringe terms (`fringes` off)")
        ev.fringes = "off"
        dof = max(n_data - (len(shifts0) + len(free) + ev.n_linear()), 1)
        chi2, x, res, nested = _refit_all(prob, [x] + first, nested, max_nfev)
    s2p, signif = estimate_pink(prob, x, drift) if noise == "auto" else (0.0, 0.0)
    not_noise = pink_refusal(s2p, [c.sigma for c in fc]) if signif > PINK_SIGNIFICANCE else None
    # the detector's 1/f noise shows on the baselines too (noise-free curves: the residual is the
    # solver's error, which sits where the model is stiff, the jump-in; no interval is given there)
    if signif > PINK_SIGNIFICANCE and not not_noise and not floor_note:
        s2b, sig_b, power = baseline_pink(prob, x)      # where the model is a line
        not_noise = baseline_refusal(s2p, s2b, sig_b, power)
        if sig_b > PINK_SIGNIFICANCE:
            s2p = min(s2p, s2b)
    if not_noise:                    # a misfit taken for 1/f noise would pass any model
        pre_warns.append(not_noise)
    elif signif > PINK_SIGNIFICANCE:  # 1/f noise: refit with the whitened residuals from the
        set_noise_model(fc, s2p)      # white optimum and the valley's best points
        chi2, x, res, nested = _refit_all(prob, [x] + first, nested, max_nfev)
        report("refit with 1/f noise")
    nested_fits = None
    if compare:   # nested models: the richer one restarts from the nested optimum if that is lower
        nested_fits = fit_nested(prob, x, fc, base, drift, max_nfev,
                                 starts=[nested[1]] if nested is not None else ())
        nf = nested_fits["no_friction"]
        if nf is not None and nf[0] < chi2:
            x2, res2 = local_fit(prob, nf[1], max_nfev)
            c2 = prob.chi2(x2)
            chi2, x, res = (c2, x2, res2) if c2 <= nf[0] else (nf[0], nf[1], res)
        report("nested models")
    failed_runs = _failed_runs(prob, x, fc)
    redchi = chi2 / dof
    J = prob.jacobian(x)
    cov = _covariance(J, max(redchi, 1.0))
    sd = np.sqrt(np.clip(np.diag(cov), 0, None)) * prob.scale()
    values, shifts = prob.unpack(x)
    warns = pre_warns + [c.metadata["velocity_from_ramp"] for c in fc
                         if c.metadata.get("velocity_from_ramp")]
    warns += preparation_warnings(fc, base)     # calibration notes, the files' k vs the model's
    warns += lever_warnings(fc, base, lever)    # a k no file gives: the model's, said so
    if failed_runs:
        warns.append(failed_runs)
    elif ev.failures > TRIAL_FAILURES_QUIET * ev.simulations:
        warns.append(f"{ev.failures} of {ev.simulations} trial simulations failed during the fit "
                     f"(last: {ev.last_error})")
    adq = adequacy(prob, x, dof, chi2, fc, jump=not floor_note)
    if not adq["adequate"]:
        warns.append(f"{adq['reason']}: the model "
                     "does not describe the data within their noise; no verdict on friction, and "
                     "the intervals (scaled by it) may be optimistic. " + "; ".join(adq["worst"])
                     + f"; {adq['advice']}")
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.sqrt(np.outer(np.diag(cov), np.diag(cov)))
    g = len(free)
    correlations = {f"{a}:{b}": float(corr[i, j]) for i, a in enumerate(free)
                    for j, b in enumerate(free) if j > i}
    for k_, r in correlations.items():
        if abs(r) > 0.98:
            warns.append(f"{k_.replace(':', ' and ')} are nearly not identifiable separately "
                         f"(correlation {r:.3f}); add curves at more different speeds or fix one")
    params = {}
    for j, name in enumerate(free):
        p = PARAMETERS[name]
        iv, note = wald_interval(values[name], float(sd[j]), level, p.lower, p.upper,
                                 p.physical_lower)
        params[name] = Estimate(values[name], float(sd[j]), iv, "wald", p.unit,
                                f"{name}: {note}" if note else "")
    profiles = {}
    for name in todo:
        lo, hi, pts, note = profile_interval(prob, x, chi2, name, float(sd[free.index(name)]),
                                             max(redchi, 1.0), level, cov=cov)
        e = params[name]
        e.interval = (lo, hi)
        e.interval_method, e.stderr, e.note = profiled_estimate(name, lo, hi, note, e.stderr, e.unit)
        profiles[name] = pts
        report(f"profile of {name}")
    if "slip_length" in params and "slip_length" not in profiles:
        why = slip_wald_unreliable(params["slip_length"], fc, level)
        if why:
            e = params["slip_length"]
            e.interval, e.interval_method, e.note = (None, None), "undetermined", f"slip_length: undetermined: {why}"
    for name in undetermined:     # a constant lever drag on approaches alone (NEEDS_RETRACT)
        e = params[name]
        e.interval, e.interval_method, e.stderr = (None, None), "undetermined", math.nan
        e.note = (f"{name}: undetermined: on the approach alone a constant lever drag is a "
                  "baseline offset (c v / k), taken up by each curve's offset, and otherwise "
                  "shows only in the ramp's start-up transient (how the instrument starts its "
                  "ramp); fit the curves with their retract runs")
    if floor_note:     # noise-free curves: chi2 in units of the model's tolerance is no likelihood
        for name, e in params.items():
            e.interval, e.interval_method, e.stderr = (None, None), "undetermined", math.nan
            e.note = (f"{name}: no interval: the curves carry no noise, so no interval is a "
                      "confidence interval; the estimate is off by the model's own error (the "
                      "`ideal` virtual AFM, seed 1 at 0.5, 2 and 8 um/s: A +0.2 %, xi -0.1 %)")
    off = lever_off_files(params, base, fc)
    if off:               # a lever 5x from its calibration: no number, the reason instead
        e = params["spring_constant" if "spring_constant" in params else "k0"]
        e.interval, e.interval_method, e.stderr = (None, None), "undetermined", math.nan
        e.note = off
    for name, e in params.items():
        note = contain_value(name, e)
        e.note = "; ".join(t for t in (e.note, note) if t)
    for e in params.values():
        if e.note:
            warns.append(e.note)
    warns += result_warnings(params, base)     # a Hamaker constant outside the physical range
    derived = {}
    if "hamaker" in free or "radius" in free:
        name = "hamaker" if "hamaker" in free else "radius"
        other = base.radius if name == "hamaker" else base.hamaker
        e = params[name]
        derived["hamaker_radius"] = Estimate(
            e.value * other, e.stderr * other,
            tuple(None if v is None else v * other for v in e.interval),
            e.interval_method, "J m", e.note)
    comparison = None
    if compare:
        comparison = compare_models(prob, x, chi2, fc, base, drift, level, max(redchi, 1.0),
                                    nested_fits, None if adq["adequate"]
                                    else undetermined_verdict(adq), max_nfev)
        report("model comparison")
        if comparison.friction_detected:     # friction standing in for the lever's damping?
            chk = damping_check(prob, x, nested_fits, level, max(redchi, 1.0), max_nfev)
            comparison.damping_check = chk
            if chk is not None and not chk["detected"]:
                comparison.friction_detected = None
                comparison.verdict = undamped_verdict(chk, comparison.p_value)
                warns.append(comparison.verdict)
            report("damping check")
    coefs = prob.linear_coefficients(x)
    cfits = []
    for i, (c, r) in enumerate(zip(fc, prob.curve_residuals(x))):
        cfits.append(CurveFit(c.name, c.velocity, c.sample_rate, c.n, int(c.mask.sum()), c.sigma,
                              float(shifts[i]), float(sd[g + i]), float(coefs[i][0]),
                              float(coefs[i][1]), float(r @ r),
                              float(np.sqrt(np.mean(r ** 2))) * c.sigma,
                              c.retract_start is not None, float(c.pink)))
    cfg = {k: v for k, v in base.to_dict().items()
           if k not in ("velocity", "sample_rate", "start", "turn", "end")}
    return FitResult(model=base.model, free=free, parameters=params, derived=derived,
                     correlations=correlations, curves=cfits, chi2=chi2, dof=dof, redchi=redchi,
                     n_data=n_data, level=level, comparison=comparison, profiles=profiles,
                     warnings=warns, model_evaluations=ev.simulations, adequacy=adq,
                     wall_time=time.perf_counter() - t0, success=bool(res.success),
                     message=str(res.message), config=cfg,
                     fringes=dict(zip(("mode", "period", "amplitude", "amplitude_stderr"),
                                      (ev.fringes, fringe_period, *prob.fringe_amplitude(x)))),
                     photodiode=_curvature_report(prob, x, redchi),
                     _problem=prob, _x=x)
