"""A JPK force map's curves sit in the grid cells of their own scan points, read curve by curve
(``afmforce.io.map_curves``, the batch and map path) as in one piece (afmformats).

Was: the curve-by-curve reader put curve ``index/<i>/`` at the i-th cell of the scan order, so a
map saved with some points only -- afmformats' ``map2x2_extracted`` (corpus
``jpk-force-map_2x2``: the four corners (0,0), (9,0), (9,9), (0,9) of a 10 x 10 grid, 600 um
wide) and ``reference-points`` ((9,4), (20,5), (16,16)) -- was drawn as a row of neighbouring
cells (0,0), (1,0), (2,0), (3,0), and the map's image fell back to grid indices instead of its
60 um pixels (the positions no longer matched the cells)."""

from __future__ import annotations

from pathlib import Path

import pytest

from afmforce.io import load
from afmforce.io.map_curves import open_map

CORPUS = Path(__file__).resolve().parents[1] / "data" / "corpus"
MAPS = sorted(CORPUS.glob("jpk-*.jpk-force-map")) + sorted(CORPUS.glob("jpk-*.jpk-qi-data"))


def _cells(curves):
    return [(c.metadata["map_x"], c.metadata["map_y"]) for c in curves]


@pytest.mark.parametrize("path", MAPS, ids=lambda p: p.name)
@pytest.mark.parametrize("format", ["jpk-force", "jpk-zip"])
def test_curve_by_curve_cells_are_the_scan_points_afmformats_gives(path, format):
    afmformats = pytest.importorskip("afmformats")
    try:
        data = afmformats.load_data(path)
    except afmformats.errors.FileFormatNotSupportedError:
        pytest.skip(f"afmformats does not read {path.name}: no reference")
    theirs = [(d.metadata["grid index x"], d.metadata["grid index y"]) for d in data]
    reader = open_map(path, format)
    try:
        ours = _cells(reader.read(i) for i in range(len(reader)))
    finally:
        reader.close()
    assert ours == theirs
    assert _cells(load(path, format=format)) == theirs


def test_the_extracted_corners_are_corners_and_the_image_is_in_um():
    """The four curves of the 2 x 2 extract at the corners of the 10 x 10 grid, 60 um apart (the
    file's positions: 31.97..571.84 um), and its map image in um with 60 um pixels."""
    import numpy as np
    import pandas as pd

    from afmforce.analysis.maps import MAP_QUANTITIES, map_images

    reader = open_map(CORPUS / "jpk-force-map_2x2.jpk-force-map", "jpk-force")
    curves = [reader.read(i) for i in range(len(reader))]
    reader.close()
    assert _cells(curves) == [(0, 0), (9, 0), (9, 9), (0, 9)]
    xs = [c.metadata["position_x"] for c in curves]
    assert (xs[1] - xs[0]) / 9 == pytest.approx(60e-6, rel=1e-3)
    path = str(CORPUS / "jpk-force-map_2x2.jpk-force-map")
    table = pd.DataFrame({"file": path, "curve": range(4), "name": [f"m#{i}" for i in range(4)],
                          "map_x": [x for x, _ in _cells(curves)], "map_y": [y for _, y in _cells(curves)],
                          "map_nx": 10, "map_ny": 10,
                          "position_x": xs, "position_y": [c.metadata["position_y"] for c in curves]})
    table[MAP_QUANTITIES["adhesion"].column] = [-1e-9, -2e-9, -3e-9, -4e-9]
    (image,) = map_images(table, MAP_QUANTITIES["adhesion"])
    assert image.has_positions and image.dx == pytest.approx(60e-6, rel=1e-3)
    assert image.shape == (10, 10) and int(np.isfinite(image.values).sum()) == 4
