"""HDF5 half of the afmforce raw format (see :mod:`afmforce.io.native.rawfile`)."""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import numpy as np

from ..._files import atomic_path
from ._common import _REQUIRED, FORMAT, TRUTH_UNITS, VERSION, _check_truth_array, _json
from ...errors import FileFormatError, MissingDependencyError
from ..curve import RawCurve


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
    file without its ``format``/``version`` attributes (also used by :mod:`afmforce.io.native.rawmap`).

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
            _check_truth_array(key, value, n)
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
            fmt = _attr_str(safe_attr(f, "format"))
            if fmt != FORMAT:
                raise FileFormatError(f"{path} is not an afmforce raw HDF5 file (format attribute {fmt!r})")
            version = safe_attr(f, "version")
            if version is None:
                raise FileFormatError(f"{path}: attribute 'version' is missing")
            if int(version) != VERSION:
                raise FileFormatError(f"{path}: raw format version {int(version)} is not supported")
        except FileFormatError as exc:
            raise FileFormatError(f"{path}: {exc}" if not str(exc).startswith(str(path)) else str(exc)) from None
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
        try:  # the datasets opened at once (a missing one is named below): half the lookups of checking first
            data = {c: f[c] for c in _REQUIRED}
        except KeyError:
            missing = [c for c in _REQUIRED if c not in f]
            if missing:
                raise FileFormatError(f"{where}: dataset(s) {', '.join(missing)} missing") from None
            raise
        dunit = _attr_str(safe_attr(f, "deflection_unit", "V"))
        metadata = json.loads(_attr_str(safe_attr(f, "metadata", "{}")))
        truth = None
        g = f.get("truth")
        if g is not None:
            truth = json.loads(_attr_str(safe_attr(g, "scalars", "{}")))
            for key in g:
                _check_size(g[key].shape or (), g[key].name)
                truth[key] = np.asarray(g[key][()], dtype=np.float64)
        measured = f.get("piezo_measured")
        measured = None if measured is None else _floats(measured)
        return RawCurve(time=_floats(data["time"]),
                        piezo_nominal=_floats(data["piezo_nominal"]),
                        deflection_signal=_floats(data["deflection_signal"]),
                        segment=np.asarray(_checked(data["segment"])[()]).astype(np.int8),
                        piezo_measured=measured, metadata=metadata, truth=truth, deflection_unit=dunit)
    except FileFormatError as exc:
        raise FileFormatError(str(exc) if str(exc).startswith(where) else f"{where}: {exc}") from None
    except (KeyError, ValueError, TypeError, OSError, json.JSONDecodeError) as exc:
        raise FileFormatError(f"{where}: malformed afmforce raw HDF5 file ({exc})") from exc


def _check_size(dims, name: str) -> None:
    """Refuse a dataset of more than :data:`afmforce.limits.MAX_SAMPLES` values before it is read: a
    compressed (or never written) dataset declared with 1e9 values is a file of a few kB."""
    from ...limits import MAX_SAMPLES

    n = int(np.prod(dims, dtype=np.float64)) if len(dims) else 1
    if n > MAX_SAMPLES:
        raise FileFormatError(f"dataset {name} declares {n:,} values, more than a force curve holds "
                              f"({MAX_SAMPLES:,} samples); a damaged file or a decompression bomb: not read")


def _checked(dataset):
    _check_size(dataset.shape or (), dataset.name)
    return dataset


def _floats(dataset) -> np.ndarray:
    """A dataset read as float64 by HDF5's own conversion into a new array (the same values as
    ``np.asarray(dataset[()], np.float64)``, without h5py's selection machinery: a map reads
    thousands of small datasets); at most :data:`afmforce.limits.MAX_SAMPLES` values."""
    h5py = _h5py()
    dset = dataset.id
    dims = dset.get_space().get_simple_extent_dims()
    _check_size(dims, dataset.name)
    out = np.empty(dims, dtype=np.float64)
    dset.read(h5py.h5s.ALL, h5py.h5s.ALL, out)
    return out


#: Largest attribute afmforce reads [bytes]; a larger declared size means a damaged file.
ATTR_LIMIT = 16 * 2**20


def safe_attr(obj, name: str, default=None, limit: int = ATTR_LIMIT):
    """Attribute ``name`` of an h5py object, read only after its declared size was checked.

    A damaged attribute header can declare gigabytes, or make h5py spin; its
    dataspace and datatype are checked first. Raises FileFormatError when they are
    implausible; returns ``default`` when there is no such attribute.
    """
    h5py = _h5py()
    key = name.encode()
    try:
        if not h5py.h5a.exists(obj.id, key):
            return default
        aid = h5py.h5a.open(obj.id, key)
        space = aid.get_space()
        if space.get_simple_extent_type() not in (h5py.h5s.SCALAR, h5py.h5s.SIMPLE):
            raise FileFormatError(f"attribute {name!r} has an unsupported dataspace")
        npoints = space.get_simple_extent_npoints()
        tid = aid.get_type()
        size = tid.get_size()
        if npoints < 0 or size <= 0 or npoints > limit or npoints * size > limit or aid.get_storage_size() > limit:
            raise FileFormatError(f"attribute {name!r} declares {npoints} x {size} bytes; damaged file")
    except FileFormatError:
        raise
    except Exception as exc:  # h5py raises KeyError, OSError, RuntimeError on damaged headers
        raise FileFormatError(f"attribute {name!r} unreadable ({type(exc).__name__}: {str(exc)[:120]})") from None
    return obj.attrs[name]


def _attr_str(value) -> str | None:
    if isinstance(value, bytes):
        return value.decode("utf-8")
    return None if value is None else str(value)


#: The first bytes of every HDF5 file.
HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"


def root_attribute(path: str | os.PathLike, name: str) -> str | None:
    """The text of the root attribute ``name`` of the HDF5 file ``path`` (its size checked before
    it is read: a damaged file must not hang), for telling formats apart; None where the file is not
    HDF5, cannot be read, or has no such attribute."""
    try:
        with open(path, "rb") as fh:
            if fh.read(8) != HDF5_SIGNATURE:
                return None
        with _h5py().File(path, "r") as f:
            return _attr_str(safe_attr(f, name, limit=256))
    except Exception:  # any failure means: not a file of the format asked about
        return None

