"""One validation for every value a client sends, against the declarations the CLI uses.

A value is checked where it enters, before any process or computation starts, against the
same declarations as ``afmforce simulate``/``fit``/``sweep``: the field's
:class:`~afmforce._fields.FieldSpec` (its range, :meth:`FieldSpec.check`; the configuration
parts carry it as field metadata, :func:`afmforce._fields.spec_of`) and the ``domain`` the
model needs (positive, non-negative, a count: :data:`afmforce.dynamics._part.DOMAINS`).

A number is a JSON number or a text with units, read by the library's parser
(:func:`afmforce.units.parse_typed`: ``"1um/s"`` -> 1e-6, a plain number is SI), as the
command line reads it. Refused: booleans, lists, objects, NaN and infinities (Python's and
browsers' JSON may send ``NaN``), numbers out of range. Every refusal is a :class:`FieldError`
naming the field as the request spells it (``velocity``, ``truth.xi``, ``velocities[0]``,
``grid[0]``): the server answers ``422 {"error": {"type", "message", "field"}}``.
"""

from __future__ import annotations

import math
from itertools import product
from pathlib import Path
from typing import Any, Iterable

from .._fields import FieldSpec
from ..errors import AfmforceError, ParameterError
from .limits import CALIBRATION_BYTES, MAX_ITEMS, MAX_RUNS, MAX_SAMPLES

__all__ = ["FieldError", "number", "flat_config", "build_config", "cycle_samples", "velocities", "sweep_spec",
           "metadata", "calibration_file", "fit_curve_count"]

#: Longest text accepted for one value (``"0.1 um/s"``).
_TEXT = 64


class FieldError(ParameterError):
    """A value a client sent is refused; ``field`` names it as the request spells it."""

    def __init__(self, field: str | None, message: str):
        super().__init__(message)
        self.field = field


