"""The summary table of a batch analysis: one row per curve, SI units.

Rows come from :func:`summary_row` (called on the workers by
:class:`~afmforce.sweep.files.CurveAnalysis`); :func:`summary_table` gathers
a batch's rows with fixed columns and types (:data:`SUMMARY_COLUMNS`, units in
:data:`SUMMARY_UNITS`), :func:`write_summary` streams them chunk by chunk into
Parquet and CSV, :func:`failures` lists the items that failed.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import Any, Mapping

from .._files import atomic_path
from .results import BatchResult

__all__ = ["SUMMARY_COLUMNS", "SUMMARY_UNITS", "ERROR_COLUMNS", "summary_row", "summary_table", "write_summary",
           "failures", "failure_records", "column_unit", "column_label", "write_table", "read_summary_csv"]

#: Where a map's curve was recorded [m] (the curve's metadata; NaN: not given).
_POSITIONS = ("position_x", "position_y")
_OSC = tuple(f"oscillation_{run}_{what}" for run in ("approach", "retract") for what in ("frequency", "velocity"))


def _floats() -> tuple[str, ...]:
    """Result fields copied into the summary (floats, SI): those the steps' records mark ``column``
    (:mod:`afmforce.analysis.registry`), in the pipeline's order."""
    from ..analysis.registry import result_fields

    return tuple(f.name for f in result_fields().values() if f.column)


def _columns() -> dict[str, str]:
    return {
        "item": "int", "source": "str", "name": "str", "file": "str", "curve": "int",
        "map_x": "int", "map_y": "int", "map_nx": "int", "map_ny": "int", "map_width": "float",
        "map_height": "float", "deflection_unit": "str", "calibration_source": "str",
        **{name: "float" for name in _floats() + _POSITIONS + _OSC},
        "contact_kind": "str", "friction": "str", "dynamic": "bool", "verdict": "str", "warnings": "str",
        "tether_fits": "str",   # every tether of a hard contact, one clause each (analysis.steps.adhesion)
        "error": "str", "error_type": "str",
    }


def _units() -> dict[str, str]:
    from ..analysis.result import AnalysisResult

    units = {name: AnalysisResult.UNITS[name] for name in _floats()}
    units.update({n: "m" for n in _POSITIONS})
    units.update({n: ("Hz" if n.endswith("frequency") else "m/s") for n in _OSC})
    units.update(map_width="m", map_height="m")
    return units


def _live(builder):
    from ..analysis.registry import LiveDict

    return LiveDict(builder)


#: Columns of the summary table and their types (``int``: -1 where not a map), kept up to date
#: with the registered analysis steps.
SUMMARY_COLUMNS: dict[str, str] = _live(_columns)

#: SI unit of each numeric summary column.
SUMMARY_UNITS: dict[str, str] = _live(_units)


def _grid(meta: Mapping[str, Any]) -> tuple[int, int, int, int]:
    """(map_x, map_y, map_nx, map_ny) from afmforce map or afmformats (JPK map) metadata;
    -1 for what is unknown (no indices: not a map; no shape: the image takes the largest indices)."""
    keys = (("map_x", "afmformats:grid index x"), ("map_y", "afmformats:grid index y"),
            ("map_nx", "afmformats:grid shape x"), ("map_ny", "afmformats:grid shape y"))
    out = []
    for ours, theirs in keys:
        try:
            out.append(int(meta.get(ours, meta.get(theirs))))
        except (TypeError, ValueError):
            out.append(-1)
    if min(out[:2]) < 0:
        return -1, -1, -1, -1
    return tuple(out)  # type: ignore[return-value]


def _grid_size(meta: Mapping[str, Any]) -> tuple[float, float]:
    """Width and height of a map's scanned area [m] (afmforce ``map_width``/``map_height`` or afmformats'
    JPK ``grid size x/y``); NaN when the file does not say."""
    out = []
    for ours, theirs in (("map_width", "afmformats:grid size x"), ("map_height", "afmformats:grid size y")):
        try:
            v = float(meta.get(ours, meta.get(theirs)))
        except (TypeError, ValueError):
            v = math.nan
        out.append(v if math.isfinite(v) and v > 0 else math.nan)
    return out[0], out[1]


