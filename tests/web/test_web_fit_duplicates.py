"""The web's fit refuses an upload listed twice in ``file_ids`` (422 naming the field) before a job
starts; before, the job fitted the one curve as two (every interval tighter by sqrt(2))."""

from __future__ import annotations

import pytest

pytest.importorskip("fastapi")

from afmforce.datasets import fit_example  # noqa: E402


def test_the_web_refuses_an_upload_listed_twice(make_client):
    client = make_client()
    p = fit_example("speeds")[0]
    up = client.post("/api/analyze", files={"file": (p.name, p.read_bytes())}, data={"step": "contact"})
    fid = up.json()["files"][0]["id"]
    r = client.post("/api/fit", json={"file_ids": [fid, fid], "free": ["hamaker"]})
    assert r.status_code == 422
    assert r.json()["error"] == {"type": "invalid_value", "field": "file_ids",
                                 "message": f"file_ids: {fid} is listed twice; give each upload once"}