def _shown(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


def number(value: Any, spec: FieldSpec, name: str, field: str | None = None, domain: str | None = None):
    """``value`` (a JSON number or a text with units) as SI, checked against ``spec`` and ``domain``.

    Returns a float (an int for a count); raises :class:`FieldError` naming ``field`` (default ``name``).
    """
    from ..units import parse_typed

    field = field or name
    if isinstance(value, bool) or not isinstance(value, (int, float, str)):
        raise FieldError(field, f"{field} expects a number [{spec.unit or '-'}], got {_shown(value)}")
    if isinstance(value, str):
        if len(value) > _TEXT:
            raise FieldError(field, f"{field} expects a number with units, got a text of {len(value)} characters")
        try:
            value = parse_typed(value.strip(), spec.dimension, field)
        except (AfmforceError, ValueError) as exc:
            raise FieldError(field, str(exc)) from None
    try:
        v = float(value)
    except OverflowError:        # a JSON integer with 400 digits
        v = math.inf
    if not math.isfinite(v):
        raise FieldError(field, f"{field} must be a finite number [{spec.unit or '-'}], got {_shown(value)}")
    if spec.dimension == "integer" or domain == "count":
        if not v.is_integer():
            raise FieldError(field, f"{field} expects a whole number, got {_shown(value)}")
    try:
        spec.check(v, name, where=None if field == name else field)
        if domain is not None:
            from ..dynamics.parts import DOMAINS

            DOMAINS[domain](name, v, spec.unit)
    except ParameterError as exc:
        raise FieldError(field, str(exc)) from None
    return int(v) if spec.dimension == "integer" or domain == "count" else v


def flat_config(flat: Any, prefix: str = "") -> dict[str, Any]:
    """Check a configuration of flat names (:data:`afmforce.dynamics.config.FLAT`), field by field.

    Returns the values in SI (``None`` values dropped: the defaults); ``prefix`` is how the request
    names the object (``"truth."``). Text fields must name an entry of their registry.
    """
    from ..dynamics.config import FLAT
    from ..dynamics.parts import MODELS

    if not isinstance(flat, dict):
        raise FieldError(prefix.rstrip(".") or None,
                         "expected a JSON object of flat configuration names (SI), e.g. {\"xi\": 0.01}")
    model = flat.get("model") or "beam"
    if not isinstance(model, str) or model not in MODELS:
        raise FieldError(f"{prefix}model", f"model must be one of {sorted(MODELS)}, got {_shown(model)}")
    out: dict[str, Any] = {}
    for name, value in flat.items():
        field = f"{prefix}{name}"
        where = FLAT.get(name)
        if where is None:
            raise FieldError(field, f"unknown simulation parameter {_shown(name)}; known: {', '.join(FLAT)}")
        if value is None:
            continue
        if model not in where.models:
            raise FieldError(field, f"{name} is a field of the {where.models[0]} model's probe; model "
                                    f"{model!r} has no {name} (give model={where.models[0]!r} or drop it)")
        if where.spec is None:          # a text field: an entry of its registry
            choices = MODELS if where.field is None else where.field.metadata.get("choices", {})
            if not isinstance(value, str) or value not in choices:
                raise FieldError(field, f"{name} must be one of {sorted(choices)}, got {_shown(value)}")
            out[name] = value
            continue
        out[name] = number(value, where.spec, name, field, where.field.metadata.get("domain"))
    return out


def cycle_samples(cfg) -> float:
    """Samples of one approach-retract cycle of ``cfg`` (from the drive and the sample rate)."""
    d = cfg.drive
    back = d.retract_velocity or d.velocity
    return ((abs(d.turn - d.start) / d.velocity + abs(d.turn - d.end) / back + d.dwell)
            * cfg.solver.sample_rate)


def _too_many(n: float, field: str | None) -> FieldError:
    return FieldError(field, f"the cycle would have about {n:.3g} samples, more than the {MAX_SAMPLES:,} a "
                             "request may simulate; lower sample_rate, raise velocity or shorten the drive")


def _samples_of(values: dict[str, Any]) -> float | None:
    """Samples of the cycle ``values`` describe, also when the record refuses it for its size
    (its drive at 1 Hz, times the sample rate); None when the drive itself is refused."""
    from ..dynamics import SimulationConfig

    from ..limits import simulation_samples

    default = SimulationConfig()
    d = {k: values.get(k, getattr(default.drive, k)) for k in
         ("start", "turn", "end", "velocity", "retract_velocity", "dwell")}
    try:
        n = simulation_samples(float(d["start"]), float(d["turn"]), float(d["end"]), float(d["velocity"]),
                               None if d["retract_velocity"] is None else float(d["retract_velocity"]),
                               float(d["dwell"]), float(values.get("sample_rate", default.solver.sample_rate)))
    except (TypeError, ValueError, ZeroDivisionError):
        return None
    return abs(n)


def build_config(flat: Any, prefix: str = ""):
    """The checked :class:`~afmforce.dynamics.SimulationConfig` of a request's flat names.

    Every field is checked (:func:`flat_config`), then the combination (the library's checks:
    k0 and B not both, the start out of contact) and the cycle's sample count (at most
    :data:`~.limits.MAX_SAMPLES`). Nothing is simulated.
    """
    from ..dynamics import SimulationConfig

    values = flat_config(flat, prefix)
    try:
        cfg = SimulationConfig(**values)
    except ParameterError:
        # the record refuses a cycle over the cap itself (afmforce.limits): name the field that sets it
        n = _samples_of(values)
        if n is not None and (not math.isfinite(n) or n > MAX_SAMPLES):
            raise _too_many(n, f"{prefix}sample_rate") from None
        raise
    n = cycle_samples(cfg)
    if not math.isfinite(n) or n > MAX_SAMPLES:
        raise _too_many(n, f"{prefix}sample_rate")
    cfg.validate()
    return cfg


def fit_curve_count(files: Iterable[Any], timeout: float | None = None,
                    meta: dict[str, Any] | None = None) -> int:
    """The curves a fit of the uploads ``files`` (``[(stored path, name given)]``) takes: every curve
    of each file, as the fit's job reads them (:func:`afmforce.io.load` with the fit's ``meta``).
    A force map's are counted from its header (:func:`afmforce.sweep.files.plan_curves`); a file
    whose count no header gives cheaply (a Nanosurf spectroscopy file of 10 curves, a WSxM file of
    5) is read, bounded by ``timeout`` [s] as the first reading of an upload is (None: the file was
    read once already). Refused past the dynamic fit's cap (:data:`afmforce.fit.core.MAX_CURVES`)
    as ``file_ids``; a file that cannot be read (the job's fit would fail on it) as ``file_ids[i]``."""
    from ..fit.core import MAX_CURVES, check_curve_count
    from ..io import load
    from ..sweep.files import TooManyCurves, plan_curves

    n = 0
    for i, (path, name) in enumerate(files):
        try:        # a map's header count past the cap: refused before a work item per declared curve is made
            refs = plan_curves([path], timeout=timeout, max_curves=MAX_CURVES - n)
        except TooManyCurves as exc:
            n += exc.declared
            break
        if len(refs) == 1 and refs[0].index is None:     # no cheap count: read it, as the job will
            try:
                refs = load(path, meta_override=meta or None, timeout=timeout)
            except AfmforceError as exc:
                text = str(exc).replace(str(path), name).replace(Path(path).name, name)
                raise FieldError(f"file_ids[{i}]", f"file_ids[{i}]: {text}") from None
        n += len(refs)
    try:
        check_curve_count(n)
    except ParameterError as exc:
        raise FieldError("file_ids", f"file_ids: the uploads hold {n} curves; {exc}") from None
    return n


def velocities(values: Any, field: str = "velocities") -> list[float]:
    """Driving speeds [m/s] of virtual curves, each checked as ``velocity``."""
    from .._fields import QUANTITIES

    if not isinstance(values, list):
        raise FieldError(field, f"{field} expects a list of speeds [m/s]")
    return [number(v, QUANTITIES["velocity"], "velocity", f"{field}[{i}]", "positive")
            for i, v in enumerate(values)]


def metadata(items: Any, field: str = "meta") -> dict[str, Any]:
    """``KEY=VALUE`` metadata overrides (:func:`afmforce.io._meta.parse_meta_args`, as ``--meta``), one
    item at a time so that a refusal names it; a key of the shared vocabulary is checked against its
    declared range (``sensitivity=1e300`` is refused, not read)."""
    from .._fields import QUANTITIES
    from ..io import parse_meta_args

    out: dict[str, Any] = {}
    for i, item in enumerate(_strings(items, field)):
        where = f"{field}[{i}]"
        try:
            parsed = parse_meta_args([item])
        except ParameterError as exc:
            raise FieldError(where, str(exc).replace("`meta_override`", where)) from None
        for key, value in parsed.items():
            spec = QUANTITIES.get(key)
            if spec is not None and isinstance(value, (int, float)) and not isinstance(value, bool):
                number(value, spec, key, where)
        out.update(parsed)
    try:                # a key given twice with different values: which one was meant, never the last silently
        parse_meta_args(_strings(items, field))
    except ParameterError as exc:
        raise FieldError(field, str(exc).replace("`meta_override`", field)) from None
    return out


def calibration_file(data: bytes, name: str, field: str = "calibration", size: int | None = None) -> dict[str, float]:
    """The probe values [SI] the analysis takes from an uploaded calibration file (the JSON of
    ``afmforce calibrate ... --out``, read by :func:`afmforce.calibration.record.parse_calibration`,
    the values of :data:`~afmforce.calibration.record.ANALYSIS_KEYS` it holds), each checked
    against its declared range as the probe field (``calibration.spring_constant``). ``size``: the
    upload's bytes when ``data`` holds only its first :data:`~.limits.CALIBRATION_BYTES` + 1 [bytes]."""
    import dataclasses

    from .._fields import spec_of
    from ..analysis.options import ProbeCalibration
    from ..calibration.record import ANALYSIS_KEYS, PROBE_KEYS, parse_calibration

    if len(data) > CALIBRATION_BYTES:
        raise FieldError(field, f"{name}: {max(len(data), size or 0):,} bytes is not a calibration file (afmforce calibrate "
                                f"--out writes about 1 kB; at most {CALIBRATION_BYTES:,} accepted)")
    try:
        values = parse_calibration(data.decode("utf-8"), name)
    except UnicodeDecodeError:
        raise FieldError(field, f"{name}: not a calibration file (not UTF-8 text; afmforce calibrate ... "
                                "--out FILE writes one)") from None
    except AfmforceError as exc:     # a value out of its range (named "<file>: <key> ..."): the key's field
        key = next((k for k in PROBE_KEYS if str(exc).startswith(f"{name}: {k} ") and "out of range" in str(exc)), None)
        raise FieldError(f"{field}.{key}" if key else field, str(exc)) from None
    specs = {f.name: spec_of(f) for f in dataclasses.fields(ProbeCalibration)}
    return {k: number(values[k], specs[k], k, f"{field}.{k}") for k in ANALYSIS_KEYS if k in values}


def _strings(items: Any, field: str) -> list[str]:
    if not isinstance(items, list) or len(items) > MAX_ITEMS:
        raise FieldError(field, f"{field} expects a list of at most {MAX_ITEMS} texts")
    for i, item in enumerate(items):
        if not isinstance(item, str) or len(item) > 200:
            raise FieldError(f"{field}[{i}]", f"{field}[{i}] expects a text NAME=VALUE, got {_shown(item)}")
    return items


def _grid_count(item: str) -> int | None:
    """How many values the grid item ``NAME=...`` asks for, read without making them (None: the
    item is malformed, and the sweep's parser says why)."""
    _, sep, rest = item.partition("=")
    if not sep:
        return None
    if "," in rest or ":" not in rest:
        return sum(1 for v in rest.split(",") if v.strip())
    parts = rest.split(":")
    if parts[-1].strip().lower() in ("log", "lin"):
        parts.pop()
    try:
        return int(parts[2]) if len(parts) == 3 else None
    except ValueError:
        return None


def sweep_spec(grid: Any, ranges: Any, sets: Any, *, sample=None, n=None, seed=None):
    """The :class:`~afmforce.sweep.SweepSpec` of a request, checked before any process starts: at
    most :data:`~.limits.MAX_RUNS` runs (counted before a grid is made), every value of every
    parameter in its declared range, every run's cycle at most :data:`~.limits.MAX_SAMPLES` samples."""
    from ..sweep import build_spec
    from ..sweep.simulation import simulation_dimensions

    grid, ranges, sets = _strings(grid, "grid"), _strings(ranges, "ranges"), _strings(sets, "sets")
    total = 1
    for i, item in enumerate(grid):
        count = _grid_count(item)
        if count is not None:
            if count > MAX_RUNS:
                raise FieldError(f"grid[{i}]", f"grid {item.partition('=')[0]} asks for {count:,} values; a "
                                 f"sweep in the web page runs at most {MAX_RUNS:,} (afmforce sweep runs more)")
            total *= max(count, 1)
    if total > MAX_RUNS:
        raise FieldError("grid", f"the grid has {total:,} points; a sweep in the web page runs at most "
                                 f"{MAX_RUNS:,} (afmforce sweep runs more)")
    from ..sweep.spec import parse_grid, parse_range, parse_setting

    dims = simulation_dimensions()
    for key, items, parse in (("grid", grid, parse_grid), ("ranges", ranges, parse_range),
                              ("sets", sets, parse_setting)):
        for i, item in enumerate(items):     # each item on its own: the error names it
            try:
                parse(item, dims)
            except ParameterError as exc:
                raise FieldError(f"{key}[{i}]", str(exc).replace(f"`{key}`", f"{key}[{i}]")) from None
    try:
        spec = build_spec(grid, ranges, sets, sample=sample, n=n, seed=seed, dimensions=dims)
    except FieldError:
        raise
    except ParameterError as exc:     # nothing to sweep, a name twice: the request field it names
        named = [k for k in exc.keys if k in ("grid", "ranges", "sets", "sample", "n", "seed")]
        raise FieldError(named[0] if named else "grid", str(exc)) from None
    if spec.n_runs > MAX_RUNS:
        raise FieldError("n", f"the sweep has {spec.n_runs:,} runs; the web page runs at most {MAX_RUNS:,}")
    fixed = {}
    for i, (name, value) in enumerate(spec.fixed):
        fixed.update(_item(f"sets[{i}]", {name: value}))
    values: dict[str, list] = {}
    for i, axis in enumerate(spec.grid):
        for v in axis.values:
            _item(f"grid[{i}]", {**fixed, axis.name: v})
        values[axis.name] = list(axis.values)
    for i, rng in enumerate(spec.ranges):
        for v in (rng.lo, rng.hi):
            _item(f"ranges[{i}]", {**fixed, rng.name: v})
        values[rng.name] = [rng.lo, rng.hi]
    _check_samples(fixed, values)
    from ..sweep.simulation import check_runs
    try:
        check_runs(spec)
    except ParameterError as exc:      # the field(s) that cause it: settings, grid axes or ranges
        causes = getattr(exc, "causes", None) or [("sets", None, None)]
        fields = ", ".join(kind if i is None else f"{kind}[{i}]" for kind, i, _ in causes)
        raise FieldError(fields, str(exc)) from None
    return spec


def _item(field: str, flat: dict[str, Any]) -> dict[str, Any]:
    try:
        return flat_config(flat)
    except FieldError as exc:
        raise FieldError(field, f"{field}: {exc}") from None


_DRIVE = ("velocity", "retract_velocity", "start", "turn", "end", "dwell", "sample_rate")


def _check_samples(fixed: dict[str, Any], values: dict[str, Iterable]) -> None:
    """Every run's cycle within :data:`~.limits.MAX_SAMPLES` samples: the count is monotonic in each
    drive value, so the extremes of each swept one bound it."""
    from ..dynamics import SimulationConfig

    swept = {k: sorted({min(v), max(v)}) for k, v in values.items() if k in _DRIVE}
    names = list(swept)
    base = {k: v for k, v in fixed.items()}
    if "model" in values:
        base.pop("model", None)
    for combo in product(*(swept[k] for k in names)):
        n = _samples_of({**base, **dict(zip(names, combo))})
        if n is None:
            continue            # an impossible combination fails as that run, not the request
        if not math.isfinite(n) or n > MAX_SAMPLES:
            raise _too_many(n, "grid")
