"""The analysis behind ``POST /api/analyze``: the same batch code and JSON as
``afmforce analyze FILE --json`` (:func:`afmforce.sweep.report.analysis_json`), plus, for
the page, per-sample arrays, the raw signal and force-map images with axes in µm."""

from __future__ import annotations

import dataclasses
import json
import re
import threading
import time
from collections import OrderedDict
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np

from .._fields import spec_of
from ..errors import ParameterError
from .limits import ANALYSIS_CURVES, ANALYSIS_POINTS
from .replies import PastBudget
from .plotdata import raw_arrays
from .tasks import decimate
from .validate import FieldError, metadata, number
from ..sweep.files import CurveAnalysis

__all__ = ["parse_inputs", "parse_choice", "parse_steps", "check_inputs", "run_analysis", "CachedAnalysis"]

#: Curves read lately: (path, size, mtime, curve index, metadata, format) -> [(index, RawCurve)],
#: at most :data:`_CURVES_KEPT` entries and :data:`_CACHE_BYTES` bytes (each cache here).
_CURVES: OrderedDict = OrderedDict()
_CURVES_KEPT = 4096
_CACHE_BYTES = 128e6
#: Rows of curves analysed lately: (curve key, options, probe, arrays) -> (summary row with its
#: JSON, (make the arrays, bytes held) or None).
_ROWS: OrderedDict = OrderedDict()
_ROWS_KEPT = 2048
_LOCK = threading.Lock()


class _Memo:
    """The sample steps' states of the curves analysed lately (``analyze(..., memo=)``), at most
    :data:`_CURVES_KEPT`: a calibration change re-runs the steps after them only."""

    def __init__(self) -> None:
        self._d: OrderedDict = OrderedDict()

    def get(self, key, default=None):
        return _recalled(self._d, key) or default

    def __setitem__(self, key, value) -> None:     # a state holds about a dozen arrays of the curve's length
        _remember(self._d, key, value, _CURVES_KEPT, lambda v: 12 * getattr(v[0][0], "nbytes", 0))


_MEMO = _Memo()
#: The modulus fit's per-sample lists (``details.indentation``), sent with the arrays only.
_FIT_SAMPLES = ("indentation", "fit_force", "residuals")
_FIT = "__fit_samples__"


def _nbytes(pairs) -> int:
    return sum(getattr(c.time, "nbytes", 0) * 5 for _, c in pairs)


_SIZES: dict = {}      # id(cache) -> {key: bytes} of the caches bounded in bytes


def _remember(cache: OrderedDict, key, value, kept: int, size=None) -> None:
    with _LOCK:
        cache[key] = value
        cache.move_to_end(key)
        sizes = _SIZES.setdefault(id(cache), {})
        if size is not None:
            sizes[key] = size(value)
        total = sum(sizes.values()) if size is not None else 0
        while len(cache) > kept or (size is not None and total > _CACHE_BYTES and len(cache) > 1):
            old, _ = cache.popitem(last=False)
            total -= sizes.pop(old, 0)


def _recalled(cache: OrderedDict, key):
    with _LOCK:
        if key in cache:
            cache.move_to_end(key)
            return cache[key]
    return None


