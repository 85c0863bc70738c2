"""Force maps' orientation and grid, end to end: a field that varies along x only must come back
along x, at the recorded positions, in the summary table, the HDF5 and the PNG (read back colour by
colour); positions that fall as the index grows keep their place; positions that form no grid are
drawn as points at those positions, never forced into a grid."""

from __future__ import annotations

import dataclasses
import warnings

import h5py
import matplotlib as mpl
import numpy as np
import pandas as pd
import pytest
from PIL import Image

from afmforce.analysis.maps import EXTENT_KEY, map_images, map_points, write_map_hdf5
from afmforce.cli.main import main
from afmforce.instrument.soft_map import SoftMapConfig, soft_curve
from afmforce.plotting import write_map_png

NX, NY, STEP = 4, 3, 1e-6
CFG = SoftMapConfig(nx=NX, ny=NY, step=STEP, seed=5)


def _modulus(x: int) -> float:
    return 2e3 * 2.0 ** x          # along x only: 2, 4, 8, 16 kPa


def _png_cells(path, ny: int, nx: int) -> np.ndarray:
    """The colour at each heat-map cell's centre, ``[row from the bottom, column from the left]``."""
    png = Image.open(path)
    left, top, right, bottom = map(float, png.text[EXTENT_KEY].split())
    rgb = np.asarray(png.convert("RGB"), dtype=float) / 255
    return np.array([[rgb[int(bottom - (j + 0.5) * (bottom - top) / ny), int(left + (i + 0.5) * (right - left) / nx)]
                      for i in range(nx)] for j in range(ny)])


