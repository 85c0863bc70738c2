"""Property maps of soft samples (issue 26, item 3): modulus, topography, adhesion; axes in um; numbers in HDF5."""

from __future__ import annotations

import dataclasses
import warnings
from pathlib import Path

import numpy as np
import pytest

from afmforce.analysis.maps import map_images, write_map_hdf5
from afmforce.analysis.options import IndentationOptions
from afmforce.cli.main import main
from afmforce.io import load
from afmforce.io.native.rawmap import write_map
from afmforce.plotting import plot_map
from afmforce.sweep.files import CurveAnalysis, analyze_files, summary_table

GEL = Path(__file__).resolve().parents[1] / "data" / "bruker-nanoscope_PyFMlab_Egel4_00025.spm"
NX, NY, STEP = 3, 2, 2e-6


@pytest.fixture(scope="module")
def gel_map(tmp_path_factory):
    """A 3 x 2 map of the gel curve (thinned to 300 + 300 points), the sample 50 nm higher per column."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        c = load(GEL)[0]
    seg = np.asarray(c.segment)
    idx = np.concatenate([np.flatnonzero(seg == s)[np.linspace(0, (seg == s).sum() - 1, 300).astype(int)]
                          for s in (0, 1)])
    base = dataclasses.replace(c, **{f.name: getattr(c, f.name)[idx] for f in dataclasses.fields(c)
                                     if isinstance(getattr(c, f.name), np.ndarray)
                                     and getattr(c, f.name).shape == seg.shape})

    def curves():
        for y in range(NY):
            for x in range(NX):
                md = {**base.metadata, "map_x": x, "map_y": y, "position_x": 10e-6 + x * STEP,
                      "position_y": y * STEP}
                yield dataclasses.replace(base, piezo_nominal=base.piezo_nominal + 50e-9 * x, metadata=md)

    path = tmp_path_factory.mktemp("map") / "gel-map.h5"
    write_map(curves(), path, shape=(NY, NX))
    return path


@pytest.fixture(scope="module")
def table(gel_map):
    analysis = CurveAnalysis(steps=("indentation", "adhesion"), options=(IndentationOptions(tip_radius=5e-6),))
    return summary_table(analyze_files([gel_map], analysis, executor="serial"))


def test_modulus_and_topography_images_with_positions(table, tmp_path):
    (mod,) = map_images(table, "modulus")
    assert mod.shape == (NY, NX) and np.isfinite(mod.values).all()
    assert np.allclose(mod.values, mod.values[0, 0], rtol=1e-6)  # the same curve everywhere
    assert np.isclose(mod.x0, 10e-6) and np.isclose(mod.dx, STEP) and np.isclose(mod.dy, STEP) and mod.has_positions
    (top,) = map_images(table, "topography")  # minus the contact position: 50 nm higher per column
    assert np.allclose(np.diff(top.values, axis=1), -50e-9, atol=1e-9)
    ax = plot_map(mod)
    assert ax.get_xlabel() == "x [µm]" and "kPa" in ax.figure.axes[-1].get_ylabel()
    assert np.allclose(ax.images[0].get_extent(), (9, 15, -1, 3))
    import h5py

    path = write_map_hdf5([mod, top], tmp_path / "gel.maps.h5")
    with h5py.File(path) as h5:
        assert np.allclose(h5["x"][()], 10e-6 + STEP * np.arange(NX)) and h5["x"].attrs["unit"] == "m"
        assert np.allclose(h5["modulus"][()], mod.values) and h5["modulus"].attrs["unit"] == "Pa"


def test_cli_writes_the_modulus_map(gel_map, tmp_path, capsys):
    out = tmp_path / "out"
    code = main(["analyze", str(gel_map), "--out", str(out), "--serial", "--no-plot", "--steps", "indentation,adhesion",
                 "--tip-radius", "5um", "--map-quantity", "modulus", "--map-quantity", "topography",
                 "--map-quantity", "adhesion"])
    assert code == 0, capsys.readouterr().err
    (folder,) = out.glob("batch-*")
    names = {p.name for p in folder.iterdir()}
    assert {"gel-map.h5.modulus.png", "gel-map.h5.topography.png", "gel-map.h5.maps.h5", "summary.csv",
            "gel-map.h5.modulus.hist.png", "gel-map.h5.adhesion.hist.png", "gel-map.h5.histograms.csv"} <= names
    hist = (folder / "gel-map.h5.histograms.csv").read_text().splitlines()
    assert hist[0] == "quantity,unit,low,high,count"
    assert sum(int(line.rsplit(",", 1)[1]) for line in hist[1:] if line.startswith("modulus,")) == NX * NY
    import pandas as pd

    summary = pd.read_parquet(folder / "summary.parquet")
    assert {"youngs_modulus", "youngs_modulus_se", "position_x", "map_x"} <= set(summary.columns)
    assert (summary["youngs_modulus"] > 0).all()
