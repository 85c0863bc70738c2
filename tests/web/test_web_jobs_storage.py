"""The storage totals (``--session-storage``, ``--server-storage``) count everything the server writes
for a session -- uploads, its sweeps' stores and its jobs' records with their results -- not uploads
alone: a job that would not fit is refused with the same 413 ``storage_full`` before a process starts,
a finished job's bytes count against the next upload, and deleting the job or the session's expiry
frees them. The bytes are checked against an independent count of the files on disk."""

from __future__ import annotations

import os
import time
from pathlib import Path

import pytest

fastapi = pytest.importorskip("fastapi")

from afmforce.web import jobs as jobs_module  # noqa: E402
from afmforce.web.guard import SESSION_COOKIE  # noqa: E402
from afmforce.web.limits import FIT_RESULT_BYTES_PER_CURVE, JOB_RECORD_BYTES  # noqa: E402
from afmforce.web.sessions import session_key  # noqa: E402

SWEEP = {"sets": ["velocity=1um/s"], "executor": "serial"}


def seed(client, size, name="stored.txt"):
    client.get("/api/files")
    return client.app.state.sessions.save(client.cookies[SESSION_COOKIE], name, b"s" * size)


def on_disk(data: Path, client) -> int:
    """Bytes of the session's files counted here: its folder (all but the index and the stamp) and the
    records of its jobs."""
    key = session_key(client.cookies[SESSION_COOKIE])
    total = 0
    for folder, _, names in os.walk(data / "sessions" / key):
        total += sum(os.path.getsize(os.path.join(folder, n)) for n in names
                     if not (folder == str(data / "sessions" / key) and n in ("index.json", "last-used")))
    for job in client.get("/api/jobs").json():
        record = data / "jobs" / f"{job['id']}.json"
        total += record.stat().st_size if record.exists() else 0
    return total


def settled(sessions, sid, data, client, tries=100):
    """The session's counted bytes and the bytes on disk, once they agree: a finished job's record is
    rewritten by its worker thread just after the state reads "done", so one count may see it and the
    other not; what must hold is that they agree once nothing is being written (at most ``tries`` x 0.1 s)."""
    for _ in range(tries):
        stored, disk = sessions.stored_bytes(sid), on_disk(data, client)
        if stored == disk and sessions.stored_bytes(sid) == stored:
            break
        time.sleep(0.1)
    return stored, disk


def finish(client, job_id, limit=300.0):
    deadline = time.monotonic() + limit
    while (state := client.get(f"/api/jobs/{job_id}").json())["state"] == "running" and time.monotonic() < deadline:
        time.sleep(0.2)
    return state


def test_a_fit_that_would_not_fit_is_refused_before_a_process_starts(make_client):
    client = make_client(session_storage=1_000_000, server_storage=100_000_000)
    seed(client, 400_000)
    refused = client.post("/api/fit", json={"velocities": [1e-6, 4e-6], "truth": {"xi": 0.005}})
    assert refused.status_code == 413
    error = refused.json()["error"]
    need = JOB_RECORD_BYTES + 2 * FIT_RESULT_BYTES_PER_CURVE        # two curves' results, at most
    assert error["type"] == "storage_full" and "\n" not in error["message"]
    assert f"{need:,} bytes more would pass the 1 MB a session may store (this fit's results, at most)" \
        in error["message"]
    assert "400,000 bytes" in error["message"] and "DELETE /api/jobs/ID" in error["message"]
    assert client.get("/api/jobs").json() == [] and client.app.state.jobs.processes() == []


def test_the_servers_total_counts_jobs_too(make_client):
    first = make_client(session_storage=10_000_000, server_storage=1_000_000)
    second = make_client(session_storage=10_000_000, server_storage=1_000_000)
    seed(first, 600_000)
    refused = second.post("/api/fit", json={"velocities": [1e-6, 4e-6], "truth": {"xi": 0.005}})
    assert refused.status_code == 413 and "the server keeps 600,000 bytes" in refused.json()["error"]["message"]
    assert second.get("/api/jobs").json() == []


