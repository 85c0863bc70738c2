"""Results of sweeps and batches: the final table, NetCDF grids, streamed files.

A sweep's table has one row per run, indexed by ``run``: the parameters, the
outputs (flattened ``a.b`` names) and ``error`` (None when the run worked).
For a grid sweep :meth:`SweepResult.to_xarray` gives an :class:`xarray.Dataset`
with one dimension per grid axis. Batch results are streamed chunk by chunk
from the store to Parquet/CSV so that a large batch is never in memory whole.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Iterator, Mapping

import numpy as np

from .._files import atomic_path

if TYPE_CHECKING:  # pragma: no cover
    import pandas as pd
    import xarray as xr

    from .spec import SweepSpec
    from .store import SweepStore

__all__ = ["SweepResult", "BatchResult", "write_table"]

_UNITS_KEY = b"afmforce.units"


def _string_columns(frame) -> list[str]:
    return [c for c in frame.columns if frame[c].dtype == object]


def write_table(frame, path: str | Path, units: Mapping[str, str] | None = None) -> Path:
    """Write a table atomically as Parquet (units in the schema metadata) or CSV (by suffix)."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    path = Path(path)
    with atomic_path(path) as tmp:
        if path.suffix == ".csv":
            frame.to_csv(tmp)
        else:
            table = pa.Table.from_pandas(frame)
            meta = dict(table.schema.metadata or {})
            meta[_UNITS_KEY] = json.dumps(dict(units or {})).encode()
            pq.write_table(table.replace_schema_metadata(meta), tmp)
    return path


@dataclass(frozen=True, eq=False)
class SweepResult:
    """Outcome of :func:`~afmforce.sweep.run_sweep`.

    Attributes
    ----------
    table : pandas.DataFrame
        One row per run (index ``run``): parameters [SI], outputs, ``error``.
    parameter_names : tuple of str
        The parameter columns of ``table``.
    failures : tuple of ChunkFailure
        Chunks that failed as a whole (their runs carry ``chunk failed: ...``).
    spec : SweepSpec or None
        The spec, when the sweep was given one (needed for grids).
    store : SweepStore or None
        Where the chunks are stored.
    chunks_total, chunks_run, chunks_skipped : int
        All chunks, those run now, those found complete in the store.
    wall_time : float
        Seconds spent in :func:`run_sweep` [s].
    executor : str
        Where the chunks ran.
    """

    table: "pd.DataFrame"
    parameter_names: tuple[str, ...]
    failures: tuple = ()
    spec: "SweepSpec | None" = None
    store: "SweepStore | None" = None
    chunks_total: int = 0
    chunks_run: int = 0
    chunks_skipped: int = 0
    wall_time: float = 0.0
    executor: str = ""

    @classmethod
    def assemble(cls, parameters, source, *, spec=None, failures=(), **info) -> "SweepResult":
        """Join the parameter table with chunk outputs from a store or ``{chunk: frame}``."""
        import pandas as pd

        frames = list(source.iter_chunks()) if hasattr(source, "iter_chunks") else [
            source[k] for k in sorted(source)]
        outputs = pd.concat(frames) if frames else pd.DataFrame(index=pd.Index([], name="run"))
        out_cols = [c for c in outputs.columns if c not in parameters.columns and c != "error"]
        table = parameters.join(outputs[out_cols]) if out_cols else parameters.copy()
        error = outputs["error"] if "error" in outputs else pd.Series(dtype=object)
        table["error"] = error.reindex(table.index).astype(object)
        table["error"] = table["error"].where(table["error"].notna(), None)
        for f in failures:
            table.loc[list(f.items), "error"] = f"chunk failed: {f.error}"
        store = source if hasattr(source, "iter_chunks") else None
        return cls(table=table, parameter_names=tuple(parameters.columns), failures=tuple(failures),
                   spec=spec, store=store, **info)

    @property
    def output_names(self) -> list[str]:
        """The output columns (neither parameters nor ``error``)."""
        return [c for c in self.table.columns if c not in self.parameter_names and c != "error"]

    @property
    def errors(self) -> "pd.DataFrame":
        """Runs that raised: their parameters and error."""
        t = self.table
        return t.loc[t["error"].notna(), list(self.parameter_names) + ["error"]]

    @property
    def n_failed(self) -> int:
        return int(self.table["error"].notna().sum())

    @property
    def is_grid(self) -> bool:
        return self.spec is not None and self.spec.is_grid

    def to_xarray(self, units: Mapping[str, str] | None = None) -> "xr.Dataset":
        """The grid as an :class:`xarray.Dataset` (one dimension per grid axis).

        Outputs and ``error`` become variables; constant settings become
        attributes; ``units`` (name -> unit) go into each variable's ``units``.
        """
        import xarray as xr

        if not self.is_grid:
            raise ValueError("only a grid sweep (no sampled ranges) forms a Dataset; use .table")
        units = dict(units or {})
        dims = [a.name for a in self.spec.grid]
        shape = self.spec.shape
        coords = {a.name: (a.name, list(a.values), {"units": units.get(a.name, ""), "spacing": "log" if a.log else "linear"})
                  for a in self.spec.grid}
        data = {}
        for name in self.output_names + ["error"]:
            values = self.table[name].to_numpy()
            if values.dtype == object:
                values = [("" if v is None or v != v else str(v)) for v in values]
                values = np.asarray(values, dtype=str)
            data[name] = (dims, values.reshape(shape), {"units": units.get(name, "")})
        attrs = {k: (v if isinstance(v, (int, float, str)) else repr(v)) for k, v in self.spec.fixed}
        return xr.Dataset(data, coords=coords, attrs=attrs)

    def write(self, folder: str | Path, units: Mapping[str, str] | None = None) -> dict[str, Path]:
        """Write ``results.parquet``, ``results.csv``, ``errors.csv`` (if any), ``results.html``
        (one self-contained page: :func:`~afmforce.sweep.page.write_page`) and, for grids,
        ``results.nc`` (NetCDF) into ``folder``. Returns the paths by kind."""
        from .page import write_page

        folder = Path(folder)
        paths = {
            "parquet": write_table(self.table, folder / "results.parquet", units),
            "csv": write_table(self.table, folder / "results.csv"),
        }
        if self.n_failed:
            paths["errors"] = write_table(self.errors, folder / "errors.csv")
        if self.is_grid:
            with atomic_path(folder / "results.nc") as tmp:
                self.to_xarray(units).to_netcdf(tmp)
            paths["netcdf"] = folder / "results.nc"
        paths["html"] = write_page(self, folder / "results.html", units)
        return paths


