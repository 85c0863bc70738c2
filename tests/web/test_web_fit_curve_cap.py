"""The web's fit refuses uploads holding more curves than the dynamic fit takes
(:data:`afmforce.fit.core.MAX_CURVES`) at the request (422 naming ``file_ids``); before, the request
was accepted (202) and the job failed inside ``fit_dynamic`` after reading every curve."""

from __future__ import annotations

from pathlib import Path

import pytest

pytest.importorskip("fastapi")

from afmforce.fit.core import MAX_CURVES  # noqa: E402
from afmforce.io.nanoscope import count_curves  # noqa: E402

MAP = Path(__file__).resolve().parents[1] / "data" / "bruker-nanoscope_force-volume_2x2_trimmed.spm"


def _upload(client, copies: int) -> list[str]:
    data = MAP.read_bytes()
    files = [("file", (f"map{i}.spm", data)) for i in range(copies)]
    up = client.post("/api/analyze", files=files, data={"step": "contact"})
    assert up.status_code == 200, up.text
    return [f["id"] for f in up.json()["files"]]


def test_uploads_past_the_fit_s_curve_cap_are_refused_at_the_request(make_client):
    per = count_curves(MAP)                              # the map's grid, from its header: 2 x 2
    assert per == 4
    copies = MAX_CURVES // per + 1                       # one map more than the cap holds
    client = make_client()
    started: list = []
    client.app.state.jobs._start = lambda job: started.append(job.id)
    ids = _upload(client, copies)
    assert len(ids) == copies
    r = client.post("/api/fit", json={"file_ids": ids, "free": ["hamaker"]})
    assert r.status_code == 422, r.text
    err = r.json()["error"]
    assert err["type"] == "invalid_value" and err["field"] == "file_ids"
    assert err["message"].startswith(f"file_ids: the uploads hold {copies * per} curves")
    assert f"takes at most {MAX_CURVES}" in err["message"]
    assert not started                                   # no job, no process
    r = client.post("/api/fit", json={"file_ids": ids[:MAX_CURVES // per], "free": ["hamaker"]})
    assert r.status_code == 202, r.text                  # exactly the cap: accepted (its job would run)
    assert len(started) == 1
