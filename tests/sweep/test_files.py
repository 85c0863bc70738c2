"""Batch analysis of files and force maps through the sweep engine (issue 7, part 3).

The synthetic map holds quasi-static curves (``analysis.synthetic.static_curve``: eq 2
with a spring, spec sections 1-2) whose probe radius grows over the grid, so that
every pixel has a known pull-off force, the strongest attraction of eq 2,
``Fs(z0) = -A R / (16 z0^2)`` (spec section 2.1; the spring is soft, k << |Fs'|),
and a known calibration factor (the sensitivity the signal was made with).
"""

from __future__ import annotations

import dataclasses
import json

import h5py
import matplotlib as mpl
import numpy as np
import pandas as pd
import pyarrow.parquet as pq
import pytest

from afmforce import forces
from afmforce.analysis.maps import EXTENT_KEY, map_images
from afmforce.plotting import write_map_png
from afmforce.analysis.synthetic import static_curve
from afmforce.cli.main import main
from afmforce.errors import FileFormatError, ParameterError
from afmforce.io import find_format, load
from afmforce.io.native.rawfile import read_raw, write_raw
from afmforce.io.native.rawmap import MapReader, map_info, read_map, write_map
from afmforce.sweep.files import (CurveAnalysis, analyze_files, failures, plan_curves, summary_table,
                                     write_summary)
from afmforce.sweep.summary import _grid

NX, NY = 5, 3
EMPTY = (2, 1)  # grid point without a curve
SENSITIVITY = 50e-9  # static_curve's default [m/V]
STEPS = ("jumps", "adhesion")  # contact, drift, compliance, calibration, zero, force, jumps


def _radius(x: int, y: int) -> float:
    return 60e-9 + 10e-9 * (x + NX * y)


def _curves():
    for y in range(NY):
        for x in range(NX):
            if (x, y) != EMPTY:
                yield static_curve(radius=_radius(x, y), velocity=2e-6, noise=0.03e-9, seed=x + NX * y)


POSITIONS = [(x, y) for y in range(NY) for x in range(NX) if (x, y) != EMPTY]


@pytest.fixture(scope="module")
def map_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("maps") / "map.h5"
    write_map(_curves(), path, shape=(NY, NX), positions=POSITIONS, metadata={"instrument": "synthetic"})
    return path


@pytest.fixture(scope="module")
def serial_table(map_file):
    return summary_table(analyze_files([map_file], CurveAnalysis(steps=STEPS), executor="serial", chunk_size=4))


# --- the map container ------------------------------------------------------------------
def test_map_file_round_trip_and_reader_registry(map_file, tmp_path):
    originals = list(_curves())
    info = map_info(map_file)
    assert info.shape == (NY, NX) and info.n_curves == len(POSITIONS) == 14
    back = read_map(map_file)
    for (x, y), a, b in zip(POSITIONS, originals, back):
        for name in ("time", "piezo_nominal", "piezo_measured", "deflection_signal", "segment"):
            np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
        assert np.array_equal(a.truth["separation"], b.truth["separation"])
        assert (b.metadata["map_x"], b.metadata["map_y"], b.metadata["map_nx"], b.metadata["map_ny"]) == (x, y, NX, NY)
        assert b.metadata["instrument"] == "synthetic" and b.metadata["velocity"] == a.metadata["velocity"]
    with MapReader(map_file) as reader:  # random access
        assert np.array_equal(reader.read(9).deflection_signal, originals[9].deflection_signal)
        with pytest.raises(FileFormatError, match="no curve 14"):
            reader.read(14)
    # the readers: a map is detected as such, a single-curve raw HDF5 file still as before
    assert find_format(map_file).identifier == "afmforce-map"
    curves = load(map_file, meta_override={"spring_constant": 0.3})
    assert len(curves) == 14 and curves[5].metadata["spring_constant"] == 0.3
    assert curves[5].metadata["map_index"] == 5 and curves[5].metadata["source_file"] == str(map_file)
    single = write_raw(originals[0], tmp_path / "one.h5")
    assert find_format(single).identifier == "afmforce-hdf5"
    assert np.array_equal(read_raw(single).deflection_signal, originals[0].deflection_signal)
    # grid indices of JPK maps come through afmformats' metadata
    assert _grid({"afmformats:grid index x": 3, "afmformats:grid index y": 1,
                  "afmformats:grid shape x": 4, "afmformats:grid shape y": 2}) == (3, 1, 4, 2)
    assert _grid({"afmformats:grid index x": 3, "afmformats:grid index y": 1}) == (3, 1, -1, -1)  # no shape
    assert _grid({}) == (-1, -1, -1, -1)


def test_map_file_errors(tmp_path, map_file):
    c = static_curve(velocity=4e-6)
    with pytest.raises(ParameterError, match="outside the map"):
        write_map([c], tmp_path / "a.h5", shape=(2, 2), positions=[(2, 0)])
    with pytest.raises(ParameterError, match="used twice"):
        write_map([c, c], tmp_path / "b.h5", shape=(2, 2), positions=[(1, 1), (1, 1)])
    with pytest.raises(ParameterError, match="at least one"):
        write_map(iter(()), tmp_path / "c.h5", shape=(2, 2))
    assert not list(tmp_path.iterdir())  # failed writes leave nothing behind
    damaged = tmp_path / "damaged.h5"
    damaged.write_bytes(map_file.read_bytes())
    with h5py.File(damaged, "a") as f:
        del f["curves/000003"]
    with pytest.raises(FileFormatError, match="13 curves stored, the file says 14"):
        read_map(damaged)


