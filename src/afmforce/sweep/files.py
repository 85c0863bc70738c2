"""The analysis of many force-curve files and force maps: the pipeline over each curve, in chunks.

The work is split into items: one per curve of a force map (an afmforce map
file, or a JPK ``.jpk-force-map``/``.jpk-qi-data``, whose curves can be
counted without reading them), one per other file (all its curves).
:func:`analyze_files` runs :class:`CurveAnalysis` over the items with
:func:`~afmforce.sweep.run_batch`: chunks of curves, in this process or on
Dask, stored as they finish (resumable), failures recorded with the curve's
name. Each curve gives one summary row (:data:`SUMMARY_COLUMNS`, SI units in
:data:`SUMMARY_UNITS`); :func:`write_summary` streams them into one Parquet
and one CSV table.

>>> from afmforce.sweep.files import CurveAnalysis, analyze_files, summary_table
>>> result = analyze_files(["map.h5", "a.ibw"], CurveAnalysis(steps=("jumps",)),
...                        executor="serial", store="results")     # doctest: +SKIP
>>> summary_table(result)                                          # doctest: +SKIP
"""

from __future__ import annotations

import glob
import hashlib
import json
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterable, Mapping

from .._files import atomic_path, atomic_write_text, display_path
from ..errors import AfmforceError, FileFormatError, OutputExistsError, ParameterError
from ..limits import BATCH_MAX_CURVES
from .batch import error_record, run_batch
from .results import BatchResult
from .summary import SUMMARY_COLUMNS, SUMMARY_UNITS, failures, summary_row, summary_table, write_summary

__all__ = ["CurveRef", "CurveAnalysis", "plan_curves", "TooManyCurves", "analyze_files", "analysis_key", "summary_row",
           "summary_table", "write_summary", "failures", "SUMMARY_COLUMNS", "SUMMARY_UNITS", "OUTPUT_SUFFIX"]

#: Per-curve output files: ``<name><OUTPUT_SUFFIX>.{json,csv,png}``.
OUTPUT_SUFFIX = ".afmforce"
_MAP_SUFFIXES = (".jpk-force-map", ".jpk-qi-data")


@dataclass(frozen=True)
class CurveRef:
    """One work item: a curve of a file (``index``), or every curve of it (``index`` None).

    Attributes
    ----------
    path : str
        As given (shown in messages); workers read :attr:`location`.
    index : int or None
        Position of the curve in the file.
    format : str or None
        Reader identifier found when planning (None: detect when loading).
    """

    path: str
    index: int | None = None
    format: str | None = None

    @property
    def location(self) -> Path:
        """The absolute path (workers may run in another folder)."""
        return Path(self.path).absolute()

    @property
    def label(self) -> str:
        """``path`` or ``path#index``: the name a failure is reported under."""
        return self.path if self.index is None else f"{self.path}#{self.index}"


def _count_curves(path: Path, fmt) -> int | None:
    """Curves in a multi-curve file, counted without reading them (None: not a map, or unknown)."""
    if fmt.identifier == "afmforce-map":
        from ..io.native.rawmap import map_info

        return map_info(path).n_curves
    if fmt.identifier in ("jpk-force", "jpk-zip") and path.name.lower().endswith(_MAP_SUFFIXES):
        from ..io.map_curves import open_map  # the curves the workers read (the zip's directory only)

        reader = open_map(path, fmt.identifier)
        try:
            return len(reader)
        finally:
            reader.close()
    if fmt.identifier == "bruker-nanoscope":  # a force volume: its grid, from the header alone
        from ..io.nanoscope import count_curves

        return count_curves(path)
    if fmt.identifier == "nanosurf-nid":  # a spectroscopy map: its grid, from the header alone
        from ..io.nanosurf import count_curves as nid_curves

        return nid_curves(path)
    if fmt.identifier == "asylum-ardf":  # a force map: its line table, from the headers alone
        from ..io.ardf import count_curves as count_ardf

        return count_ardf(path)
    return None


def _plan_one(path: Path, format: str | None) -> tuple[str, int | None]:
    from ..io import FORMATS, find_format

    fmt = FORMATS[format] if format else find_format(path)
    return fmt.identifier, _count_curves(path, fmt)


class TooManyCurves(ParameterError):
    """The files hold more curves than the caller takes (``max_curves``); ``path`` is the file that passed
    it, ``declared`` its curves, ``total`` the curves of the files up to it."""

    def __init__(self, message: str, path: str, declared: int, total: int):
        super().__init__(message)
        self.path, self.declared, self.total = path, declared, total


