"""HDF5 half of the afmforce raw format (see :mod:`afmforce.rawfile`)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from ._files import atomic_path
from ._rawcommon import _REQUIRED, FORMAT, TRUTH_UNITS, VERSION, _json
from .errors import FileFormatError, MissingDependencyError, ParameterError
from .raw import RawCurve


def _h5py():
    try:
        import h5py
    except ImportError as exc:  # pragma: no cover - h5py is a dependency
        raise MissingDependencyError("HDF5 raw files need h5py: pip install h5py") from exc
    return h5py


def _write_hdf5(curve: RawCurve, path: Path, force: bool) -> None:
    h5py = _h5py()
    with atomic_path(path, force) as tmp:
        with h5py.File(tmp, "w") as f:
            f.attrs["format"] = FORMAT
            f.attrs["version"] = VERSION
            write_curve_group(f, curve)


def write_curve_group(group, curve: RawCurve) -> None:
    """Write ``curve`` into an open h5py File or Group: the layout of a raw HDF5
    file without its ``format``/``version`` attributes (also used by :mod:`afmforce.rawmap`).

    Raises
    ------
    ParameterError
        Metadata or truth values that cannot be stored.
    """
    n = len(curve)
    meta_json = _json(dict(curve.metadata), "metadata")
    scalars: dict[str, Any] = {}
    arrays: dict[str, np.ndarray] = {}
    for key, value in (curve.truth or {}).items():
        if isinstance(value, np.ndarray):
            if value.ndim != 1 or value.size != n:
                raise ParameterError(f"truth array {key!r} has shape {value.shape}; only 1-D arrays of the "
                                     f"curve's length ({n}) can be stored")
            arrays[key] = value
        else:
            scalars[key] = value
    scalars_json = _json(scalars, "truth")
    f = group
    f.attrs["deflection_unit"] = curve.deflection_unit
    f.attrs["metadata"] = meta_json
    cols = {"time": ("s", curve.time), "piezo_nominal": ("m", curve.piezo_nominal),
            "deflection_signal": (curve.deflection_unit, curve.deflection_signal),
            "segment": ("1", curve.segment)}
    if curve.piezo_measured is not None:
        cols["piezo_measured"] = ("m", curve.piezo_measured)
    for name, (unit, values) in cols.items():
        dtype = np.int8 if name == "segment" else np.float64
        ds = f.create_dataset(name, data=np.asarray(values, dtype=dtype))
        ds.attrs["unit"] = unit
    if curve.truth is not None:
        g = f.create_group("truth")
        g.attrs["scalars"] = scalars_json
        for key, values in arrays.items():
            ds = g.create_dataset(key, data=np.asarray(values, dtype=np.float64))
            ds.attrs["unit"] = TRUTH_UNITS.get(key, "")


def _read_hdf5(path: Path) -> RawCurve:
    h5py = _h5py()
    try:
        f = h5py.File(path, "r")
    except (OSError, ValueError) as exc:
        raise FileFormatError(f"cannot read {path} as HDF5: {exc}") from exc
    with f:
        try:
            fmt = _attr_str(f.attrs.get("format"))
            if fmt != FORMAT:
                raise FileFormatError(f"{path} is not an afmforce raw HDF5 file (format attribute {fmt!r})")
            if f.attrs.get("version") is None:
                raise FileFormatError(f"{path}: attribute 'version' is missing")
            if int(f.attrs["version"]) != VERSION:
                raise FileFormatError(f"{path}: raw format version {int(f.attrs['version'])} is not supported")
        except (KeyError, ValueError, TypeError, OSError) as exc:
            raise FileFormatError(f"{path}: malformed afmforce raw HDF5 file ({exc})") from exc
        return read_curve_group(f, str(path))


def read_curve_group(group, where: str) -> RawCurve:
    """Read a curve written by :func:`write_curve_group` (``where`` names it in errors).

    Raises
    ------
    FileFormatError
        Missing datasets or malformed attributes.
    """
    f = group
    try:
        missing = [c for c in _REQUIRED if c not in f]
        if missing:
            raise FileFormatError(f"{where}: dataset(s) {', '.join(missing)} missing")
        dunit = _attr_str(f.attrs.get("deflection_unit", "V"))
        metadata = json.loads(_attr_str(f.attrs.get("metadata", "{}")))
        truth = None
        if "truth" in f:
            g = f["truth"]
            truth = json.loads(_attr_str(g.attrs.get("scalars", "{}")))
            for key in g:
                truth[key] = np.asarray(g[key][()], dtype=np.float64)
        measured = np.asarray(f["piezo_measured"][()], np.float64) if "piezo_measured" in f else None
        return RawCurve(time=np.asarray(f["time"][()], np.float64),
                        piezo_nominal=np.asarray(f["piezo_nominal"][()], np.float64),
                        deflection_signal=np.asarray(f["deflection_signal"][()], np.float64),
                        segment=np.asarray(f["segment"][()]).astype(np.int8),
                        piezo_measured=measured, metadata=metadata, truth=truth, deflection_unit=dunit)
    except FileFormatError:
        raise
    except (KeyError, ValueError, TypeError, OSError, json.JSONDecodeError) as exc:
        raise FileFormatError(f"{where}: malformed afmforce raw HDF5 file ({exc})") from exc


def _attr_str(value) -> str | None:
    if isinstance(value, bytes):
        return value.decode("utf-8")
    return None if value is None else str(value)

