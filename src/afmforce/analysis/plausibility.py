"""Plausibility of the derived numbers: every one outside its physical range carries a warning.

Run on the final state of every analysis (:func:`plausibility_warnings`), whatever steps ran.
Each check says the number, its range and what usually causes it:

* the Hamaker constant ``A`` (the probe's radius, else the pull-off's JKR/DMT radius with the
  fitted ``A R``) outside :data:`HAMAKER_RANGE` (1e-21 to 1e-18 J: condensed media across vacuum,
  air or water);
* a spring constant outside :data:`SPRING_CONSTANT_RANGE` (1e-3 to 100 N/m, the cantilevers made; declared with the quantity in `afmforce._fields.QUANTITIES`),
  and one inferred from a compliance slope far from the file's (one inferred outside that range: the
  force steps refuse, :func:`impossible_steps`);
* a sensitivity fitted on fewer than :data:`MIN_COMPLIANCE_SAMPLES` contact samples;
* a contact line the deflection follows faster than the position (the separation then runs
  backwards in contact: the force panel curls back on itself);
* a force panel wider than the signal's own span (a baseline correction larger than the data).
"""

from __future__ import annotations

import math

import numpy as np

from .._fields import QUANTITIES
from ._glue_kernel import COMPILED, span_stats
from ._numeric import ptp
from .state import State

__all__ = ["plausibility_warnings", "hamaker_warning", "HAMAKER_RANGE", "SPRING_CONSTANT_RANGE",
           "MIN_COMPLIANCE_SAMPLES", "IMPOSSIBLE", "K_UNDETERMINED", "UNDETERMINED", "undetermined", "interval_undetermined", "SURFACE_ENERGY_MAX", "unphysical_surface_energy", "MODULUS_RANGE", "impossible_modulus", "DETECTOR_RANGE", "MAX_CALIBRATION_RATIO", "FORCE_STEPS",
           "beyond_detector", "impossible_steps", "impossible_reasons", "slope_not_the_levers", "spring_constant_warnings"]

#: How the reason of a step whose number would be physically impossible starts (``not_applicable``);
#: the verdict repeats every such reason, each naming the suspect input.
IMPOSSIBLE = "physically impossible"
#: How the reason starts when a force signal's spring constant cannot be inferred (its contact slope is
#: softer than any lever: no hard contact); a refusal like :data:`IMPOSSIBLE`'s, repeated in the verdict.
K_UNDETERMINED = "spring constant undetermined"
#: How a number the data cannot determine is reported in a verdict, a warning, a table cell (:func:`undetermined`).
UNDETERMINED = "undetermined"
#: The widest photodiode ADC of the instruments read [V]: a 16-bit NanoScope channel at 0.375 mV/LSB
#: (+-12.3 V; JPK and Asylum digitise +-10 V). A reader may give its own as metadata ``adc_range`` [V].
DETECTOR_RANGE = 2**15 * 0.000375
#: A hard contact's compliance slope and the file's sensitivity may differ by at most this factor [-]:
#: beyond it one of them is wrong (a stale or mistyped sensitivity, a file read with a wrong scale).
MAX_CALIBRATION_RATIO = 10.0
#: Steps whose numbers are forces or come from them (not reported when the calibration is impossible).
FORCE_STEPS = ("jumps", "adhesion", "surface_energy", "vdw", "indentation")

#: Hamaker constants of condensed media across vacuum, air or water [J].
HAMAKER_RANGE = (1e-21, 1e-18)
#: Young's moduli of the softest (mucus, biofilms, brain: ~10 Pa) to the stiffest (diamond: 1.2 TPa) materials an
#: AFM indents, with margin [Pa]: a modulus outside comes from a wrong scale, not from the sample.
MODULUS_RANGE = (1.0, 1.2e12)
#: Spring constants of AFM cantilevers [N/m]: the band declared with the quantity (its ``plausible``).
SPRING_CONSTANT_RANGE = QUANTITIES["spring_constant"].plausible
#: Fewest contact samples a fitted sensitivity is trusted from [-].
MIN_COMPLIANCE_SAMPLES = 20
#: A contact line steeper than this (deflection per position, calibrated) runs backwards [-].
MAX_CONTACT_SLOPE = 1.25
#: The corrected force may span at most this multiple of the signal's own span [-].
MAX_SPAN_RATIO = 1.5


