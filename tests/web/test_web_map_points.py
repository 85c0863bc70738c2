"""The web shows force maps whose positions form no grid (``layout=points`` in the CLI's HDF5) as points at the
recorded positions, as the CLI's PNG: before (findings 2026-11-29) the page had no map of them at all (its
``maps`` held the grid images only). The payload's points carry the positions, the curves and the values of
:func:`afmforce.analysis.maps.map_points`, the same numbers as the curves' own results."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("fastapi")

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "io"))
from _park_build import write_park  # noqa: E402


def test_the_web_draws_free_points_at_their_positions(client, tmp_path):
    path = write_park(tmp_path / "free.tiff", points=5)       # spectra at x = 1..5 um, y = 2 um, no grid
    r = client.post("/api/analyze", files={"file": (path.name, path.read_bytes())}, data={"arrays": "true"})
    assert r.status_code == 200, r.text[:300]
    body = r.json()
    points = [m for m in body["maps"] if m.get("layout") == "points"]
    assert points and not [m for m in body["maps"] if m.get("layout") == "grid"]
    adhesion = next(m for m in points if m["quantity"] == "adhesion")
    np.testing.assert_allclose(adhesion["x_um"], 1.0 + np.arange(5), rtol=1e-6)
    np.testing.assert_allclose(adhesion["y_um"], [2.0] * 5, rtol=1e-6)
    assert adhesion["curves"] == [f"free.tiff#{i}" for i in range(5)] and "no grid" in adhesion["why"]
    given = 0
    for name, value in zip(adhesion["curves"], adhesion["z"]):    # the map's adhesion: the depth of the dip
        own = body["results"][name]["adhesion_force"]
        if value is None:                                          # no value: none made up
            assert own is None
            continue
        assert value == pytest.approx(-own, rel=1e-12)
        given += 1
    assert given >= 3


def test_the_page_draws_a_points_map_as_a_scatter():
    js = (Path(__file__).resolve().parents[2] / "src" / "afmforce" / "web" / "static" / "app.js").read_text()
    assert 'if (m.layout === "points") return drawMapPoints(div, m, f, u);' in js
    assert "function drawMapPoints(div, m, f, u)" in js and 'type: "scatter", mode: "markers"' in js
