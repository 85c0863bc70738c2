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
from .._fields import QUANTITIES
from ..errors import FileFormatError

__all__ = ["PROBE_KEYS", "ANALYSIS_KEYS", "INVOLS_METHODS", "write_calibration", "read_calibration",
           "parse_calibration", "calibration_basis", "read_calibration_basis"]

#: the probe values a calibration file hands on: name -> unit
PROBE_KEYS = {"spring_constant": "N/m", "resonance_frequency": "Hz", "quality_factor": "",
              "sensitivity": "m/V"}
#: the probe values ``afmforce analyze`` (and the web's analyse view) take from a calibration file
ANALYSIS_KEYS = ("spring_constant", "sensitivity", "resonance_frequency")
#: The calibration methods (a file's ``"method"``) whose spring constant rests on the InvOLS its spectrum was
#: converted with: the thermal one, ``k = chi kB T / <z^2>`` with ``<z^2> = InvOLS^2 <V^2>``, so k goes as
#: 1/InvOLS^2 and a refitted sensitivity (``afmforce analyze --calibration fit``) rescales it. Sader's k (the
#: lever's plan view, f0 and Q in the fluid) and the virtual AFM's (a simulated probe's truth) rest on no
#: InvOLS and are never rescaled; ``invols`` writes no spring constant.
INVOLS_METHODS = ("thermal",)
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


class _DuplicateKey(ValueError):
    pass


def _unique_keys(pairs: list) -> dict:
    """A JSON object's pairs as a dict; a key given twice raises (json took the last one silently)."""
    out: dict = {}
    for key, value in pairs:
        if key in out:
            raise _DuplicateKey(key)
        out[key] = value
    return out


def _load_object(text: str, source: str):
    """``json.loads`` refusing a key given twice in one object (which one was meant cannot be told)."""
    try:
        return json.loads(text, object_pairs_hook=_unique_keys)
    except _DuplicateKey as exc:
        raise FileFormatError(f"{source}: the key {str(exc.args[0])[:40]!r} is given twice; a calibration file "
                              "gives each value once (afmforce calibrate writes one)") from None


def parse_calibration(text: str, source: str = "calibration") -> dict[str, float]:
    """:func:`read_calibration` of a file's text (an upload); ``source`` names it in errors.
    A probe value that is not finite (NaN, Infinity: never written by afmforce) is refused, and so is a
    key given twice (json would take the last)."""
    try:
        obj = _load_object(text, source)
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
        if value is None:
            continue
        if not isinstance(value, (int, float)) or isinstance(value, bool):   # "abc", true, [1]: never dropped silently
            raise FileFormatError(f"{source}: {key} is {str(value)[:20]!r}, not a number [{PROBE_KEYS[key] or '-'}]; "
                                  "calibrate again (afmforce calibrate)")
        if not abs(value) < 1e308:      # NaN, Infinity, 1e999, a 400-digit integer: a damaged file
            raise FileFormatError(f"{source}: {key} is {str(value)[:20]}, not a finite number; "
                                  "calibrate again (afmforce calibrate)")
        out[key] = QUANTITIES[key].check(float(value), key, f"{source}: {key}")   # its declared range, named here
    return out


def calibration_basis(text: str) -> tuple[str | None, float | None]:
    """``(method, invols)`` of a calibration file's text (read as :func:`parse_calibration` reads it):
    its ``"method"`` and, for :data:`INVOLS_METHODS`, the InvOLS [m/V] its spring constant rests on (its
    ``sensitivity``; ``None`` when it records none: a spectrum in m^2/Hz, converted by the instrument)."""
    try:
        obj = _load_object(text, "calibration")
    except (ValueError, FileFormatError):
        return None, None
    if not isinstance(obj, dict):
        return None, None
    method = obj.get("method") if isinstance(obj.get("method"), str) else None
    invols = obj.get("sensitivity")
    ok = isinstance(invols, (int, float)) and not isinstance(invols, bool) and math.isfinite(invols) and invols > 0
    return method, (float(invols) if ok and method in INVOLS_METHODS else None)


def read_calibration_basis(path) -> tuple[str | None, float | None]:
    """:func:`calibration_basis` of the calibration file at ``path`` (read by :func:`read_calibration` first)."""
    return calibration_basis(read_settings(Path(path), "a calibration file"))