def plan_curves(paths: Iterable[str | os.PathLike], format: str | None = None,
                timeout: float | None = None, on_file: Callable[[], None] | None = None,
                max_curves: int | None = BATCH_MAX_CURVES) -> list[CurveRef]:
    """Work items for ``paths``: one per curve of a force map, one per other file.

    Never raises for a bad file: it becomes one item, whose analysis reports the error.
    ``timeout`` [s] bounds the detection of each file (see :func:`afmforce.io.load`);
    ``on_file()`` is called after each file (a progress bar). ``max_curves``: the most items taken,
    counted from the maps' headers before any item is made (:class:`TooManyCurves` past it; default
    :data:`afmforce.limits.BATCH_MAX_CURVES`, None: no cap).
    """
    from ..io import run_with_timeout

    refs: list[CurveRef] = []
    for p in paths:
        path = Path(p)
        n, ident = None, format
        try:
            ident, n = run_with_timeout(_plan_one, path, format, timeout=timeout, path=str(path))
        except Exception:  # unreadable, unknown, damaged, too slow: analysed (and reported) as a whole file
            pass
        if max_curves is not None and len(refs) + (n or 1) > max_curves:
            raise TooManyCurves(f"{path}: {n or 1:,} curves (read from its header)"
                                + (f", {len(refs) + (n or 1):,} with the files before it" if refs else "")
                                + f", more than the {max_curves:,} taken", str(path), n or 1, len(refs) + (n or 1))
        if n:
            refs.extend(CurveRef(str(path), i, ident) for i in range(n))
        else:
            refs.append(CurveRef(str(path), None, ident))
        if on_file is not None:
            on_file()
    return refs


# One open file per worker process, reused by consecutive items of the same file:
# an afmforce map reader, or the curves of a multi-curve vendor file read whole.
_OPEN: dict[str, Any] = {}


def _identity(path: Path, *extra) -> tuple:
    st = path.stat()
    return (str(path.resolve()), st.st_size, st.st_mtime_ns, *extra)


def _map_reader(path: Path, format: str = "afmforce-map", meta: Mapping[str, Any] | None = None):
    """The worker's open map (:func:`afmforce.io.map_curves.open_map`): its curves read one at a time."""
    from ..io.map_curves import open_map

    ident = _identity(path, "map", format, json.dumps(dict(meta or {}), sort_keys=True, default=repr))
    if _OPEN.get("id") != ident:
        _close_open()
        _OPEN.update(id=ident, value=open_map(path, format, meta))
    return _OPEN["value"]


def _load_cached(path: Path, meta: Mapping[str, Any], format: str | None, timeout: float | None = None) -> list:
    from ..io import load

    ident = _identity(path, json.dumps(dict(meta), sort_keys=True), format)
    if _OPEN.get("id") != ident:
        _close_open()
        _OPEN.update(id=ident, value=load(path, meta_override=meta, format=format, timeout=timeout))
    return _OPEN["value"]


def _close_open() -> None:
    value = _OPEN.pop("value", None)
    _OPEN.clear()
    if hasattr(value, "close"):
        value.close()


