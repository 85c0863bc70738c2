"""The analyse view's fast re-run paths (issue 33 item 7): what they skip must not change a number.

The speed itself is measured by ``benchmarks/bench_web.py``; these tests check that the shortcuts
give what the full path gives: a curve re-read with a new calibration from memory equals a fresh
reading with it (and the CLI's ``--spring-constant``), the arrays thinned for the screen keep each
screen column's extremes and the segment ends, and a map sends the arrays of the curve drawn only.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

fastapi = pytest.importorskip("fastapi")

DATA = Path(__file__).resolve().parents[1] / "data"


def test_screen_indices_keep_every_columns_extremes_and_the_segment_ends():
    from afmforce.web.plotdata import screen_indices

    rng = np.random.default_rng(3)
    y = rng.normal(size=10_000)
    y[4321] = 50.0                      # a spike between two evenly spread samples
    y[777] = np.nan                     # never chosen as an extreme
    seg = np.r_[np.zeros(6000, int), np.ones(4000, int)]
    idx = screen_indices(y, seg, 1000)
    assert len(idx) <= 1000 + 4 and np.all(np.diff(idx) > 0)
    assert 4321 in idx and 777 not in idx
    assert {0, 5999, 6000, 9999} <= set(idx.tolist())
    columns = (np.arange(y.size) * (1000 // 2 - 2)) // y.size       # independently: per column
    for c in (0, 17, 250, 497):
        members = np.flatnonzero(columns == c)
        finite = members[np.isfinite(y[members])]
        assert finite[np.argmin(y[finite])] in idx and finite[np.argmax(y[finite])] in idx
    assert np.array_equal(screen_indices(y, seg, None), np.arange(y.size))


@pytest.mark.parametrize("file", ["afmforce-raw_jpk-cellhesion-spot3.txt",       # afmforce's own: from memory
                                  "asylum-mfp3d_SiN-tip_air.ibw"])                # another reader: read again
def test_a_calibration_change_read_from_memory_equals_a_fresh_reading(client, make_client, file):
    """The spring constant given after the upload: the re-run (curve from memory, metadata replaced)
    gives the numbers of a new session that uploads the file with that spring constant at once."""
    src = DATA / file
    data = src.read_bytes()
    first = client.post("/api/analyze", files={"file": (src.name, data)}, data={"arrays": "true"}).json()
    fid = first["files"][0]["id"]
    k = "spring_constant=0.123N/m"
    again = client.post("/api/analyze", data={"file_id": fid, "probe": k, "arrays": "true"}).json()
    other = make_client()       # a new session (a fresh cookie jar)
    cold = other.post("/api/analyze", files={"file": (src.name, data)}, data={"probe": k, "arrays": "true"}).json()
    (name, a), = again["results"].items()
    b = cold["results"][name]
    assert a["spring_constant"] == pytest.approx(0.123) and b["spring_constant"] == pytest.approx(0.123)
    for key in ("adhesion_force", "pull_off_force", "jump_in_force", "hamaker_radius", "force"):
        assert a[key] == b[key], key
    assert first["results"][name]["adhesion_force"] != a["adhesion_force"]      # the change took effect


def test_a_map_sends_the_arrays_of_the_curve_drawn(client):
    """With ``curve``, the per-sample arrays and raw signal of that curve only (the first when none
    matches); every curve's numbers are there; the same curve's arrays as when every curve is sent."""
    src = DATA / "afmforce-map_jpk-map2x2.h5"
    up = client.post("/api/analyze", files={"file": (src.name, src.read_bytes())}, data={"arrays": "true"}).json()
    names = list(up["results"])
    assert len(names) == 4 and all("force" in up["results"][n] for n in names)
    fid = up["files"][0]["id"]
    one = client.post("/api/analyze", data={"file_id": fid, "arrays": "true", "curve": names[2]}).json()
    assert one["arrays_for"] == [names[2]] and list(one["raw"]) == [names[2]]
    assert "force" in one["results"][names[2]] and all("force" not in one["results"][n] for n in names if n != names[2])
    assert all(one["results"][n]["adhesion_force"] == up["results"][n]["adhesion_force"] for n in names)
    assert one["results"][names[2]]["force"] == up["results"][names[2]]["force"]
    first = client.post("/api/analyze", data={"file_id": fid, "arrays": "true", "curve": ""}).json()
    assert first["arrays_for"] == [names[0]]