def summary_row(result, curve, *, file: str, index: int, name: str) -> dict[str, Any]:
    """The summary of one analysed curve (see :data:`SUMMARY_COLUMNS`)."""
    mx, my, nx, ny = _grid(curve.metadata)
    row: dict[str, Any] = {"name": name, "file": file, "curve": int(index), "map_x": mx, "map_y": my,
                           "map_nx": nx, "map_ny": ny, "deflection_unit": result.deflection_unit,
                           "calibration_source": result.calibration_source or None}
    row["map_width"], row["map_height"] = _grid_size(curve.metadata) if mx >= 0 else (math.nan, math.nan)
    row.update({f: float(getattr(result, f, math.nan)) for f in _floats()})
    for axis in _POSITIONS:  # where the map's curve was recorded [m] (NaN: not given)
        try:
            row[axis] = float(curve.metadata.get(axis, math.nan))
        except (TypeError, ValueError):
            row[axis] = math.nan
    osc = result.details.get("oscillation")
    confirmed = osc is not None and osc.origin != "none"  # a peak in both runs (see oscillation.both_runs)
    for run in ("approach", "retract"):
        peak = getattr(osc, run, None)
        found = confirmed and peak is not None and peak.found
        row[f"oscillation_{run}_frequency"] = float(peak.frequency) if found else math.nan
        row[f"oscillation_{run}_velocity"] = float(peak.velocity) if found else math.nan
    row.update(contact_kind=result.contact_kind, friction=result.friction, dynamic=bool(result.dynamic),
               verdict=result.verdict, warnings=" | ".join(result.warnings),
               tether_fits=str(getattr(result, "tether_fits", "") or "") or None)
    return row



def _normalise(frame, extra: tuple[str, ...] = ()):
    """A chunk's rows with the summary columns, in order and with fixed types."""
    import pandas as pd

    frame = frame.reindex(columns=list(SUMMARY_COLUMNS) + list(extra))
    for name, kind in SUMMARY_COLUMNS.items():
        col = frame[name]
        if kind == "int":
            frame[name] = pd.to_numeric(col, errors="coerce").astype("Int64")
        elif kind == "float":
            if col.dtype != float:
                frame[name] = pd.to_numeric(col, errors="coerce").astype(float)
        elif kind == "bool":
            frame[name] = col.astype("boolean")
        elif col.dtype != object or col.isna().any():
            frame[name] = col.astype(object).where(col.notna(), None)
    return frame


def summary_table(result: BatchResult, *, with_json: bool = False):
    """All summary rows of a batch in item order (pandas DataFrame; the ``json``
    column only with ``with_json``)."""
    import pandas as pd

    extra = ("json",) if with_json else ()  # present even when the first chunk failed (no rows)
    frames = [f for f in result.iter_tables() if len(f)]
    if not frames:
        return _normalise(pd.DataFrame(), extra)
    # the chunks joined first, then typed once (typing each chunk cost ~50 ms: 13 s for a 16 x 16
    # map analysed a curve a chunk, as afmforce serve does)
    return _normalise(pd.concat(frames, ignore_index=True), extra)


def column_unit(name: str) -> str | None:
    """SI unit of a summary column (None: a count, a string or a ratio): the analysis result's
    (:data:`SUMMARY_UNITS`, from the steps' records), else the indentation result's field (the fast map's
    further columns, :data:`afmforce.sweep.map_fast.PIXEL_COLUMNS`): each quantity's unit declared once."""
    unit = SUMMARY_UNITS.get(name)
    if unit:
        return unit
    import dataclasses

    from ..analysis.indentation import IndentationResult

    for f in dataclasses.fields(IndentationResult):
        if f.name == name:
            return f.metadata.get("unit") or None
    return None


def column_label(name: str) -> str:
    """The name of a column in ``summary.csv``: ``youngs_modulus [Pa]`` (with its unit, :func:`column_unit`),
    or the bare name where it has none. Both faces' tables (``analyze`` and ``analyze --fast-map``) use it."""
    unit = column_unit(name)
    return f"{name} [{unit}]" if unit else name


def read_summary_csv(path: str | os.PathLike):
    """A ``summary.csv`` as a pandas DataFrame with the bare column names (``youngs_modulus``), the units in
    ``frame.attrs["units"]`` (name -> unit, from the header's ``[unit]``)."""
    import pandas as pd

    frame = pd.read_csv(path)
    units, names = {}, []
    for label in frame.columns:
        name, _, rest = str(label).partition(" [")
        names.append(name)
        if rest.endswith("]"):
            units[name] = rest[:-1]
    frame.columns = names
    frame.attrs["units"] = units
    return frame


