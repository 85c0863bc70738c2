"""afmforce raw files: a :class:`~afmforce.io.curve.RawCurve` as text or HDF5.

Text format (``.txt``, ``.tsv``, ``.raw``, anything but ``.h5``/``.hdf5``)
-------------------------------------------------------------------------
UTF-8. Header lines ``# key: value unit``, then one tab-separated row of
column names with units in brackets, then tab-separated data::

    # format: "afmforce-raw"
    # version: 1
    # spring_constant: 0.21 N/m
    # velocity: 1.7e-05 m/s
    # resonance_frequency: 4061.8 Hz
    # instrument: "paper"
    # truth.calibration_factor: 0.000129 m/rad
    time [s]	piezo_nominal [m]	piezo_measured [m]	deflection_signal [V]	segment [1]	truth.separation [m]
    0	-4e-08	-4e-08	0.2	0	4e-08
    ...

* ``format`` and ``version`` are required and come first. Files written by
  afmforce also carry ``rows`` (the number of data rows) and end with a
  ``# end`` line, so that a truncated file is detected; both are optional in
  files you write yourself. Values are JSON
  (numbers, ``"strings"``, lists, objects, ``true``/``null``); a value that is
  not JSON is taken as a plain string (``# instrument: Park Autoprobe``).
  Lines starting with ``#`` that are not ``# word: value`` are comments.
* The unit follows the value. Known keys (:data:`METADATA_UNITS`) are
  converted to SI from any unit pint understands (``# velocity: 1 um/s``);
  other keys with a unit are stored in SI base units when pint knows the
  unit, else as the text ``"value unit"``.
* Columns: ``time`` [s], ``piezo_nominal`` [m], ``deflection_signal`` [V, m or
  N -- the unit sets ``deflection_unit``; mV, nm, nN ... are converted] and
  ``segment`` (0 approach, 1 retract, 2 dwell) are required;
  ``piezo_measured`` [m] and ``truth.<name>`` columns are optional. Positions
  increase towards the probe (see :mod:`afmforce.io.curve`).
* ``resonance_frequency`` [Hz] and ``quality_factor`` are the lever's first free mode (a thermal
  tune's; the virtual AFM writes the model's own, docs/instrument.md): the dynamic diagnosis
  (eq 3) reads the first. Both are optional; a file without them reads as before.
  ``lever_drag`` [N s/m] (and ``lever_height`` [m] when the drag is not constant) are the lever
  body's drag in a liquid (the virtual AFM writes the model's own); optional too.
* Keys and columns prefixed ``truth.`` form ``RawCurve.truth`` (simulated curves).

We write SI values with Python's ``repr`` of each float (the shortest text
that reads back to the same number), so a written file reads back bit for bit
(NaN is written as ``nan``: its sign and payload are not kept).

HDF5 (``.h5``, ``.hdf5``)
-------------------------
Root attributes ``format``, ``version``, ``deflection_unit`` and
``metadata`` (a JSON object); one dataset per column (attribute ``unit``);
group ``truth`` with one dataset per truth array and the attribute
``scalars`` (JSON) for the rest. :func:`write_curve_group` and
:func:`read_curve_group` write and read this layout in any HDF5 group; a force
map (many curves on a grid, one group each) is :mod:`afmforce.io.native.rawmap`.
"""

from __future__ import annotations

import io
import json
import os
import re
from pathlib import Path
from typing import Any

import numpy as np

from ..._fields import QUANTITIES
from ..._files import atomic_path
from ...errors import FileFormatError, ParameterError
from ._common import _REQUIRED, FORMAT, TRUTH_UNITS, VERSION, _check_truth_array, _json
from ._hdf5 import _read_hdf5, _write_hdf5, read_curve_group, write_curve_group
from ..curve import DEFLECTION_UNITS, RawCurve

__all__ = ["write_raw", "read_raw", "write_curve_group", "read_curve_group", "FORMAT", "VERSION", "METADATA_UNITS",
           "TRUTH_UNITS", "HDF5_SUFFIXES"]

HDF5_SUFFIXES = (".h5", ".hdf5", ".hdf")

