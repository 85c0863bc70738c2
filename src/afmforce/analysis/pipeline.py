"""Analysis pipeline: named steps from a raw curve to an :class:`AnalysisResult`.

The paper's recipe (section 3, spec section 6) as an explicit registry
(:data:`STEPS`): each step has an identifier, a name, options with defaults,
the steps it requires, and its source in the paper. :func:`analyze` runs the
steps asked for (all by default) plus whatever they require, in registry order.

>>> from afmforce.io import load
>>> from afmforce.pipeline import analyze
>>> curve = load("curve.ibw")[0]                                   # doctest: +SKIP
>>> res = analyze(curve, options={"vdw": {"radius": 20e-9}})        # doctest: +SKIP
>>> res.pull_off_force, res.hamaker                                  # doctest: +SKIP
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Callable, Mapping, Sequence

import numpy as np

from . import steps as S
from .result import AnalysisResult
from .state import NoContact, State, prepare
from ..constants import HAMAKER, Z0
from ..errors import ParameterError
from ..io.curve import RawCurve

__all__ = ["Step", "STEPS", "DEFAULT_STEPS", "analyze", "resolve_steps", "steps_table", "AnalysisResult"]


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
        ``func(state, **options) -> state``.
    options : mapping
        Option names and defaults (SI).
    requires : tuple of str
        Steps that must run before.
    reference : str
        Where the method comes from.
    """

    identifier: str
    name: str
    func: Callable[..., State]
    options: Mapping[str, Any] = field(default_factory=dict)
    requires: tuple[str, ...] = ()
    reference: str = ""


#: The registry, in execution order.
STEPS: dict[str, Step] = {s.identifier: s for s in (
    Step("smooth", "Digitization smoothing of the position (running average)", S.smooth,
         {"window": "auto"}, (), "section 3.1, Fig 7C"),
    Step("contact", "Contact, constant-compliance and zero-force regions", S.contact,
         {"min_points": 5, "baseline_fraction": 0.7, "compliance_fraction": 0.5, "flat_ratio": 0.05,
          "max_slope_ratio": "auto"}, (), "section 3.1, Fig 7"),
    Step("drift", "Thermal drift: line in time in the zero-force region, per run", S.drift,
         {"order": 1, "tail": True}, ("contact",), "section 3.1, Fig 7"),
    Step("fringes", "Interferometric calibration from baseline fringes", S.fringes,
         {"apply": "auto", "period": None, "order": "auto", "in_contact": "hold", "margin": 0.1}, ("drift",),
         "section 3.1, Fig 7A; spec section 6"),
    Step("compliance", "Constant-compliance lines (robust fit)", S.compliance, {}, ("drift",),
         "section 3.1"),
    Step("calibration", "Deflection sensitivity (InvOLS): the file's, or from the compliance slope", S.calibration,
         {"source": "auto", "run": "approach"}, ("compliance",), "section 3.1; eq 15"),
    Step("kind", "Contact kind (hard: jump-in or straight line; soft: curved) and a soft contact point",
         S.kind, {"nsigma": 5.0, "min_stiffness": 0.7, "max_curvature": 1.6, "method": "power_local",
                  "force_fraction": 0.65, "window": 0.15}, ("calibration",),
         "afmforce (baseline line + power-law contact term; checked against nanite's fit_line_polynomial)"),
    Step("shift", "Inward/outward shift overlaying the compliance lines", S.shift,
         {"apply": True}, ("kind",), "section 3.2, Fig 9; Fig 7C"),
    Step("zero", "Zero of separation at the compliance line", S.zero,
         {"contact_separation": Z0, "run": "auto", "parallel_tolerance": 0.25}, ("kind",),
         "section 3.2, Fig 9"),
    Step("force", "Deflection to force (tilt-corrected spring constant)", S.force,
         {"spring_constant": None, "theta0": None, "L0": None, "L1": None, "L2": None},
         ("calibration",), "eqs 13, 14"),
    Step("jumps", "Jump into contact and pull-off", S.jumps, {"nsigma": 5.0, "window": 3, "onset_tolerance": 3e-9},
         ("zero", "force"),
         "section 2.1, Fig 9"),
    Step("adhesion", "Adhesion: deepest retract dip below its own baseline, last rupture, unbinding steps",
         S.adhesion_step, {"nsigma": 5.0}, ("zero", "force"), "afmforce (every contact kind)"),
    Step("surface_energy", "Surface energy and radius from the pull-off (JKR/DMT; hard contacts)", S.surface_energy,
         {"radius": None, "model": "jkr", "hamaker": HAMAKER, "z0": Z0}, ("jumps",), "section 2.1"),
    Step("vdw", "van der Waals fit before the jump (A R or A)", S.vdw,
         {"radius": None, "z0": Z0, "max_separation": 30e-9, "baseline": "line",
          "fit_separation_offset": False}, ("jumps",), "eq 2"),
    Step("oscillation", "Post-contact oscillation: frequency, temporal or spatial", S.oscillation,
         {"false_alarm": 1e-3, "min_cycles": 3.0}, ("calibration",), "section 3.2"),
    Step("friction", "Friction signature of the compliance lines (hard contacts, straight lines)", S.friction,
         {"nsigma": 3.0, "slope_tolerance": 0.02, "offset_tolerance": 0.2e-9, "max_curvature": 1.25}, ("kind",),
         "sections 2.2.2-2.2.4, eqs 16-21"),
    Step("diagnosis", "Dynamic diagnosis: inertia parameter, lag, jump-in distance", S.diagnosis,
         {"resonance_frequency": None, "resolution": None, "min_resolution": 0.01e-9, "attraction_ratio": 0.75},
         ("jumps", "adhesion", "vdw", "friction"), "eqs 3, 4; sections 2.3, 3.2"),
)}

