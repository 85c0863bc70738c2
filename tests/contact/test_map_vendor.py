"""Force maps in the vendors' formats (issue 35, items 1, 3): the virtual AFM's 4 x 4 map written as
JPK QI data and as a Bruker force volume, read back and analysed curve by curve (never loaded
whole): the recovered modulus, topography, adhesion and work of adhesion equal the known fields
within their intervals, and the rows equal those of the same map in afmforce's own format within
what the vendor's encoding keeps. ``afmforce analyze FILE --fast-map`` writes the maps (PNG, HDF5
with the grid, histograms, CSV and Parquet per curve) from a vendor file."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from afmforce.analysis.options import IndentationOptions
from afmforce.instrument.soft_map import SoftMapConfig, soft_map_fields, write_soft_map
from afmforce.sweep.map_fast import PixelAnalysis, analyze_map
from afmforce.sweep.summary import read_summary_csv

CFG = SoftMapConfig(nx=4, ny=4, seed=11)
ANALYSIS = PixelAnalysis(IndentationOptions(tip_radius=CFG.radius, poisson=CFG.poisson))
NAMES = {"jpk-qi": "soft.jpk-qi-data", "bruker-fv": "soft.spm"}


def _analyse(paths, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return analyze_map(paths, ANALYSIS, executor="serial", **kw).table().sort_values(["map_y", "map_x"]) \
            .reset_index(drop=True)


@pytest.fixture(scope="module")
def native(tmp_path_factory):
    return _analyse([write_soft_map(CFG, tmp_path_factory.mktemp("native") / "soft.h5")])


@pytest.fixture(scope="module", params=sorted(NAMES))
def vendor(request, tmp_path_factory):
    folder = tmp_path_factory.mktemp(request.param)
    path = write_soft_map(CFG, folder / NAMES[request.param], format=request.param)
    return request.param, path, _analyse([path], store=folder / "store")


def _at(table, field):
    return soft_map_fields(CFG)[field][table["map_y"].to_numpy(int), table["map_x"].to_numpy(int)]


def test_every_pixel_analysed_on_its_grid_cell(vendor):
    _, _, table = vendor
    assert len(table) == 16 and table["error"].isna().all()
    assert list(zip(table["map_y"], table["map_x"])) == [(y, x) for y in range(4) for x in range(4)]
    assert (table["spring_constant"] == CFG.spring_constant).all()
    assert np.allclose(table["sensitivity"], CFG.sensitivity, rtol=1e-12)


def test_modulus_and_topography_within_their_intervals(vendor):
    _, _, table = vendor
    for column, sign, field in (("youngs_modulus", 1, "youngs_modulus"), ("contact_point", -1, "topography")):
        z = np.abs(sign * table[column] - _at(table, field)) / table[column + "_se"]
        assert z.max() < 4.5 and np.median(z) < 1.5, column
    assert (table["youngs_modulus_se"] < 0.02 * _at(table, "youngs_modulus")).all()


def test_adhesion_and_work_of_adhesion_within_the_noise_and_one_step(vendor):
    _, _, table = vendor
    noise = table["adhesion_noise"].to_numpy()
    assert np.allclose(noise, CFG.noise * CFG.spring_constant, rtol=0.35)
    dz = CFG.ramp / (CFG.points - 1)
    sampling = 4 / 3 * _at(table, "youngs_modulus") / (1 - CFG.poisson ** 2) * math.sqrt(CFG.radius) * dz ** 1.5
    short = _at(table, "adhesion") + table["adhesion_force"].to_numpy()
    assert (short > -4 * noise).all() and (short < sampling + 4 * noise).all()
    w = table["work_of_adhesion"].to_numpy()
    assert (np.abs(w - _at(table, "work_of_adhesion")) < (sampling + 4 * noise) / (2 * math.pi * CFG.radius)).all()


def test_rows_equal_the_native_maps_within_the_encoding(vendor, native):
    fmt, _, table = vendor
    # JPK: 32-bit encoders (5e-9 V, 1e-14 m); NanoScope: the virtual ADC's counts exactly, Z in 0.1 nm steps
    tol = {"jpk-qi": 1e-6, "bruker-fv": 2e-3}[fmt]
    for column in ("youngs_modulus", "adhesion_force"):
        rel = np.abs(table[column] / native[column] - 1)
        assert rel.max() < tol, (column, rel.max())
    assert np.abs(table["contact_point"] - native["contact_point"]).max() < {"jpk-qi": 1e-12, "bruker-fv": 0.3e-9}[fmt]


def test_vendor_maps_are_streamed_never_loaded_whole(vendor, monkeypatch, tmp_path):
    import afmforce.io
    from afmforce.sweep import files

    def whole(*args, **kwargs):
        raise AssertionError("the whole map was loaded")

    monkeypatch.setattr(afmforce.io, "load", whole)
    monkeypatch.setattr(files, "_load_cached", whole)
    _, path, table = vendor
    again = _analyse([path])
    assert again["error"].isna().all()
    assert np.array_equal(again["youngs_modulus"].to_numpy(), table["youngs_modulus"].to_numpy())


def test_cli_writes_the_maps_of_a_vendor_file(vendor, tmp_path, capsys):
    import h5py
    import pandas as pd

    from afmforce.cli.main import main

    _, path, table = vendor
    argv = ["analyze", str(path), "--fast-map", "--tip-radius", "5um", "--poisson", "0.5", "--serial",
            "--out", str(tmp_path)]
    assert main(argv) == 0, capsys.readouterr().err
    assert "16 of 16 curves analysed" in capsys.readouterr().out
    (folder,) = tmp_path.glob("batch-*")
    names = {p.name for p in folder.iterdir()}
    for q in ("modulus", "topography", "adhesion", "work_of_adhesion"):
        assert f"{path.name}.{q}.png" in names and f"{path.name}.{q}.hist.png" in names
    assert {f"{path.name}.maps.h5", f"{path.name}.histograms.csv", "summary.parquet", "summary.csv"} <= names
    csv = read_summary_csv(folder / "summary.csv").sort_values(["map_y", "map_x"])   # names with units, read bare
    assert np.allclose(csv["youngs_modulus"], table["youngs_modulus"], rtol=1e-12)
    with h5py.File(folder / f"{path.name}.maps.h5", "r") as h5:
        modulus, x, y = h5["modulus"][()], h5["x"][()], h5["y"][()]
        assert h5["x"].attrs["unit"] == "m" and modulus.shape == (4, 4)
    assert np.allclose(modulus[table["map_y"], table["map_x"]], table["youngs_modulus"], rtol=1e-12)
    first = table.iloc[0]
    assert np.allclose(x - x[0], CFG.step * np.arange(4)) and math.isclose(x[0], first["position_x"], abs_tol=1e-15)
    assert np.allclose(y - y[0], CFG.step * np.arange(4)) and math.isclose(y[0], first["position_y"], abs_tol=1e-15)


def test_indentation_and_force_maps_follow_the_setpoint(vendor):
    """The fast map's further quantities as images: QI turns at the force setpoint, so the largest
    force is the setpoint and the deepest indentation Hertz's (F / (4/3 E* sqrt(R)))^(2/3)."""
    from afmforce.analysis.maps import map_images

    _, _, table = vendor
    (force,) = map_images(table, "max_force")
    (depth,) = map_images(table, "max_indentation")
    assert force.quantity.unit == "N" and depth.quantity.unit == "m" and depth.has_positions
    noise = CFG.noise * CFG.spring_constant
    assert np.abs(force.values - CFG.setpoint).max() < 5 * noise
    e_star = soft_map_fields(CFG)["youngs_modulus"] / (1 - CFG.poisson ** 2)
    hertz = (CFG.setpoint / (4 / 3 * e_star * math.sqrt(CFG.radius))) ** (2 / 3)
    assert np.allclose(depth.values, hertz, rtol=0.015)
