"""Batches of items (files, curves) through the same engine (issue 7, part 3)."""

from __future__ import annotations

import pandas as pd
import pytest
import sweep_funcs as f

from afmforce.errors import ParameterError
from afmforce.sweep import run_batch


@pytest.fixture(autouse=True)
def _clear_calls():
    f.CALLS.clear()


@pytest.fixture
def files(tmp_path):
    """Seven files of numbers (like curves in map files); file 4 is empty."""
    folder = tmp_path / "data"
    folder.mkdir()
    paths = []
    for i in range(7):
        p = folder / f"map{i}.txt"
        p.write_text("" if i == 4 else " ".join(str(i + k / 10) for k in range(i % 3 + 1)))
        paths.append(p)
    return paths


def test_batch_of_files_lists_failures_and_streams_to_one_file(files, tmp_path):
    result = run_batch(files, f.read_numbers, executor="serial", chunk_size=3, store=tmp_path / "store")
    table = result.table()
    expected = [(i, i + k / 10) for i in range(7) if i != 4 for k in range(i % 3 + 1)]
    ok = table[table["error"].isna()]
    assert list(zip(ok["item"], ok["value"])) == expected  # str(float) round-trips exactly
    assert (ok["square"] == ok["value"] ** 2).all()
    bad = table[table["error"].notna()]
    assert list(bad["item"]) == [4] and bad["source"].iloc[0] == str(files[4])
    assert "holds no numbers" in bad["error"].iloc[0]
    # streamed output (chunk by chunk) equals the table, also across chunks with different columns
    for name in ("all.parquet", "all.csv"):
        path = result.write(tmp_path / name)
        back = pd.read_parquet(path) if name.endswith("parquet") else pd.read_csv(path)
        pd.testing.assert_series_equal(back["value"], table["value"], check_dtype=False)
        assert list(back["source"]) == list(table["source"])
    # a rerun finds every chunk stored; a touched file changes the key and is redone
    again = run_batch(files, f.read_numbers, executor="serial", store=tmp_path / "store")
    assert again.chunks_run == 0 and again.chunks_skipped == 3
    files[0].write_text("9")
    redo = run_batch(files, f.read_numbers, executor="serial", chunk_size=3, store=tmp_path / "store")
    assert redo.store.root != result.store.root and redo.chunks_run == 3


def test_batch_consumes_a_generator_one_chunk_at_a_time_and_resumes(tmp_path):
    produced = []

    def curves(n=23):
        for i in range(n):
            produced.append(i)
            yield float(i)

    seen = []

    def func(item):
        seen.append((item, len(produced)))
        return f.square(item)

    size = 5
    result = run_batch(curves(), func, executor="serial", chunk_size=size, store=tmp_path, key="gen")
    # when item k runs, only its own chunk has been drawn from the generator
    assert [p for _, p in seen] == [min(23, (int(k) // size + 1) * size) for k, _ in seen]
    assert result.chunks_total is None and result.chunks_run == 5
    assert list(result.table()["square"]) == [float(i * i) for i in range(23)]
    f.CALLS.clear()
    again = run_batch(curves(), f.square, executor="serial", store=tmp_path, key="gen")
    assert f.CALLS == [] and again.chunks_skipped == 5
    with pytest.raises(ParameterError, match="key"):
        run_batch(curves(), f.square, executor="serial", store=tmp_path)


def test_batch_on_dask_equals_serial(files, dask_client):
    serial = run_batch(files, f.read_numbers, executor="serial", chunk_size=2).table()
    dask = run_batch(files, f.read_numbers, executor=dask_client, chunk_size=2).table()
    pd.testing.assert_frame_equal(serial, dask)