@dataclass(frozen=True)
class CachedAnalysis(CurveAnalysis):
    """:class:`~afmforce.sweep.files.CurveAnalysis` for the page: what it read and computed lately
    stays in memory, and it sends the plots only what they draw.

    * A re-run does not parse the file again (a 10,000-row text file: 0.1-0.3 s), also after a
      calibration change: the curves are read with the file's own calibration and the given spring
      constant and sensitivity are put over them by the analysis (:mod:`afmforce.io.given`).
    * A curve analysed before with the same options, probe and metadata is not analysed again.
    * With :attr:`json_arrays`, the per-sample arrays are thinned to ``points`` samples per curve
      on the screen's terms (:func:`~.plotdata.result_arrays`) before they are written as JSON.
    """

    points: int | None = None
    #: the thinned arrays of the curves analysed by this instance, by row name (joined to the
    #: payload after :func:`~afmforce.sweep.report.analysis_json`: never through a JSON text)
    arrays: dict = dataclasses.field(default_factory=dict, compare=False, hash=False, repr=False)

    def _file_key(self, ref, override) -> tuple:
        path = Path(ref.location)
        st = path.stat()
        return (str(path), st.st_size, st.st_mtime_ns, ref.index,
                json.dumps(dict(override), sort_keys=True, default=repr), self.format)

    def _read(self, ref, override) -> list:
        key = self._file_key(ref, override)
        pairs = _recalled(_CURVES, key)
        if pairs is None:
            pairs = dataclasses.replace(self, meta_override=override).load_uncached(ref)
            _remember(_CURVES, key, pairs, _CURVES_KEPT, _nbytes)
        return pairs

    def load_uncached(self, ref):
        return super().load(ref)

    def load(self, ref):
        from ..io.given import reader_override

        # read with the file's own calibration, the probe's put over it by the analysis (afmforce.io.given):
        # a new spring constant or sensitivity reads nothing again
        return self._read(ref, reader_override(self.meta_override, self.probe))

    def analyze_curve(self, ref, index, curve, several):
        key = (self._file_key(ref, self.meta_override), index, several, self.channel,
               json.dumps(self.key_fields(), sort_keys=True, default=repr), self.points)
        hit = _recalled(_ROWS, key)
        if hit is None:
            self.arrays.pop(None, None)
            row = super().analyze_curve(ref, index, curve, several)
            hit = (row, self.arrays.pop(None, None))
            _remember(_ROWS, key, hit, _ROWS_KEPT,
                      lambda h: len(h[0].get("json") or "") + (h[1][1] if h[1] is not None else 0))
        row, arrays = hit
        if arrays is not None:
            self.arrays[row["name"]] = arrays
        return dict(row)

    def result_json(self, res) -> str:
        if not self.json_arrays:
            return res.to_json(indent=None, arrays=False)
        from .plotdata import result_arrays

        # kept aside (under None until the row has its name), made when sent: the arrays, and the
        # modulus fit's samples (most of a map curve's JSON, drawn for the curve shown only)
        out = res.to_dict(arrays=False)
        fit = (out.get("details") or {}).get("indentation")
        samples = {k: fit.pop(k) for k in _FIT_SAMPLES if isinstance(fit, dict) and isinstance(fit.get(k), list)}
        points = self.points
        held = sum(getattr(getattr(res, name), "nbytes", 0) for name in res.ARRAYS)
        self.arrays[None] = (lambda: {**result_arrays(res, points), _FIT: samples}, held)
        return json.dumps(out, allow_nan=False)


def _probe_fields() -> dict[str, Any]:
    """The probe record's fields and their specs (:class:`~afmforce.analysis.options.ProbeCalibration`)."""
    from ..analysis.options import ProbeCalibration

    return {f.name: spec_of(f) for f in dataclasses.fields(ProbeCalibration) if spec_of(f) is not None}


def parse_inputs(options: Sequence[str], meta: Sequence[str], probe: Sequence[str],
                 calibration: tuple | None = None):
    """``option`` (STEP.NAME=VALUE), ``meta`` (KEY=VALUE) and ``probe`` (NAME=VALUE) texts, values
    with units, -> (step option records, probe record, metadata override). ParameterError when bad.
    ``calibration``: ``(names, method, invols)`` of an uploaded probe calibration file, the ``probe``
    names whose values are its (:meth:`~afmforce.analysis.options.ProbeCalibration.from_calibration_file`,
    as ``--probe-calibration`` marks them); a ``meta`` probe value is marked as typed metadata."""
    from ..analysis.options import OPTIONS, ProbeCalibration
    from ..analysis.options_text import parse_option
    from ..analysis.pipeline import resolve_options

    given: dict[str, dict[str, Any]] = {}
    for text in options:
        try:
            step, name, value = parse_option(text, where="option")
        except ParameterError as exc:
            raise FieldError(f"option.{str(text).partition('=')[0].strip()[:60]}", str(exc)) from None
        if name in given.setdefault(step, {}):      # which one was meant: never the last silently
            raise FieldError(f"option.{step}.{name}", f"option {step}.{name} given twice")   # the CLI's words
        given[step][name] = value
    records = []
    for step, values in given.items():     # the record's own checks (a model of the registry, ...)
        try:
            records.append(OPTIONS[step](**values))
        except ParameterError as exc:
            named = [n for n in values if n in str(exc)] or list(values)
            raise FieldError(f"option.{step}.{named[0]}" if len(named) == 1 else f"option.{step}", str(exc)) from None
    records = tuple(records)
    values: dict[str, float] = {}
    fields = _probe_fields()
    for text in probe:
        key, sep, value = str(text).partition("=")
        key = key.strip()
        if not sep or key not in fields:
            raise FieldError("probe", f"probe {text[:60]!r}: expected NAME=VALUE with NAME one of {', '.join(fields)}")
        values[key] = number(value.strip(), fields[key], key, f"probe.{key}")
    probe_record = ProbeCalibration(**values)
    resolve_options(records, probe_record)
    typed = metadata(list(meta))
    override = typed   # the probe's values are the user's, never the file's metadata (afmforce.io.given)
    probe_record = probe_record.given_as_metadata(k for k in typed if k not in values)
    if calibration is not None and calibration[0]:
        names, method, invols = calibration
        probe_record = probe_record.from_calibration_file([n for n in names if n in values], method=method,
                                                          invols=invols)
    return records, probe_record, override


