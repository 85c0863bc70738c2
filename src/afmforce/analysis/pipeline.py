"""Analysis pipeline: the registered steps from a raw curve to an :class:`AnalysisResult`.

The paper's recipe (section 3, spec section 6) as a registry of steps (:mod:`.registry`), each
declared once by its record in its own module: identifier, name, options record
(:mod:`.options`, whose field defaults are the only defaults), the steps it requires, the
state channels it needs, its source in the paper, and its result fields with their units.
:func:`analyze` runs the steps asked for (all by default) plus whatever they require, in the
registry's order, and reads each step's fields off its details with the step's ``collect``.

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
from typing import Any, Mapping, MutableMapping, Sequence

import numpy as np

from . import options as O
from . import registry
from .contact_point import CONTACT_POINT_METHODS
from .options_text import show_default
from .orientation import orient, plain_scan
from .plausibility import (beyond_detector, impossible_reasons, impossible_steps, plausibility_warnings,
                           slope_not_the_levers)
from .registry import AnalysisStep, ResultField, register_step
from .result import AnalysisResult
from .state import NoContact, State, _default_probe, prepare
from .steps.contact import retract_dip
from ..errors import ParameterError
from ..io.curve import RawCurve
from ..io.deflection import signal_factor

__all__ = ["Step", "AnalysisStep", "ResultField", "register_step", "STEPS", "DEFAULT_STEPS", "analyze", "inverted_sign",
           "resolve_steps", "resolve_options", "steps_table", "AnalysisResult"]

#: The record of one step (the name it had before the registry moved to :mod:`.registry`).
Step = AnalysisStep

#: The registry: identifier -> record, in execution order (kept up to date by :func:`register_step`).
STEPS: registry.LiveDict = registry.LiveDict(registry.steps)

#: Steps run when none are named: all of them.
DEFAULT_STEPS: registry.LiveTuple = registry.LiveTuple(registry.order)

#: The first steps, which read the recorded samples (time, position, signal, segments, the signal's
#: unit) and their own options only, never the metadata's calibration nor the probe record: after a
#: new spring constant or sensitivity their state is the same, and ``analyze(..., memo=)`` reuses it.
SAMPLE_STEPS: tuple[str, ...] = ("smooth", "contact", "drift", "fringes", "compliance")


def resolve_steps(steps: Sequence[str] | None) -> list[str]:
    """The steps to run: those asked for plus their requirements, in registry order."""
    known = registry.steps()
    if steps is None:
        return list(known)
    wanted = set()

    def add(name: str) -> None:
        if name not in known:
            raise ParameterError(f"unknown analysis step {name!r}; choose from {', '.join(known)}")
        if name not in wanted:
            wanted.add(name)
            for r in known[name].requires:
                add(r)

    for s in steps:
        add(s)
    return [s for s in known if s in wanted]


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

    ``options``: options records (one per step at most).

    Raises
    ------
    ParameterError
        Not an options record (the ``{step: {option: value}}`` dict of earlier versions is
        refused, saying what to pass instead), two records for one step, or a bad value.
    """
    if options is None:
        given: list[Any] = []
    elif isinstance(options, Mapping):
        raise ParameterError("options must be step options records, e.g. options=[VdwOptions(max_separation=20e-9)]"
                             ", with the probe's radius, spring constant, inclination, lengths, sensitivity and "
                             "resonance frequency as probe=ProbeCalibration(radius=..., spring_constant=...); the "
                             "{step: {option: value}} dict of earlier versions is no longer accepted")
    elif isinstance(options, O.StepOptions):
        given = [options]
    else:
        given = list(options)
    known = registry.steps()
    out = dict(registry._cached("default_options", lambda: {name: _default_options(step.options)
                                                             for name, step in registry.steps().items()}))
    seen = set()
    for rec in given:
        if not isinstance(rec, O.StepOptions):
            raise ParameterError(f"options must be step options records (e.g. VdwOptions(...)), got {rec!r}")
        if rec.step in seen:
            raise ParameterError(f"options for step {rec.step!r} given twice")
        if rec.step not in known:
            raise ParameterError(f"options {type(rec).__name__} are for step {rec.step!r}, which is not registered")
        seen.add(rec.step)
        out[rec.step] = rec
    out["kind"].check_method(CONTACT_POINT_METHODS)
    if probe is not None and not isinstance(probe, O.ProbeCalibration):
        raise ParameterError(f"probe must be a ProbeCalibration, got {probe!r}")
    return out, probe if probe is not None else _default_probe()


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
        (SI; see :mod:`afmforce.analysis.options`).
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
        Unknown step or option, an invalid option value, or options not given as records.
    """
    if steps is not None and (isinstance(steps, str) or not all(isinstance(s, str) for s in steps)):
        raise ParameterError(f"steps are step names (e.g. ['vdw']), got {steps!r}; options records go to "
                             "options=[...]")
    order = resolve_steps(steps)
    opts, probe = resolve_options(options, probe)
    return _analyze(_given_sensitivity(curve, probe), order, opts, probe, channel, memo)


def _given_sensitivity(curve: RawCurve, probe) -> RawCurve:
    """The user's spring constant and sensitivity (``probe``) put over the curve as its reader does with
    ``meta_override``: :func:`afmforce.io.given.apply_given`, the one function every face uses."""
    from ..io.given import apply_given

    return apply_given(curve, probe)


def _analyze(curve: RawCurve, order: list[str], opts, probe, channel: str, memo: MutableMapping | None,
             negated: str = "") -> AnalysisResult:
    """:func:`analyze` of resolved steps and options; ``negated`` is the note of a curve whose deflection
    signal was negated because its compliance line fell (:func:`inverted_sign`), analysed once more."""
    known = registry.steps()
    given = curve
    scan = plain_scan(curve, channel)   # the readers' curves: shown in one pass to need no change
    # one cycle, each run in acquisition order, labelled right
    curve, reordered = (curve, ()) if scan is not None else orient(curve, channel)
    st = prepare(curve, channel, probe, scan=scan)
    if reordered or negated:
        st = st.update(warnings=((negated,) if negated else ()) + reordered + st.warnings)
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
            st, start = dataclasses.replace(hit[1], curve=st.curve, probe=st.probe), head  # prepare's (deglitched)
    missing = st.missing_run
    for i, name in enumerate(order[start:], start):
        if missing and missing in known[name].runs:  # a curve of one run: the step needs the other
            st = st.update(skipped={**st.skipped, name: f"not available: no {missing} run"})
            continue
        if name == "calibration" and not negated:
            why = inverted_sign(st, opts[name].run)
            if why:  # oriented first, then every step sees a lever that bends away from the sample
                flipped = dataclasses.replace(given, deflection_signal=-np.asarray(given.deflection_signal))
                return _analyze(flipped, order, opts, probe, channel, None, negated=why)
        try:
            st = known[name].run(st, opts[name])
        except NoContact as exc:  # a curve that never touches: contact kind "none", not a failure
            if not negated and any("sign is inverted" in w for w in st.warnings):
                alt = _negated_contact(given, order, opts, probe, channel, st, name)
                if alt is not None:  # its contact fell along a clear line: stored with the other sign
                    return alt
            return _no_contact(st, tuple(order), str(exc))
        if key is not None and i == head - 1:
            memo[key] = (arrays, st)
    if missing:  # said once, where every output shows it (the steps' own reasons are in not_applicable)
        why = f"not available: no {missing} run"
        gone = [s for s, w in st.skipped.items() if w == why]
        if gone:
            st = st.update(warn=f"the curve holds the {'retract' if missing == 'approach' else 'approach'} run only: "
                                f"{why}: {', '.join(gone)}")
    return _result(st, tuple(order), known)


#: A falling compliance line says the signal's sign is inverted only when it is a compliance line: its fall
#: over the contact at least this many times its robust residual scale [-] (NSFopen 1.1.18's FluidFM cell
#: curve 1 falls by 1.0 x its scale: a drifting, creeping contact, no line; the calibration refuses it), and,
#: where the file's (or the user's) calibration converts it, at least this steep in deflection per
#: position [m/m] (a very soft gel's indentation line, Bruker's Egel4 file, is 0.021; that FluidFM curve's 0.0014).
INVERTED_LINE_SIGMAS = 20.0
INVERTED_LINE_MIN_SLOPE = 0.005


def inverted_sign(st: State, run: str = "approach") -> str | None:
    """Why the deflection signal's sign is inverted, read off the compliance line the calibration would
    use (``run``; None when it rises, as it does on every contact).

    Pressed on the sample, a lever bends away from it: on its compliance (or indentation) line the
    deflection rises as the position advances, in every unit (volts, metres, newtons). A line that falls
    clearly (:data:`INVERTED_LINE_SIGMAS`, :data:`INVERTED_LINE_MIN_SLOPE`) says the signal was stored with
    the other sign convention; its slope would calibrate a negative sensitivity, which no detector has. The
    curve is then negated and analysed again (:func:`analyze`), the note saying so, so that the
    sensitivity, the forces and the contact come out as for the curve stored the usual way. A line that
    falls within its noise, or too gently to be a contact, is left to the calibration (no sensitivity
    from it)."""
    comp = st.details.get("compliance")
    if comp is None:
        return None
    md = st.metadata if st.probe.sensitivity is None else {**st.metadata, "sensitivity": st.probe.sensitivity}
    slope = _clear_line(comp, run, st.unit, md, -1.0)
    return None if slope is None else _inverted_note(slope, st.unit)


def _clear_line(comp, run: str, unit: str, md: Mapping[str, Any], sign: float) -> float | None:
    """The slope of the compliance line the calibration would use (``run``) when it runs clearly in the
    direction ``sign`` (-1 falling, +1 rising) by :data:`INVERTED_LINE_SIGMAS` and
    :data:`INVERTED_LINE_MIN_SLOPE`; None otherwise."""
    a, r = comp.approach, comp.retract
    line = a if (run != "retract" and a.found) or not r.found else r
    slope = float(line.slope)
    if not (line.found and math.isfinite(slope) and sign * slope > 0.0):
        return None
    if not abs(slope) * (line.z_max - line.z_min) > INVERTED_LINE_SIGMAS * line.sigma:
        return None
    scale = signal_factor(unit, md.get("sensitivity"), md.get("spring_constant"))
    if math.isfinite(scale) and scale > 0 and abs(slope) * scale < INVERTED_LINE_MIN_SLOPE:
        return None
    return slope


def _inverted_note(slope: float, unit: str) -> str:
    """The note of a curve negated because its compliance line fell at ``slope`` [unit/m] (< 0)."""
    what = (f"a sensitivity of {-1e9 / slope:.4g} nm/V once negated" if unit == "V"
            else "the forces of the curve stored the usual way once negated")
    return (f"the deflection signal's sign is inverted: on its compliance line it falls as the position presses "
            f"the tip on the sample ({slope:.4g} {unit}/m), which no lever in contact does (it bends away "
            f"from the sample); a calibration from that slope would be a negative sensitivity. The signal was "
            f"negated (the deflection away from the sample positive, as the readers give it) and analysed: "
            f"{what}")


def _negated_contact(given: RawCurve, order, opts, probe, channel: str, st: State, name: str):
    """A curve the contact step finds no contact on (its approach falls: :data:`~.steps.contact.
    CONTACT_RISE_SIGMAS`) and whose signal ``prepare`` found falling far below its baseline: analysed
    negated, it is taken when it then climbs along a clear compliance line (:func:`_clear_line`); an
    approach held off the surface by an attraction bends by a few noise sigmas, never along such a line.
    None otherwise (the curve stays "no contact")."""
    flipped = dataclasses.replace(given, deflection_signal=-np.asarray(given.deflection_signal))
    probe_note = "\x00negated"
    alt = _analyze(flipped, order, opts, probe, channel, None, negated=probe_note)
    comp = alt.details.get("compliance")
    if comp is None or alt.contact_kind == "none":
        return None
    cal = opts["calibration"] if "calibration" in opts else O.CalibrationOptions()
    md = st.metadata if st.probe.sensitivity is None else {**st.metadata, "sensitivity": st.probe.sensitivity}
    slope = _clear_line(comp, cal.run, st.unit, md, +1.0)
    if slope is None:
        return None
    note = _inverted_note(-slope, st.unit)  # the probe's placeholder, replaced: the curve is analysed once
    return dataclasses.replace(alt, warnings=tuple(note if w == probe_note else w for w in alt.warnings))


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
    depth, sigma = retract_dip(st.signal, st.curve.run_indices(1) if hasattr(st.curve, "run_indices")
                                 else np.flatnonzero(st.curve.segment == 1))
    # the approach's own dip (read from its far end): an attraction that never touched dips both runs alike,
    # a touch leaves the retract deeper
    reach, _ = retract_dip(st.signal, np.flatnonzero(st.curve.segment == 0)[::-1])
    deeper = depth - (reach if math.isfinite(reach) and reach > 0 else 0.0)
    if math.isfinite(depth) and sigma > 0 and deeper > nsigma * sigma:
        to_force = signal_factor(st.unit, sens, k, to="force")
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


def _result(st: State, order: tuple[str, ...], known: Mapping[str, AnalysisStep]) -> AnalysisResult:
    implausible = plausibility_warnings(st)
    if implausible:
        st = st.update(warn=implausible)
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
    kw: dict[str, Any] = {}
    for name, step in known.items():  # each step reads its own fields off its details
        if step.collect is not None and name in d:
            kw.update(step.collect(st))
    if not_levers:
        kw.pop("spring_constant", None)
    impossible = impossible_reasons(st.skipped)
    if impossible:  # the verdict says first why numbers are missing, naming the suspect input
        kw["verdict"] = "; ".join(impossible + ([kw["verdict"]] if kw.get("verdict") else []))
    full = lambda a: a if a is not None else st.z * math.nan  # noqa: E731
    return AnalysisResult(
        source=str(st.metadata.get("source_file", "")), steps_run=order, deflection_unit=st.unit,
        position_channel=st.channel, warnings=st.warnings, time=st.time,
        position=st.position if st.position is not None else st.z, separation=full(st.separation),
        deflection=full(st.deflection), force=full(st.force), segment=st.curve.segment.astype("int8"),
        details=d, not_applicable=st.skipped, values=kw)  # (copied by AnalysisResult)


def steps_table() -> list[dict[str, str]]:
    """One row per step (the docs table is built from this)."""
    return [{"identifier": s.identifier, "name": s.name, "requires": ", ".join(s.requires) or "-",
             "options": ", ".join(f"{f.name}={show_default(f)}" for f in dataclasses.fields(s.options)) or "-",
             "reference": s.reference or "-"} for s in registry.steps().values()]