@dataclass(frozen=True)
class CurveAnalysis:
    """The function a batch runs on each item: load, :func:`~afmforce.analysis.pipeline.analyze`, summarise.

    Picklable (Dask workers run it). Returns one summary row per curve of the
    item; an item that cannot be read, or whose one curve cannot be analysed,
    raises, and the batch records the error under the item's name. Of an item of
    several curves (a file read whole), a curve that fails gives its own error row
    (``error``, ``error_type``, ``traceback``) and every other curve's row is kept.

    Attributes
    ----------
    steps : tuple of str or None
        Analysis steps (None: all).
    options : tuple of StepOptions
        Options records of the steps (:mod:`afmforce.analysis.options`; the registry's
        defaults for the others).
    probe : ProbeCalibration or None
        The user's probe record (radius, spring constant, theta0, sensitivity, ...).
    meta_override : mapping
        Metadata replacing the files' (``spring_constant`` [N/m], ``sensitivity`` [m/V]).
    format : str or None
        Reader identifier (None: detect).
    channel : str
        Position channel.
    keep_json : bool
        Add each full result as JSON (column ``json``).
    json_arrays : bool
        With ``keep_json``: the JSON holds the per-sample arrays too (time, position,
        separation, deflection, force, segment; what the web page draws).
    out : str or None
        Folder for per-curve outputs (``<name>.afmforce.json/.csv/.png``); None: none.
    force : bool
        Recompute every curve and overwrite its outputs (otherwise a curve whose outputs are complete
        is skipped: its summary row is read back from its JSON).
    plot : bool
        Write the per-curve figure.
    protect : tuple of str
        Resolved input paths that per-curve outputs must never replace.
    file_timeout : float or None
        Time budget [s] for reading one file (None: no limit); a file past it fails alone.
    """

    steps: tuple[str, ...] | None = None
    options: Any = ()
    probe: Any = None
    meta_override: Mapping[str, Any] = field(default_factory=dict)
    format: str | None = None
    channel: str = "auto"
    keep_json: bool = False
    json_arrays: bool = False
    out: str | None = None
    force: bool = False
    plot: bool = True
    protect: tuple[str, ...] = ()
    file_timeout: float | None = None
    #: kept state of the sample steps (``analyze(..., memo=)``): a re-run after a calibration change
    #: starts after them; None: none (it does not travel to workers)
    memo: Any = field(default=None, compare=False, repr=False)

    def key_fields(self) -> dict[str, Any]:
        """What determines the results (and so the store they resume from)."""
        opts = self.options
        if not isinstance(opts, Mapping):  # records: {step: {option: value}} (SI), as the JSON shows them
            opts = {o.step: o.to_dict() for o in opts}
        probe = self.probe.given() if self.probe is not None else {}
        origins = self.probe.origins() if self.probe is not None else {}   # the warnings' words, a thermal k
        return {"steps": self.steps, "options": opts, "probe": probe, "meta": self.meta_override,
                "format": self.format, "channel": self.channel, "json": self.keep_json,
                **({"json_arrays": True} if self.json_arrays else {}), **({"origins": origins} if origins else {})}

    def _load_own(self, path, cached: bool = False) -> list:
        """The file's curves read with its own calibration (:func:`afmforce.io.given.read_own`: the user's
        spring constant and sensitivity are the probe's, put over each curve by the analysis,
        :func:`afmforce.io.given.apply_given`); a file that cannot be read without them gets them."""
        from ..io import load
        from ..io.given import read_own

        if cached:
            return read_own(lambda meta: _load_cached(path, meta, self.format, self.file_timeout),
                            self.meta_override, self.probe)
        return read_own(lambda meta: load(path, meta_override=meta, format=self.format, timeout=self.file_timeout),
                        self.meta_override, self.probe)

    def load(self, ref: CurveRef) -> list[tuple[int, Any]]:
        """``(index in the file, RawCurve)`` of the item's curves, as read (the file's own calibration)."""
        from ..io import check_meta_override
        from ..io.given import read_own
        from ..io.map_curves import STREAMED_FORMATS

        path = ref.location
        if ref.index is None:
            return list(enumerate(self._load_own(path)))
        if ref.format in STREAMED_FORMATS:  # a force map: this curve alone, from the worker's open map
            curve = read_own(lambda meta: _map_reader(path, ref.format, check_meta_override(meta)).read(ref.index),
                             self.meta_override, self.probe)
            return [(ref.index, curve)]
        curves = self._load_own(path, cached=True)
        if not 0 <= ref.index < len(curves):
            raise FileFormatError(f"{path}: no curve {ref.index} (the file holds {len(curves)})")
        return [(ref.index, curves[ref.index])]

    def __call__(self, ref: CurveRef) -> list[dict[str, Any]]:
        pairs = self.load(ref)
        several = ref.index is not None or len(pairs) > 1
        base = Path(ref.path).name
        rows = []
        for index, curve in pairs:
            if len(pairs) == 1 and ref.index is None:  # the item is this file's one curve: its failure is the item's
                rows.append(self.analyze_curve(ref, index, curve, several))
                continue
            if len(pairs) == 1:   # a map's curve: refused, it keeps its place (a blank pixel, the reason beside it)
                try:
                    rows.append(self.analyze_curve(ref, index, curve, several))
                except AfmforceError as exc:
                    if isinstance(exc, OutputExistsError):
                        raise
                    from .summary import pixel_place

                    rows.append({**pixel_place(curve.metadata, display_path(ref.path), int(index)),
                                 "name": f"{display_path(base)}#{index}", **error_record(exc)})
                continue
            try:  # one of a file's many curves: its failure is its own row, the others are kept
                rows.append(self.analyze_curve(ref, index, curve, several))
            except OutputExistsError:
                raise
            except Exception as exc:
                rows.append({"name": f"{display_path(base)}#{index}", "file": display_path(ref.path), "curve": int(index), **error_record(exc)})
        return rows

    def analyze_curve(self, ref: CurveRef, index: int, curve, several: bool) -> dict[str, Any]:
        """The summary row of one curve of the item (its outputs written, or read back when complete)."""
        from ..analysis.pipeline import analyze

        base = Path(ref.path).name
        stem = f"{base}_{index:04d}" if several else base
        if self.out is not None and not self.force:
            row = self.finished(stem)
            if row is not None:  # a rerun resumes: this curve's outputs are complete
                return row
            if self.foreign(stem):
                raise OutputExistsError(
                    f"{self._paths(stem)['json']} holds another analysis (other steps, options or "
                    "metadata); choose another `out`, or pass `force` to replace it")
        res = analyze(curve, steps=self.steps, options=self.options or None, probe=self.probe,
                      channel=self.channel, memo=self.memo)
        shown = display_path(base)      # a file name that is not UTF-8: \xNN in the tables
        row = summary_row(res, curve, file=display_path(ref.path), index=index,
                          name=f"{shown}#{index}" if several else shown)
        if self.keep_json:
            row["json"] = self.result_json(res)
        if self.out is not None:
            self.write_outputs(res, curve, stem, row)
        return row

    def result_json(self, res) -> str:
        """The ``json`` column of a curve's row (with ``keep_json``): the result's JSON, with the
        per-sample arrays when :attr:`json_arrays` (a subclass may send less: the web's plots)."""
        return res.to_json(indent=None, arrays=self.json_arrays)

    def _settings(self) -> str:
        fields = {k: v for k, v in self.key_fields().items() if k != "json"}
        return json.dumps(fields, sort_keys=True, default=repr)

    def _paths(self, stem: str) -> dict[str, Path]:
        paths = {ext: Path(self.out) / f"{stem}{OUTPUT_SUFFIX}.{ext}" for ext in ("json", "csv", "png")}
        if not self.plot:
            paths.pop("png")
        return paths

    def foreign(self, stem: str) -> bool:
        """Does :attr:`out` hold this curve's outputs of an analysis with other settings?"""
        path = self._paths(stem)["json"]
        if not path.exists():
            return False
        try:
            settings = json.loads(path.read_text()).get("analysis_settings")
        except (OSError, ValueError, AttributeError):
            return True  # not ours to replace silently
        return settings != self._settings()

    def clashes(self, refs: Iterable["CurveRef"]) -> list[Path]:
        """Outputs in :attr:`out` of an analysis of these items with other settings (checked before any
        work: a rerun with other options never replaces another run's files without ``force``)."""
        if self.out is None or self.force or not Path(self.out).is_dir():
            return []
        found = []
        for base in dict.fromkeys(Path(r.path).name for r in refs):
            for pattern in (f"{glob.escape(base)}{OUTPUT_SUFFIX}.json",
                            f"{glob.escape(base)}_[0-9][0-9][0-9][0-9]{OUTPUT_SUFFIX}.json"):
                found += [p for p in sorted(Path(self.out).glob(pattern))
                          if self.foreign(p.name[: -len(OUTPUT_SUFFIX + ".json")])]
        return found

    def finished(self, stem: str) -> dict[str, Any] | None:
        """The summary row stored with a curve's complete outputs (None: analyse it)."""
        paths = self._paths(stem)
        if not all(p.exists() for p in paths.values()):
            return None
        try:
            stored = json.loads(paths["json"].read_text())
            row = dict(stored.pop("summary_row"))
            settings = stored.pop("analysis_settings")
        except (OSError, ValueError, KeyError, TypeError):
            return None
        if settings != self._settings():  # written with other steps, options or metadata: recompute
            return None
        if self.keep_json:
            row["json"] = json.dumps(stored, allow_nan=False)
        return row

    def write_outputs(self, result, curve, stem: str, row: Mapping[str, Any] | None = None) -> dict[str, Path]:
        """Write ``<stem>.afmforce.{json,csv,png}`` into :attr:`out`, atomically (the JSON last: it marks
        the curve finished, with its summary row for a rerun)."""
        from .._json import to_jsonable

        paths = self._paths(stem)
        for path in paths.values():
            if str(path.resolve()) in self.protect:
                raise OutputExistsError(f"an output would replace an input file ({path}); choose another `out`")
        result.write_table(paths["csv"])
        if self.plot:
            from ..plotting import plot_summary

            fig = plot_summary(result, curve)
            with atomic_path(paths["png"]) as tmp:
                fig.savefig(tmp, dpi=100, format="png")
        payload = result.to_dict()
        if row is not None:
            payload["summary_row"] = to_jsonable({k: v for k, v in row.items() if k != "json"}, use_to_dict=False)
            payload["analysis_settings"] = self._settings()
        atomic_write_text(paths["json"], json.dumps(payload, indent=2, allow_nan=False))
        return paths