#: Steps run when none are named: all of them.
DEFAULT_STEPS: tuple[str, ...] = tuple(STEPS)


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


def _check_options(options: Mapping[str, Mapping[str, Any]] | None) -> dict[str, dict[str, Any]]:
    out: dict[str, dict[str, Any]] = {}
    for step, opts in (options or {}).items():
        if step not in STEPS:
            raise ParameterError(f"options for unknown step {step!r}; steps: {', '.join(STEPS)}")
        bad = set(opts) - set(STEPS[step].options)
        if bad:
            known = ", ".join(STEPS[step].options) or "none"
            raise ParameterError(f"unknown option(s) {', '.join(sorted(bad))} for step {step!r}; known: {known}")
        out[step] = dict(opts)
    return out


def analyze(curve: RawCurve, steps: Sequence[str] | None = None,
            options: Mapping[str, Mapping[str, Any]] | None = None, *, channel: str = "auto") -> AnalysisResult:
    """Analyse one force curve.

    Parameters
    ----------
    curve : RawCurve
        The recorded curve (left unchanged).
    steps : sequence of str, optional
        Step identifiers (see :data:`STEPS`); required steps are added.
    options : mapping, optional
        ``{step: {option: value}}`` in SI, e.g. ``{"force": {"spring_constant": 0.21,
        "theta0": -0.26}, "vdw": {"radius": 220e-9}}``.
    channel : str
        Position channel: ``"auto"``, ``"measured"`` or ``"nominal"``.

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
    order = resolve_steps(steps)
    opts = _check_options(options)
    st = prepare(curve, channel)
    for name in order:
        step = STEPS[name]
        try:
            st = step.func(st, **{**step.options, **opts.get(name, {})})
        except NoContact as exc:  # a curve that never touches: contact kind "none", not a failure
            return _no_contact(st, tuple(order), str(exc))
    return _result(st, tuple(order))


def _no_contact(st: State, order: tuple[str, ...], why: str, nsigma: float = 10.0) -> AnalysisResult:
    nan = st.z * math.nan
    md = st.metadata
    k = float(md.get("spring_constant", math.nan) or math.nan)
    sens = float(md.get("sensitivity", math.nan) or math.nan)
    verdict = f"no contact reached ({why}): nothing to analyse beyond the baseline"
    extra: dict[str, Any] = {}
    depth, sigma = S.retract_dip(st.signal, st.curve.run_indices(1) if hasattr(st.curve, "run_indices")
                                 else np.flatnonzero(st.curve.segment == 1))
    if math.isfinite(depth) and sigma > 0 and depth > nsigma * sigma:
        to_force = {"N": 1.0, "m": k, "V": k * sens}.get(st.unit, math.nan)
        force, noise = -depth * to_force, sigma * to_force
        what = (f"{-force * 1e9:.4g} nN ({depth / sigma:.3g} x the noise)" if math.isfinite(force)
                else f"{depth:.4g} {st.unit} ({depth / sigma:.3g} x the noise; in force with --spring-constant"
                     + (" and --sensitivity" if st.unit == "V" and not math.isfinite(sens) else "") + ")")
        verdict = (f"no repulsive contact on the approach ({why}), but the retract pulls off {what} below its "
                   "baseline: the tip touched the surface; adhesion only")
        why = "the approach never pushed; the retract shows the pull-off"
        extra = dict(adhesion_force=force, adhesion_noise=noise, adhesion_verdict=verdict)
    return AnalysisResult(
        source=str(md.get("source_file", "")), steps_run=("contact",), deflection_unit=st.unit,
        position_channel=st.channel, contact_kind="none", contact_kind_reason=why,
        sensitivity=float(md.get("sensitivity", math.nan) or math.nan), spring_constant=k,
        verdict=verdict, warnings=st.warnings + (why,), **extra, time=st.time, position=st.z, separation=nan, deflection=nan, force=nan,
        segment=st.curve.segment.astype("int8"), details={"skipped": {s: "no contact reached" for s in order
                                                                       if s not in ("smooth", "contact")}})


def _result(st: State, order: tuple[str, ...]) -> AnalysisResult:
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
    if "force" in d:
        kw["spring_constant"] = d["force"].spring_constant
    if "shift" in d:
        kw["shift"] = d["shift"].shift
    if "zero" in d:
        kw["contact_separation"] = d["zero"].contact_separation
    if "jumps" in d and "jumps" not in d.get("skipped", {}):
        ji, po = d["jumps"]["jump_in"], d["jumps"]["pull_off"]
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
    if "vdw" in d and "vdw" not in d.get("skipped", {}):
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
    kw["not_applicable"] = dict(d.get("skipped", {}))
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
             "options": ", ".join(f"{k}={v!r}" for k, v in s.options.items()) or "-",
             "reference": s.reference or "-"} for s in STEPS.values()]