# --- the engine -----------------------------------------------------------------------
def test_serial_and_dask_give_identical_tables_with_the_static_pull_off(map_file, serial_table, dask_client):
    dask = summary_table(analyze_files([map_file], CurveAnalysis(steps=STEPS), executor=dask_client, chunk_size=4))
    pd.testing.assert_frame_equal(serial_table, dask)
    t = serial_table
    assert t["error"].isna().all() and list(zip(t["map_x"], t["map_y"])) == POSITIONS
    radius = np.array([_radius(x, y) for x, y in POSITIONS])
    np.testing.assert_allclose(t["pull_off_force"], forces.max_attraction_force(radius), rtol=0.02)  # eq 2
    np.testing.assert_allclose(t["sensitivity_fit"], SENSITIVITY, rtol=0.01)
    assert list(t["name"]) == [f"map.h5#{i}" for i in range(14)]


class _Counting(CurveAnalysis):
    """Records each call; raises KeyboardInterrupt (Ctrl-C) on call number ``stop``."""

    calls: list = []
    stop: int | None = None

    def __call__(self, ref):
        _Counting.calls.append(ref.index)
        if len(_Counting.calls) == _Counting.stop:
            raise KeyboardInterrupt
        return super().__call__(ref)


def test_interrupted_batch_resumes_without_recomputing_finished_chunks(map_file, serial_table, tmp_path):
    _Counting.calls, _Counting.stop = [], 8  # Ctrl-C in chunk 2 (items 6-8): chunks 0 and 1 are stored
    with pytest.raises(KeyboardInterrupt):
        analyze_files([map_file], _Counting(steps=STEPS), executor="serial", chunk_size=3, store=tmp_path)
    _Counting.calls, _Counting.stop = [], None
    result = analyze_files([map_file], _Counting(steps=STEPS), executor="serial", chunk_size=3, store=tmp_path)
    assert (result.chunks_skipped, result.chunks_run, result.chunks_total) == (2, 3, 5)
    assert _Counting.calls == list(range(6, 14))  # nothing of chunks 0 and 1 recomputed
    pd.testing.assert_frame_equal(summary_table(result), serial_table)


def test_bad_file_and_bad_curve_are_reported_while_the_others_finish(tmp_path):
    good = static_curve(radius=100e-9, velocity=2e-6, noise=0.03e-9, seed=3)
    flat = dataclasses.replace(good, deflection_signal=0.3 + 1e-4 * np.random.default_rng(0).standard_normal(len(good)))
    write_map([good, flat, good], tmp_path / "m.h5", shape=(1, 3))
    write_raw(good, tmp_path / "single.h5")
    (tmp_path / "broken.ibw").write_bytes(b"not an igor wave")
    files = [tmp_path / "broken.ibw", tmp_path / "m.h5", tmp_path / "single.h5"]
    refs = plan_curves(files)
    assert [r.label for r in refs] == [str(files[0])] + [f"{files[1]}#{i}" for i in range(3)] + [str(files[2])]
    result = analyze_files(refs, CurveAnalysis(steps=STEPS), executor="serial", chunk_size=2, store=tmp_path / "s")
    failed = dict(failures(result))
    assert set(failed) == {str(files[0])}  # the flat curve is a result: contact kind "none" (issue 13)
    assert "Igor" in failed[str(files[0])]
    t = summary_table(result)
    ok = t[t["error"].isna()]
    assert list(ok["name"]) == ["m.h5#0", "m.h5#1", "m.h5#2", "single.h5"]
    assert list(ok["contact_kind"]) == ["hard", "none", "hard", "hard"]
    hard = ok[ok["contact_kind"] == "hard"]
    np.testing.assert_allclose(hard["pull_off_force"], forces.max_attraction_force(100e-9), rtol=0.02)
    paths = write_summary(result, tmp_path / "out")
    errors = pd.read_csv(paths["errors"])
    assert set(errors["source"]) == set(failed)


