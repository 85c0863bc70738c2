"""Force maps at instrument speed (issue 35, item 1): an 8 x 8 virtual QI map of a soft, adhesive
sample with known fields, analysed by ``analyze_map``; every recovered field equals the known one
within its interval. (The 128 x 128 map and its time: benchmarks/bench_map.py.)"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from afmforce.sweep.map_fast import ADHESION_MODELS, PixelAnalysis, analyze_map
from afmforce.analysis.maps import map_histogram, map_images
from afmforce.analysis.options import IndentationOptions
from afmforce.errors import ParameterError
from afmforce.instrument.soft_map import SoftMapConfig, config_of, soft_map_fields, write_soft_map
from afmforce.io.native.rawmap import map_info
from afmforce.plotting.maps import write_map_histograms

CFG = SoftMapConfig(nx=8, ny=8, seed=3)


@pytest.fixture(scope="module")
def mapped(tmp_path_factory):
    folder = tmp_path_factory.mktemp("softmap")
    path = write_soft_map(CFG, folder / "soft.h5")
    analysis = PixelAnalysis(IndentationOptions(tip_radius=CFG.radius, poisson=CFG.poisson))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = analyze_map([path], analysis, executor="serial", store=folder / "store")
    return path, folder, result.table()


def _at(table, field):
    return soft_map_fields(CFG)[field][table["map_y"].to_numpy(int), table["map_x"].to_numpy(int)]


def test_the_file_records_its_fields(mapped):
    path, _, table = mapped
    info = map_info(path)
    assert info.shape == (8, 8) and info.n_curves == 64
    assert config_of(info.metadata) == CFG
    assert len(table) == 64 and table["error"].isna().all()
    assert sorted(zip(table["map_y"], table["map_x"])) == [(y, x) for y in range(8) for x in range(8)]


def test_modulus_within_its_interval(mapped):
    table = mapped[2]
    true = _at(table, "youngs_modulus")
    z = np.abs(table["youngs_modulus"] - true) / table["youngs_modulus_se"]
    assert z.max() < 4.5 and np.median(z) < 1.2  # every pixel within ~4 sigma, no bias
    assert (table["youngs_modulus_se"] < 0.02 * true).all()  # a tight interval, not a wide one
    assert np.ptp(np.log10(true)) > 0.8  # the field spans the configured decade


def test_topography_within_its_interval(mapped):
    table = mapped[2]
    true = _at(table, "topography")
    z = np.abs(-table["contact_point"] - true) / table["contact_point_se"]
    assert z.max() < 4.5 and np.median(z) < 1.2
    assert np.ptp(true) > 0.5 * CFG.topography


def test_adhesion_and_work_of_adhesion(mapped):
    table = mapped[2]
    f_ad = _at(table, "adhesion")
    noise = table["adhesion_noise"].to_numpy()
    assert np.allclose(noise, CFG.noise * CFG.spring_constant, rtol=0.3)  # the virtual AFM's noise, in force
    # the retract is sampled every dz: its deepest sample lies within the Hertz force of one step above -F_ad
    dz = CFG.ramp / (CFG.points - 1)
    e_star = _at(table, "youngs_modulus") / (1 - CFG.poisson ** 2)
    sampling = 4 / 3 * e_star * math.sqrt(CFG.radius) * dz ** 1.5
    short = f_ad + table["adhesion_force"].to_numpy()  # how much the measured dip falls short of F_ad
    assert (short > -4 * noise).all() and (short < sampling + 4 * noise).all()
    w = table["work_of_adhesion"].to_numpy()
    assert np.allclose(w, -table["adhesion_force"] / (2 * math.pi * CFG.radius), rtol=1e-12)  # DMT
    true_w = _at(table, "work_of_adhesion")
    assert (np.abs(w - true_w) < (sampling + 4 * noise) / (2 * math.pi * CFG.radius)).all()


def test_map_images_in_micrometres(mapped, tmp_path):
    table = mapped[2]
    for q in ("modulus", "topography", "adhesion", "work_of_adhesion"):
        (image,) = map_images(table, q)
        assert image.shape == (8, 8) and np.isfinite(image.values).all() and image.has_positions
        assert math.isclose(image.dx, CFG.step, rel_tol=1e-9) and math.isclose(image.x0, 0.0, abs_tol=1e-12)
    (top,) = map_images(table, "topography")
    assert np.allclose(top.values, soft_map_fields(CFG)["topography"], atol=5 * float(table["contact_point_se"].max()))


def test_histograms_png_and_counts(mapped, tmp_path):
    table = mapped[2]
    images = [map_images(table, q)[0] for q in ("modulus", "adhesion")]
    paths = write_map_histograms(images, tmp_path / "soft", bins=16)
    assert [p.name for p in paths] == ["soft.modulus.hist.png", "soft.adhesion.hist.png", "soft.histograms.csv"]
    import pandas as pd

    hist = pd.read_csv(paths[-1])
    for q, image in zip(("modulus", "adhesion"), images):
        rows = hist[hist["quantity"] == q]
        assert rows["count"].sum() == 64
        counts, edges = np.histogram(image.values, bins=16)
        assert np.array_equal(map_histogram(image, 16)[0], counts)
        assert np.array_equal(rows["count"].to_numpy(), counts) and np.allclose(rows["low"], edges[:-1])


def test_rerun_resumes_from_the_store(mapped):
    path, folder, table = mapped
    analysis = PixelAnalysis(IndentationOptions(tip_radius=CFG.radius, poisson=CFG.poisson))
    again = analyze_map([path], analysis, executor="serial", store=folder / "store")
    assert again.chunks_run == 0 and again.chunks_skipped >= 1  # every chunk from the store, none recomputed
    t2 = again.table().sort_values(["map_y", "map_x"]).reset_index(drop=True)
    t1 = table.sort_values(["map_y", "map_x"]).reset_index(drop=True)
    assert np.array_equal(t1["youngs_modulus"], t2["youngs_modulus"])


def test_jkr_closed_form_and_bad_model():
    assert math.isclose(ADHESION_MODELS["jkr"] / ADHESION_MODELS["dmt"], 4 / 3)
    with pytest.raises(ParameterError, match="adhesion_model"):
        PixelAnalysis(adhesion_model="maugis")


def test_a_damaged_curve_is_named(mapped, tmp_path):
    """The map reader opens a curve's datasets directly: a missing one is still named."""
    import shutil

    import h5py

    from afmforce.errors import FileFormatError
    from afmforce.io.native.rawmap import MapReader

    path = tmp_path / "damaged.h5"
    shutil.copy(mapped[0], path)
    with h5py.File(path, "r+") as f:
        del f["curves/000003/segment"]
    with MapReader(path) as reader:
        assert reader.read(2).segment.size == 2 * CFG.points
        with pytest.raises(FileFormatError, match=r"#3: dataset\(s\) segment missing"):
            reader.read(3)
        with pytest.raises(FileFormatError, match="no curve 64"):
            reader.read(64)