#: SI unit of each known metadata key ("" for plain values).
METADATA_UNITS: dict[str, str] = {
    "spring_constant": "N/m", "sensitivity": "m/V", "velocity": "m/s", "retract_velocity": "m/s",
    "sample_rate": "Hz", "dwell_time": "s", "temperature": "K", "resonance_frequency": "Hz", "quality_factor": "",
    "seed": "", "instrument": "", "source": "", "source_file": "", "comment": "",
    **{key: QUANTITIES[key].unit for key in ("lever_drag", "lever_height")},   # the lever body's drag in a liquid
}
_COLUMNS = {"time": "s", "piezo_nominal": "m", "piezo_measured": "m", "deflection_signal": None, "segment": "1"}
_DIMENSIONLESS = {"", "1", "-"}
_END = "# end"
_FORMAT_KEYS = ("format", "version", "rows")
_FLOAT = float.__repr__  # shortest text that reads back to the same float
_INT = str
_KEY = re.compile(r"[A-Za-z_][\w.\-]*")
_HEAD = re.compile(r"^\s*([^\[\]]+?)\s*(?:\[([^\]]*)\])?\s*$")


# --- public API -----------------------------------------------------------------
def write_raw(curve: RawCurve, path: str | os.PathLike, force: bool = False) -> Path:
    """Write ``curve`` to ``path`` atomically (HDF5 for ``.h5``/``.hdf5``, text otherwise).

    Raises
    ------
    OutputExistsError
        ``path`` exists and ``force`` is false.
    ParameterError
        Metadata or truth values that cannot be stored (not JSON-able, or
        truth arrays that are not 1-D of the curve's length).
    """
    path = Path(path)
    if path.suffix.lower() in HDF5_SUFFIXES:
        _write_hdf5(curve, path, force)
    else:
        text = format_text(curve)
        with atomic_path(path, force) as tmp:
            tmp.write_text(text, encoding="utf-8")
    return path


def read_raw(path: str | os.PathLike) -> RawCurve:
    """Read an afmforce raw file (text or HDF5, by suffix).

    Raises
    ------
    FileFormatError
        Unreadable, truncated or malformed file, missing header keys or columns.
    """
    path = Path(path)
    if path.suffix.lower() in HDF5_SUFFIXES:
        return _read_hdf5(path)
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise FileFormatError(f"{path} is not an afmforce raw text file (not UTF-8 text)") from exc
    except OSError as exc:
        raise FileFormatError(f"cannot read {path}: {exc.strerror or exc}") from exc
    return parse_text(text, source=str(path))


# --- text -----------------------------------------------------------------------
def format_text(curve: RawCurve) -> str:
    """The afmforce raw text of ``curve``."""
    n = len(curve)
    lines = [f"# format: {_json(FORMAT, 'format')}", f"# version: {VERSION}", f"# rows: {n}"]
    for key, value in curve.metadata.items():
        lines.append(_header_line(key, value, METADATA_UNITS.get(key, "")))
    cols: list[tuple[str, str, np.ndarray, Any]] = [
        ("time", "s", np.asarray(curve.time, float), _FLOAT),
        ("piezo_nominal", "m", np.asarray(curve.piezo_nominal, float), _FLOAT),
    ]
    if curve.piezo_measured is not None:
        cols.append(("piezo_measured", "m", np.asarray(curve.piezo_measured, float), _FLOAT))
    cols.append(("deflection_signal", curve.deflection_unit, np.asarray(curve.deflection_signal, float), _FLOAT))
    cols.append(("segment", "1", np.asarray(curve.segment), _INT))
    for key, value in (curve.truth or {}).items():
        name = f"truth.{key}"
        if isinstance(value, np.ndarray):
            _check_truth_array(key, value, n)
            cols.append((name, TRUTH_UNITS.get(key, ""), np.asarray(value, float), _FLOAT))
        else:
            lines.append(_header_line(name, value, TRUTH_UNITS.get(key, "")))
    lines.append("\t".join(f"{name} [{unit}]" for name, unit, _, _ in cols))
    buf = io.StringIO()
    buf.write("\n".join(lines) + "\n")
    cells = [list(map(fmt, values.tolist())) for _, _, values, fmt in cols]
    buf.write("".join("\t".join(row) + "\n" for row in zip(*cells)))
    buf.write(_END + "\n")
    return buf.getvalue()