def _colour_value(rgb: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """Values of viridis colours (the nearest of 256 entries) between ``lo`` and ``hi``."""
    lut = mpl.colormaps["viridis"](np.linspace(0, 1, 256))[:, :3]
    k = np.argmin(((rgb[..., None, :] - lut) ** 2).sum(-1), axis=-1)
    return lo + (hi - lo) * k / 255


# --- the images from a table whose positions fall as the index grows --------------------------------
def _table(sign_x: float = 1.0, sign_y: float = 1.0, positions=None) -> pd.DataFrame:
    rows = []
    for y in range(NY):
        for x in range(NX):
            px, py = (5e-6 + sign_x * x * STEP, 7e-6 + sign_y * y * STEP) if positions is None else positions(x, y)
            rows.append({"file": "m.jpk-qi-data", "curve": y * NX + x, "map_x": x, "map_y": y, "map_nx": NX,
                         "map_ny": NY, "position_x": px, "position_y": py, "youngs_modulus": _modulus(x),
                         "error": None})
    return pd.DataFrame(rows)


@pytest.mark.parametrize("sign_x, sign_y", [(1, 1), (-1, 1), (1, -1), (-1, -1)])
def test_falling_positions_keep_their_place_in_hdf5_and_png(sign_x, sign_y, tmp_path):
    table = _table(sign_x, sign_y)
    (image,) = map_images(table, "modulus")
    assert image.has_positions and image.dx == pytest.approx(sign_x * STEP) and image.dy == pytest.approx(sign_y * STEP)
    h5path = write_map_hdf5([image], tmp_path / "m.maps.h5")
    with h5py.File(h5path, "r") as h5:
        values, xs, ys = h5["modulus"][()], h5["x"][()], h5["y"][()]
    for _, r in table.iterrows():        # the HDF5's value at the curve's recorded position is the curve's
        i = int(np.argmin(np.abs(xs - r["position_x"])))
        j = int(np.argmin(np.abs(ys - r["position_y"])))
        assert abs(xs[i] - r["position_x"]) < 1e-12 and abs(ys[j] - r["position_y"]) < 1e-12
        assert values[j, i] == r["youngs_modulus"]
    cells = _colour_value(_png_cells(write_map_png(image, tmp_path / "m.png"), NY, NX), 2.0, 16.0)  # kPa
    expected_left_to_right = np.array([_modulus(x) / 1e3 for x in range(NX)])[:: int(sign_x)]
    for j in range(NY):                  # x increasing to the right: the modulus follows the positions
        np.testing.assert_allclose(cells[j], expected_left_to_right, atol=0.1)


def test_a_field_along_x_stays_along_x_in_the_png(tmp_path):
    (image,) = map_images(_table(), "modulus")
    cells = _colour_value(_png_cells(write_map_png(image, tmp_path / "m.png"), NY, NX), 2.0, 16.0)
    assert np.ptp(cells, axis=0).max() < 0.1             # constant up each column
    assert np.all(np.diff(cells, axis=1) > 1.0)          # rising to the right


# --- positions that make no grid ---------------------------------------------------------------------
def _rotated(x, y):
    c, s = np.cos(np.radians(30)), np.sin(np.radians(30))
    return x * STEP * c - y * STEP * s, x * STEP * s + y * STEP * c


@pytest.mark.parametrize("positions", [_rotated, lambda x, y: (np.sin(3.7 * (x + 5 * y)) * 1e-5, (x * y % 5) * 1e-6)],
                         ids=["rotated-grid", "free-points"])
def test_positions_off_the_grid_are_points_not_an_image(positions, tmp_path):
    table = _table(positions=positions)
    assert map_images(table, "modulus") == []
    (points,) = map_points(table, "modulus")
    assert points.x.size == NX * NY and "grid" in points.why
    np.testing.assert_array_equal(points.x, table["position_x"].to_numpy())
    np.testing.assert_array_equal(points.values, table["youngs_modulus"].to_numpy())


def test_a_grid_is_not_points():
    assert map_points(_table(), "modulus") == []
    table = _table()
    table["position_x"] = table["position_x"] + 0.1 * STEP * np.sin(np.arange(len(table)))   # stage jitter: a grid
    assert len(map_images(table, "modulus")) == 1 and map_points(table, "modulus") == []


def test_curves_with_positions_and_no_indices_are_points():
    table = _table(positions=_rotated).drop(columns=["map_x", "map_y", "map_nx", "map_ny"])
    (points,) = map_points(table, "modulus")
    assert points.why == "the file records positions, no grid"
    failed = _table(positions=_rotated)
    failed.loc[3, "youngs_modulus"] = np.nan
    failed.loc[3, "error"] = "FitError: no contact"
    (points,) = map_points(failed, "modulus")
    assert np.isnan(points.values[3]) and np.isfinite(np.delete(points.values, 3)).all()


# --- end to end: a JPK QI map written with a modulus gradient along x, one pixel without contact ----------
BROKEN = (2, 1)          # (x, y): a flat curve (no contact): refused, its pixel blank, the reason in the table


@pytest.fixture(scope="module")
def gradient_map(tmp_path_factory):
    from afmforce.io.writers import write_jpk_qi

    def curves():
        for y in range(NY):
            for x in range(NX):
                c = soft_curve(CFG, _modulus(x), 0.2e-6, 10e-6, seed=y * NX + x)
                if (x, y) == BROKEN:
                    c = dataclasses.replace(c, deflection_signal=np.zeros_like(c.deflection_signal))
                md = {**c.metadata, "map_x": x, "map_y": y, "position_x": x * STEP, "position_y": y * STEP}
                yield dataclasses.replace(c, metadata=md)

    path = tmp_path_factory.mktemp("grad") / "grad.jpk-qi-data"
    return write_jpk_qi(curves(), path, shape=(NY, NX), step=STEP, instrument="virtual QI")


def _expected():
    e = np.array([[_modulus(x) for x in range(NX)]] * NY)
    e[BROKEN[1], BROKEN[0]] = np.nan
    return e


def _run(argv, capsys):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        code = main(argv)
    return code, capsys.readouterr()


def _check_outputs(folder, name, csv_modulus_rtol):
    csv = pd.read_csv(folder / "summary.csv")
    csv.columns = [c.split(" [")[0] for c in csv.columns]     # the full analysis's CSV names carry the unit
    broken = csv[(csv["map_x"] == BROKEN[0]) & (csv["map_y"] == BROKEN[1])]
    assert len(broken) == 1 and broken["error"].iloc[0].startswith("AnalysisError: ")   # the reason, at its place
    assert broken["position_x"].iloc[0] == pytest.approx(BROKEN[0] * STEP, abs=1e-12)
    assert np.isnan(broken["youngs_modulus"].iloc[0])                        # no made-up value
    good = csv[csv["error"].isna()]
    assert len(good) == NX * NY - 1
    np.testing.assert_allclose(good["youngs_modulus"], [_modulus(x) for x in good["map_x"]], rtol=csv_modulus_rtol)
    np.testing.assert_allclose(good["position_x"], good["map_x"] * STEP, atol=1e-12)
    with h5py.File(folder / f"{name}.maps.h5", "r") as h5:
        modulus, xs, ys = h5["modulus"][()], h5["x"][()], h5["y"][()]
    np.testing.assert_allclose(xs, np.arange(NX) * STEP, atol=1e-12)
    np.testing.assert_allclose(ys, np.arange(NY) * STEP, atol=1e-12)
    np.testing.assert_allclose(modulus, _expected(), rtol=csv_modulus_rtol)        # NaN where broken
    rgb = _png_cells(folder / f"{name}.modulus.png", NY, NX)
    np.testing.assert_allclose(rgb[BROKEN[1], BROKEN[0]], mpl.colors.to_rgb("lightgrey"), atol=0.01)
    cells = _colour_value(rgb, np.nanmin(modulus) / 1e3, np.nanmax(modulus) / 1e3)
    ok = np.isfinite(modulus)
    np.testing.assert_allclose(cells[ok], modulus[ok] / 1e3, atol=0.2)
    return csv


def test_cli_fast_map_keeps_the_gradient_along_x_and_blanks_the_refused_pixel(gradient_map, tmp_path, capsys):
    code, out = _run(["analyze", str(gradient_map), "--fast-map", "--tip-radius", "5um", "--poisson", "0.5",
                      "--serial", "--out", str(tmp_path)], capsys)
    assert code == 1 and "1 of 12 curves failed" in out.err
    (folder,) = tmp_path.glob("batch-*")
    _check_outputs(folder, gradient_map.name, 0.03)


def test_cli_map_equals_the_single_curve_analysis(gradient_map, tmp_path, capsys):
    from afmforce.analysis.options import IndentationOptions
    from afmforce.analysis.pipeline import analyze
    from afmforce.io import load

    code, out = _run(["analyze", str(gradient_map), "--tip-radius", "5um", "--poisson", "0.5", "--serial",
                      "--map-quantity", "modulus", "--out", str(tmp_path)], capsys)
    assert code == 1, out.err
    (folder,) = tmp_path.glob("batch-*")
    csv = _check_outputs(folder, gradient_map.name, 0.05)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        curves = load(gradient_map)
        for i in (1, 7):                   # two pixels, analysed alone: the map's numbers, to rounding
            one = analyze(curves[i], options=[IndentationOptions(tip_radius=5e-6, poisson=0.5)])
            row = csv[csv["curve"] == i].iloc[0]
            assert (row["map_x"], row["map_y"]) == (curves[i].metadata["map_x"], curves[i].metadata["map_y"])
            assert row["youngs_modulus"] == pytest.approx(one.youngs_modulus, rel=1e-12)
            assert row["contact_point"] == pytest.approx(one.contact_point, rel=1e-12)


def test_cli_maps_park_spectra_at_free_points_as_points(tmp_path, capsys):
    """Park spectra at chosen points (no volume grid): the CLI draws them at their recorded positions."""
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "io"))
    from _park_build import write_park

    path = write_park(tmp_path / "free.tiff", points=5)         # spectra at x = 1..5 um, y = 2 um
    code, out = _run(["analyze", str(path), "--serial", "--map-quantity", "adhesion", "--out", str(tmp_path / "o")],
                     capsys)
    assert code == 0, out.err
    assert "free.tiff: mapped as points at the recorded positions: the file records positions, no grid" in out.err
    (folder,) = (tmp_path / "o").glob("batch-*")
    assert (folder / "free.tiff.adhesion.png").is_file() and (folder / "free.tiff.adhesion.hist.png").is_file()
    with h5py.File(folder / "free.tiff.maps.h5", "r") as h5:
        assert h5.attrs["layout"] == "points"
        np.testing.assert_allclose(h5["x"][()], (1.0 + np.arange(5)) * 1e-6, rtol=1e-6)
        np.testing.assert_allclose(h5["y"][()], 2e-6, rtol=1e-6)
        np.testing.assert_array_equal(h5["curve"][()], np.arange(5))
        adhesion = h5["adhesion"][()]
    csv = pd.read_csv(folder / "summary.csv")
    csv.columns = [c.split(" [")[0] for c in csv.columns]
    np.testing.assert_array_equal(adhesion, -csv.sort_values("curve")["adhesion_force"].to_numpy())


def test_the_printed_median_is_the_histograms_median():
    """An even number of pixels: the median is the mean of the middle two, in the printed line as on the
    histogram (was: the upper middle value printed, 0.4982 kPa for the HeLa map's 0.4952)."""
    from afmforce.cli._analyze_fast import summary_lines

    table = pd.DataFrame({"youngs_modulus": [1e3, 2e3, 4e3, 8e3]})
    (line,) = summary_lines(table, ["modulus"])
    assert "median 3 kPa" in line and "from 1 to 8 kPa" in line


def test_a_map_is_an_image_or_points_never_both():
    """Rows of a gridded map without a cell (a curve the reader could not place) do not turn the map into
    points beside its image: the CLI would write both to one file name."""
    table = _table()
    table.loc[[2, 5], ["map_x", "map_y"]] = -1
    assert len(map_images(table, "modulus")) == 1 and map_points(table, "modulus") == []
    rotated = _table(positions=_rotated)
    rotated.loc[[2, 5], ["map_x", "map_y"]] = -1
    assert map_images(rotated, "modulus") == [] and len(map_points(rotated, "modulus")) == 1