def write_table(frame, folder: str | os.PathLike) -> dict[str, Path]:
    """Write a whole table (``analyze --fast-map``'s rows) as ``summary.parquet`` (units in the schema metadata
    key ``afmforce.units``) and ``summary.csv`` (units in the header: :func:`column_label`), as
    :func:`write_summary` writes a batch's. Returns the paths by kind."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    from .._files import atomic_write_text

    folder = Path(folder)
    paths = {"parquet": folder / "summary.parquet", "csv": folder / "summary.csv"}
    units = {c: u for c in frame.columns if (u := column_unit(str(c)))}
    table = pa.Table.from_pandas(frame, preserve_index=False)
    meta = dict(table.schema.metadata or {})
    meta[b"afmforce.units"] = json.dumps(units).encode()
    with atomic_path(paths["parquet"]) as tmp:
        pq.write_table(table.replace_schema_metadata(meta), tmp)
    labelled = frame.rename(columns={c: column_label(str(c)) for c in frame.columns})
    atomic_write_text(paths["csv"], labelled.to_csv(index=False))
    return paths


def _csv_header() -> list[str]:
    return [column_label(c) for c in SUMMARY_COLUMNS]


def write_summary(result: BatchResult, folder: str | os.PathLike) -> dict[str, Path]:
    """Stream the batch's rows into ``summary.parquet`` (units in the schema metadata
    key ``afmforce.units``) and ``summary.csv`` (units in the header), a chunk at a
    time, plus ``errors.csv`` (items and curves that failed: :data:`ERROR_COLUMNS`) when any did.
    Returns the paths by kind."""
    import pandas as pd
    import pyarrow as pa
    import pyarrow.parquet as pq

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    paths = {"parquet": folder / "summary.parquet", "csv": folder / "summary.csv"}
    types = {"int": pa.int64(), "float": pa.float64(), "bool": pa.bool_(), "str": pa.string()}
    schema = pa.schema([(c, types[k]) for c, k in SUMMARY_COLUMNS.items()],
                       metadata={b"afmforce.units": json.dumps(dict(SUMMARY_UNITS)).encode()})
    errors = []
    with atomic_path(paths["parquet"]) as ptmp, atomic_path(paths["csv"]) as ctmp:
        writer = pq.ParquetWriter(ptmp, schema)
        try:
            with open(ctmp, "w", encoding="utf-8", newline="") as fh:
                fh.write(",".join(_csv_header()) + "\n")
                for frame in result.iter_tables():
                    errors.extend(_failed_rows(frame))
                    frame = _normalise(frame)
                    writer.write_table(pa.Table.from_pandas(frame, schema=schema, preserve_index=False))
                    frame.to_csv(fh, header=False, index=False)
        finally:
            writer.close()
    errors.extend(_chunk_failures(result))
    if errors:
        paths["errors"] = folder / "errors.csv"
        with atomic_path(paths["errors"]) as tmp:
            pd.DataFrame(errors, columns=list(ERROR_COLUMNS)).to_csv(tmp, index=False)
    else:  # a resumed batch that now has none
        (folder / "errors.csv").unlink(missing_ok=True)
    return paths


#: Columns of ``errors.csv``: the failed item or curve (``file#curve``), the exception's class, its message.
ERROR_COLUMNS = ("source", "error_type", "error")


def _failed_rows(frame) -> list[dict[str, str]]:
    """The failed rows of a chunk: source (``file#curve`` for one failed curve of a file read whole, else
    the item's label), error type, error, traceback."""
    if "error" not in frame.columns:
        return []
    bad = frame[frame["error"].notna()]
    out = []
    for _, row in bad.iterrows():
        file, curve = row.get("file"), row.get("curve")
        named = isinstance(file, str) and file and curve is not None and curve == curve  # one curve of a file
        error = str(row["error"])
        kind = row.get("error_type")
        tb = row.get("traceback")
        out.append({"source": f"{file}#{int(curve)}" if named else str(row["source"]),
                    "error_type": str(kind) if isinstance(kind, str) and kind else error.partition(":")[0],
                    "error": error, "traceback": str(tb) if isinstance(tb, str) else ""})
    return out


def _chunk_failures(result: BatchResult) -> list[dict[str, str]]:
    return [{"source": str(p.get("source", i)), "error_type": f.error.partition(":")[0],
             "error": f"chunk failed: {f.error}", "traceback": f.traceback or ""}
            for f in result.failures for i, p in zip(f.items, f.parameters)]


def failure_records(result: BatchResult) -> list[dict[str, str]]:
    """Every failed item or curve: ``source`` (``file`` or ``file#curve``), ``error_type`` (the
    exception's class), ``error`` (``Type: message``) and ``traceback`` (what ``--debug`` shows):
    rows with an error, then items of chunks that failed as a whole."""
    out = []
    for frame in result.iter_tables():
        out.extend(_failed_rows(frame))
    return out + _chunk_failures(result)


def failures(result: BatchResult) -> list[tuple[str, str]]:
    """``(item name, error)`` of every item that failed (see :func:`failure_records`)."""
    return [(r["source"], r["error"]) for r in failure_records(result)]


def pixel_place(md, file: str, index: int) -> dict[str, Any]:
    """A pixel's place: its name, file, curve, grid cell and size, position [m] (NaN: not recorded)."""
    mx, my, nx, ny = _grid(md)
    width, height = _grid_size(md) if mx >= 0 else (math.nan, math.nan)
    place: dict[str, Any] = {"name": f"{os.path.basename(file)}#{index}", "file": file, "curve": index,
                             "map_x": mx, "map_y": my, "map_nx": nx, "map_ny": ny, "map_width": width,
                             "map_height": height}
    for axis in ("position_x", "position_y"):
        try:
            place[axis] = float(md.get(axis, math.nan))
        except (TypeError, ValueError):
            place[axis] = math.nan
    return place