def _header_line(key: str, value: Any, unit: str) -> str:
    if not _KEY.fullmatch(key):
        raise ParameterError(f"raw-file header key {key!r} must be a word without spaces or colons")
    text = _json(value, key)
    return f"# {key}: {text} {unit}".rstrip()


def parse_text(text: str, source: str = "<text>") -> RawCurve:
    """Parse afmforce raw text (see the module docstring)."""
    lines = text.splitlines()
    header: dict[str, tuple[Any, str]] = {}
    i = 0
    while i < len(lines) and (lines[i].startswith("#") or not lines[i].strip()):
        line = lines[i].lstrip("#").strip()
        i += 1
        key, sep, rest = line.partition(":")
        key = key.strip()
        if not sep or not _KEY.fullmatch(key):
            continue  # a comment
        if key in header:
            raise FileFormatError(f"{source}: header key {key!r} appears twice")
        header[key] = _parse_value(rest.strip())
    fmt = header.get("format", (None, ""))[0]
    if fmt != FORMAT:
        raise FileFormatError(f"{source} is not an afmforce raw file: it must start with "
                              f"'# format: \"{FORMAT}\"' (found {fmt!r})")
    if "version" not in header:
        raise FileFormatError(f"{source}: header key 'version' is missing (add '# version: {VERSION}')")
    if header["version"][0] != VERSION:
        raise FileFormatError(f"{source}: raw format version {header['version'][0]!r} is not supported "
                              f"(this afmforce reads version {VERSION})")
    if i >= len(lines):
        raise FileFormatError(f"{source}: the column header row and the data are missing")
    names, units = _parse_columns(lines[i], source)
    body = [line for line in lines[i + 1:] if line.strip()]
    if "rows" in header:  # written by afmforce: a row count and an end marker detect truncation
        if not body or body[-1].strip() != _END:
            raise FileFormatError(f"{source} is truncated: the final '{_END}' line is missing")
    body = [line for line in body if not line.startswith("#")]
    if "rows" in header:
        if len(body) != header["rows"][0]:
            raise FileFormatError(f"{source} is truncated or edited: {len(body)} data rows, "
                                  f"the header says {header['rows'][0]}")
    if not body:
        raise FileFormatError(f"{source}: no data rows after the column header")
    try:
        data = np.loadtxt(body, delimiter="\t", ndmin=2, dtype=float, comments=None)
    except ValueError as exc:
        raise FileFormatError(f"{source}: malformed data ({exc}); every row needs {len(names)} "
                              "tab-separated numbers") from None
    if data.shape[1] != len(names):
        raise FileFormatError(f"{source}: {data.shape[1]} data columns but {len(names)} names in the header row")
    columns = {name: data[:, j].copy() for j, name in enumerate(names)}
    metadata: dict[str, Any] = {}
    truth: dict[str, Any] = {}
    for key, (value, unit) in header.items():
        if key in _FORMAT_KEYS:
            continue
        if key.startswith("truth."):
            truth[key[6:]] = _value_si(value, unit, TRUTH_UNITS.get(key[6:]), f"{source}: {key}")
        else:
            metadata[key] = _value_si(value, unit, METADATA_UNITS.get(key), f"{source}: {key}")
    return _assemble(columns, dict(zip(names, units)), metadata, truth, source)


def _parse_value(rest: str) -> tuple[Any, str]:
    try:
        value, end = json.JSONDecoder().raw_decode(rest)
    except (ValueError, RecursionError):
        return rest, ""
    unit = rest[end:].strip()
    if unit and not rest[end:end + 1].isspace():  # "12abc": not a JSON value followed by a unit
        return rest, ""
    return value, unit


