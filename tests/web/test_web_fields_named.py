"""Every refusal of the analyse and sweep endpoints names its field (faces audit, 2026-11-29):
an unknown example or reader, no input at all, an empty sweep and a parameter swept twice answered
422 with ``field: null`` before."""

from __future__ import annotations

import pytest

pytest.importorskip("fastapi")


@pytest.mark.parametrize("data, field", [
    ({"example": "bogus"}, "example[0]"),
    ({"example": ["asylum-air", "../x"]}, "example[1]"),
    ({"example": "asylum-air", "format": "bogus"}, "format"),
    ({}, "file"),
])
def test_analyse_refusals_name_their_field(client, data, field):
    r = client.post("/api/analyze", data=data)
    assert r.status_code == 422, r.text
    err = r.json()["error"]
    assert err["field"] == field and err["type"] == "invalid_value", err


@pytest.mark.parametrize("body, field, words", [
    ({}, "grid", "nothing to sweep"),
    ({"grid": ["xi=0.001:0.1:3", "xi=0.001:0.1:3"]}, "grid", "given more than once"),
])
def test_sweep_refusals_name_their_field(client, body, field, words):
    r = client.post("/api/sweep", json=body)
    assert r.status_code == 422, r.text
    err = r.json()["error"]
    assert err["field"] == field and words in err["message"], err
