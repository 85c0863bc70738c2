"""Analysis pipeline: named steps from a raw curve to an :class:`AnalysisResult`.

The paper's recipe (section 3, spec section 6) as an explicit registry
(:data:`STEPS`): each step has an identifier, a name, an options dataclass
(:mod:`.options`, whose field defaults are the only defaults),
the steps it requires, and its source in the paper. :func:`analyze` runs the
steps asked for (all by default) plus whatever they require, in registry order.

>>> from afmforce.io import load
>>> from afmforce.analysis.pipeline import analyze
>>> from afmforce.analysis.options import ProbeCalibration, VdwOptions
>>> curve = load("curve.ibw")[0]                                   # doctest: +SKIP
>>> res = analyze(curve, options=[VdwOptions(max_separation=20e-9)],
...               probe=ProbeCalibration(radius=20e-9))             # doctest: +SKIP
>>> res.pull_off_force, res.hamaker                                  # doctest: +SKIP
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from dataclasses import dataclass
from typing import Any, Callable, Mapping, MutableMapping, Sequence

import numpy as np

from . import options as O
from . import steps as S
from .contact_point import CONTACT_POINT_METHODS
from .indentation import indentation
from .liquid_step import liquid
from .options_text import show_default
from .plausibility import (beyond_detector, impossible_reasons, impossible_steps, plausibility_warnings,
                           slope_not_the_levers)
from .result import AnalysisResult
from .state import NoContact, State, prepare
from ..errors import ParameterError
from ..io.curve import RawCurve

__all__ = ["Step", "STEPS", "DEFAULT_STEPS", "analyze", "resolve_steps", "resolve_options", "options_from_dict",
           "steps_table", "AnalysisResult"]


@dataclass(frozen=True)
class Step:
    """One analysis step.

    Attributes
    ----------
    identifier : str
        Name used in ``steps=`` and ``--steps``.
    name : str
        Human-readable name.
    func : callable
        ``func(state, options) -> state``; ``options`` an instance of :attr:`options`.
    options : type
        The step's options dataclass (:mod:`.options`): its field defaults are the
        step's defaults, its field metadata their units and valid ranges.
    requires : tuple of str
        Steps that must run before.
    reference : str
        Where the method comes from.
    """

    identifier: str
    name: str
    func: Callable[[State, Any], State]
    options: type[O.StepOptions]
    requires: tuple[str, ...] = ()
    reference: str = ""


#: The registry, in execution order.
STEPS: dict[str, Step] = {s.identifier: s for s in (
    Step("smooth", "Digitization smoothing of the position (running average)", S.smooth, O.SmoothOptions,
         (), "section 3.1, Fig 7C"),
    Step("contact", "Contact, constant-compliance and zero-force regions", S.contact, O.ContactOptions,
         (), "section 3.1, Fig 7"),
    Step("drift", "Thermal drift: line in time in the zero-force region, per run", S.drift, O.DriftOptions,
         ("contact",), "section 3.1, Fig 7"),
    Step("fringes", "Interferometric calibration from baseline fringes", S.fringes, O.FringesOptions,
         ("drift",), "section 3.1, Fig 7A; spec section 6"),
    Step("compliance", "Constant-compliance lines (robust fit)", S.compliance, O.ComplianceOptions, ("drift",),
         "section 3.1"),
    Step("calibration", "Deflection sensitivity (InvOLS): the file's, or from the compliance slope", S.calibration,
         O.CalibrationOptions, ("compliance",), "section 3.1; eq 15"),
    Step("kind", "Contact kind (hard: jump-in or straight line; soft: curved) and a soft contact point",
         S.kind, O.KindOptions, ("calibration",),
         "afmforce (baseline line + power-law contact term; checked against nanite's fit_line_polynomial)"),
    Step("shift", "Inward/outward shift overlaying the compliance lines", S.shift, O.ShiftOptions, ("kind",),
         "section 3.2, Fig 9; Fig 7C"),
    Step("zero", "Zero of separation at the compliance line", S.zero, O.ZeroOptions, ("kind",),
         "section 3.2, Fig 9"),
    Step("force", "Deflection to force (tilt-corrected spring constant)", S.force, O.ForceOptions,
         ("calibration",), "eqs 13, 14"),
    Step("jumps", "Jump into contact and pull-off", S.jumps, O.JumpsOptions, ("zero", "force"),
         "section 2.1, Fig 9"),
    Step("adhesion", "Adhesion: deepest retract dip below its own baseline, last rupture, unbinding steps",
         S.adhesion_step, O.AdhesionOptions, ("zero", "force"), "afmforce (every contact kind)"),
    Step("surface_energy", "Surface energy and radius from the pull-off (JKR/DMT; hard contacts)", S.surface_energy,
         O.SurfaceEnergyOptions, ("jumps",), "section 2.1"),
    Step("vdw", "van der Waals fit before the jump (A R or A)", S.vdw, O.VdwOptions, ("jumps",), "eq 2"),
    Step("oscillation", "Post-contact oscillation: frequency, temporal or spatial", S.oscillation,
         O.OscillationOptions, ("calibration",), "section 3.2"),
    Step("friction", "Friction signature of the compliance lines (hard contacts, straight lines)", S.friction,
         O.FrictionOptions, ("kind",), "sections 2.2.2-2.2.4, eqs 16-21"),
    Step("indentation", "Young's modulus (and work of adhesion) of a soft contact: indentation model fitted with "
         "the contact point", indentation, O.IndentationOptions, ("kind", "force"),
         "Hertz, Sneddon, Bilodeau, Dimitriadis, JKR, DMT, Maugis (docs/contact.md); checked against nanite"),
    Step("diagnosis", "Dynamic diagnosis: inertia parameter, lag, jump-in distance", S.diagnosis,
         O.DiagnosisOptions, ("jumps", "adhesion", "vdw", "friction"), "eqs 3, 4; sections 2.3, 3.2"),
    Step("liquid", "Colloid probe in a liquid: quadratic compliance, lever drag, drainage vs static force, DLVO fit",
         liquid, O.LiquidOptions, (), "Attard, arXiv 1212.3019 (2012); Vinogradova et al., RSI 72, 2330 (2001)"),
)}

#: Steps run when none are named: all of them.
DEFAULT_STEPS: tuple[str, ...] = tuple(STEPS)

#: The first steps, which read the recorded samples (time, position, signal, segments, the signal's
#: unit) and their own options only, never the metadata's calibration nor the probe record: after a
#: new spring constant or sensitivity their state is the same, and ``analyze(..., memo=)`` reuses it.
SAMPLE_STEPS: tuple[str, ...] = ("smooth", "contact", "drift", "fringes", "compliance")


def resolve_steps(steps: Sequence[str] | None) -> list[str]:
    """The steps to run: those asked for plus their requirements, in registry order."""
    if steps is None:
        return list(DEFAULT_STEPS)
    wanted = set()

    def add(name: str) -> None:
        if name not in STEPS:
            raise ParameterError(f"unknown analysis step {name!r}; choose from {', '.join(STEPS)}")
        if name not in wanted:
            wanted.add(name)
            for r in STEPS[name].requires:
                add(r)

    for s in steps:
        add(s)
    return [s for s in STEPS if s in wanted]


#: Options of the old ``{step: {option: value}}`` form that are now the probe's.
_PROBE_OPTIONS = {("force", "spring_constant"): "spring_constant", ("force", "theta0"): "theta0",
                  ("force", "L0"): "L0", ("force", "L1"): "L1", ("force", "L2"): "L2",
                  ("surface_energy", "radius"): "radius", ("vdw", "radius"): "radius",
                  ("diagnosis", "resonance_frequency"): "resonance_frequency"}


def options_from_dict(options: Mapping[str, Mapping[str, Any]]) -> tuple[list[O.StepOptions], dict[str, Any]]:
    """The old ``{step: {option: value}}`` form -> (options records, probe fields).

    ``radius``, ``spring_constant``, ``theta0``, ``L0``-``L2`` and ``resonance_frequency``
    go to the probe (:class:`~.options.ProbeCalibration`); ``None`` values are dropped.

    Raises
    ------
    ParameterError
        Unknown step or option, an invalid value, or two different radii.
    """
    records, probe = [], {}
    for step, opts in options.items():
        if step not in STEPS:
            raise ParameterError(f"options for unknown step {step!r}; steps: {', '.join(STEPS)}")
        cls = STEPS[step].options
        known = [f.name for f in dataclasses.fields(cls)]
        moved = [n for (s, n) in _PROBE_OPTIONS if s == step]
        bad = set(opts) - set(known) - set(moved)
        if bad:
            raise ParameterError(f"unknown option(s) {', '.join(sorted(bad))} for step {step!r}; known: "
                                 f"{', '.join(known + moved) or 'none'}")
        for name in moved:
            value = opts.get(name)
            if value is None:
                continue
            field_name = _PROBE_OPTIONS[(step, name)]
            if probe.get(field_name, value) != value:
                raise ParameterError(f"two different values of {field_name} ({probe[field_name]!r}, {value!r}): "
                                     "the probe has one (ProbeCalibration)")
            probe[field_name] = value
        records.append(cls(**{k: v for k, v in opts.items() if k in known}))
    return records, probe


#: Each options class's default record: records are frozen, so one instance serves every curve
#: (building and checking the 20 records took about a sixth of a QI curve's analysis; issue 35).
_DEFAULTS: dict[type, O.StepOptions] = {}


def _default_options(cls: type[O.StepOptions]) -> O.StepOptions:
    rec = _DEFAULTS.get(cls)
    if rec is None:
        rec = _DEFAULTS[cls] = cls()
    return rec


def resolve_options(options: Any = None, probe: O.ProbeCalibration | None = None
                    ) -> tuple[dict[str, O.StepOptions], O.ProbeCalibration]:
    """Every step's options record (the registry's defaults unless given) and the probe.

    ``options``: options records (one per step at most), or the deprecated
    ``{step: {option: value}}`` dict (a :class:`DeprecationWarning`).
    """
    if options is None:
        given: list[Any] = []
    elif isinstance(options, Mapping):
        warnings.warn("analyze(options={step: {option: value}}) is deprecated and will be removed in the next "
                      "release: pass option records (e.g. options=[VdwOptions(max_separation=20e-9)]) and the "
                      "probe as probe=ProbeCalibration(radius=..., spring_constant=...)",
                      DeprecationWarning, stacklevel=3)
        given, moved = options_from_dict(options)
        if moved:
            mine = probe.given() if probe is not None else {}
            clash = {k for k in set(mine) & set(moved) if mine[k] != moved[k]}
            if clash:
                raise ParameterError(f"{', '.join(sorted(clash))} given twice with different values (options "
                                     "and probe)")
            probe = O.ProbeCalibration(**{**moved, **mine})
    elif isinstance(options, O.StepOptions):
        given = [options]
    else:
        given = list(options)
    out = {name: _default_options(step.options) for name, step in STEPS.items()}
    seen = set()
    for rec in given:
        if not isinstance(rec, O.StepOptions):
            raise ParameterError(f"options must be step options records (e.g. VdwOptions(...)), got {rec!r}")
        if rec.step in seen:
            raise ParameterError(f"options for step {rec.step!r} given twice")
        seen.add(rec.step)
        out[rec.step] = rec
    out["kind"].check_method(CONTACT_POINT_METHODS)
    if probe is not None and not isinstance(probe, O.ProbeCalibration):
        raise ParameterError(f"probe must be a ProbeCalibration, got {probe!r}")
    return out, probe or O.ProbeCalibration()


def analyze(curve: RawCurve, steps: Sequence[str] | None = None, options: Any = None, *,
            probe: O.ProbeCalibration | None = None, channel: str = "auto",
            memo: MutableMapping | None = None) -> AnalysisResult:
    """Analyse one force curve.

    Parameters
    ----------
    curve : RawCurve
        The recorded curve (left unchanged).
    steps : sequence of str, optional
        Step identifiers (see :data:`STEPS`); required steps are added.
    options : sequence of StepOptions, optional
        Options records of the steps whose defaults you change, e.g.
        ``[VdwOptions(max_separation=20e-9), ZeroOptions(contact_separation=0.0)]``
        (SI; see :mod:`afmforce.analysis.options`). The old ``{step: {option: value}}``
        dict is still accepted for one release, with a :class:`DeprecationWarning`.
    probe : ProbeCalibration, optional
        Radius [m], spring constant [N/m], inclination [rad], sensitivity [m/V], ...
        given by the user; a field left ``None`` takes the file's value.
    channel : str
        Position channel: ``"auto"``, ``"measured"`` or ``"nominal"``.
    memo : mutable mapping, optional
        Where the state after the :data:`SAMPLE_STEPS` is kept, keyed by the curve's arrays
        (identity), the channel and those steps' options; a later call with the same curve
        arrays (another spring constant, sensitivity or probe, other options of later steps)
        starts after them. The result is the same as without it.

    Returns
    -------
    AnalysisResult

    Raises
    ------
    AnalysisError
        The curve cannot be analysed (no contact, flat, one segment, NaNs...).
    ParameterError
        Unknown step or option, or an invalid option value.
    """
    if steps is not None and (isinstance(steps, str) or not all(isinstance(s, str) for s in steps)):
        raise ParameterError(f"steps are step names (e.g. ['vdw']), got {steps!r}; options records go to "
                             "options=[...]")
    order = resolve_steps(steps)
    opts, probe = resolve_options(options, probe)
    st = prepare(curve, channel, probe)
    misread = beyond_detector(curve)
    if misread:  # no photodiode gives this signal: every number from it would be impossible
        return _refused(st, tuple(order), misread)
    head = 0
    while head < len(order) and head < len(SAMPLE_STEPS) and order[head] == SAMPLE_STEPS[head]:
        head += 1
    key, start = None, 0
    if memo is not None and head:
        key, arrays = _memo_key(curve, st.channel, order[:head], opts)
        hit = memo.get(key)
        if hit is not None and all(a is b for a, b in zip(hit[0], arrays)):
            st, start = dataclasses.replace(hit[1], curve=curve, probe=st.probe), head
    for i, name in enumerate(order[start:], start):
        try:
            st = STEPS[name].func(st, opts[name])
        except NoContact as exc:  # a curve that never touches: contact kind "none", not a failure
            return _no_contact(st, tuple(order), str(exc))
        if key is not None and i == head - 1:
            memo[key] = (arrays, st)
    return _result(st, tuple(order))


def _memo_key(curve: RawCurve, channel: str, names, opts) -> tuple[tuple, tuple]:
    """The key of the state after the sample steps ``names`` (and the arrays it is valid for)."""
    arrays = (curve.time, curve.piezo_nominal, curve.piezo_measured, curve.deflection_signal, curve.segment)
    md = curve.metadata
    return ((tuple(id(a) for a in arrays), channel, curve.deflection_unit, md.get("single_run"),
             md.get("processed"), bool(md.get("time_is_sample_index", False)),
             tuple(repr(opts[n]) for n in names)), arrays)


def _no_contact(st: State, order: tuple[str, ...], why: str, nsigma: float = 10.0) -> AnalysisResult:
    nan = st.z * math.nan
    md = st.metadata
    k = float(st.probe.value("spring_constant", md) or math.nan)
    sens = float(st.probe.value("sensitivity", md) or math.nan)
    verdict = f"no contact reached ({why}): nothing to analyse beyond the baseline"
    extra: dict[str, Any] = {}
    depth, sigma = S.retract_dip(st.signal, st.curve.run_indices(1) if hasattr(st.curve, "run_indices")
                                 else np.flatnonzero(st.curve.segment == 1))
    if math.isfinite(depth) and sigma > 0 and depth > nsigma * sigma:
        to_force = {"N": 1.0, "m": k, "V": k * sens}.get(st.unit, math.nan)
        force, noise = -depth * to_force, sigma * to_force
        what = (f"{-force * 1e9:.4g} nN ({depth / sigma:.3g} x the noise)" if math.isfinite(force)
                else f"{depth:.4g} {st.unit} ({depth / sigma:.3g} x the noise; in force with `spring_constant`"
                     + (" and `sensitivity`" if st.unit == "V" and not math.isfinite(sens) else "") + ")")
        verdict = (f"no repulsive contact on the approach ({why}), but the retract pulls off {what} below its "
                   "baseline: the tip touched the surface; adhesion only")
        why = "the approach never pushed; the retract shows the pull-off"
        extra = dict(adhesion_force=force, adhesion_noise=noise, adhesion_verdict=verdict)
    return AnalysisResult(
        source=str(md.get("source_file", "")), steps_run=("contact",), deflection_unit=st.unit,
        position_channel=st.channel, contact_kind="none", contact_kind_reason=why,
        sensitivity=sens, spring_constant=k,
        verdict=verdict, warnings=st.warnings + (why,), **extra, time=st.time, position=st.z, separation=nan, deflection=nan, force=nan,
        segment=st.curve.segment.astype("int8"),
        not_applicable={s: "no contact reached" for s in order if s not in ("smooth", "contact")})


def _refused(st: State, order: tuple[str, ...], why: str) -> AnalysisResult:
    """The result of a curve whose signal itself is impossible: no step's number, the reason as the verdict."""
    nan = st.z * math.nan
    md = st.metadata
    return AnalysisResult(
        source=str(md.get("source_file", "")), steps_run=(), deflection_unit=st.unit, position_channel=st.channel,
        contact_kind="none", contact_kind_reason=why,
        sensitivity=float(st.probe.value("sensitivity", md) or math.nan),
        spring_constant=float(st.probe.value("spring_constant", md) or math.nan), verdict=why,
        warnings=st.warnings + (why,), time=st.time, position=st.z, separation=nan, deflection=nan, force=nan,
        segment=st.curve.segment.astype("int8"), not_applicable={s: why for s in order})