def _hamaker(st: State) -> list[str]:
    fit = st.details.get("vdw")
    if fit is None or "vdw" in st.skipped or not math.isfinite(getattr(fit, "hamaker_radius", math.nan)):
        return []
    a, how = getattr(fit, "hamaker", math.nan), "with the probe's radius"
    se = st.details.get("surface_energy")
    if not math.isfinite(a) and se is not None and math.isfinite(getattr(se, "radius", math.nan)) and se.radius > 0:
        a, how = fit.hamaker_radius / se.radius, f"with the pull-off's radius {se.radius * 1e9:.3g} nm"
    note = hamaker_warning(a, how, fit.hamaker_radius)
    return [note] if note else []


def hamaker_warning(a: float, how: str, hamaker_radius: float) -> str | None:
    """The warning for a Hamaker constant ``a`` [J] outside :data:`HAMAKER_RANGE` (None inside it);
    ``how`` says which radius gave it, ``hamaker_radius`` [J m] is the fitted product. Shared with
    the dynamic fit (:mod:`afmforce.fit.preprocess`)."""
    lo, hi = HAMAKER_RANGE
    if not math.isfinite(a) or lo <= a <= hi:
        return None
    cause = ("an extra attraction (a capillary meniscus in air, electrostatics) or dynamics in the fit" if a > hi
             else "a weak attraction: a fit of noise, or friction hiding the precontact force")
    return (f"Hamaker constant {a:.3g} J ({how}; A R {hamaker_radius:.3g} J m) is outside the physical range "
            f"{lo:.0e}..{hi:.0e} J: {cause}")


def _spring_constant(st: State) -> list[str]:
    conv = st.details.get("force")
    k = st.spring_constant
    if conv is None or not math.isfinite(k):
        return []
    inferred = getattr(conv, "method", "") == "compliance slope"
    out = spring_constant_warnings(k, inferred)
    header = float(st.metadata.get("spring_constant", math.nan) or math.nan)
    if inferred and math.isfinite(header) and header > 0 and not 1 / 3 <= k / header <= 3:
        out.append(f"spring constant {k:.3g} N/m inferred from the compliance slope is {k / header:.3g} x the "
                   f"file's {header:.3g} N/m")
    return out


def spring_constant_warnings(k: float, inferred: bool = False) -> list[str]:
    """The warning for a spring constant ``k`` [N/m] outside :data:`SPRING_CONSTANT_RANGE` (none inside it);
    ``inferred``: ``k`` came from a compliance slope, not from the file or the user. One wording for
    ``analyze`` and the fast map (``--fast-map``'s ``warnings`` column)."""
    lo, hi = SPRING_CONSTANT_RANGE
    if not math.isfinite(k) or lo <= k <= hi:
        return []
    src = ("inferred from the compliance slope of the force signal (a rigid contact assumed; on a soft "
           "sample the slope is the contact's, not the lever's)" if inferred else "of the file or the user")
    return [f"spring constant {k:.3g} N/m {src} is outside the range of cantilevers made "
            f"({lo:g}..{hi:g} N/m): give `spring_constant`"]


def _sensitivity(st: State) -> list[str]:
    cal, comp = st.details.get("calibration"), st.details.get("compliance")
    if cal is None or comp is None or cal.source != "fit":
        return []
    out = []
    for line in (comp.approach, comp.retract):
        if line.found and math.isclose(line.slope, cal.compliance_slope, rel_tol=1e-12):
            n = int(line.n_points)
            if n < MIN_COMPLIANCE_SAMPLES:
                rel = abs(line.slope_se / line.slope) if line.slope else math.nan
                unit = f"nm/{st.unit}" if st.unit != "m" else "nm/nm"
                value = cal.sensitivity_fit if math.isfinite(cal.sensitivity_fit) else cal.factor
                out.append(f"sensitivity {value * 1e9:.4g} {unit} fitted on only {n} contact samples (fewer than "
                           f"{MIN_COMPLIANCE_SAMPLES}; slope standard error {rel * 100:.2g} %): record more samples in "
                           "contact (slower ramp, higher rate) or give `sensitivity`")
            break
    return out


def _contact_slopes(st: State) -> list[str]:
    comp = st.details.get("compliance")
    if comp is None or not math.isfinite(st.factor):
        return []
    out = []
    for run, line in (("approach", comp.approach), ("retract", comp.retract)):
        rate = line.slope * st.factor if line.found else math.nan
        if math.isfinite(rate) and rate > MAX_CONTACT_SLOPE:
            out.append(f"on the {run}'s contact line the deflection moves {rate:.3g} x the position (at most 1 on "
                       "any sample): its separation runs backwards in contact (the force curve curls back on "
                       "itself); the sensitivity does not fit this run")
    return out