@dataclass(frozen=True, eq=False)
class BatchResult:
    """Outcome of :func:`~afmforce.sweep.run_batch`.

    Rows (one per record returned by the function) hold ``item``, ``source``,
    ``record``, the outputs and ``error``. With a store they stay on disk until
    read: :meth:`iter_tables` yields one chunk at a time and :meth:`write`
    streams them into one file.
    """

    store: "SweepStore | None" = None
    frames: Mapping[int, Any] | None = None
    failures: tuple = ()
    chunks_total: int | None = None
    chunks_run: int = 0
    chunks_skipped: int = 0
    wall_time: float = 0.0
    executor: str = ""

    def iter_tables(self) -> Iterator["pd.DataFrame"]:
        """Each finished chunk's rows, in item order."""
        if self.store is not None:
            yield from self.store.iter_chunks()
        else:
            for k in sorted(self.frames or {}):
                yield self.frames[k]

    def table(self) -> "pd.DataFrame":
        """All rows in memory (fine for summaries; use :meth:`write` for huge batches)."""
        import pandas as pd

        frames = list(self.iter_tables())
        return pd.concat(frames, ignore_index=True) if frames else pd.DataFrame()

    def write(self, path: str | Path, units: Mapping[str, str] | None = None) -> Path:
        """Stream every chunk into one ``.parquet`` or ``.csv`` file, a chunk at a time."""
        import pyarrow as pa
        import pyarrow.csv as pacsv
        import pyarrow.parquet as pq

        path = Path(path)
        if self.store is not None:
            schemas = [pq.read_schema(p) for p in self.store.chunk_paths()]
        else:
            schemas = [pa.Schema.from_pandas(f, preserve_index=False) for f in self.iter_tables()]
        if not schemas:
            raise ValueError("no finished chunks to write")
        schema = pa.unify_schemas([s.remove_metadata() for s in schemas], promote_options="permissive")
        meta = {_UNITS_KEY: json.dumps(dict(units or {})).encode()}
        with atomic_path(path) as tmp:
            if path.suffix == ".csv":
                writer = pacsv.CSVWriter(tmp, schema)
            else:
                writer = pq.ParquetWriter(tmp, schema.with_metadata(meta))
            try:
                for frame in self.iter_tables():
                    t = pa.Table.from_pandas(frame, preserve_index=False)
                    cols = [t.column(n).cast(schema.field(n).type) if n in t.column_names
                            else pa.nulls(len(t), schema.field(n).type) for n in schema.names]
                    writer.write_table(pa.Table.from_arrays(cols, schema=schema))
            finally:
                writer.close()
        return path
