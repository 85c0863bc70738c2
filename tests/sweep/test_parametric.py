"""Chunked execution, resume and failure handling of sweeps (issue 7, parts 1-2).

The swept functions (``sweep_funcs``) are cheap closed forms so that the tests
check the engine, not the physics: serial and Dask tables are identical,
interrupted sweeps resume without recomputing stored chunks, and runs or
chunks that raise are reported with their parameters while the others finish.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import sweep_funcs as f
from scipy.optimize import brentq

from afmforce import forces
from afmforce.errors import ParameterError
from afmforce.sweep import (
    SerialExecutor,
    StoreBusyError,
    SweepStore,
    build_spec,
    flatten,
    run_sweep,
)

HERE = Path(__file__).parent


@pytest.fixture(autouse=True)
def _clear_calls():
    f.CALLS.clear()


def grid(nx: int = 5, ny: int = 4):
    return build_spec([f"x=1:{nx}:{nx}", f"y=0.5:2:{ny}"])


def test_serial_sweep_reproduces_the_static_jump_in_closed_form():
    # spec section 2: static jump-in is the largest h with Fs'(h) = k; solved here
    # independently with brentq between the steepest-gradient point and 100 nm.
    spec = build_spec(["spring_constant=0.1:0.5:3", "radius=100e-9,220e-9"])
    result = run_sweep(f.jump_in, spec, executor="serial", chunk_size=4)
    assert result.table.shape[0] == 6 and result.n_failed == 0
    for _, row in result.table.iterrows():
        k, r = row["spring_constant"], row["radius"]
        h_steep = 3 ** (1 / 6) * forces.Z0  # maximum of Fs'(h)
        h = brentq(lambda x: forces.vdw_force_gradient(x, r) - k, h_steep, 100e-9, xtol=1e-16)
        assert row["jump_in.separation"] == pytest.approx(h, rel=1e-9)
        assert row["jump_in.deflection"] == pytest.approx(forces.vdw_force(h, r) / k, rel=1e-9)
    # spec section 2: 4.4 nm for R = 220 nm, k = 0.21 N/m
    paper = run_sweep(f.jump_in, {"spring_constant": [0.21], "radius": [220e-9]}, executor="serial")
    assert paper.table["jump_in.separation"].iloc[0] == pytest.approx(4.4e-9, abs=0.05e-9)


def test_serial_and_dask_give_identical_tables_and_failure_records(dask_client, tmp_path):
    spec = grid(6, 5)
    serial = run_sweep(f.fragile, spec, executor="serial", chunk_size=4)
    dask = run_sweep(f.fragile, spec, executor=dask_client, chunk_size=4, store=tmp_path)
    pd.testing.assert_frame_equal(serial.table, dask.table)
    assert dask.chunks_run == 8 and "Dask" in dask.executor
    # the --scheduler route: connect to the running cluster by address (and leave it running)
    remote = run_sweep(f.fragile, spec, scheduler=dask_client.scheduler.address, chunk_size=4)
    pd.testing.assert_frame_equal(serial.table, remote.table)
    assert dask_client.scheduler.address in remote.executor and dask_client.status == "running"
    assert serial.n_failed == 5 and set(serial.errors["x"]) == {3.0}
    # a chunk that raises as a whole on a worker is recorded with its parameters
    failed = run_sweep(f.fragile, spec, executor=dask_client, chunk_size=4, errors="raise", key="raise")
    runs_with_x3 = {r for r in range(30) if spec.table()["x"][r] == 3.0}
    bad_chunks = {r // 4 for r in runs_with_x3}
    assert {c.chunk for c in failed.failures} == bad_chunks
    for c in failed.failures:
        assert "ValueError: cannot handle x = 3" in c.error
        assert [p["run"] for p in c.parameters] == c.items
        assert all(set(p) == {"run", "x", "y"} for p in c.parameters)
    ok = failed.table["error"].isna()
    assert ok.sum() == 30 - 4 * len(bad_chunks)
    np.testing.assert_array_equal(failed.table.loc[ok, "product"], serial.table.loc[ok, "product"])


def test_interrupted_sweep_resumes_without_recomputing_stored_chunks(tmp_path):
    spec = grid(5, 4)  # 20 runs, chunks of 3 -> 7 chunks
    with pytest.raises(KeyboardInterrupt):  # Ctrl-C during the 8th call: chunks 0 and 1 are done
        run_sweep(f.Interrupt(at=8), spec, executor="serial", chunk_size=3, store=tmp_path, key="k")
    assert len(f.CALLS) == 7
    store = SweepStore(next(tmp_path.iterdir()))
    assert store.completed() == {0, 1} and not (store.root / "lock").exists()
    f.CALLS.clear()
    seen = []
    result = run_sweep(f.counted, spec, executor="serial", store=tmp_path, key="k", progress=seen.append)
    assert len(f.CALLS) == 20 - 6  # only the 5 chunks not stored ran
    assert result.chunks_skipped == 2 and result.chunks_run == 5
    assert seen[0].done == 2 and seen[-1].done == seen[-1].total == 7 and seen[-1].fraction == 1.0
    assert {p.unit for p in seen} == {"chunk"} and seen[-1].skipped == 2
    assert [p.done for p in seen] == sorted(p.done for p in seen)
    reference = run_sweep(f.counted, spec, executor="serial")
    pd.testing.assert_frame_equal(result.table, reference.table)
    # a third run finds everything stored and starts nothing
    f.CALLS.clear()
    again = run_sweep(f.counted, spec, executor="dask", store=tmp_path, key="k")
    assert f.CALLS == [] and again.chunks_run == 0 and again.executor.startswith("none")


def test_killed_sweep_process_resumes_where_it_stopped(tmp_path):
    script = textwrap.dedent(f"""
        import sys
        sys.path.insert(0, {str(HERE)!r})
        import sweep_funcs as f
        from afmforce.sweep import build_spec, run_sweep
        spec = build_spec(["x=1:5:5", "y=0.5:2:4"])
        run_sweep(f.slow, spec, executor="serial", chunk_size=2, store={str(tmp_path)!r}, key="kill")
    """)
    env = dict(os.environ, AFMFORCE_TEST_SLEEP="0.1")
    proc = subprocess.Popen([sys.executable, "-c", script], env=env)
    try:
        deadline = time.monotonic() + 600     # a wide margin: the child imports dask under any load
        chunks = []
        while len(chunks) < 3 and time.monotonic() < deadline and proc.poll() is None:
            chunks = list(tmp_path.glob("sweep-*/chunks/chunk-*.parquet"))
            time.sleep(0.01)
        assert proc.poll() is None, "the sweep finished before it could be killed"
        os.kill(proc.pid, signal.SIGKILL)
    finally:
        proc.wait()
    store = SweepStore(next(tmp_path.glob("sweep-*")))
    done = store.completed()
    assert 3 <= len(done) < 10
    assert json.loads((store.root / "lock").read_text())["pid"] == proc.pid  # stale lock left behind
    result = run_sweep(f.counted, grid(5, 4), executor="serial", store=tmp_path, key="kill")
    assert len(f.CALLS) == 20 - 2 * len(done)
    assert result.chunks_skipped == len(done) and result.n_failed == 0
    np.testing.assert_allclose(result.table["product"], result.table["x"] * result.table["y"], rtol=0)
    assert not list(store.chunk_dir.glob(".*"))  # no half-written files


def test_failing_chunk_is_recorded_and_retried_on_rerun(tmp_path):
    spec = grid(5, 4)  # x == 3 are runs 8..11, i.e. chunk 2 of 4-run chunks
    first = run_sweep(f.fragile, spec, executor="serial", chunk_size=4, store=tmp_path, errors="raise")
    assert [c.chunk for c in first.failures] == [2] and first.chunks_run == 5
    assert len(f.CALLS) == 16
    record = json.loads((first.store.root / "failed" / "chunk-000002.json").read_text())
    assert record["items"] == [8, 9, 10, 11]
    assert [p["x"] for p in record["parameters"]] == [3.0] * 4
    assert "cannot handle x = 3" in record["error"] and "Traceback" in record["traceback"]
    assert list(first.table["error"].dropna().index) == [8, 9, 10, 11]
    f.CALLS.clear()
    second = run_sweep(f.fragile, spec, executor="serial", store=tmp_path, errors="raise")
    assert f.CALLS == [] and second.chunks_run == 1 and second.chunks_skipped == 4  # only chunk 2 retried


def test_store_refuses_a_different_chunk_size_and_a_live_writer(tmp_path):
    spec = grid(3, 2)
    run_sweep(f.counted, spec, executor="serial", chunk_size=2, store=tmp_path, key="cs")
    with pytest.raises(ParameterError, match="`chunk_size` 2"):
        run_sweep(f.counted, spec, executor="serial", chunk_size=3, store=tmp_path, key="cs")
    store = SweepStore(next(tmp_path.iterdir()))
    sleeper = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(30)"])
    try:
        (store.root / "lock").write_text(json.dumps({"pid": sleeper.pid, "host": os.uname().nodename}))
        with pytest.raises(StoreBusyError, match=str(sleeper.pid)):
            run_sweep(f.counted, spec, executor="serial", store=tmp_path, key="cs")
    finally:
        sleeper.kill()
        sleeper.wait()


def test_grid_results_as_xarray_netcdf_and_parquet_with_units(tmp_path):
    xr = pytest.importorskip("xarray")
    result = run_sweep(f.counted, grid(3, 4), executor=SerialExecutor(), store=tmp_path)
    paths = result.write(tmp_path / "out", units={"x": "m", "product": "m"})
    ds = xr.open_dataset(paths["netcdf"])
    assert ds["product"].dims == ("x", "y") and ds["product"].shape == (3, 4)
    np.testing.assert_allclose(ds["product"].values, np.outer([1, 2, 3], [0.5, 1, 1.5, 2]), rtol=1e-15)
    assert ds["x"].attrs["units"] == "m" and ds["product"].attrs["units"] == "m"
    ds.close()
    import pyarrow.parquet as pq

    meta = pq.read_schema(paths["parquet"]).metadata
    assert json.loads(meta[b"afmforce.units"])["product"] == "m"
    back = pd.read_csv(paths["csv"], index_col="run")
    np.testing.assert_allclose(back["sum"], result.table["sum"], rtol=1e-15)


def test_flatten_nests_mappings_and_refuses_long_arrays():
    assert flatten({"a": {"b": np.float64(1.5), "c": None}, "d": np.int64(2)}) == {"a.b": 1.5, "a.c": None, "d": 2}
    assert flatten({"v": (1, 2)}) == {"v": "[1, 2]"}
    with pytest.raises(ParameterError, match="array of 100 values"):
        flatten({"curve": np.zeros(100)})


def test_heat_map_shows_the_grid_values_on_log_axes():
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from afmforce.plotting import plot_metric

    spec = build_spec(["x=1:100:3:log", "y=1,2,3,4"])
    result = run_sweep(f.counted, spec, executor="serial")
    ax = plot_metric(result, "product", units={"x": "m", "product": "m"})
    mesh = ax.collections[0]
    # rows are y, columns x; lengths are shown in nm (x 1e9)
    np.testing.assert_allclose(mesh.get_array().reshape(4, 3), np.outer([1, 2, 3, 4], [1, 10, 100]) * 1e9)
    assert ax.get_xscale() == "log" and ax.get_yscale() == "linear"
    assert ax.get_xlabel() == "x [nm]"
    plt.close(ax.figure)


def test_worker_warmup_runs_once_and_turns_the_compile_helper_off(monkeypatch):
    """The warm-up on a Dask worker: one call, errors ignored, and no compile helper process
    for that worker (the workers compile side by side already)."""
    import os

    from afmforce.dynamics._helper import ENV
    from afmforce.sweep.parametric import _warm_call

    monkeypatch.setenv(ENV, "1")
    calls = []
    _warm_call(lambda **kw: calls.append(kw), {"x": 1.0})
    assert calls == [{"x": 1.0}] and os.environ[ENV] == "0"

    def broken(**kw):
        raise ValueError("bad row")

    _warm_call(broken, {})                                   # ignored
