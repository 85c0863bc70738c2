"""Optics11 Chiaro indenter text exports, through afmformats (with two of its gaps filled)."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any, Callable, Mapping

import numpy as np

from .curve import RawCurve
from ._afmformats import load_afmformats
from ._meta import finalize_curve

__all__ = ["detect_chiaro", "load_chiaro"]


def detect_chiaro(path: Path) -> bool:
    """Optics11 Chiaro text export: a ``Device:<TAB>Chiaro`` line and a ``Time (s)<TAB>Load`` header."""
    try:
        with open(path, "rb") as fh:
            head = fh.read(65536)
    except OSError:
        return False
    return b"Device:\tChiaro" in head and b"Time (s)\tLoad" in head


#: UTF-8 spellings of the micro sign that afmformats (reading ISO-8859-1) does not find in its keys.
_MICRO = (b"\xc2\xb5", b"\xce\xbc")


def load_chiaro(path: Path, *, meta_override: Mapping[str, Any], callback: Callable | None = None) -> list[RawCurve]:
    """Optics11 Chiaro indenter export: load [N] vs piezo position.

    afmformats reads the file as ISO-8859-1 and looks up keys such as
    ``Max load (µN)``; a file saved in UTF-8 (µ as two bytes, or the Greek mu)
    fails there with a KeyError. Such a file is transcoded to ISO-8859-1 in a
    temporary copy first (the input is never changed). The Chiaro "Indentation"
    column is not a position: z is the piezo column only. The header's piezo speed
    is kept for a run only if the piezo column agrees within 10 %; else the run's
    measured speed replaces it (``velocity_note``/``retract_velocity_note`` say so).
    """
    import shutil
    import tempfile

    data = path.read_bytes()
    if not any(m in data for m in _MICRO):
        curves = load_afmformats(path, meta_override=meta_override, callback=callback, reader="chiaro-txt")
    else:
        for m in _MICRO:
            data = data.replace(m, b"\xb5")
        tmp = Path(tempfile.mkdtemp(prefix="afmforce-chiaro-"))
        try:
            copy = tmp / path.name
            copy.write_bytes(data)
            curves = load_afmformats(copy, meta_override=meta_override, callback=callback, reader="chiaro-txt")
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
        curves = [dataclasses.replace(c, metadata={**c.metadata, "source_file": str(path),
                                                   "note": "micro sign transcoded from UTF-8"}) for c in curves]
    out = []
    for c in curves:
        meta = dict(c.metadata)
        for key, run in (("velocity", 0), ("retract_velocity", 1)):
            if key in meta and key not in meta_override:
                meta[key] = float(meta[key]) * 1e-6  # afmformats 0.18 passes the file's um/s on as m/s
                measured = _run_speed(c, run)
                if measured is not None and abs(measured - meta[key]) > 0.1 * meta[key]:
                    meta[f"{key}_note"] = (f"header 'Piezo speed' {meta[key]:.3g} m/s; the piezo column moves at "
                                           f"{measured:.3g} m/s on this run: taken from the data")
                    meta[key] = measured
        out.append(finalize_curve(dataclasses.replace(c, piezo_measured=None, metadata=meta), str(path)))
    return out


def _run_speed(curve: RawCurve, run: int) -> float | None:
    """Mean piezo speed [m/s] of a run: its travel over its duration (None if it has < 2 samples).

    The header's single ``Piezo speed`` is the approach speed; a "Peak Load Poking"
    export retracts about ten times faster (afmformats passes the header value on for both).
    """
    idx = np.flatnonzero(curve.segment == run)
    if idx.size < 2 or not curve.time[idx[-1]] > curve.time[idx[0]]:
        return None
    z = curve.piezo_nominal
    return float(abs(z[idx[-1]] - z[idx[0]]) / (curve.time[idx[-1]] - curve.time[idx[0]]))
