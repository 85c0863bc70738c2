"""Glue between the registry and afmforce's own formats (raw text, raw HDF5, force maps).

The formats themselves are written and read by :mod:`afmforce.io.native.rawfile` and
:mod:`afmforce.io.native.rawmap`; these functions detect them (reading at most a few bytes
of an untrusted attribute) and return curves in the registry's conventions.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path
from typing import Any, Mapping

from ..curve import RawCurve
from ._hdf5 import HDF5_SIGNATURE, root_attribute, safe_attr

__all__ = ["detect_raw_text", "detect_raw_hdf5", "detect_raw_map", "load_rawfile", "load_rawmap", "safe_attr",
           "root_attribute", "HDF5_SIGNATURE"]


def rawfile_available() -> bool:
    return importlib.util.find_spec("afmforce.io.native.rawfile") is not None


def detect_raw_text(path: Path) -> bool:
    """afmforce raw text: ``# format: "afmforce-raw"`` header, or ``#`` lines and a deflection_signal column."""
    if not rawfile_available():
        return False
    try:
        with open(path, "rb") as fh:
            head = fh.read(16384).decode("utf-8", errors="replace")
    except OSError:
        return False
    return head.startswith("#") and ("afmforce-raw" in head or "deflection_signal" in head)


def detect_raw_hdf5(path: Path) -> bool:
    """HDF5 signature and the root attribute ``format = "afmforce-raw"``."""
    return rawfile_available() and root_attribute(path, "format") == "afmforce-raw"


def load_rawfile(path: Path, *, meta_override: Mapping[str, Any], callback=None) -> list[RawCurve]:
    """afmforce raw text / HDF5, written by :mod:`afmforce.io.native.rawfile`."""
    import dataclasses

    from .rawfile import read_raw

    from .._meta import finalize_curve

    curve = read_raw(path)
    reader = "afmforce-hdf5" if path.suffix.lower() in (".h5", ".hdf5", ".hdf") else "afmforce-raw"
    meta = {**dict(curve.metadata), **dict(meta_override), "reader": reader}
    if meta.get("source_file") not in (None, str(path)):
        meta["recorded_source"] = meta["source_file"]
    meta["source_file"] = str(path)
    curve = finalize_curve(dataclasses.replace(curve, metadata=meta), str(path))
    if callback is not None:
        callback(1.0)
    return [curve]


def detect_raw_map(path: Path) -> bool:
    """HDF5 signature and the root attribute ``format = "afmforce-map"``."""
    if not rawfile_available():
        return False
    from .rawmap import is_map

    return is_map(path)


def load_rawmap(path: Path, *, meta_override: Mapping[str, Any], callback=None,
                 indices: list[int] | None = None, reader=None) -> list[RawCurve]:
    """afmforce force map (HDF5, many curves on a grid), written by :mod:`afmforce.io.native.rawmap`.

    ``indices`` reads only those curves and ``reader`` (an open
    :class:`~afmforce.io.native.rawmap.MapReader` of ``path``) saves opening the file:
    the batch analysis reads a map a chunk at a time.
    """
    import dataclasses

    from .rawmap import MapReader

    from .._meta import finalize_curve

    own = reader is None
    reader = MapReader(path) if own else reader
    try:
        indices = list(range(len(reader))) if indices is None else list(indices)
        out = []
        for i in indices:
            curve = reader.read(i)
            meta = {**dict(curve.metadata), **dict(meta_override), "reader": "afmforce-map", "map_index": int(i)}
            if meta.get("source_file") not in (None, str(path)):
                meta["recorded_source"] = meta["source_file"]
            meta["source_file"] = str(path)
            out.append(finalize_curve(dataclasses.replace(curve, metadata=meta), f"{path}#{i}"))
            if callback is not None:
                callback(len(out) / len(indices))
    finally:
        if own:
            reader.close()
    return out