def _parse_columns(line: str, source: str) -> tuple[list[str], list[str]]:
    names, units = [], []
    for cell in line.split("\t"):
        m = _HEAD.match(cell)
        if not m:
            raise FileFormatError(f"{source}: bad column header {cell!r}; write 'name [unit]'")
        name, unit = m.group(1).strip(), (m.group(2) or "").strip()
        if name not in _COLUMNS and not name.startswith("truth."):
            raise FileFormatError(f"{source}: unknown column {name!r}; columns are {', '.join(_COLUMNS)} "
                                  "and truth.<name>")
        if name in names:
            raise FileFormatError(f"{source}: column {name!r} appears twice")
        names.append(name)
        units.append(unit)
    missing = [c for c in _REQUIRED if c not in names]
    if missing:
        raise FileFormatError(f"{source}: required column(s) {', '.join(missing)} missing from the header row")
    return names, units


def _assemble(columns, units, metadata, truth, source) -> RawCurve:
    t = _column_si(columns["time"], units["time"], "s", f"{source}: time")
    nominal = _column_si(columns["piezo_nominal"], units["piezo_nominal"], "m", f"{source}: piezo_nominal")
    measured = None
    if "piezo_measured" in columns:
        measured = _column_si(columns["piezo_measured"], units["piezo_measured"], "m", f"{source}: piezo_measured")
    signal, dunit = _deflection_si(columns["deflection_signal"], units["deflection_signal"], source)
    seg = columns["segment"]
    if not np.all(np.isin(seg, (0, 1, 2))):
        raise FileFormatError(f"{source}: segment must be 0 (approach), 1 (retract) or 2 (dwell)")
    truth_out = dict(truth)
    for name, values in columns.items():
        if name.startswith("truth."):
            key = name[6:]
            truth_out[key] = _column_si(values, units[name], TRUTH_UNITS.get(key), f"{source}: {name}")
    return RawCurve(time=t, piezo_nominal=nominal, deflection_signal=signal, segment=seg.astype(np.int8),
                    piezo_measured=measured, metadata=metadata, truth=truth_out or None, deflection_unit=dunit)


# --- units ----------------------------------------------------------------------
def _factor(unit: str, si: str, where: str) -> float | None:
    """Multiplier from ``unit`` to ``si`` (None: already SI)."""
    if unit == si or (unit in _DIMENSIONLESS and si in _DIMENSIONLESS):
        return None
    from ...units import unit_registry

    try:
        return float(unit_registry().Quantity(1.0, unit.replace("µ", "u")).to(si or "dimensionless").magnitude)
    except Exception:
        raise FileFormatError(f"{where}: unit {unit!r} is not {si or 'dimensionless'} or convertible to it") from None


def _column_si(values: np.ndarray, unit: str, si: str | None, where: str) -> np.ndarray:
    if si is None:
        return values
    f = _factor(unit, si, where)
    return values if f is None else values * f


def _deflection_si(values, unit, source) -> tuple[np.ndarray, str]:
    if unit in DEFLECTION_UNITS:
        return values, unit
    for si in DEFLECTION_UNITS:
        try:
            return values * _factor(unit, si, ""), si
        except FileFormatError:
            continue
    raise FileFormatError(f"{source}: deflection_signal unit {unit!r} must be a voltage, length or force")


def _value_si(value: Any, unit: str, si: str | None, where: str) -> Any:
    if si and isinstance(value, str):  # "1e-6m/s" (no space) or "1 um / s" read as text
        return _text_quantity(value if not unit else f"{value} {unit}", si, where)
    if not unit:
        return value
    if si is None:  # unknown key with a unit: SI base units if pint knows it, else keep the text
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            from ...units import unit_registry

            try:
                return float(unit_registry().Quantity(value, unit).to_base_units().magnitude)
            except Exception:
                pass
        return f"{json.dumps(value) if not isinstance(value, str) else value} {unit}"
    f = _factor(unit, si, where)
    if f is None:
        return value
    if isinstance(value, bool) or not isinstance(value, (int, float, list)):
        raise FileFormatError(f"{where}: a value with unit {unit!r} must be a number")
    return [v * f for v in value] if isinstance(value, list) else value * f


def _text_quantity(text: str, si: str, where: str) -> float:
    from ...units import unit_registry

    try:
        return float(unit_registry().Quantity(text.replace("µ", "u")).to(si).magnitude)
    except Exception:
        raise FileFormatError(f"{where}: expected a number in {si} (or with a unit convertible to it), "
                              f"got {text!r}") from None
