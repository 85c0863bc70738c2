"""The web's force-map images carry the note of a quantity no curve gave
(:attr:`afmforce.analysis.maps.MapImage.note`), as the CLI and the PNG say it."""

from __future__ import annotations

from pathlib import Path

import pytest

pytest.importorskip("fastapi")

NID = Path(__file__).resolve().parents[1] / "data" / "nanosurf-nid_spectroscopy-map_2x2_trimmed.nid"


def test_the_web_map_carries_the_note(client):
    r = client.post("/api/analyze", files={"file": (NID.name, NID.read_bytes())},
                    data={"arrays": "true", "option": ["indentation.model=hertz_paraboloid"]})
    assert r.status_code == 200, r.text[:300]
    maps = {m["quantity"]: m for m in r.json()["maps"]}
    assert maps["adhesion"]["note"] == ""
    assert "indentation" in maps and maps["indentation"]["note"].startswith("no curve gave it (4 curves: 4 hard")