# --- images -------------------------------------------------------------------------------
def test_map_png_pixel_grid_matches_the_map(serial_table, tmp_path):
    from PIL import Image

    (image,) = map_images(serial_table, "adhesion")
    assert image.shape == (NY, NX) and np.isnan(image.values[EMPTY[1], EMPTY[0]])
    path = write_map_png(image, tmp_path / "map.h5.adhesion.png")
    assert [p.name for p in tmp_path.iterdir()] == ["map.h5.adhesion.png"]  # atomic: no temporary left
    png = Image.open(path)
    assert png.format == "PNG"
    left, top, right, bottom = map(float, png.text[EXTENT_KEY].split())
    rgb = np.asarray(png.convert("RGB"), dtype=float)
    nn = -forces.max_attraction_force(np.array([[_radius(x, y) for x in range(NX)] for y in range(NY)])) * 1e9
    norm = mpl.colors.Normalize(np.nanmin(image.values) * 1e9, np.nanmax(image.values) * 1e9)
    for y in range(NY):
        for x in range(NX):  # the colour at each cell's centre: x to the right, y upwards
            px = rgb[int(bottom - (y + 0.5) * (bottom - top) / NY), int(left + (x + 0.5) * (right - left) / NX)]
            if (x, y) == EMPTY:
                np.testing.assert_allclose(px, np.array(mpl.colors.to_rgb("lightgrey")) * 255, atol=1.5)
            else:
                expected = np.array(mpl.colormaps["viridis"](norm(nn[y, x]))[:3]) * 255
                np.testing.assert_allclose(px, expected, atol=12)  # 2 % pull-off error moves the colour a little


# --- the command line ----------------------------------------------------------------------
def _run(argv, capsys):
    code = main(argv)
    out = capsys.readouterr()
    return code, out.out, out.err


def test_cli_batch_resume_outputs_and_exit_codes(map_file, serial_table, tmp_path, capsys, dask_client):
    broken = tmp_path / "broken.ibw"
    broken.write_bytes(b"not an igor wave")
    out = tmp_path / "out"
    argv = ["analyze", str(map_file), str(broken), "--out", str(out), "--serial", "--chunk-size", "4",
            "--steps", "jumps", "--map-quantity", "adhesion", "--map-quantity", "sensitivity_fit"]
    code, text, err = _run(argv, capsys)
    assert code == 1 and f"failed: {broken}" in err and err.count("\n") == 2  # one line for the one failed file
    assert err.startswith("note: map.h5: map of adhesion empty: no curve gave it")  # and why a map asked for is empty
    assert "4 of 4 chunks run" in text
    (folder,) = out.glob("batch-*")
    assert not list(out.glob("*.afmforce.*"))  # a batch writes no per-curve files (unless --per-curve)
    csv = (folder / "summary.csv").read_text().splitlines()
    assert "pull_off_force [N]" in csv[0].split(",") and len(csv) == 16
    table = pd.read_parquet(folder / "summary.parquet")
    assert json.loads(pq.read_schema(folder / "summary.parquet").metadata[b"afmforce.units"])["pull_off_force"] == "N"
    np.testing.assert_array_equal(table["pull_off_force"].to_numpy()[:14], serial_table["pull_off_force"])
    assert {p.name for p in folder.glob("*.png")} == {"map.h5.adhesion.png", "map.h5.sensitivity_fit.png",
                                                      "map.h5.adhesion.hist.png", "map.h5.sensitivity_fit.hist.png"}
    assert "broken.ibw" in (folder / "errors.csv").read_text()
    # rerun: every chunk is stored; remove one and only that one runs again
    code, text, _ = _run(argv, capsys)
    assert code == 1 and "all 4 chunks were already stored" in text
    sorted((folder / "chunks").glob("chunk-*.parquet"))[2].unlink()
    code, text, _ = _run(argv, capsys)
    assert code == 1 and "1 of 4 chunks run" in text and "3 were already stored" in text
    # the same batch on a Dask scheduler: the same table
    code, text, _ = _run(["analyze", str(map_file), "--out", str(tmp_path / "dask"), "--scheduler",
                          dask_client.scheduler.address, "--steps", "jumps"], capsys)
    assert code == 0 and "Dask cluster at" in text
    (dfolder,) = (tmp_path / "dask").glob("batch-*")
    np.testing.assert_array_equal(pd.read_parquet(dfolder / "summary.parquet")["pull_off_force"],
                                  serial_table["pull_off_force"])
    # usage errors: exit 2
    for bad in (["--map-quantity", "nope"], ["--workers", "0"], ["--serial", "--scheduler", "tcp://127.0.0.1:1"],
                ["--chunk-size", "0"], ["--chunk-size", "5"]):  # the last: the stored batch has chunks of 4
        try:
            code = main(["analyze", str(map_file), str(broken), "--steps", "jumps", "--out", str(out)] + bad)
        except SystemExit as exc:  # argparse
            code = exc.code
        assert code == 2, bad
        capsys.readouterr()


def test_cli_small_run_keeps_per_curve_outputs(map_file, tmp_path, capsys):
    out = tmp_path / "small"
    code, text, _ = _run(["analyze", str(map_file), "--out", str(out), "--steps", "jumps", "--no-plot"], capsys)
    assert code == 0 and "map.h5#13" in text and "chunks run" not in text  # in process, no store
    assert len(list(out.glob("map.h5_*.afmforce.json"))) == 14
    (folder,) = out.glob("batch-*")
    # the default maps some curve gave (analysis.maps.DEFAULT_MAPS): with --steps jumps, the jump-in distance
    assert {p.name for p in folder.iterdir()} == {"summary.parquet", "summary.csv", "map.h5.jump_in_distance.png",
                                                  "map.h5.maps.h5",  # the image's numbers (issue 26)
                                                  "map.h5.jump_in_distance.hist.png",
                                                  "map.h5.histograms.csv"}  # issue 35