def parse_choice(name: str, value: str | None) -> str:
    """A word setting of :data:`afmforce._fields.ANALYSIS_CHOICES` (None: its default), or FieldError ``name``
    naming the choices."""
    from .._fields import ANALYSIS_CHOICES

    spec = ANALYSIS_CHOICES[name]
    if value is None:
        return spec.default
    try:
        return spec.check(value, name)
    except ParameterError as exc:
        raise FieldError(name, str(exc)) from None


def parse_steps(steps: Sequence[str] | None) -> tuple[str, ...] | None:
    """The steps asked for (None: all), checked against the registry (FieldError ``step[i]`` naming the
    unknown one and the choices)."""
    if not steps:
        return None
    from ..analysis.pipeline import resolve_steps

    out = tuple(str(s).strip() for s in steps)
    for i, name in enumerate(out):
        try:
            resolve_steps([name])
        except ParameterError as exc:
            raise FieldError(f"step[{i}]", str(exc)) from None
    return out


def check_inputs(options=(), meta=(), probe=(), *, calibration=None, steps: Sequence[str] | None = None,
                 format: str | None = None, channel: str | None = None):
    """Every value of an analysis request but its files, checked (FieldError naming the field):
    ``(channel, parse_inputs(...), parse_steps(steps))``. The route checks them before it stores
    an upload: a request refused for a typed option leaves nothing on the server's disk."""
    if format is not None:
        from ..io import FORMATS

        if format not in FORMATS:
            raise FieldError("format", f"format {format[:60]!r}: unknown; choose one of {', '.join(FORMATS)}")
    return parse_choice("channel", channel), parse_inputs(options, meta, probe, calibration), parse_steps(steps)


