"""afmforce force maps: many force curves on a grid in one HDF5 file.

A force map (a "force volume": one curve per point of a grid over the sample)
in the layout of :mod:`afmforce.io.native.rawfile`'s HDF5 files, one group per curve::

    /                 attributes: format = "afmforce-map", version = 1,
                      map_shape = [ny, nx] (rows, columns of the grid),
                      n_curves, metadata (JSON object shared by every curve)
    /curves/000000    one group per curve, in the order written, laid out like an
    /curves/000001    afmforce raw HDF5 file: datasets time [s], piezo_nominal [m],
    ...               [piezo_measured [m]], deflection_signal [V, m or N], segment;
                      attributes deflection_unit and metadata (JSON, with the
                      curve's grid indices map_x (column) and map_y (row)); group truth

Grid indices start at 0; ``map_x`` runs along a row, ``map_y`` across rows.
A curve read back carries the file's shared metadata updated with its own,
plus ``map_nx`` and ``map_ny`` (the grid shape). Not every grid point needs a
curve. Curves are written one at a time (a generator of curves is never held
whole) and can be read back one at a time or by index.

>>> from afmforce.io.native.rawmap import write_map, read_map, map_info
>>> write_map(curves, "map.h5", shape=(64, 64))          # doctest: +SKIP
>>> map_info("map.h5").shape, read_map("map.h5", [0, 5])  # doctest: +SKIP
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Iterable, Iterator, Mapping, Sequence

from ..._files import atomic_path
from ...errors import FileFormatError, ParameterError
from ..curve import RawCurve
from ._common import _json
from ._hdf5 import _attr_str, _h5py, read_curve_group, root_attribute, safe_attr, write_curve_group

__all__ = ["MAP_FORMAT", "MAP_VERSION", "MapInfo", "MapReader", "write_map", "read_map", "iter_map", "map_info",
           "is_map"]

MAP_FORMAT = "afmforce-map"
MAP_VERSION = 1
_GROUP = "curves"


@dataclass(frozen=True)
class MapInfo:
    """What a map file holds (read without its curves).

    Attributes
    ----------
    shape : (int, int)
        Grid shape (rows ny, columns nx) [-].
    n_curves : int
        Number of curves stored [-].
    metadata : mapping
        Metadata shared by every curve (SI).
    """

    shape: tuple[int, int]
    n_curves: int
    metadata: Mapping[str, Any] = field(default_factory=dict)


def _shape(shape: Sequence[int]) -> tuple[int, int]:
    try:
        ny, nx = (int(v) for v in shape)
    except (TypeError, ValueError):
        raise ParameterError(f"map shape must be two integers (rows, columns), got {shape!r}") from None
    if ny < 1 or nx < 1:
        raise ParameterError(f"map shape must be positive, got {(ny, nx)}")
    return ny, nx


def _position(index: int, curve: RawCurve, positions, shape: tuple[int, int]) -> tuple[int, int]:
    ny, nx = shape
    if positions is not None:
        x, y = positions[index]
    elif "map_x" in curve.metadata and "map_y" in curve.metadata:
        x, y = curve.metadata["map_x"], curve.metadata["map_y"]
    else:  # row after row
        x, y = index % nx, index // nx
    x, y = int(x), int(y)
    if not (0 <= x < nx and 0 <= y < ny):
        raise ParameterError(f"curve {index}: grid position (x={x}, y={y}) is outside the map shape {shape} "
                             "(rows, columns)")
    return x, y


def write_map(curves: Iterable[RawCurve], path: str | os.PathLike, *, shape: Sequence[int],
              positions: Sequence[tuple[int, int]] | None = None, metadata: Mapping[str, Any] | None = None,
              force: bool = False) -> Path:
    """Write force curves on a grid to an afmforce map file (HDF5), atomically.

    Parameters
    ----------
    curves : iterable of RawCurve
        The curves, consumed one at a time (a generator is fine).
    path : path
        Output file (``.h5``/``.hdf5``).
    shape : (int, int)
        Grid shape: rows ``ny``, columns ``nx``.
    positions : sequence of (x, y), optional
        Grid indices of each curve; default: the curve's ``map_x``/``map_y``
        metadata, else row after row (curve i at x = i % nx, y = i // nx).
    metadata : mapping, optional
        Metadata shared by every curve (SI values, JSON-able).
    force : bool
        Overwrite an existing file.

    Raises
    ------
    OutputExistsError
        ``path`` exists and ``force`` is false.
    ParameterError
        No curves, a position outside the grid or used twice, or metadata that
        cannot be stored.
    """
    h5py = _h5py()
    grid = _shape(shape)
    path = Path(path)
    shared = _json(dict(metadata or {}), "metadata")
    seen: set[tuple[int, int]] = set()
    with atomic_path(path, force) as tmp:
        with h5py.File(tmp, "w") as f:
            f.attrs["format"] = MAP_FORMAT
            f.attrs["version"] = MAP_VERSION
            f.attrs["map_shape"] = list(grid)
            f.attrs["metadata"] = shared
            group = f.create_group(_GROUP)
            n = 0
            for n, curve in enumerate(curves, start=1):
                x, y = _position(n - 1, curve, positions, grid)
                if (x, y) in seen:
                    raise ParameterError(f"curve {n - 1}: grid position (x={x}, y={y}) is used twice")
                seen.add((x, y))
                meta = {k: v for k, v in curve.metadata.items() if k not in ("map_nx", "map_ny")}
                write_curve_group(group.create_group(f"{n - 1:06d}"),
                                  replace(curve, metadata={**meta, "map_x": x, "map_y": y}))
            if n == 0:
                raise ParameterError("a map needs at least one curve")
            f.attrs["n_curves"] = n
    return path


def _open(path: Path):
    h5py = _h5py()
    if not path.is_file():
        raise FileFormatError(f"{path}: no such file")
    try:
        f = h5py.File(path, "r")
    except (OSError, ValueError) as exc:
        raise FileFormatError(f"cannot read {path} as HDF5: {exc}") from None
    try:
        fmt = _attr_str(safe_attr(f, "format"))
        if fmt != MAP_FORMAT:
            raise FileFormatError(f"{path} is not an afmforce map file (format attribute {fmt!r})")
        version = safe_attr(f, "version")
        if version is None or int(version) != MAP_VERSION:
            raise FileFormatError(f"{path}: map format version {version!r} is not supported "
                                  f"(this afmforce reads version {MAP_VERSION})")
        if _GROUP not in f:
            raise FileFormatError(f"{path}: the group '{_GROUP}' is missing")
    except FileFormatError as exc:
        f.close()
        raise FileFormatError(str(exc) if str(exc).startswith(str(path)) else f"{path}: {exc}") from None
    except (KeyError, ValueError, TypeError, OSError) as exc:
        f.close()
        raise FileFormatError(f"{path}: malformed afmforce map file ({exc})") from None
    return f


def _info(f, path: Path) -> MapInfo:
    try:
        shape = tuple(int(v) for v in safe_attr(f, "map_shape", (), limit=64))
        meta = json.loads(_attr_str(safe_attr(f, "metadata", "{}")))
        stored = len(f[_GROUP])
        n = int(safe_attr(f, "n_curves", stored, limit=64))
    except (KeyError, ValueError, TypeError, FileFormatError, json.JSONDecodeError) as exc:
        raise FileFormatError(f"{path}: malformed afmforce map file ({exc})") from None
    if len(shape) != 2 or min(shape) < 1 or not isinstance(meta, dict):
        raise FileFormatError(f"{path}: malformed afmforce map file (map_shape {shape}, metadata {type(meta)})")
    if stored != n:
        raise FileFormatError(f"{path}: {stored} curves stored, the file says {n} (truncated write?)")
    return MapInfo(shape=shape, n_curves=n, metadata=meta)


class MapReader:
    """An open map file: :attr:`info` and :meth:`read` of one curve at a time.

    Use as a context manager (or call :meth:`close`); the file is opened for reading only.

    Raises
    ------
    FileFormatError
        Not an afmforce map file, or a damaged one.
    """

    def __init__(self, path: str | os.PathLike) -> None:
        self.path = Path(path)
        self._file = _open(self.path)
        try:
            self.info = _info(self._file, self.path)
        except FileFormatError:
            self._file.close()
            raise
        self._group = self._file[_GROUP]

    def __len__(self) -> int:
        return self.info.n_curves

    def read(self, index: int) -> RawCurve:
        """Curve ``index`` with the shared metadata, ``map_nx`` and ``map_ny`` added."""
        i = int(index)
        if not 0 <= i < self.info.n_curves:
            raise FileFormatError(f"{self.path}: no curve {i} (the map holds {self.info.n_curves})")
        name = f"{i:06d}"
        try:
            group = self._group[name]
        except KeyError:
            raise FileFormatError(f"{self.path}: curve group {name} is missing") from None
        curve = read_curve_group(group, f"{self.path}#{i}")
        ny, nx = self.info.shape
        return replace(curve, metadata={**self.info.metadata, **curve.metadata, "map_nx": nx, "map_ny": ny})

    def close(self) -> None:
        self._file.close()

    def __enter__(self) -> "MapReader":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def map_info(path: str | os.PathLike) -> MapInfo:
    """Grid shape, number of curves and shared metadata of a map file.

    Raises
    ------
    FileFormatError
        Not an afmforce map file, or a damaged one.
    """
    with MapReader(path) as reader:
        return reader.info


def iter_map(path: str | os.PathLike, indices: Iterable[int] | None = None) -> Iterator[RawCurve]:
    """Yield the curves of a map file one at a time (all, or those at ``indices``).

    Raises
    ------
    FileFormatError
        Not an afmforce map file, a damaged curve, or an index out of range.
    """
    with MapReader(path) as reader:
        for i in (range(len(reader)) if indices is None else indices):
            yield reader.read(i)


def read_map(path: str | os.PathLike, indices: Iterable[int] | None = None) -> list[RawCurve]:
    """The curves of a map file (all, or those at ``indices``), as a list."""
    return list(iter_map(path, indices))


def is_map(path: str | os.PathLike) -> bool:
    """True if ``path`` is an HDF5 file whose ``format`` attribute says afmforce-map."""
    return root_attribute(path, "format") == MAP_FORMAT
