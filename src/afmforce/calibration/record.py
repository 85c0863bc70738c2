"""The probe calibration file (``afmforce calibrate ... --out calib.json``) and its reader.

One JSON object, SI values::

    {"afmforce_calibration": 1, "method": "thermal", "spring_constant": 0.0451,
     "resonance_frequency": 25323.6, "quality_factor": 1.99, "sensitivity": 1.104e-08,
     "temperature": 298.15, ..., "units": {"spring_constant": "N/m", ...}}

``afmforce analyze --probe-calibration calib.json`` and ``afmforce simulate
--probe-calibration calib.json`` take the probe's values from it (:func:`read_calibration`);
a value given on the command line wins.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any, Mapping

from .._files import atomic_write_text, read_settings
from .._json import to_jsonable
from ..errors import FileFormatError

__all__ = ["PROBE_KEYS", "ANALYSIS_KEYS", "write_calibration", "read_calibration", "parse_calibration"]

#: the probe values a calibration file hands on: name -> unit
PROBE_KEYS = {"spring_constant": "N/m", "resonance_frequency": "Hz", "quality_factor": "",
              "sensitivity": "m/V"}
#: the probe values ``afmforce analyze`` (and the web's analyse view) take from a calibration file
ANALYSIS_KEYS = ("spring_constant", "sensitivity", "resonance_frequency")
_VERSION = 1


def write_calibration(path, method: str, values: Mapping[str, Any], units: Mapping[str, str],
                      force: bool = True) -> Path:
    """Write a calibration file atomically: ``values`` (SI) with their ``units``."""
    obj = {"afmforce_calibration": _VERSION, "method": method, **to_jsonable(dict(values)),
           "units": dict(units)}
    return atomic_write_text(path, json.dumps(obj, indent=1, allow_nan=False) + "\n", force=force)


def read_calibration(path) -> dict[str, float]:
    """The probe values of a calibration file: the finite ones of :data:`PROBE_KEYS` [SI]
    (not the sensitivity of an InvOLS marked ``"determined": false``).

    Raises
    ------
    FileFormatError
        Not an afmforce calibration file.
    """
    path = Path(path)
    try:
        text = read_settings(path, "a calibration file")
    except (OSError, ValueError) as exc:
        raise FileFormatError(f"{path}: not a readable JSON calibration file ({exc})") from None
    return parse_calibration(text, str(path))


def parse_calibration(text: str, source: str = "calibration") -> dict[str, float]:
    """:func:`read_calibration` of a file's text (an upload); ``source`` names it in errors.
    A probe value that is not finite (NaN, Infinity: never written by afmforce) is refused."""
    try:
        obj = json.loads(text)
    except ValueError as exc:
        raise FileFormatError(f"{source}: not a readable JSON calibration file ({exc})") from None
    if not isinstance(obj, dict) or "afmforce_calibration" not in obj:
        raise FileFormatError(f"{source}: not an afmforce calibration file (one is written by afmforce "
                              "calibrate, or by write_calibration in Python)")
    out = {}
    undetermined = obj.get("determined") is False     # an InvOLS the curve did not determine
    for key in PROBE_KEYS:
        if undetermined and key == "sensitivity":
            continue
        value = obj.get(key)
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            if not abs(value) < 1e308:      # NaN, Infinity, 1e999, a 400-digit integer: a damaged file
                raise FileFormatError(f"{source}: {key} is {str(value)[:20]}, not a finite number; "
                                      "calibrate again (afmforce calibrate)")
            out[key] = float(value)
    return out