def run_analysis(files: Sequence[tuple[Path, str]], options=(), meta=(), probe=(), *, calibration=None,
                 steps: Sequence[str] | None = None, format: str | None = None, channel: str | None = None,
                 arrays: bool = False, max_points: int = 4000, budget: float = 60.0,
                 guard: bool = True, deadline: float | None = None,
                 curves: Sequence[str] = (), stop: Callable[[], bool] | None = None,
                 fields: Sequence[str] | None = None) -> dict[str, Any]:
    """Analyse stored files; ``files`` are ``(path on disk, name the user gave)``; ``steps``: the
    analysis steps to run (their requirements added; None: all).

    Returns the JSON of ``afmforce analyze --json`` with every stored name replaced by the
    user's; with ``arrays``: each result holds its per-sample arrays (at most ``max_points``
    samples, evenly spread), ``raw`` the raw signal per curve, ``maps`` the force maps.
    ``budget`` [s] bounds the reading of each file when ``guard`` (a file past it is reported as
    failed; the reader runs in a forked child, :mod:`afmforce.io._guard`); files read before
    without failing are read here directly (``guard=False``). Past ``deadline`` (``time.monotonic``)
    the analysis stops after the curve it is on (:class:`~.replies.PastBudget`): a request that
    timed out does not keep computing; so it does once ``stop()`` is true (its client left,
    :func:`~.compute.compute`). With ``arrays``, the curves together carry at most
    :data:`~.limits.ANALYSIS_POINTS` samples (``max_points`` is lowered for many curves).
    ``curves``: with ``arrays``, only these results (names as returned) get their arrays and raw
    signal, the first result when none of them is one (a page draws one curve of a map; the
    others are asked for when shown); empty: every result. ``arrays_for`` lists those sent.
    ``calibration``: ``(names, method, invols)`` of a probe calibration file (:func:`parse_inputs`).
    ``fields``: how the request names each file (``file[0]``, ``file_id[1]``, ``example[0]``): files
    holding more than :data:`~.limits.ANALYSIS_CURVES` curves together are refused naming it (FieldError,
    before any curve is read). ``channel``: the position channel, as ``--channel`` (:data:`afmforce._fields.ANALYSIS_CHOICES`;
    None: its default).
    """
    from ..sweep.files import TooManyCurves, analyze_files, plan_curves
    from ..sweep.report import analysis_json
    from ..sweep.summary import summary_table

    channel, (records, probe_record, override), chosen = check_inputs(options, meta, probe, calibration=calibration,
                                                                       steps=steps, format=format, channel=channel)
    t0 = time.perf_counter()
    rename = {str(p): name for p, name in files}        # full stored paths first, then bare names
    rename.update({Path(p).name: name for p, name in files})
    rename.update(_channel_prefixes(files))
    timeout = budget if guard else None
    try:        # a map's curves counted from its header: never a work item per declared curve past the cap
        refs = plan_curves([p for p, _ in files], format, timeout=timeout, max_curves=ANALYSIS_CURVES)
    except TooManyCurves as exc:
        where = [str(p) for p, _ in files].index(exc.path)
        field = fields[where] if fields is not None and where < len(fields) else "file"
        raise FieldError(field, f"{field} {files[where][1][:80]!r}: {exc.declared:,} curves"
                         + (f" ({exc.total:,} with the files before it)" if exc.total > exc.declared else "")
                         + f", more than the {ANALYSIS_CURVES:,} one request analyses (afmforce.limits."
                         "SERVER_MAX_CURVES); analyse it with `afmforce analyze` (it streams a map curve by "
                         "curve), or send fewer files") from None
    if arrays and not curves:     # the response's size cap
        max_points = max(10, min(max_points, ANALYSIS_POINTS // max(1, len(refs))))
    analysis = CachedAnalysis(steps=chosen, options=records, probe=probe_record, meta_override=override,
                             format=format, channel=channel, keep_json=True, json_arrays=arrays, file_timeout=timeout,
                             points=max_points if arrays else None, memo=_MEMO)

    def on_curve(_progress) -> None:
        if deadline is not None and time.monotonic() > deadline:
            raise PastBudget(f"cancelled: the analysis ran past its budget of {budget:g} s")
        if stop is not None and stop():
            raise PastBudget("cancelled: the request ended before the analysis (its client left)")

    # chunks of up to 32 curves: each chunk is a table (a curve a chunk cost 1-2 s of pandas for a
    # 16 x 16 map); the budget is checked between chunks (a chunk: well under a second)
    chunk = min(32, max(1, len(refs) // 8))
    result = analyze_files(refs, analysis, chunk_size=chunk, executor="serial", progress=on_curve)
    table = summary_table(result, with_json=True)
    payload = analysis_json(result, table)
    made = {name: analysis.arrays[name] for name in payload["results"] if name in analysis.arrays}
    payload = _renamed(payload, rename)
    made = {_renamed_name(name, rename): v for name, v in made.items()}
    wanted = list(payload["results"])
    if arrays and curves:
        wanted = [n for n in wanted if n in set(curves)] or wanted[:1]
    if arrays:
        for name in wanted:
            if name in made:
                extra = made[name][0]()
                samples = extra.pop(_FIT, {})
                payload["results"][name].update(extra)
                if samples:
                    payload["results"][name]["details"]["indentation"].update(samples)
        for name, res in payload["results"].items():     # the per-sample arrays are thinned already
            fit = (res.get("details") or {}).get("indentation")
            if isinstance(fit, dict) and isinstance(fit.get("indentation"), list):   # the modulus fit's samples
                keep = decimate(len(fit["indentation"]), max_points)
                for key in ("indentation", "fit_force", "residuals"):
                    if isinstance(fit.get(key), list):
                        fit[key] = [fit[key][i] for i in keep]
        from dataclasses import replace

        direct = replace(analysis, file_timeout=None)   # read once already, in this call
        payload["raw"] = _raw_signals(refs, direct, rename, max_points, set(wanted))
        payload["arrays_for"] = wanted
        # a map file read curve by curve (refs with an index), or one read whole whose curves record positions
        # off any grid (a Park file's spectra at free points: map_points), as the CLI maps them
        maps = any(r.index is not None for r in refs) or table["file"].duplicated().any()
        payload["maps"] = _maps(table, rename) if maps else []
    payload["wall_time"] = time.perf_counter() - t0
    payload["max_points"] = max_points if arrays else None
    return payload


def _channel_prefixes(files: Sequence[tuple[Path, str]]) -> dict[str, str]:
    """The stored prefix of each uploaded one-channel Asylum wave -> the user's prefix
    (:func:`afmforce.web.sessions.channel_name`): a message naming the partner wave names it as
    the user does (``Map1Point0000ZSnsr.ibw``), never by its stored name."""
    out = {}
    for p, name in files:
        stored = Path(p).name
        if re.fullmatch(r"[0-9a-f]{32}[A-Za-z]+\.ibw", stored) and name.endswith(stored[32:]):
            out.setdefault(stored[:32], name[: -len(stored[32:])])
    return out


def _renamed(payload: dict[str, Any], rename: dict[str, str]) -> dict[str, Any]:
    def fix(text: str) -> str:
        for stored, name in rename.items():   # full paths first (dict order)
            text = text.replace(stored, name)
        return text

    results = {}
    for key, res in payload["results"].items():
        res["source"] = fix(str(res.get("source", "")))
        results[fix(key)] = res
    payload["results"] = results
    for entry in payload["failed"]:
        entry["file"] = fix(Path(entry["file"]).name)
        entry["error"] = fix(entry["error"])
    return payload


def _renamed_name(name: str, rename: dict[str, str]) -> str:
    for stored, shown in rename.items():   # full paths first (dict order), as _renamed
        name = name.replace(stored, shown)
    return name


def _raw_signals(refs, analysis, rename, max_points, wanted) -> dict[str, Any]:
    out = {}
    for ref in refs:
        base = rename.get(Path(ref.path).name, Path(ref.path).name)
        if ref.index is not None and f"{base}#{ref.index}" not in wanted:
            continue        # a map's curve not drawn: not even looked up
        try:
            pairs = analysis.load(ref)
        except Exception:  # the failure is in payload["failed"] already
            continue
        several = ref.index is not None or len(pairs) > 1
        for index, curve in pairs:
            name = f"{base}#{index}" if several else base
            if name not in wanted:
                continue
            # the same signal read before (a calibration changes the metadata, not the samples)
            key = (id(curve.deflection_signal), max_points)
            raw = _recalled(_RAW, key)
            if raw is None or raw[0] is not curve.deflection_signal:
                raw = (curve.deflection_signal, raw_arrays(curve, max_points))
                _remember(_RAW, key, raw, _CURVES_KEPT)
            out[name] = raw[1]
    return out


#: The thinned raw signals of the cached curves: (id of the signal, points) -> (signal, arrays).
_RAW: OrderedDict = OrderedDict()


def _maps(table, rename) -> list[dict[str, Any]]:
    """The force maps' images (:func:`afmforce.analysis.maps.map_images`: axes in µm from the curves'
    stage positions, else the scanned area's size; grid indices when neither is known; ``layout`` ``grid``)
    and the maps whose positions form no grid (:func:`~afmforce.analysis.maps.map_points`, ``layout``
    ``points``: ``x_um``, ``y_um``, ``z`` and ``curves`` one entry per curve, ``why`` no grid), drawn as a
    scatter at the recorded positions as the CLI's PNG."""
    from ..analysis.maps import DEFAULT_MAPS, MAP_QUANTITIES, map_images, map_points

    out = []
    for q in DEFAULT_MAPS:
        for image in map_images(table, MAP_QUANTITIES[q]):
            rows = table[table["file"] == image.source]
            name = rename.get(Path(image.source).name, image.name)
            ny, nx = image.shape
            names = [[None] * nx for _ in range(ny)]
            for _, r in rows.iterrows():
                if 0 <= r["map_x"] < nx and 0 <= r["map_y"] < ny:
                    names[int(r["map_y"])][int(r["map_x"])] = f"{name}#{int(r['curve'])}"
            x = [(image.x0 + i * image.dx) * 1e6 for i in range(nx)] if image.has_positions else None
            y = [(image.y0 + j * image.dy) * 1e6 for j in range(ny)] if image.has_positions else None
            z = [[None if not np.isfinite(v) else float(v) for v in row] for row in image.values]
            out.append({"file": name, "quantity": q, "label": image.quantity.label, "unit": image.quantity.unit,
                        "layout": "grid", "z": z, "x_um": x, "y_um": y, "axes": "um" if x is not None else "index",
                        "curves": names, "note": image.note})
        for pts in map_points(table, MAP_QUANTITIES[q]):
            name = rename.get(Path(pts.source).name, Path(pts.source).name)
            out.append({"file": name, "quantity": q, "label": pts.quantity.label, "unit": pts.quantity.unit,
                        "layout": "points", "z": [float(v) if np.isfinite(v) else None for v in pts.values],
                        "x_um": [float(v) * 1e6 for v in pts.x], "y_um": [float(v) * 1e6 for v in pts.y],
                        "axes": "um", "curves": [f"{name}#{int(c)}" if c >= 0 else None for c in pts.curves],
                        "note": pts.note, "why": pts.why})
    return out
