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
from typing import Any, Sequence

import numpy as np

from .._fields import spec_of
from ..errors import ParameterError
from .limits import ANALYSIS_POINTS
from .replies import PastBudget
from .tasks import decimate
from .validate import FieldError, metadata, number
from ..sweep.files import CurveAnalysis

__all__ = ["parse_inputs", "parse_steps", "run_analysis", "CachedAnalysis"]

#: Curves read lately: (path, size, mtime, curve index, metadata, format) -> [(index, RawCurve)].
_CURVES: OrderedDict = OrderedDict()
_CURVES_KEPT = 16
_LOCK = threading.Lock()


@dataclass(frozen=True)
class CachedAnalysis(CurveAnalysis):
    """:class:`~afmforce.sweep.files.CurveAnalysis` that keeps the last curves it read in memory:
    a re-run after an option change does not parse the file again (a 10,000-row text file: 0.3 s)."""

    def load(self, ref):
        path = Path(ref.location)
        st = path.stat()
        key = (str(path), st.st_size, st.st_mtime_ns, ref.index,
               json.dumps(dict(self.meta_override), sort_keys=True, default=repr), self.format)
        with _LOCK:
            if key in _CURVES:
                _CURVES.move_to_end(key)
                return _CURVES[key]
        pairs = super().load(ref)
        with _LOCK:
            _CURVES[key] = pairs
            while len(_CURVES) > _CURVES_KEPT:
                _CURVES.popitem(last=False)
        return pairs

def _probe_fields() -> dict[str, Any]:
    """The probe record's fields and their specs (:class:`~afmforce.analysis.options.ProbeCalibration`)."""
    from ..analysis.options import ProbeCalibration

    return {f.name: spec_of(f) for f in dataclasses.fields(ProbeCalibration) if spec_of(f) is not None}


def parse_inputs(options: Sequence[str], meta: Sequence[str], probe: Sequence[str]):
    """``option`` (STEP.NAME=VALUE), ``meta`` (KEY=VALUE) and ``probe`` (NAME=VALUE) texts, values
    with units, -> (step option records, probe record, metadata override). ParameterError when bad."""
    from ..analysis.options import OPTIONS, ProbeCalibration
    from ..analysis.options_text import parse_option
    from ..analysis.pipeline import resolve_options

    given: dict[str, dict[str, Any]] = {}
    for text in options:
        try:
            step, name, value = parse_option(text, where="option")
        except ParameterError as exc:
            raise FieldError(f"option.{str(text).partition('=')[0].strip()[:60]}", str(exc)) from None
        if name in given.setdefault(step, {}):
            raise ParameterError(f"option {step}.{name} given twice")
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
    override = {**metadata(list(meta)), **{k: values[k] for k in ("spring_constant", "sensitivity") if k in values}}
    return records, probe_record, override


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