def _result(st: State, order: tuple[str, ...]) -> AnalysisResult:
    st = st.update(warn=plausibility_warnings(st))
    bad = impossible_steps(st)
    if bad:  # numbers no physics allows are not results: the steps say why, their details are dropped
        st = st.update(skipped={**st.skipped, **bad},
                       details={k: v for k, v in st.details.items() if k not in bad or k == "jumps"})
    not_levers = slope_not_the_levers(st)
    if not_levers:  # a soft contact's (or a separation's) slope: no spring constant, no modulus from it
        st = st.update(warn=(not_levers,), skipped={**st.skipped, **(
            {"indentation": not_levers} if "indentation" in st.details or "indentation" in st.skipped else {})},
            details={k: v for k, v in st.details.items() if k != "indentation"})
    d = st.details
    nan = math.nan
    kw: dict[str, Any] = {}
    if "calibration" in d:
        c = d["calibration"]
        kw.update(sensitivity=c.sensitivity, sensitivity_fit=c.sensitivity_fit, calibration_source=c.source)
    if "kind" in d:
        kw.update(contact_kind=d["kind"].kind, contact_kind_reason=d["kind"].reason)
    if "contact_point" in d:
        kw["indentation"] = d["contact_point"].indentation
    if "force" in d and not not_levers:
        kw["spring_constant"] = d["force"].spring_constant
    if "shift" in d:
        kw["shift"] = d["shift"].shift
    if "zero" in d:
        kw["contact_separation"] = d["zero"].contact_separation
    if "jumps" in d and "jumps" not in st.skipped:
        ji, po = d["jumps"].jump_in, d["jumps"].pull_off
        kw.update(contact_onset_separation=ji.separation, pull_off_force=po.force,
                  pull_off_position=po.position, jump_out_distance=po.jump_out_distance,
                  pull_off_saturated=po.saturated, pull_off_force_extrapolated=(
                      po.deflection_extrapolated * d["force"].spring_constant if "force" in d else nan))
        if ji.found:  # without a significant jump the tip crept in: only the onset of contact
            kw.update(jump_in_separation=ji.separation, jump_in_force=ji.force_after,
                      jump_in_deflection=ji.deflection_after)
    if "adhesion" in d:
        a = d["adhesion"]
        kw.update(adhesion_force=a.force, adhesion_deflection=a.deflection, adhesion_distance=a.distance,
                  adhesion_noise=a.noise, rupture_distance=a.rupture_distance, unbinding_steps=len(a.steps),
                  adhesion_verdict=a.verdict)
    if "surface_energy" in d:
        kw.update(surface_energy=d["surface_energy"].surface_energy, radius=d["surface_energy"].radius)
    if "vdw" in d and "vdw" not in st.skipped:
        v = d["vdw"]
        kw.update(hamaker_radius=v.hamaker_radius, hamaker_radius_se=v.hamaker_radius_se, hamaker=v.hamaker,
                  hamaker_se=v.hamaker_se)
    if "oscillation" in d:
        o = d["oscillation"]
        if o.origin != "none" and o.approach.found and o.retract.found:
            kw["oscillation_frequency"] = 0.5 * (o.approach.frequency + o.retract.frequency)
        kw["oscillation_verdict"] = o.verdict
    if "friction" in d:
        kw["friction"] = d["friction"].kind
    if "diagnosis" in d:
        g = d["diagnosis"]
        kw.update(velocity=g.velocity, inertia_parameter=g.inertia_parameter, force_gradient=g.force_gradient,
                  resonance_frequency=g.resonance_frequency, dynamic=g.dynamic, verdict=g.verdict,
                  dynamic_assessed=g.assessed)
    if "friction" in d:
        kw["friction_verdict"] = d["friction"].verdict
    if "indentation" in d:
        i = d["indentation"]
        kw.update(indentation_model=i.model, youngs_modulus=i.youngs_modulus, youngs_modulus_se=i.youngs_modulus_se,
                  youngs_modulus_low=i.youngs_modulus_low, youngs_modulus_high=i.youngs_modulus_high,
                  contact_point=i.contact_point, work_of_adhesion=i.work_of_adhesion,
                  work_of_adhesion_se=i.work_of_adhesion_se)
    if "liquid" in d:
        q = d["liquid"]
        kw.update(drag_offset=q.drag_offset, lever_drag=q.lever_drag, surface_potential=q.surface_potential,
                  surface_potential_se=q.surface_potential_se, debye_length=q.debye_length,
                  debye_length_se=q.debye_length_se, dlvo_hamaker=q.hamaker, dlvo_hamaker_se=q.hamaker_se)
    kw["not_applicable"] = dict(st.skipped)
    impossible = impossible_reasons(st.skipped)
    if impossible:  # the verdict says first why numbers are missing, naming the suspect input
        kw["verdict"] = "; ".join(impossible + ([kw["verdict"]] if kw.get("verdict") else []))
    full = lambda a: a if a is not None else st.z * nan  # noqa: E731
    return AnalysisResult(
        source=str(st.metadata.get("source_file", "")), steps_run=order, deflection_unit=st.unit,
        position_channel=st.channel, warnings=st.warnings, time=st.time,
        position=st.position if st.position is not None else st.z, separation=full(st.separation),
        deflection=full(st.deflection), force=full(st.force), segment=st.curve.segment.astype("int8"),
        details=dict(d), **kw)


def steps_table() -> list[dict[str, str]]:
    """One row per step (the docs table is built from this)."""
    return [{"identifier": s.identifier, "name": s.name, "requires": ", ".join(s.requires) or "-",
             "options": ", ".join(f"{f.name}={show_default(f)}" for f in dataclasses.fields(s.options)) or "-",
             "reference": s.reference or "-"} for s in STEPS.values()]
