"""The real force maps' grids against their headers, read here independently of the readers: size,
which curve is pixel (0, 0), row order (JPK's back-and-forth rows), pixel size and the image's extent
in um (``analysis.maps.map_images`` on a table of the curves' metadata, as the batch writes it)."""

from __future__ import annotations

import re
import warnings
import zipfile

import numpy as np
import pandas as pd
import pytest

from afmforce.analysis.maps import map_images, map_points
from afmforce.io import load

from realdata import real_file  # noqa: E402  (tests/ is on sys.path: tests/conftest.py)


def _table(path) -> pd.DataFrame:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        curves = load(path)
    keys = ("map_x", "map_y", "map_nx", "map_ny", "position_x", "position_y", "map_width", "map_height")
    rows = [{"file": str(path), "curve": i, "youngs_modulus": float(i),
             **{k: c.metadata.get(k, -1 if k.startswith("map_") and "w" not in k and "h" not in k else np.nan)
                for k in keys}} for i, c in enumerate(curves)]
    return pd.DataFrame(rows)


def test_hela_jpk_map_back_and_forth_rows_and_5_um_pixels():
    path = real_file("jpk-force-map_HeLa_4x4.jpk-force-map")
    with zipfile.ZipFile(path) as z:
        head = dict(line.split("=", 1) for line in z.read("header.properties").decode().splitlines()
                    if "=" in line and not line.startswith("#"))
    pre = "force-scan-map.position-pattern."
    n, size = int(head[pre + "grid.ilength"]), float(head[pre + "grid.ulength"])
    centre = float(head[pre + "grid.xcenter"]), float(head[pre + "grid.ycenter"])
    assert head[pre + "back-and-forth"] == "true" and n == 4 and int(head[pre + "grid.jlength"]) == 4
    table = _table(path)
    (image,) = map_images(table, "modulus")              # "modulus" here: each pixel's curve index
    assert image.shape == (4, 4) and map_points(table, "modulus") == []
    assert image.dx == pytest.approx(size / n, rel=1e-6) and image.dy == pytest.approx(size / n, rel=1e-6)
    assert image.x0 + 1.5 * image.dx == pytest.approx(centre[0], abs=1e-9)   # the grid's centre, as the header
    assert image.y0 + 1.5 * image.dy == pytest.approx(centre[1], abs=1e-9)
    # acquisition order: row 0 left to right, row 1 right to left, ... (back and forth)
    np.testing.assert_array_equal(image.values, [[0, 1, 2, 3], [7, 6, 5, 4], [8, 9, 10, 11], [15, 14, 13, 12]])


def test_nanosurf_map_grid_is_its_map_table():
    path = real_file("nanosurf-nid_spectroscopy-map_10x10_Tap150Al.nid")
    text = path.read_bytes()[:400_000].decode("latin-1")
    x0, x1, y0, y1, nx, ny = re.search(r"Map0=([^;]+);([^;]+);([^;]+);([^;]+);(\d+);(\d+)", text).groups()
    nx, ny, x0, x1, y0, y1 = int(nx), int(ny), float(x0), float(x1), float(y0), float(y1)
    table = _table(path)
    (image,) = map_images(table, "modulus")
    # the first curve at (x min, y min): the reader's reading of Map0 (xmin;xmax;ymin;ymax), kept here
    assert image.shape == (ny, nx) == (10, 10)
    assert (image.x0, image.y0) == pytest.approx((x0, y0), abs=1e-12)
    assert (image.dx, image.dy) == pytest.approx(((x1 - x0) / (nx - 1), (y1 - y0) / (ny - 1)), rel=1e-9)
    assert np.isfinite(image.values).all()


def test_bruker_force_volume_grid_is_its_scan_size():
    path = real_file("bruker-nanoscope_force-volume_v9.2_Egel.spm")
    text = path.read_bytes()[:80_000].decode("latin-1")
    image_list = text[text.index("\\*Ciao image list"):]
    n = int(re.search(r"\\Samps/line: (\d+)", image_list).group(1))
    lines = int(re.search(r"\\Number of lines: (\d+)", image_list).group(1))
    size = float(re.search(r"\\Scan Size: ([\d.]+) [\d.]+ ~m", image_list).group(1)) * 1e-6
    table = _table(path)
    (image,) = map_images(table, "modulus")
    assert image.shape == (lines, n) == (16, 16)
    assert (image.dx, image.dy) == pytest.approx((size / n, size / lines), rel=1e-9)
    assert (image.x0, image.y0) == pytest.approx((size / n / 2, size / lines / 2), rel=1e-9)   # cells in the area
    # stored row after row, curve 0 at the bottom left: the reader's reading (Bruker's documents do not
    # say it; this file's 16 x 16 Height image correlates with the contact heights at |r| <= 0.55 in
    # every orientation, so it cannot settle it): kept here so that a change is seen
    np.testing.assert_array_equal(image.values.ravel(), np.arange(n * lines))