def run_analysis(files: Sequence[tuple[Path, str]], options=(), meta=(), probe=(), *,
                 steps: Sequence[str] | None = None, format: str | None = None,
                 arrays: bool = False, max_points: int = 4000, budget: float = 60.0,
                 guard: bool = True, deadline: float | None = None) -> dict[str, Any]:
    """Analyse stored files; ``files`` are ``(path on disk, name the user gave)``; ``steps``: the
    analysis steps to run (their requirements added; None: all).

    Returns the JSON of ``afmforce analyze --json`` with every stored name replaced by the
    user's; with ``arrays``: each result holds its per-sample arrays (at most ``max_points``
    samples, evenly spread), ``raw`` the raw signal per curve, ``maps`` the force maps.
    ``budget`` [s] bounds the reading of each file when ``guard`` (a file past it is reported as
    failed; the reader runs in a forked child, :mod:`afmforce.io._guard`); files read before
    without failing are read here directly (``guard=False``). Past ``deadline`` (``time.monotonic``)
    the analysis stops after the curve it is on (:class:`~.replies.PastBudget`): a request that
    timed out does not keep computing. With ``arrays``, the curves together carry at most
    :data:`~.limits.ANALYSIS_POINTS` samples (``max_points`` is lowered for many curves).
    """
    from ..sweep.files import analyze_files, plan_curves
    from ..sweep.report import analysis_json
    from ..sweep.summary import summary_table

    if format is not None:
        from ..io import FORMATS

        if format not in FORMATS:
            raise ParameterError(f"format {format}: unknown; choose one of {', '.join(FORMATS)}")
    records, probe_record, override = parse_inputs(options, meta, probe)
    chosen = parse_steps(steps)
    t0 = time.perf_counter()
    rename = {str(p): name for p, name in files}        # full stored paths first, then bare names
    rename.update({Path(p).name: name for p, name in files})
    rename.update(_channel_prefixes(files))
    timeout = budget if guard else None
    refs = plan_curves([p for p, _ in files], format, timeout=timeout)
    if arrays:     # the response's size cap
        max_points = max(10, min(max_points, ANALYSIS_POINTS // max(1, len(refs))))
    analysis = CachedAnalysis(steps=chosen, options=records, probe=probe_record, meta_override=override,
                             format=format,
                             keep_json=True, json_arrays=arrays, file_timeout=timeout)

    def on_curve(_progress) -> None:
        if deadline is not None and time.monotonic() > deadline:
            raise PastBudget(f"cancelled: the analysis ran past its budget of {budget:g} s")

    result = analyze_files(refs, analysis, chunk_size=1, executor="serial", progress=on_curve)
    payload = analysis_json(result)
    payload = _renamed(payload, rename)
    if arrays:
        for res in payload["results"].values():
            idx = decimate(len(res.get("time") or ()), max_points)
            for key in ("time", "position", "separation", "deflection", "force", "segment"):
                if res.get(key) is not None:
                    res[key] = [res[key][i] for i in idx]
            fit = (res.get("details") or {}).get("indentation")
            if isinstance(fit, dict) and isinstance(fit.get("indentation"), list):   # the modulus fit's samples
                keep = decimate(len(fit["indentation"]), max_points)
                for key in ("indentation", "fit_force", "residuals"):
                    if isinstance(fit.get(key), list):
                        fit[key] = [fit[key][i] for i in keep]
        from dataclasses import replace

        direct = replace(analysis, file_timeout=None)   # read once already, in this call
        payload["raw"] = _raw_signals(refs, direct, rename, max_points)
        maps = any(r.index is not None for r in refs)
        payload["maps"] = _maps(summary_table(result), rename) if maps else []
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


def _raw_signals(refs, analysis, rename, max_points) -> dict[str, Any]:
    out = {}
    for ref in refs:
        try:
            pairs = analysis.load(ref)
        except Exception:  # the failure is in payload["failed"] already
            continue
        several = ref.index is not None or len(pairs) > 1
        base = rename.get(Path(ref.path).name, Path(ref.path).name)
        for index, curve in pairs:
            name = f"{base}#{index}" if several else base
            piezo = curve.position()
            idx = decimate(len(curve.time), max_points)
            out[name] = {"time": curve.time[idx].tolist(), "piezo": np.asarray(piezo)[idx].tolist(),
                         "signal": curve.deflection_signal[idx].tolist(), "segment": curve.segment[idx].tolist(),
                         "unit": curve.deflection_unit,
                         # False: the file has no time base, "time" is the sample index (the page says so)
                         "time_base": not curve.metadata.get("time_is_sample_index", False),
                         "position": [curve.metadata.get("position_x"), curve.metadata.get("position_y")]}
    return out


def _maps(table, rename) -> list[dict[str, Any]]:
    """The force maps' images (:func:`afmforce.analysis.maps.map_images`: axes in µm from the curves'
    stage positions, else the scanned area's size; grid indices when neither is known)."""
    from ..analysis.maps import MAP_QUANTITIES, map_images

    out = []
    for q in ("adhesion", "jump_in_distance", "hamaker_radius", "indentation"):
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
                        "z": z, "x_um": x, "y_um": y, "axes": "um" if x is not None else "index",
                        "curves": names})
    return out