def test_cli_fast_map(mapped, tmp_path, capsys):
    """``afmforce analyze MAP --fast-map --tip-radius 5um --out DIR``: the rows of analyze_map, the four
    maps as PNG, histograms, HDF5 and tables; a rerun resumes from the store."""
    import pandas as pd

    from afmforce.cli.main import main

    path, _, table = mapped
    argv = ["analyze", str(path), "--fast-map", "--tip-radius", "5um", "--serial", "--out", str(tmp_path)]
    assert main(argv) == 0, capsys.readouterr().err
    text = capsys.readouterr().out
    assert "64 of 64 curves analysed" in text and "modulus" in text and "kPa" in text
    # each quantity's line as its map image shows it (the registry's sign: adhesion is the dip's depth, >= 0)
    line = next(s for s in text.splitlines() if s.strip().startswith("adhesion ("))
    median = float(line.split("median ")[1].split()[0])
    ok = table[table["error"].isna()]
    assert median == pytest.approx(-float(np.median(ok["adhesion_force"].dropna())) * 1e9, rel=0.05) and median >= 0
    (folder,) = tmp_path.glob("batch-*")
    names = {p.name for p in folder.iterdir()}
    for q in ("modulus", "topography", "adhesion", "work_of_adhesion"):
        assert f"soft.h5.{q}.png" in names and f"soft.h5.{q}.hist.png" in names
    assert {"soft.h5.maps.h5", "soft.h5.histograms.csv", "summary.parquet", "summary.csv"} <= names
    summary = pd.read_parquet(folder / "summary.parquet").sort_values(["map_y", "map_x"])
    ref = table.sort_values(["map_y", "map_x"])
    assert np.array_equal(summary["youngs_modulus"].to_numpy(), ref["youngs_modulus"].to_numpy())
    assert main(argv) == 0 and "0 chunks run" in capsys.readouterr().out  # resumed


def test_cli_fast_map_needs_a_map(tmp_path, capsys):
    from afmforce.cli.main import main

    curve = __import__("pathlib").Path(__file__).resolve().parents[1] / "data" / "jpk_cellhesion_spot3.jpk-force"
    assert main(["analyze", str(curve), "--fast-map", "--serial"]) == 2
    assert "force maps" in capsys.readouterr().err