def _span(st: State) -> list[str]:
    if st.force is None or not math.isfinite(st.spring_constant) or not math.isfinite(st.factor):
        return []
    signal = st.curve.deflection_signal
    if (COMPILED and st.approach is not None and st.retract is not None and _f64(signal) and _f64(st.force)
            and st.approach.index.dtype == np.int64 and st.retract.index.dtype == np.int64):
        # one compiled pass: the same extremes (exact in any order), without a dozen numpy calls
        n, fmin, fmax, smin, smax = span_stats(st.force, signal, st.approach.index, st.retract.index)
        if n < 2:
            return []
        signal_span = float(smax - smin) * abs(st.factor) * st.spring_constant
        span = float(fmax - fmin)
    else:
        present = [r.index for r in (st.approach, st.retract) if r is not None]  # a curve of one run: its own
        runs = np.concatenate(present) if present else np.array([], int)
        f = st.force[runs]
        f = f[np.isfinite(f)]
        if f.size < 2:
            return []
        signal_span = float(ptp(signal[runs])) * abs(st.factor) * st.spring_constant
        span = float(ptp(f))
    if signal_span > 0 and span > MAX_SPAN_RATIO * signal_span:
        return [f"the corrected force spans {span * 1e9:.4g} nN where the signal itself spans {signal_span * 1e9:.4g} "
                "nN: the baseline correction is larger than the data (a drift line extrapolated too far)"]
    return []


def _f64(a) -> bool:
    """A float64 array (what the compiled pass takes)."""
    return isinstance(a, np.ndarray) and a.dtype == np.float64


def plausibility_warnings(st: State) -> tuple[str, ...]:
    """Warnings for the derived numbers of ``st`` outside their physical ranges (with the numbers)."""
    out: list[str] = []
    for check in (_hamaker, _spring_constant, _sensitivity, _contact_slopes, _span):
        out.extend(check(st))
    return tuple(w for w in out if w not in st.warnings)


def beyond_detector(curve) -> str | None:
    """Why a curve's deflection signal [V] cannot be a photodiode's: beyond the ADC's range (None: within).

    The range is the reader's ``adc_range`` metadata [V] when given, else :data:`DETECTOR_RANGE`
    (a simulated curve, with its truth, is checked only against a stated ``adc_range``).
    """
    if curve.deflection_unit != "V" or (curve.truth is not None and "adc_range" not in curve.metadata):
        return None  # a simulation without a stated ADC has no photodiode range
    try:
        limit = float(curve.metadata.get("adc_range", DETECTOR_RANGE))
    except (TypeError, ValueError):
        limit = DETECTOR_RANGE
    signal = np.asarray(curve.deflection_signal, float)
    if not signal.size:
        peak = 0.0
    else:
        peak = max(float(signal.max()), -float(signal.min()))  # max |signal|, in two reductions
        if not math.isfinite(peak):  # NaN (or infinite) samples: the NaN-aware maximum
            peak = float(np.nanmax(np.abs(signal)))
    if not peak > 1.01 * limit:
        return None
    reader = curve.metadata.get("reader", "the reader")
    return (f"{IMPOSSIBLE}: the deflection signal reaches {peak:.4g} V, beyond the photodiode ADC's range "
            f"(+-{limit:.3g} V): the file is read with a wrong scale, or damaged; no force can come from it; "
            f"suspect input: the file's data scale (reader {reader})")