def analysis_key(refs: list[CurveRef], analysis: CurveAnalysis) -> str:
    """Hash of the analysis settings and of every item (file path, size, modification time, curve)."""
    h = hashlib.sha256(b"afmforce-analyze/1\n")
    h.update(json.dumps(analysis.key_fields(), sort_keys=True, default=repr).encode())
    stats: dict[str, str] = {}
    for ref in refs:
        if ref.path not in stats:
            path = Path(ref.path).resolve()
            st = path.stat() if path.exists() else None
            stats[ref.path] = f"{path}|{st.st_size if st else -1}|{st.st_mtime_ns if st else -1}"
        h.update(f"{stats[ref.path]}|{ref.index}\n".encode("utf-8", "surrogateescape"))
    return h.hexdigest()


#: Seconds to start a local cluster whose workers import the analysis (pandas, the pipeline, numba
#: kernels): measured about 6 s on the idle 2-core development machine (28 s at a load of 10).
ANALYSIS_CLUSTER_START = 8.0


def choose_executor(refs: list[CurveRef], analysis: CurveAnalysis, workers: int | None = None):
    """Where a batch runs fastest on this machine: ``(ExecutionPlan, workers of the cluster)``.

    Times the analysis of three items here (first, middle, last; outputs not written) and
    compares serial with a local cluster of the cores that are free now: ``available_cores``
    less the load average (other processes), at least one. On 2 busy cores that is serial
    (72 files at a load of 10: 32 s serial, 58 s on a 2-worker cluster; benchmarks/bench_executor.py).
    """
    import dataclasses
    from functools import partial

    from .._cores import available_cores
    from .autoplan import plan_execution

    from .autoplan import ExecutionPlan

    cores = workers or available_cores()
    try:
        load = os.getloadavg()[0]
    except (AttributeError, OSError):
        load = 0.0
    usable = max(1, min(cores, int(cores - load + 1.0)))  # this process's own core is ours
    if usable <= 1:
        return ExecutionPlan("serial", 1, None, None, None,
                             f"{cores} core(s), load {load:.1f}: no core free for a cluster"), 1
    probe = dataclasses.replace(analysis, out=None, keep_json=False)
    picks = sorted({0, len(refs) // 2, len(refs) - 1})
    plan = plan_execution([partial(probe, refs[i]) for i in picks], len(refs), usable,
                          cluster_start=ANALYSIS_CLUSTER_START)
    return plan, usable


def analyze_files(items: Iterable, analysis: CurveAnalysis | None = None, *, chunk_size: int | None = None,
                  executor=None, workers: int | None = None, scheduler: str | None = None, store=None,
                  progress: Callable | None = None, max_curves: int | None = BATCH_MAX_CURVES) -> BatchResult:
    """Analyse files (paths, planned with :func:`plan_curves`, at most ``max_curves`` curves) or
    :class:`CurveRef` items in chunks.

    Arguments as in :func:`~afmforce.sweep.run_batch` (default executor: a local
    Dask cluster; ``"serial"`` runs here). With ``store`` (a parent folder) the
    results go to ``<store>/batch-<hash>/`` chunk by chunk and a rerun with the
    same files and settings resumes; the hash is :func:`analysis_key`.
    """
    analysis = analysis or CurveAnalysis()
    items = list(items)
    refs = items if all(isinstance(i, CurveRef) for i in items) else plan_curves(items, analysis.format, max_curves=max_curves)
    key = analysis_key(refs, analysis) if store is not None else None
    try:
        return run_batch(refs, analysis, chunk_size=chunk_size, executor=executor, workers=workers,
                         scheduler=scheduler, store=store, key=key, progress=progress,
                         label=lambda ref, i: ref.label)
    finally:
        _close_open()  # what the serial executor opened in this process
