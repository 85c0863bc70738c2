"""Force maps at instrument speed: modulus, topography, adhesion and work of adhesion per pixel.

:class:`PixelAnalysis` is the map's per-curve work, about 1 ms a curve (issue 35): the
indentation fit of :func:`~afmforce.analysis.indentation.fast_modulus` (the file's calibration,
the tip depth, the contact point, E and the force baseline fitted together: nanite's work) and,
from the same calibrated curve, the adhesion (the retract's deepest point below the fitted
baseline) and the work of adhesion from it in closed form:

* ``dmt`` (default): ``w = F_ad / (2 pi R)`` (Derjaguin, Muller & Toporov 1975; stiff, small,
  weakly adhesive contacts, Tabor/Maugis lambda < 0.1);
* ``jkr``: ``w = 2 F_ad / (3 pi R)`` (Johnson, Kendall & Roberts 1971; soft, large, strongly
  adhesive contacts, lambda > 5).

The fitted work of adhesion (a JKR, DMT or Maugis fit of the whole retract, ``analyze`` with
``IndentationOptions(model="jkr", run="retract")``) costs 10 ms to 2 s a curve; the closed form
is what a map of 16,384 curves can afford. Nothing else of the pipeline runs (no smoothing,
drift line, contact kind, hard-contact check): for those, analyse the map with ``analyze``.

:func:`analyze_map` runs it over the curves of afmforce map files (or any force map) on the batch
engine: curves read one at a time by each worker, rows stored chunk by chunk (resumable), the
summary table with the map's grid columns, so that :func:`~afmforce.analysis.maps.map_images`
draws every quantity.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from typing import Any, Iterable

import numpy as np

from .summary import pixel_place
from ..analysis.registry import LiveDict
from ..analysis.indentation import fast_modulus
from ..analysis.options import IndentationOptions, ProbeCalibration
from ..errors import AfmforceError, AnalysisError, ParameterError

__all__ = ["PixelAnalysis", "ADHESION_MODELS", "PIXEL_COLUMNS", "analyze_map", "analyze_refs"]

#: Work of adhesion from the adhesion force F_ad and the tip radius R: model -> w / (F_ad / R).
ADHESION_MODELS: dict[str, float] = {"dmt": 1.0 / (2.0 * math.pi), "jkr": 2.0 / (3.0 * math.pi)}

_PIXEL_NAMES = ("youngs_modulus", "youngs_modulus_se", "youngs_modulus_low", "youngs_modulus_high", "contact_point",
                "contact_point_se", "max_indentation", "max_force", "adhesion_force", "adhesion_noise",
                "work_of_adhesion", "work_of_adhesion_se", "spring_constant", "sensitivity", "tip_radius",
                "position_x", "position_y")


def _pixel_columns() -> dict[str, str]:
    from .summary import column_unit

    return {name: column_unit(name) for name in _PIXEL_NAMES}


#: The numbers of each pixel's row, with their SI units: the full summary's (:func:`afmforce.sweep.summary.column_unit`,
#: declared once: the analysis steps' records, the indentation result's fields).
PIXEL_COLUMNS: dict[str, str] = LiveDict(_pixel_columns)
#: Each pixel's row also holds ``warnings``: the full analysis's column (:data:`afmforce.sweep.summary.SUMMARY_COLUMNS`),
#: its warnings joined by `` | `` (empty: none).


@dataclass(frozen=True)
class PixelAnalysis:
    """One map pixel: a picklable callable for the batch engine (``func(ref) -> row``).

    Parameters
    ----------
    indentation : IndentationOptions
        The indentation fit (model, tip radius, Poisson's ratio, run, ...).
    adhesion_model : str
        ``"dmt"`` or ``"jkr"``: the closed form giving the work of adhesion.
    probe : ProbeCalibration or None
        Spring constant [N/m], sensitivity [m/V], radius [m] given by the user (None: the file's).
    nsigma : float
        An adhesion under this many baseline-noise sigmas is reported as none (0) [-].
    meta_override : dict
        Metadata typed as the files' (``--meta``; SI), given to the readers; the probe's spring constant
        and sensitivity are the user's, put over each curve as ``analyze`` does (:mod:`afmforce.io.given`).
    channel : str
        Position channel (``"auto"``: measured if recorded; ``"measured"``, ``"nominal"``), as ``analyze``'s.
    """

    indentation: IndentationOptions = field(default_factory=IndentationOptions)
    adhesion_model: str = "dmt"
    probe: ProbeCalibration | None = None
    nsigma: float = 5.0
    meta_override: dict[str, Any] = field(default_factory=dict)
    channel: str = "auto"

    def __post_init__(self) -> None:
        if self.adhesion_model not in ADHESION_MODELS:
            raise ParameterError(f"adhesion_model = {self.adhesion_model!r}: choose one of "
                                 f"{', '.join(ADHESION_MODELS)}")
        if not (self.nsigma > 0):
            raise ParameterError(f"nsigma must be > 0, got {self.nsigma!r}")

    def __call__(self, ref) -> dict[str, Any]:
        """The row of one curve: a :class:`~afmforce.sweep.files.CurveRef` of a map, or a RawCurve."""
        from .files import CurveRef

        if isinstance(ref, CurveRef):
            curve, file, index = _read(ref, self.meta_override, self.probe), ref.path, int(ref.index or 0)
        else:
            curve, file, index = ref, str(ref.metadata.get("source_file", "")), -1
        try:
            return self.row(curve, file=file, index=index)
        except AfmforceError as exc:    # refused (no contact, bad calibration...): the pixel keeps its place
            from .batch import error_record

            return {**pixel_place(curve.metadata, file, index), **error_record(exc)}

    def row(self, curve, *, file: str = "", index: int = -1) -> dict[str, Any]:
        """The pixel's numbers (:data:`PIXEL_COLUMNS`) and its place in the map (raises what the fit
        raises; in a batch, :meth:`__call__` keeps a refused curve's place with its error: a blank pixel,
        the reason in the table)."""
        from ..io.given import apply_given

        p = self.probe if self.probe is not None else ProbeCalibration()
        curve = apply_given(curve, p)      # the user's calibration over the file's (afmforce.io.given)
        fit = fast_modulus(curve, self.indentation, p, self.channel)
        md = curve.metadata
        k = float(p.value("spring_constant", md))
        seg = np.asarray(curve.segment)
        sig = np.asarray(curve.deflection_signal, dtype=float)
        sens = float(p.value("sensitivity", md) or math.nan)  # reported also for a force the reader calibrated
        scale = curve.force_factor(sens, k)                    # uses the sensitivity for volts only
        z = curve.position(self.channel)
        force = sig * scale
        app, ret = seg == 0, seg == 1
        # the baseline's noise: the approach's free part, before the fitted contact (tip depth above it)
        free = app & (z - sig * scale / k < fit.contact_depth - 0.05 * max(fit.max_indentation, 0.0))
        resid = force[free] - fit.baseline
        noise = float(np.std(resid)) if resid.size >= 8 else math.nan
        dip = float(force[ret].min() - fit.baseline) if ret.any() else math.nan
        if not math.isfinite(dip):
            adhesion = math.nan
        elif math.isfinite(noise) and -dip < self.nsigma * noise:
            adhesion = 0.0  # no dip above the noise: no adhesion
        else:
            adhesion = min(dip, 0.0)
        radius = fit.tip_radius
        factor = ADHESION_MODELS[self.adhesion_model] / radius if radius > 0 else math.nan
        row: dict[str, Any] = pixel_place(md, file, index)
        row.update(
            youngs_modulus=fit.youngs_modulus, youngs_modulus_se=fit.youngs_modulus_se,
            youngs_modulus_low=fit.youngs_modulus_low, youngs_modulus_high=fit.youngs_modulus_high,
            contact_point=fit.contact_point, contact_point_se=fit.contact_point_se,
            max_indentation=fit.max_indentation, max_force=fit.max_force,
            adhesion_force=adhesion, adhesion_noise=noise,
            work_of_adhesion=-adhesion * factor, work_of_adhesion_se=noise * factor,
            spring_constant=k, sensitivity=sens, tip_radius=radius,
            adhesion_model=self.adhesion_model, indentation_model=fit.model,
            warnings=" | ".join(pixel_warnings(self.indentation, fit, k)))
        return row


def pixel_warnings(options: IndentationOptions, fit, k: float) -> list[str]:
    """A pixel's warnings, worded as the full analysis words them (its per-curve table's ``warnings``
    column, joined by `` | ``): the indentation fit's, the file's Poisson ratio, a spring constant [N/m]
    outside the cantilevers made."""
    from ..analysis.indentation import fit_warnings, poisson_warnings
    from ..analysis.plausibility import spring_constant_warnings

    return spring_constant_warnings(k) + fit_warnings(options, fit) + poisson_warnings(fit.poisson, fit.poisson_source)


def _read(ref, meta_override=None, probe=None):
    """The curve of ``ref``, read with the file's own calibration (:func:`afmforce.io.given.read_own`): from
    the worker's open map (afmforce, JPK, NanoScope), else the file's curves (cached)."""
    from . import files as F
    from ..io import check_meta_override
    from ..io.given import read_own

    if ref.index is None:
        raise AnalysisError(f"{ref.path}: not a force map (one curve per pixel expected)")
    from ..io.map_curves import STREAMED_FORMATS

    if ref.format in STREAMED_FORMATS:  # one curve from the worker's open map: memory flat in the map's size
        return read_own(lambda meta: F._map_reader(ref.location, ref.format, check_meta_override(meta)).read(ref.index),
                        meta_override, probe)
    return read_own(lambda meta: F._load_cached(ref.location, meta, ref.format)[ref.index], meta_override, probe)


def analyze_map(paths: Iterable[str | os.PathLike], analysis: PixelAnalysis | None = None, *,
                workers: int | None = None, executor=None, scheduler: str | None = None, store=None,
                chunk_size: int | None = None, progress=None):
    """Every pixel of the force maps ``paths`` through :class:`PixelAnalysis` on the batch engine.

    Returns the :class:`~afmforce.sweep.BatchResult` (``.table()``: one row per curve, the map's
    grid columns included; ``store``: a parent folder where the rows go chunk by chunk, and where a
    rerun resumes). ``executor``/``workers``/``scheduler`` as in :func:`~afmforce.sweep.run_batch`
    (default: a local Dask cluster; ``scheduler="tcp://HOST:8786"``: a running cluster of several
    machines, each able to read the map files at the same path).
    """
    from .files import plan_curves

    paths = [str(p) for p in paths]
    return analyze_refs(plan_curves(paths), analysis, workers=workers, executor=executor, scheduler=scheduler,
                        store=store, chunk_size=chunk_size, progress=progress)


def analyze_refs(refs: list, analysis: PixelAnalysis | None = None, *, workers: int | None = None, executor=None,
                 scheduler: str | None = None, store=None, chunk_size: int | None = None, progress=None):
    """:func:`analyze_map` of planned curves (:func:`~afmforce.sweep.files.plan_curves`)."""
    from .batch import batch_key, run_batch
    from .files import _close_open

    analysis = analysis or PixelAnalysis()
    paths = sorted({r.path for r in refs})
    # the store's key: the files (path, size, modification time) and the analysis's settings
    key = None if store is None else f"{batch_key(analysis, paths)[:20]}-{_hash(repr(analysis))}"
    try:
        return run_batch(refs, analysis, chunk_size=chunk_size, executor=executor, workers=workers,
                         scheduler=scheduler, store=store,
                         key=key, progress=progress, label=lambda ref, i: ref.label)
    finally:
        _close_open()


def _hash(text: str) -> str:
    import hashlib

    return hashlib.sha256(text.encode()).hexdigest()[:12]
