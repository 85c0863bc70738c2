"""Parameter sweeps and batch runs: chunked, resumable, local or on Dask.

>>> from afmforce.sweep import build_spec, run_sweep
>>> from afmforce.sweep.simulation import simulate_run, simulation_dimensions
>>> spec = build_spec(["velocity=1um/s:10um/s:4:log", "xi=0.01,0.1"],
...                   dimensions=simulation_dimensions())                  # doctest: +SKIP
>>> result = run_sweep(simulate_run, spec, store="sweeps")                # doctest: +SKIP
>>> result.table, result.to_xarray()                                      # doctest: +SKIP

``run_sweep`` (:mod:`.parametric`) calls a function once per row of a parameter
table, ``run_batch`` (:mod:`.batch`) once per item (files, curves), and
``analyze_files`` (:mod:`.files`) runs the analysis pipeline over many files and
force maps on ``run_batch``. All three use one chunk runner (:mod:`.chunks`):
chunks run in this process or on a local Dask cluster (``executor="auto"``
chooses from the measured cost of a run), finished chunks are stored as they
arrive and a rerun resumes from the store. See ``docs/sweep.md``.
"""

from __future__ import annotations

from .batch import run_batch
from ..progress import Progress
from .chunks import ChunkFailure, default_chunk_size, flatten
from .parametric import run_sweep
from .executors import DaskExecutor, SerialExecutor, make_executor
from .results import BatchResult, SweepResult
from .spec import (
    SAMPLERS,
    GridAxis,
    SampledRange,
    SweepSpec,
    build_spec,
    parse_grid,
    parse_range,
    parse_setting,
)
from .store import StoreBusyError, SweepStore

__all__ = [
    "BatchResult",
    "ChunkFailure",
    "DaskExecutor",
    "GridAxis",
    "Progress",
    "SAMPLERS",
    "SampledRange",
    "SerialExecutor",
    "StoreBusyError",
    "SweepResult",
    "SweepSpec",
    "SweepStore",
    "build_spec",
    "default_chunk_size",
    "flatten",
    "make_executor",
    "parse_grid",
    "parse_range",
    "parse_setting",
    "run_batch",
    "run_sweep",
]