def impossible_steps(st: State) -> dict[str, str]:
    """``{step: reason}`` of the steps whose numbers would be physically impossible on this curve.

    A hard contact whose compliance slope gives a sensitivity more than :data:`MAX_CALIBRATION_RATIO`
    times off the file's (or the user's): one of the two is wrong, so no force is a result
    (:data:`FORCE_STEPS`), even when the pipeline recalibrated from the slope: a realigned laser moves the
    sensitivity by tens of per cent, not ten times. A soft contact's slope is the sample's, not the lever's,
    and ``calibration.source=fit`` says the user wants the slope's: neither is checked.
    """
    inferred = _inferred_spring_constant(st)
    if inferred:
        return {step: inferred for step in ("force", *FORCE_STEPS) if step in st.details or step in st.skipped}
    negative = _negative_indentation(st)
    if negative:
        return {"indentation": negative}
    cal, kind = st.details.get("calibration"), st.details.get("kind")
    if cal is None or st.unit != "V" or (kind is not None and kind.kind != "hard") or \
            getattr(cal, "requested", "") == "fit":  # the user asked for the slope's calibration, not the file's
        return {}
    given = st.probe.value("sensitivity", st.metadata)
    fit = getattr(cal, "factor_fit", math.nan)
    try:
        ratio = float(fit) / float(given)
    except (TypeError, ValueError, ZeroDivisionError):
        return {}
    if not math.isfinite(ratio) or ratio <= 0 or 1 / MAX_CALIBRATION_RATIO <= ratio <= MAX_CALIBRATION_RATIO:
        return {}
    why = (f"{IMPOSSIBLE}: on this hard contact the compliance slope gives a sensitivity {ratio:.3g} x the file's "
           f"{float(given) * 1e9:.4g} nm/V (more than {MAX_CALIBRATION_RATIO:g} x off): the file's sensitivity is "
           "stale or mistyped, or the file is read with a wrong scale; suspect input: sensitivity")
    return {step: why for step in FORCE_STEPS if step in st.details or step in st.skipped}


def _negative_indentation(st: State) -> str | None:
    """Why a soft contact gives no modulus (None: it may): its deflection rises more than its position travels
    after the contact point (the kind step's ``NEGATIVE_INDENTATION``: no indentation is reported), so the
    deflection is overestimated and the fitted modulus rests on indentations no sample allows.

    Found on an Asylum MFP-3D SMFS curve of 2025 (YY-Zhang1999/Gen_SMFS ``data/raw/Imagef1_0000.ibw``, InvOLS
    179.86 nm/V where the straight part of the contact gives 1.63 x less): with a 20 nm paraboloid it gave
    E = 55.35 kPa beside the warnings that the indentation is impossible and not reported."""
    kind, cp = st.details.get("kind"), st.details.get("contact_point")
    if kind is None or kind.kind != "soft" or cp is None or not ("indentation" in st.details
                                                              or "indentation" in st.skipped):
        return None
    depth = getattr(cp, "indentation", math.nan)
    if not (math.isfinite(depth) and depth <= 0):
        return None
    return (f"{IMPOSSIBLE}: after the contact point the deflection rises {-depth * 1e9:.3g} nm more than the "
            "position travels (a negative indentation): the deflection is overestimated, no modulus is a result; "
            "suspect input: sensitivity (an uncalibrated or stale InvOLS; calibrate on a hard surface)")


def _inferred_spring_constant(st: State) -> str | None:
    """Why a spring constant inferred from a compliance slope cannot be the lever's (None: it can be).

    With no spring constant given, a force signal's contact slope is taken for the lever's stiffness
    (a rigid contact); it is inferred only when neither the file nor the user gives one (a given one is
    used, never compared). A value outside :data:`SPRING_CONSTANT_RANGE` (no cantilever is made so soft
    or so stiff) says the contact was not rigid or not reached: the separations and every number from
    them would be wrong. Softer than any lever (a force that barely rises in "contact": a soft sample, or
    an approach that never reached a hard contact) the spring constant is undetermined (:data:`K_UNDETERMINED`),
    not impossible: the signal is a force, only not one that fixes k. Stiffer than any lever is
    impossible (a rigid contact's slope is the lever's, a soft one's less): the position is mis-scaled.
    """
    conv = st.details.get("force")
    if conv is None or getattr(conv, "method", "") != "compliance slope" or "force" in st.skipped:
        return None
    k = float(conv.spring_constant)
    lo, hi = SPRING_CONSTANT_RANGE
    if not math.isfinite(k) or lo <= k <= hi:
        return None
    if k < lo:
        return (f"{K_UNDETERMINED}: the force signal has no hard contact: its compliance slope, {k:.3g} N/m, is "
                f"softer than any cantilever made (at least {lo:g} N/m), so it is a soft sample's or an approach's "
                "that never reached a hard contact, not the lever's; without the lever's spring constant the "
                "deflection, the separations and every number from them are unknown; give spring_constant (the "
                "lever's)")
    cause = "the position is mis-scaled or does not move the lever's base"
    return (f"{IMPOSSIBLE}: the spring constant {k:.3g} N/m inferred from the compliance slope of the force signal "
            f"is outside the range of cantilevers made ({lo:g}..{hi:g} N/m): {cause}, so the slope is not the "
            "lever's; suspect input: "
            "spring_constant (give the lever's spring constant, and its sensitivity for a signal in volts)")


