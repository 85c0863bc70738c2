"""Metadata table shared by the readers: each key with its label, SI unit and validator.

Readers put SI values under these keys in :attr:`afmforce.io.curve.RawCurve.metadata`;
unknown vendor keys are kept as they are. ``meta_override`` (from the user, e.g.
``--spring-constant``) is validated against this table and wins over values read
from the file.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, Callable, Mapping

import numpy as np

from .._fields import QUANTITIES
from ..errors import FileFormatError, MissingMetadataError, ParameterError
from .curve import SEGMENT_APPROACH, SEGMENT_DWELL, SEGMENT_RETRACT, RawCurve

__all__ = ["MetaField", "METADATA", "check_meta_override", "finalize_curve", "segment_code",
           "missing_metadata", "require_metadata", "orient", "afmformats_override", "parse_meta_args",
           "positive_entry", "first_approach_only", "SENSOR_RAMP_TOLERANCE", "sensor_note"]


def _positive(value: Any) -> float:
    v = float(value)
    if not math.isfinite(v) or v <= 0:
        raise ValueError("must be a positive finite number")
    return v


def positive_entry(entries: Mapping[str, str], key: str) -> float | None:
    """The positive finite number a reader finds under ``key`` of a file's header or note, or None
    where the key is missing or its value is not such a number (optional metadata)."""
    try:
        v = float(entries[key])
    except (KeyError, ValueError):
        return None
    return v if np.isfinite(v) and v > 0 else None


def _finite(value: Any) -> float:
    v = float(value)
    if not math.isfinite(v):
        raise ValueError("must be a finite number")
    return v


def _non_negative(value: Any) -> float:
    v = float(value)
    if not math.isfinite(v) or v < 0:
        raise ValueError("must be a finite number >= 0")
    return v


def _poisson(value: Any) -> float:
    v = float(value)
    if not (-1.0 < v <= 0.5):
        raise ValueError("must lie in (-1, 0.5]")
    return v


def _text(value: Any) -> str:
    return str(value)


@dataclass(frozen=True)
class MetaField:
    """One metadata key: what it is, its SI unit and how to validate it."""

    label: str
    unit: str
    validate: Callable[[Any], Any]


#: The metadata keys afmforce understands (SI values).
METADATA: dict[str, MetaField] = {
    "spring_constant": MetaField("Spring constant", "N/m", _positive),
    "sensitivity": MetaField("Deflection sensitivity (InvOLS)", "m/V", _positive),
    "velocity": MetaField("Approach speed", "m/s", _positive),
    "retract_velocity": MetaField("Retract speed", "m/s", _positive),
    "sample_rate": MetaField("Sample rate", "Hz", _positive),
    "resonance_frequency": MetaField("Resonance frequency", "Hz", _positive),
    "quality_factor": MetaField("Quality factor of the free resonance (tells air from liquid)", "", _positive),
    "lever_drag": MetaField("Drag coefficient of the lever body in the liquid", QUANTITIES["lever_drag"].unit,
                            _non_negative),
    "lever_height": MetaField("Lever height above the substrate at contact (drag c H/(h + H))",
                              QUANTITIES["lever_height"].unit, _non_negative),
    "theta0": MetaField("Cantilever inclination", "rad", _finite),
    "radius": MetaField("Probe radius", "m", _positive),
    "poisson": MetaField("Poisson ratio of the sample (the indentation step's default)", "", _poisson),
    "instrument": MetaField("Instrument", "", _text),
    "date": MetaField("Date of the measurement (as the file or the user writes it)", "", _text),
    "format": MetaField("File format", "", _text),
    "source_file": MetaField("Source file", "", _text),
    "reader": MetaField("afmforce reader identifier", "", _text),
}

#: Vendor (afmformats) key -> afmforce key.
AFMFORMATS_KEYS = {
    "spring constant": "spring_constant",
    "sensitivity": "sensitivity",
    "speed approach": "velocity",
    "speed retract": "retract_velocity",
    "rate approach": "sample_rate",
    "instrument": "instrument",
}


_DIMENSION = {"N/m": "stiffness", "m/V": "sensitivity", "m/s": "velocity", "Hz": "frequency", "rad": "angle",
              "m": "length"}


def _same(a, b) -> bool:
    """Whether two parsed metadata values are the same (numbers to rounding: ``0.3`` and ``300mN/m``)."""
    if isinstance(a, (int, float)) and isinstance(b, (int, float)):
        return math.isclose(a, b, rel_tol=1e-9)
    return a == b


def parse_meta_args(items) -> dict[str, Any]:
    """``["sample_rate=6kHz", "instrument=MFP-3D"]`` (the command line's ``KEY=VALUE`` items) -> SI metadata.

    Values with units are parsed in the key's unit (:data:`METADATA`); a plain
    number is taken as SI. Raises ParameterError for an unknown key or a bad value.
    """
    from ..units import parse_value

    out: dict[str, Any] = {}
    for item in items or ():
        key, sep, value = str(item).partition("=")
        key = key.strip()
        if not sep or not key:
            raise ParameterError(f"`meta_override` {item!r}: expected KEY=VALUE, e.g. sample_rate=6kHz")
        if key not in METADATA:
            raise ParameterError(f"`meta_override` {key}: unknown metadata key; known keys: "
                                 f"{', '.join(sorted(METADATA))}")
        dim = _DIMENSION.get(METADATA[key].unit)
        parsed = parse_value(value.strip(), dim, f"`meta_override` {key}") if dim else value.strip()
        if key in out and not _same(out[key], parsed):       # which one was meant: never the last silently
            raise ParameterError(f"`meta_override` {key} given twice with different values ({out[key]!r} and "
                                 f"{parsed!r} [SI]); give it once")
        out[key] = parsed
        if key in QUANTITIES:   # the same range as the quantity's own flag or field and the records
            QUANTITIES[key].check(out[key], key, f"`meta_override` {key}", typed=value.strip())
    return check_meta_override(out)


def check_meta_override(meta_override: Mapping[str, Any] | None) -> dict[str, Any]:
    """Validate a user's ``meta_override`` against :data:`METADATA`.

    Accepts afmforce keys (``spring_constant``) and afmformats keys
    (``"spring constant"``); unknown keys raise :class:`ParameterError`.
    """
    out: dict[str, Any] = {}
    for key, value in (meta_override or {}).items():
        if value is None:
            continue
        name = AFMFORMATS_KEYS.get(key, key)
        if name not in METADATA:
            raise ParameterError(
                f"unknown metadata key {key!r}; known keys: {', '.join(sorted(METADATA))}")
        field = METADATA[name]
        try:
            out[name] = field.validate(value)
        except (TypeError, ValueError) as exc:
            raise ParameterError(f"metadata {name} [{field.unit}] {exc}, got {value!r}") from None
        if name in QUANTITIES:
            QUANTITIES[name].check(out[name], name)
    return out


#: Vendor segment words -> afmforce segment code (raw.py: 0 approach, 1 retract, 2 dwell).
SEGMENT_WORDS: dict[str, int] = {
    "extend": SEGMENT_APPROACH, "approach": SEGMENT_APPROACH, "trace": SEGMENT_APPROACH,
    "ex": SEGMENT_APPROACH, "retract": SEGMENT_RETRACT, "retrace": SEGMENT_RETRACT,
    "rt": SEGMENT_RETRACT, "withdraw": SEGMENT_RETRACT, "pause": SEGMENT_DWELL,
    "dwell": SEGMENT_DWELL, "hold": SEGMENT_DWELL, "wait": SEGMENT_DWELL,
}


def segment_code(style: str) -> int:
    """afmforce segment code of a vendor's segment type (``"extend"``, ``"retract"``, ``"pause"``...).

    Anything that is neither an approach nor a retract (pause, dwell, modulation,
    an unknown word) is a dwell (2): it is kept, but never taken as approach or retract.
    """
    return SEGMENT_WORDS.get(str(style).strip().lower(), SEGMENT_DWELL)


def orient(z_nominal: np.ndarray, z_measured: np.ndarray | None, segment: np.ndarray):
    """Flip the sign of the position channels if z decreases on the approach run."""
    zref = z_measured if z_measured is not None else z_nominal
    app = np.flatnonzero(segment == SEGMENT_APPROACH)
    sign = 1.0
    if app.size >= 2 and zref[app[-1]] < zref[app[0]]:
        sign = -1.0
    return sign * z_nominal, (None if z_measured is None else sign * z_measured), sign


def afmformats_override(meta: Mapping[str, Any]) -> dict[str, float]:
    """The part of a (checked) ``meta_override`` that afmformats understands, in its keys and units."""
    out = {}
    if "spring_constant" in meta:
        out["spring constant"] = float(meta["spring_constant"])
    if "sensitivity" in meta:
        out["sensitivity"] = float(meta["sensitivity"])
    return out


def _needed(curve: RawCurve, key: str) -> bool:
    """Is ``key`` needed to turn this curve's deflection signal into a force?"""
    if key == "spring_constant":
        return curve.deflection_unit in ("V", "m")
    if key == "sensitivity":
        return curve.deflection_unit == "V"
    return True


def missing_metadata(path: str, keys, what: str = "the file stores") -> MissingMetadataError:
    """The one-line error for metadata a user must give: names the keys (`` `key` ``) and units."""
    keys = tuple(keys)
    fields = [METADATA[k] for k in keys]
    names = " and no ".join(f"{f.label[0].lower()}{f.label[1:]} [{f.unit}]" for f in fields)
    return MissingMetadataError(f"{path}: {what} no {names}; give {' and '.join(f'`{k}`' for k in keys)}",
                                keys=keys)


def require_metadata(curve: RawCurve, keys=("spring_constant", "sensitivity"), path: str | None = None) -> None:
    """Raise :class:`~afmforce.errors.MissingMetadataError` if ``curve`` lacks a key it needs.

    ``spring_constant`` is needed for a deflection in V or m, ``sensitivity`` for
    one in V (a force in N needs neither); any other key is needed as such.
    """
    path = path or str(curve.metadata.get("source_file", "<curve>"))
    unknown = [k for k in keys if k not in METADATA]
    if unknown:
        raise ParameterError(f"unknown metadata key(s) {', '.join(map(repr, unknown))}; "
                             f"known keys: {', '.join(sorted(METADATA))}")
    missing = [k for k in keys if _needed(curve, k) and curve.metadata.get(k) is None]
    if missing:
        raise missing_metadata(path, missing)


def first_approach_only(curve: RawCurve) -> RawCurve:
    """The curve whose approach is its first extend run only (a step indentation's later extends: dwell).

    A step (multi-) indentation extends, holds, extends again deeper, holds... before it retracts
    (JPK segmented force settings: extend, pause, extend, pause, ..., retract). Its extend segments
    together are no approach: the holds between them relax the force (drops of ~1 nN in afmToolkit's
    ``force-save-JPK-multiIndent.txt``), so a contact point, a baseline or a Hertz fit over them fits
    steps, not a contact. The first extend (from free to contact) is the approach; every later extend
    before the retract is kept with the holds as a dwell (segment 2), and ``approach_steps`` (metadata) says
    so. A curve with one extend run before its retract is returned unchanged (extends after a retract: cycles).
    """
    seg = np.asarray(curve.segment)
    ret = np.flatnonzero(seg == SEGMENT_RETRACT)
    app = seg == SEGMENT_APPROACH
    app[ret[0] if ret.size else seg.size:] = False   # an extend after a retract is a new cycle: left as it is
    starts = np.flatnonzero(app & ~np.r_[False, app[:-1]])
    if starts.size <= 1:
        return curve
    first_end = int(starts[0] + np.argmin(app[starts[0]:]))   # a later run exists: a False lies between
    later = app.copy()
    later[:first_end] = False
    new = seg.copy()
    new[later] = SEGMENT_DWELL
    z = np.asarray(curve.piezo_measured if curve.piezo_measured is not None else curve.piezo_nominal, float)
    deeper = float(np.max(z[later]) - z[first_end - 1])
    note = (f"step indentation: {starts.size} extend segments with holds between them; the first "
            f"({first_end - int(starts[0])} samples, free to contact) is the approach, the {starts.size - 1} "
            f"later ({int(later.sum())} samples, reaching {deeper * 1e9:.4g} nm deeper) are kept with the holds "
            "as dwell and not analysed (the holds relax the force between them: no single loading curve)")
    return dataclasses.replace(curve, segment=new, metadata={**curve.metadata, "approach_steps": note})


def finalize_curve(curve: RawCurve, path: str) -> RawCurve:
    """Check that a freshly read curve is usable: finite columns, monotonic time; a step indentation's
    approach is its first extend (:func:`first_approach_only`).

    Raises
    ------
    FileFormatError
        Non-finite values in a column, or no sample on the approach run.
    """
    cols = {"time": curve.time, "piezo_nominal": curve.piezo_nominal,
            "deflection_signal": curve.deflection_signal}
    if curve.piezo_measured is not None:
        cols["piezo_measured"] = curve.piezo_measured
    for name, col in cols.items():
        arr = np.asarray(col, dtype=float)
        bad = ~np.isfinite(arr)
        if bad.any():
            raise FileFormatError(
                f"{path}: column {name} has {int(bad.sum())} non-finite values (first at sample "
                f"{int(np.argmax(bad))}); the file is damaged or padded: remove those rows")
    if not np.any(curve.approach) and curve.metadata.get("single_run") != "retract":  # an export of the retract only
        raise FileFormatError(f"{path}: no approach (extend) segment found")
    if not curve.metadata.get("time_is_sample_index"):
        step = np.diff(np.asarray(curve.time, dtype=float))
        if step.size and not np.all(step > 0):
            j = int(np.argmax(~(step > 0)))
            raise FileFormatError(f"{path}: time does not increase at sample {j + 1} "
                                  f"({curve.time[j]!r} s then {curve.time[j + 1]!r} s); the file is damaged")
    for key, value in curve.metadata.items():
        field = METADATA.get(key)
        if field is None or value is None:
            continue
        try:
            field.validate(value)
        except (TypeError, ValueError) as exc:
            raise FileFormatError(f"{path}: metadata {key} [{field.unit}] {exc}, got {value!r}; "
                                  f"the file is damaged, give the right value (`{key}`)"
                                  ) from None
        spec = QUANTITIES.get(key)   # the quantity's declared valid range: k = 2^31-1 N/m is no result
        if spec is not None and spec.bounded and not isinstance(value, (str, bool)) and not spec.contains(value):
            raise FileFormatError(f"{path}: metadata {key} = {spec.show(value)} is out of range: no instrument "
                                  f"gives it ({key} must lie in {spec.range_text()}); the file's header is "
                                  f"damaged or mis-scaled, give the right value (`{key}`)")
    return first_approach_only(curve)


#: How far [fraction] a measured position's span over the approach (a Z sensor's, a strain gauge's) may differ
#: from the nominal ramp's unsaid (readers' ``position_note``: Bruker NanoScope, JPK text exports)
SENSOR_RAMP_TOLERANCE = 0.10


def sensor_note(zm: np.ndarray, zn: np.ndarray, seg: np.ndarray, *, sensor: str, nominal: str, used: str,
                scales: str) -> str | None:
    """The reader's ``position_note``: what the analysis says when the measured position (``zm`` [m]) spans
    the approach more than :data:`SENSOR_RAMP_TOLERANCE` off the nominal ramp (``zn`` [m]): the modulus
    depends on which is taken (about as the ratio^1.5). Its steps against the ramp's over the first and the
    last fifth of the approach tell a scale (equal) from an open-loop piezo's motion (unequal); None within
    the tolerance. ``sensor``, ``nominal``, ``used`` and ``scales`` are the reader's words for the sensor, the
    nominal ramp's product, the position used and the two scales that disagree."""
    app = np.flatnonzero(seg == SEGMENT_APPROACH)
    if app.size < 10 or not np.ptp(zn[app]) > 0 or not np.all(np.isfinite(zm[app])):
        return None
    ratio = float(np.ptp(zm[app]) / np.ptp(zn[app]))
    if abs(ratio - 1.0) <= SENSOR_RAMP_TOLERANCE:
        return None
    fifth = app.size // 5
    first, last = (abs(float(np.polyfit(zn[part], zm[part], 1)[0])) for part in (app[:fifth], app[-fifth:]))
    steps = (f"its steps are {first:.3g} x the ramp's over the approach's first fifth and {last:.3g} x over its "
             "last " + ("(the sensor records a motion the ramp does not: an open-loop piezo's hysteresis and creep)"
                        if abs(last - first) > 0.05 * min(first, last) else
                        f"(a constant ratio: {scales}, the file cannot tell which is right)"))
    return (f"{sensor} travels {ratio:.3g} x the nominal ramp ({np.ptp(zn[app]) * 1e9:.4g} nm = {nominal}) over the "
            f"approach; {steps}; {used} is the position used: a modulus on the nominal ramp would be about "
            f"{last ** 1.5:.2g} x as large (the last steps' ratio^1.5; `channel nominal` gives it)")
