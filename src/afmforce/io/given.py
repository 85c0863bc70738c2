"""The user's calibration over a curve read with the file's own: declared once for every face.

A spring constant [N/m] or sensitivity (InvOLS) [m/V] the user gives (``--spring-constant``,
``--sensitivity``, the web's ``probe``, ``ProbeCalibration(...)`` in Python) is the probe's, never the
file's metadata: the file's own values stay what its thermal spring constant rests on (a thermal k goes
as 1/InvOLS^2, so under ``calibration fit`` it is rescaled by (the file's InvOLS / the fitted)^2, not
by the user's). Every face (``afmforce analyze`` of a file, a folder or a streamed force map,
``--fast-map``, the web's analysis, ``afmforce sweep`` over files, the Python API) therefore

1. reads the file with its own metadata (:func:`read_own`: the metadata override less the probe's values;
   the probe's given to the reader only where the file cannot be read without them), and
2. puts the user's values over the curve with :func:`apply_given`, as the readers themselves do with
   ``meta_override``: a deflection stored in newtons or metres (computed by the instrument with the file's
   calibration) is rescaled by given / file's, and the file's InvOLS is kept under :data:`FILE_SENSITIVITY`.

The faces only collect the values (into a :class:`~afmforce.analysis.options.ProbeCalibration`).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any, Callable, Mapping, TypeVar

import numpy as np

from .._fields import QUANTITIES
from ..errors import MissingMetadataError

__all__ = ["CALIBRATION_KEYS", "FILE_SENSITIVITY", "GIVEN_NOTE", "given_calibration", "reader_override", "read_own",
           "apply_given", "file_sensitivity"]

#: The probe's values a reader would otherwise take as the file's (``meta_override``): spring constant
#: [N/m], sensitivity [m/V].
CALIBRATION_KEYS = ("spring_constant", "sensitivity")
#: Metadata key of a curve rescaled to the user's sensitivity (:func:`apply_given`): the file's own
#: InvOLS [m/V], the one its thermal spring constant rests on.
FILE_SENSITIVITY = "file_sensitivity"
#: Metadata key of the note :func:`apply_given` leaves where a given value cannot rescale the stored
#: deflection (the analysis says it among its warnings).
GIVEN_NOTE = "given_calibration_note"

T = TypeVar("T")


def given_calibration(probe: Any) -> dict[str, float]:
    """The probe's (the user's) spring constant [N/m] and sensitivity [m/V], those given (name -> SI)."""
    if probe is None:
        return {}
    return {k: float(getattr(probe, k)) for k in CALIBRATION_KEYS if getattr(probe, k, None) is not None}


def reader_override(meta_override: Mapping[str, Any] | None, probe: Any) -> dict[str, Any]:
    """What a reader gets as ``meta_override``: the metadata typed as the file's (``--meta``, the web's
    ``meta``) less the probe's calibration values (the user's, put over the curve by :func:`apply_given`)."""
    given = given_calibration(probe)
    return {k: v for k, v in dict(meta_override or {}).items()
            if not (k in given and isinstance(v, (int, float)) and math.isclose(float(v), given[k], rel_tol=1e-12))}


def read_own(read: Callable[[dict[str, Any]], T], meta_override: Mapping[str, Any] | None, probe: Any) -> T:
    """``read(meta)`` with the file's own calibration (:func:`reader_override`); a file that cannot be read
    without a spring constant or sensitivity (:class:`~afmforce.errors.MissingMetadataError`: none of its
    own) is read with the probe's given as its metadata."""
    own = reader_override(meta_override, probe)
    full = {**dict(meta_override or {}), **given_calibration(probe)}
    try:
        return read(own)
    except MissingMetadataError:
        if full == own:
            raise
    return read(full)


def _own(metadata: Mapping[str, Any], key: str) -> float | None:
    """The file's ``key`` where it is one a lever can have (a damaged header value: None, nothing to rescale from)."""
    v = metadata.get(key)
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        return None
    v = float(v)
    return v if math.isfinite(v) and v > 0 and QUANTITIES[key].contains(v) else None


def apply_given(curve: T, probe: Any) -> T:
    """``curve`` (read with the file's own calibration) with the user's spring constant and sensitivity
    (``probe``) put over it, as its reader does with ``meta_override``: the instrument's deflection in
    metres (volts x the file's InvOLS) scales by given / file's InvOLS, its force in newtons (volts x InvOLS
    x k) by given / file's InvOLS and given / file's k, and the metadata then says the values used; the file's
    InvOLS is kept under :data:`FILE_SENSITIVITY`. A curve in volts is returned as it is (the probe's value is
    used where the volts are converted); one whose file holds no usable value (none, or one no lever has)
    keeps its stored signal, and a given sensitivity that cannot rescale it is said (:data:`GIVEN_NOTE`,
    among the analysis's warnings), never applied silently.

    Was: a curve stored in newtons kept the file's forces under ``ProbeCalibration(sensitivity=...)``
    (jpk_cellhesion_spot3, 11.04 against 70 nm/V: adhesion -0.419 nN either way, -0.066 nN through the
    reader); and the readers' rescaling (the CLI's maps, ``--fast-map``, the web) lost the file's InvOLS,
    so that ``calibration fit`` rescaled the file's thermal k with the user's (0.04349 -> 0.000276 N/m
    instead of 0.01108 N/m on that curve)."""
    given = given_calibration(probe)
    unit = getattr(curve, "deflection_unit", None)
    if not given or unit not in ("m", "N"):
        return curve
    md = curve.metadata
    factor, new, stuck = 1.0, {}, []
    keys = ("sensitivity", "spring_constant") if unit == "N" else ("sensitivity",)
    for key in keys:
        own = _own(md, key)
        if key == "sensitivity" and key in given and own is None and not md.get(GIVEN_NOTE):
            stuck.append(key)    # (a k the file lacks still turns its force into deflections: used)
        if key not in given or own is None or math.isclose(own, given[key], rel_tol=1e-12):
            continue
        factor *= given[key] / own
        new[key] = given[key]
        if key == "sensitivity":
            new[FILE_SENSITIVITY] = md.get(FILE_SENSITIVITY, own)
    if stuck:     # never silent: the forces stay the file's while the value is reported as used
        what = {"N": "a force [N]", "m": "a deflection [m]"}[unit]
        new[GIVEN_NOTE] = (f"the file stores {what} computed with a sensitivity (InvOLS) it does not record (or one "
                           "no lever has): yours cannot rescale it, so the forces are the file's as stored (`sensitivity` "
                           f"given: {given['sensitivity'] * 1e9:.4g} nm/V)")
    if not new:
        return curve
    signal = curve.deflection_signal if factor == 1.0 else np.asarray(curve.deflection_signal) * factor
    return dataclasses.replace(curve, deflection_signal=signal, metadata={**md, **new})


def file_sensitivity(metadata: Mapping[str, Any]) -> float:
    """The file's own InvOLS [m/V] (:data:`FILE_SENSITIVITY` of a curve rescaled to the user's, else its
    ``sensitivity``); NaN when it has none."""
    for key in (FILE_SENSITIVITY, "sensitivity"):
        try:
            v = float(metadata.get(key))
        except (TypeError, ValueError):
            continue
        if math.isfinite(v) and v > 0:
            return v
    return math.nan
