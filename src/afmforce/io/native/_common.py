"""Names shared by the text and HDF5 halves of the afmforce raw format."""

from __future__ import annotations

import json
from typing import Any

import numpy as np

from ...errors import ParameterError

FORMAT = "afmforce-raw"
VERSION = 1
_REQUIRED = ("time", "piezo_nominal", "deflection_signal", "segment")

#: SI unit of each known truth entry.
TRUTH_UNITS: dict[str, str] = {
    "piezo_position": "m", "deflection": "m", "apparent_deflection": "m", "separation": "m",
    "apparent_separation": "m", "angle": "rad", "lateral_position": "m", "normal_force": "N",
    "friction_force": "N", "interference": "V", "drift": "V", "backlash_offset": "m",
    "calibration_factor": "m/rad", "spring_constant": "N/m", "trajectory_sample_rate": "Hz",
    "fringe_period": "m", "run_speeds": "m/s", "drift_rates": "V/s", "backlash_widths": "m",
    "piezo_loop_width": "m", "instrument": "",
}


def _check_truth_array(key: str, value: np.ndarray, n: int) -> None:
    """A truth array is stored as a column: 1-D, of the curve's length ``n`` (else ParameterError)."""
    if value.ndim != 1 or value.size != n:
        raise ParameterError(f"truth array {key!r} has shape {value.shape}; only 1-D arrays of the "
                             f"curve's length ({n}) can be stored")


def _plain(value):
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, np.ndarray):
        if value.ndim == 0:
            return _plain(value[()])
        raise TypeError("arrays are not allowed here")
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, np.floating):
        return float(value)
    if isinstance(value, np.bool_):
        return bool(value)
    return value


def _json(value: Any, key: str) -> str:
    try:
        return json.dumps(_plain(value), ensure_ascii=False, allow_nan=True)
    except (TypeError, ValueError) as exc:
        raise ParameterError(f"raw-file header value {key!r} cannot be stored ({exc}); "
                             "use numbers, strings, lists or dicts") from None