def slope_not_the_levers(st: State) -> str | None:
    """Why a spring constant inferred from a force signal's compliance slope is not the lever's, though
    within the levers' range (None: it may be): the contact is soft (curved: the slope is the series
    stiffness of lever and sample, below the lever's), or the position is already the tip-sample
    separation (a processed export: the slope is the sample's alone). The forces are the file's and
    stay; the spring constant is not reported, nor the modulus (its indentation needs the lever's)."""
    conv, kind = st.details.get("force"), st.details.get("kind")
    if conv is None or getattr(conv, "method", "") != "compliance slope" or "force" in st.skipped:
        return None
    if st.metadata.get("position_is_separation"):
        why = "the position is the tip-sample separation (a processed export): the slope is the sample's"
    elif kind is not None and kind.kind == "soft":
        why = "the contact is soft (curved): the slope is the lever and the sample in series, not the lever"
    else:
        return None
    return (f"spring constant {conv.spring_constant:.3g} N/m from the compliance slope not reported: {why}; "
            "give the lever's spring constant (the forces are the file's)")


#: The largest surface energy of a solid [J/m^2]: polymers ~0.02-0.05, oxides and mica ~0.1-1, clean metals
#: 1-3, diamond's (111) face ~5.3 (calculated). A JKR/DMT gamma from a pull-off above it is no surface energy.
SURFACE_ENERGY_MAX = 6.0


def unphysical_surface_energy(gamma: float, radius: float) -> str | None:
    """Why a surface energy [J/m^2] from the pull-off and the radius [m] is none (None: it can be one)."""
    if not (math.isfinite(gamma) and gamma > SURFACE_ENERGY_MAX):
        return None
    return (f"not a surface energy: {gamma:.3g} J/m^2 from the pull-off and the radius {radius * 1e9:.3g} nm is "
            f"beyond any solid's (at most {SURFACE_ENERGY_MAX:g} J/m^2): the pull-off is not the JKR/DMT "
            "adhesion of that radius (a capillary meniscus in air, a blunter probe than the radius given, "
            "electrostatics); give the probe's real radius, or read the adhesion force itself")


def undetermined(value: float, bound: float, resolution: float = 0.0) -> bool:
    """Whether a measured ``value`` whose systematic bound (a half-width, same unit) is ``bound`` is undetermined.

    The one rule of every face (the analysis steps, the command-line table, the JSON and CSV, the web page): a
    value is undetermined when its interval ``value +- bound`` is wider than the value itself *and* than the
    ``resolution`` the quantity is read to (the interval then holds zero and both signs, and its width is not a
    small error on a small number). An unassessed bound (NaN) leaves the value as it is.

    Parameters
    ----------
    value : float
        The measured number [its unit].
    bound : float
        Its bound (half-width of its interval) [the same unit]; NaN: not assessed.
    resolution : float
        A bound up to this is a small error, never undetermined [the same unit].

    Returns
    -------
    bool
        True: report the value as undetermined (with its interval), not as a result.
    """
    return math.isfinite(value) and math.isfinite(bound) and bound > max(abs(value), resolution)


def interval_undetermined(low: float, high: float) -> bool:
    """Whether a 95 % interval ``[low, high]`` is the undetermined one, ``[0, open]`` (``high`` NaN): how a fitted
    modulus the data do not bound, or a law used beyond its range, is reported (``youngs_modulus_low`` 0,
    ``youngs_modulus_high`` NaN; :func:`afmforce.contact.fit.fit_indentation`)."""
    return low == 0.0 and not math.isfinite(high)


def impossible_modulus(modulus: float) -> str | None:
    """Why a fitted Young's modulus [Pa] cannot be a material's (None: it can be, or it is undetermined)."""
    lo, hi = MODULUS_RANGE
    if not math.isfinite(modulus) or lo <= modulus <= hi:
        return None
    return (f"{IMPOSSIBLE}: the fitted Young's modulus {modulus:.3g} Pa is outside the range of materials "
            f"({lo:g} Pa..{hi / 1e12:g} TPa): the position or the deflection is read with a wrong scale, or the "
            "calibration is wrong; suspect input: spring_constant, sensitivity or the file's position scale")


def impossible_reasons(skipped) -> list[str]:
    """The distinct physically-impossible reasons (and an undetermined spring constant's, :data:`K_UNDETERMINED`)
    among a result's ``not_applicable`` (for the verdict)."""
    return list(dict.fromkeys(r for r in dict(skipped).values()
                              if str(r).startswith(IMPOSSIBLE) or str(r).startswith(K_UNDETERMINED)))
