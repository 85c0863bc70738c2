"""The web fit's curve cap counts every curve of an upload whose reader gives no cheap count.

Before, such a file (not a force map: a WSxM file of 5 curves, a Nanosurf spectroscopy file of 10)
counted as one curve against :data:`afmforce.fit.core.MAX_CURVES`, so 7 uploads of the 5-curve file
(35 curves) were accepted (202) and the job failed inside ``fit_dynamic``; an upload no reader can
read was accepted too and failed in its job. Now the file is read (as the job reads it) and counted,
and an unreadable one is refused at the request naming ``file_ids[i]`` and the name given.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

pytest.importorskip("fastapi")

from afmforce.fit.core import MAX_CURVES  # noqa: E402
from afmforce.io import load  # noqa: E402
from afmforce.sweep.files import plan_curves  # noqa: E402

WSXM = Path(__file__).resolve().parents[1] / "data" / "corpus" / "wsxm-curves_spectrocurve_0001_Normalforce.f.curves"


def _upload(client, files) -> list[str]:
    up = client.post("/api/analyze", files=[("file", f) for f in files], data={"step": "contact"})
    assert up.status_code == 200, up.text
    return [f["id"] for f in up.json()["files"]]


def _client(make_client):
    client = make_client()
    started: list = []
    client.app.state.jobs._start = lambda job: started.append(job.id)     # no process: the request's verdict only
    return client, started


def test_a_file_without_a_cheap_count_counts_all_its_curves(make_client):
    per = len(load(WSXM))                                   # the reader's own count: 5 curves
    assert per == 5
    assert [r.index for r in plan_curves([WSXM])] == [None]  # no header count: the case of this test
    copies = MAX_CURVES // per + 1                          # 7 x 5 = 35 > 32
    client, started = _client(make_client)
    ids = _upload(client, [(f"w{i}.curves", WSXM.read_bytes()) for i in range(copies)])
    r = client.post("/api/fit", json={"file_ids": ids, "free": ["hamaker"], "meta": ["sensitivity=50nm/V"]})
    assert r.status_code == 422, r.text
    err = r.json()["error"]
    assert err["field"] == "file_ids"
    assert err["message"].startswith(f"file_ids: the uploads hold {copies * per} curves")
    assert not started
    r = client.post("/api/fit", json={"file_ids": ids[:MAX_CURVES // per], "free": ["hamaker"],
                                      "meta": ["sensitivity=50nm/V"]})
    assert r.status_code == 202, r.text                     # 30 curves: within the cap
    assert len(started) == 1


def test_an_unreadable_upload_is_refused_at_the_request_by_its_name(make_client):
    client, started = _client(make_client)
    good = _upload(client, [("w.curves", WSXM.read_bytes())])
    bad = _upload(client, [("noise.ibw", os.urandom(4000))])
    r = client.post("/api/fit", json={"file_ids": good + bad, "free": ["hamaker"]})
    assert r.status_code == 422, r.text
    err = r.json()["error"]
    assert err["field"] == "file_ids[1]"
    assert "noise.ibw" in err["message"] and "Igor" in err["message"]
    assert bad[0] not in err["message"]                     # the server's stored name is never shown
    assert not started