def test_sweep_results_count_and_are_freed_by_delete_and_by_expiry(make_client, tmp_path, monkeypatch):
    data = tmp_path / "jobsdata"
    client = make_client(data=data, session_storage=50_000_000, server_storage=500_000_000)
    sessions = client.app.state.sessions
    sid = client.cookies.get(SESSION_COOKIE) or (client.get("/api/files") and client.cookies[SESSION_COOKIE])
    ids = [client.post("/api/sweep", json={"grid": [grid], **SWEEP}).json()["id"]
           for grid in ("xi=0.01,0.1", "xi=0.02,0.2")]
    for job_id in ids:
        assert finish(client, job_id)["state"] == "done"
        store = data / "sessions" / session_key(sid) / "sweeps" / job_id
        assert list(store.glob("sweep-*/results.parquet"))        # the store lives in the session's folder
    stored, disk = settled(sessions, sid, data, client)
    assert stored == disk > 0                                     # all of it counted, nothing else
    assert stored <= 2 * jobs_module.sweep_reserve(2, 2)          # the declared most held while they ran
    assert client.get("/api/session").json()["stored"] == stored
    # no upload yet, but the results fill the session: an upload past the total is refused
    monkeypatch.setattr(sessions, "session_bytes", stored + 100)
    refused = client.post("/api/analyze", files=[("file", ("x.txt", b"x" * 200))])
    assert refused.status_code == 413 and f"{stored:,} bytes" in refused.json()["error"]["message"]
    # deleting a job frees its record and its store at once
    assert client.delete(f"/api/jobs/{ids[0]}").status_code == 200
    assert not (data / "sessions" / session_key(sid) / "sweeps" / ids[0]).exists()
    assert not (data / "jobs" / f"{ids[0]}.json").exists()
    assert client.get(f"/api/jobs/{ids[0]}").status_code == 404
    left, disk = settled(sessions, sid, data, client)
    assert left == disk and 0 < left < stored
    assert client.post("/api/analyze", files=[("file", ("x.txt", b"x" * 200))]).status_code != 413
    # the session's expiry frees the rest: its folder (uploads, stores) and its jobs' records
    gone = sessions.expire(now=time.time() + sessions.ttl + 10)
    client.app.state.jobs.expire(gone, sessions.ttl, live=sessions.keys())
    assert session_key(sid) in gone and sessions.stored_bytes() == 0
    assert not (data / "jobs" / f"{ids[1]}.json").exists()


def test_a_running_job_cannot_be_deleted(make_client):
    client = make_client()
    job_id = client.post("/api/fit", json={"velocities": [1e-6, 4e-6], "truth": {"xi": 0.005}}).json()["id"]
    r = client.delete(f"/api/jobs/{job_id}")
    assert r.status_code == 422 and "cancel it first" in r.json()["error"]["message"]
    client.post(f"/api/jobs/{job_id}/cancel")
    assert finish(client, job_id)["state"] == "cancelled"
    assert client.delete(f"/api/jobs/{job_id}").status_code == 200 and client.get("/api/jobs").json() == []
    assert make_client().delete(f"/api/jobs/{job_id}").status_code == 404      # never another session's


def test_results_past_the_total_are_not_kept(make_client, tmp_path, monkeypatch):
    """A job whose declared most under-counts (here made 0) and whose results pass the total fails saying
    so, and its store is removed: nothing over the totals stays on disk."""
    monkeypatch.setattr(jobs_module, "SWEEP_BYTES_PER_VALUE", 0)
    monkeypatch.setattr(jobs_module, "JOB_RECORD_BYTES", 0)
    data = tmp_path / "smalldata"
    client = make_client(data=data, session_storage=5_000, server_storage=1_000_000)
    job_id = client.post("/api/sweep", json={"grid": ["xi=0.01,0.1"], **SWEEP}).json()["id"]
    state = finish(client, job_id)
    assert state["state"] == "failed" and "results were not kept" in state["error"]
    assert "5,000 bytes a session may store (this sweep's results)" in state["error"]
    sid = client.cookies[SESSION_COOKIE]
    assert not (data / "sessions" / session_key(sid) / "sweeps" / job_id).exists()
    assert client.app.state.sessions.stored_bytes(sid) == on_disk(data, client) < 5_000
