"""The reproductions of issue 33 as regression tests: validation, leaks, budgets, origins, sessions."""

from __future__ import annotations

import json
import os
import threading
import time

import pytest

fastapi = pytest.importorskip("fastapi")
psutil = pytest.importorskip("psutil")

from afmforce.web import Settings, create_app  # noqa: E402


def _raw(client, url, text):
    return client.post(url, content=text.encode(), headers={"content-type": "application/json"})


def _error(r, status=422):
    assert r.status_code == status, (r.status_code, r.text[:300])
    err = r.json()["error"]
    assert set(err) == {"type", "message", "field"} and err["message"]
    return err


# -- 1. one validation ---------------------------------------------------------------------------
def test_fit_with_a_nan_velocity_is_refused_and_leaks_nothing(workers, make_client):
    """Was: 500, a ~190 MB worker left alive and a job 'running' for ever, each call."""
    c = make_client()
    before = workers()
    for _ in range(3):
        err = _error(_raw(c, "/api/fit", '{"velocities":[NaN,1e-6],"profile":false,"compare":false}'))
        assert err["field"] == "velocities[0]" and "finite" in err["message"]
    assert c.get("/api/jobs").json() == []
    assert c.app.state.jobs.processes() == [] and workers() == before
    assert c.get("/api/health").json()["jobs_running"] == 0


@pytest.mark.parametrize("url", ["/api/simulate", "/api/simulate/raw"])
@pytest.mark.parametrize("body, field", [({"velocity": "abc"}, "velocity"), ({"velocity": [1e-6]}, "velocity"),
                                         ({"max_steps": 1e300}, "max_steps"), ({"xi": 200}, "xi"),
                                         ({"hamaker": 2e-17}, "hamaker"),
                                         ({"model": "spring", "spring_constant": 5000}, "spring_constant")])
def test_simulate_refuses_what_the_cli_refuses(client, url, body, field):
    """Was: 500 for text, lists and 1e300; 200 for values out of the declared ranges."""
    from afmforce.dynamics.config import FLAT

    err = _error(client.post(url, json=body))
    assert err["field"] == field and err["type"] == "invalid_value"
    spec = FLAT[field].spec
    value = body[field]
    if isinstance(value, (int, float)) and value < 1e300:    # the range the page shows, in the message
        assert spec.range_text() in err["message"] and not spec.contains(value)


def test_the_same_values_are_refused_by_the_cli(tmp_path):
    """The web refuses what the command line refuses: the same declared range."""
    import subprocess
    import sys

    from afmforce.dynamics.config import FLAT

    for flag, value in (("--xi", "200"), ("--hamaker", "2e-17")):
        out = subprocess.run([sys.executable, "-m", "afmforce.cli.main", "simulate", flag, value, "--out",
                              str(tmp_path / "x.h5")], capture_output=True, text=True,
                             env={**os.environ, "PYTHONPATH": os.environ.get("PYTHONPATH", "")}, timeout=120)
        assert out.returncode == 2 and FLAT[flag[2:]].spec.range_text() in out.stderr, out.stderr


def test_unit_texts_are_read_by_the_librarys_parser(client):
    """Decision: a value may be a text with units, read by afmforce.units (as the CLI reads it)."""
    a = client.post("/api/simulate?max_points=100", json={"velocity": "1um/s"}).json()
    b = client.post("/api/simulate?max_points=100", json={"velocity": 1e-6}).json()
    assert a["config"]["velocity"] == 1e-6 and a["summary"]["pull_off"] == b["summary"]["pull_off"]
    err = _error(client.post("/api/simulate", json={"velocity": "1 kg"}))
    assert err["field"] == "velocity"


def test_fit_refuses_bad_truth_and_negative_speeds(workers, client):
    before = workers()
    err = _error(client.post("/api/fit", json={"velocities": [1e-6, 2e-6], "truth": {"xi": "abc"}}))
    assert err["field"] == "truth.xi"
    err = _error(client.post("/api/fit", json={"velocities": [-1e-6, 0], "profile": False, "compare": False}))
    assert err["field"] == "velocities[0]" and "out of range" in err["message"]
    err = _error(client.post("/api/fit", json={"velocities": [1e-6, 2e-6], "truth": {"xi": 200}}))
    assert err["field"] == "truth.xi"
    assert workers() == before and client.get("/api/jobs").json() == []


def test_a_huge_sweep_grid_is_refused_before_anything_is_made(workers, client):
    """Was: a worker that grew to 3 GB before it refused. Now 422 at once, and the server did not
    make the grid either (its memory stays within a few MB)."""
    before = workers()
    rss = psutil.Process().memory_info().rss
    err = _error(client.post("/api/sweep", json={"grid": ["xi=0.001:0.1:100000000:log"]}))
    assert err["field"] == "grid[0]" and "100,000,000" in err["message"]
    assert psutil.Process().memory_info().rss - rss < 100e6        # 1e8 floats would be 800 MB
    err = _error(client.post("/api/sweep", json={"grid": ["xi=0.001:0.1:200:log", "hamaker=1e-20:1e-19:200"]}))
    assert err["field"] == "grid" and "40,000" in err["message"]
    err = _error(client.post("/api/sweep", json={"grid": ["xi=-0.1:0.1:3"]}))
    assert err["field"] == "grid[0]" and "xi" in err["message"]
    err = _error(client.post("/api/sweep", json={"grid": ["xi=0.01,0.1"], "sets": ["sample_rate=1e8",
                                                                                     "velocity=1e-9"]}))
    assert "samples" in err["message"]
    assert workers() == before and client.get("/api/jobs").json() == []


def test_simulation_size_is_bounded(client):
    """Was: max_points=2000000 with sample_rate 6e5 grew the server by 1.6 GB. Now the response
    carries at most RESPONSE_POINTS per column, and a cycle at most MAX_SAMPLES samples."""
    from afmforce.web.limits import MAX_SAMPLES, RESPONSE_POINTS

    err = _error(client.post("/api/simulate?max_points=2000000", json={"sample_rate": 6e5}))
    assert err["field"] == "max_points"
    err = _error(client.post("/api/simulate", json={"sample_rate": 6e5}))   # 1.86e6 samples
    assert err["field"] == "sample_rate" and f"{MAX_SAMPLES:,}" in err["message"]
    from afmforce import limits
    assert MAX_SAMPLES is limits.SERVER_MAX_SAMPLES     # declared with the library's caps
    r = client.post("/api/simulate", json={"sample_rate": 1e5}).json()       # 310,001 samples
    assert r["n_samples"] > RESPONSE_POINTS and len(r["columns"]["time"]) <= RESPONSE_POINTS
    err = _error(client.post("/api/simulate/raw", json={"sample_rate": 1e5}))
    assert err["field"] == "sample_rate" and "rows" in err["message"]


def test_an_analysis_past_its_budget_stops_computing(monkeypatch, tmp_path):
    """The analysis thread stops after the curve it is on once the deadline is past (cooperative
    cancellation), instead of computing on after the 504."""
    from afmforce.web import analysis
    from afmforce.web.replies import PastBudget

    calls = []
    real = analysis.CachedAnalysis.__call__

    def counting(self, ref):
        calls.append(ref)
        return real(self, ref)

    monkeypatch.setattr(analysis.CachedAnalysis, "__call__", counting)
    from afmforce.datasets import path

    src = path("asylum-air")
    files = []
    for i in range(3):
        p = tmp_path / f"c{i}{src.suffix}"
        p.write_bytes(src.read_bytes())
        files.append((p, p.name))
    with pytest.raises(PastBudget):
        analysis.run_analysis(files, guard=False, deadline=time.monotonic() - 1)
    assert len(calls) <= 1          # the first curve (in its chunk), not the three


def test_a_job_that_cannot_be_saved_is_failed_and_its_process_reaped(workers, tmp_path, monkeypatch):
    from afmforce.web.jobs import JobManager
    from afmforce.web.replies import JobStartError

    jobs = JobManager(tmp_path, spare=False)
    before = workers()

    def broken(job):
        raise OSError("disk full")

    monkeypatch.setattr(jobs, "_save", broken)
    with pytest.raises(JobStartError, match="disk full"):
        jobs.submit("fit", "s" * 40, {"velocities": [1e-6, 2e-6]})
    job = jobs.list("s" * 40)[0]
    assert job.state == "failed" and "disk full" in job.error
    assert jobs.processes() == [] and workers() == before
    jobs.shutdown()


def test_shutdown_stops_every_worker(workers, tmp_path):
    """A running fit and the warm spare: both stopped when the server stops."""
    from afmforce.web.jobs import JobManager

    jobs = JobManager(tmp_path, spare=True)
    before = workers()
    jobs.start_spare()
    jobs.submit("fit", "s" * 40, {"velocities": [1e-6, 2e-6, 4e-6], "truth": {"xi": 0.01}})
    assert len(jobs.processes()) == 2 and workers() >= before + 2
    jobs.shutdown()
    assert jobs.processes() == []
    deadline = time.monotonic() + 300
    while workers() > before and time.monotonic() < deadline:
        time.sleep(0.1)
    assert workers() == before


def test_a_result_that_cannot_be_saved_fails_the_job(tmp_path):
    """A report the record cannot carry (NaN): the job fails instead of 'running' for ever."""
    import queue

    from afmforce.web.jobs import Job, JobManager

    jobs = JobManager(tmp_path, spare=False)

    class Dead:
        exitcode = 0

        def is_alive(self):
            return False

        def join(self, timeout=None):
            pass

    q = queue.Queue()
    q.put(("result", {"value": float("nan")}))
    job = Job("a" * 16, "fit", "o" * 32, {})
    jobs._jobs[job.id] = job
    jobs._watch(job, Dead(), q, None)
    assert job.state == "failed" and "could not be saved" in job.error
    assert json.loads((tmp_path / "jobs" / f"{job.id}.json").read_text())["state"] == "failed"


# -- 2. origins ----------------------------------------------------------------------------------
def test_null_and_foreign_origins_cannot_write(client, tmp_path):
    before = sorted(p.name for p in (tmp_path / "data").rglob("*"))
    for origin in ("null", "http://evil.example", "http://127.0.0.1.evil.example"):
        h = {"origin": origin}
        err = _error(client.post("/api/simulate", json={}, headers=h), 403)
        assert err["type"] == "forbidden"
        assert client.post("/api/analyze", data={"example": "asylum-air"}, files={"file": ("x.ibw", b"x")},
                           headers=h).status_code == 403
        assert client.post("/api/fit", json={"velocities": [1e-6, 2e-6]}, headers=h).status_code == 403
    # a write without Origin that the browser marks as sent by another site
    assert client.post("/api/simulate", json={}, headers={"sec-fetch-site": "cross-site"}).status_code == 403
    assert sorted(p.name for p in (tmp_path / "data").rglob("*")) == before      # nothing stored
    assert client.get("/api/jobs").json() == []
    # the server's own page, and a client that is not a browser (no Origin), may
    own = client.post("/api/simulate?max_points=100", json={}, headers={"origin": "http://127.0.0.1"})
    assert own.status_code == 200
    assert client.post("/api/simulate?max_points=100", json={}).status_code == 200


def test_allow_origin_lets_a_listed_page_write(make_client):
    c = make_client(allow_origins=("https://lab.example.org",))
    ok = c.post("/api/simulate?max_points=100", json={}, headers={"origin": "https://lab.example.org"})
    assert ok.status_code == 200 and ok.headers["access-control-allow-origin"] == "https://lab.example.org"
    pre = c.options("/api/simulate", headers={"origin": "https://lab.example.org",
                                              "access-control-request-method": "POST",
                                              "access-control-request-headers": "content-type"})
    assert pre.status_code == 200
    assert c.post("/api/simulate", json={}, headers={"origin": "https://other.example.org"}).status_code == 403
    assert c.post("/api/simulate", json={}, headers={"origin": "null"}).status_code == 403


def test_allow_origin_must_be_an_origin():
    from afmforce.errors import ParameterError
    from afmforce.web import Settings

    for bad in ("null", "*", "lab.example.org", "https://lab.example.org/path", "ftp://x.org"):
        with pytest.raises(ParameterError, match="allow-origin"):
            Settings(allow_origins=(bad,))
    assert Settings(allow_origins=("HTTPS://Lab.Example.org:8443/",)).allow_origins == ("https://lab.example.org:8443",)


# -- 3. sessions ---------------------------------------------------------------------------------
def test_a_cookie_less_request_costs_nothing(client, tmp_path):
    sessions = tmp_path / "data" / "sessions"
    for url in ("/", "/api/health", "/api/files", "/api/jobs", "/api/session", "/api/schema"):
        client.cookies.clear()
        assert client.get(url).status_code == 200
        client.post("/api/analyze", data={"file_id": "0" * 32})           # refused: nothing stored
    assert not sessions.exists() or not any(sessions.iterdir())


def test_a_session_survives_a_reload_and_lists_its_uploads(make_client):
    from afmforce.datasets import path

    c = make_client()
    src = path("asylum-air")
    first = c.post("/api/analyze", files={"file": (src.name, src.read_bytes())}).json()
    fid = first["files"][0]["id"]
    # a reload: the same cookie, a new page; the page asks what the session holds
    state = c.get("/api/session").json()
    assert [f["id"] for f in state["files"]] == [fid] and state["files"][0]["name"] == src.name
    assert state["ttl"] == 24 * 3600 and state["expires"] > time.time() + 23 * 3600
    again = c.post("/api/analyze", data={"file_id": fid}).json()          # reopened: the same result
    assert again["results"][src.name] == first["results"][src.name]
    assert c.delete(f"/api/files/{fid}").status_code == 200 and c.get("/api/files").json() == []


def test_a_requests_budget_starts_after_the_servers_warm_up(make_client, monkeypatch):
    """The race behind the reload test's failure under load: its first upload came while the server's
    warm-up was compiling the kernels (cold cache), waited for numba's compile lock inside its own
    60 s and came back 504 past_budget. Now the budget starts when the warm-up has ended: the
    warm-up here ends only after the upload has been stored, and the analysis' deadline is taken
    after that (an order of events, read on one clock; no wait is a verdict)."""
    import threading

    import afmforce.web.app as web_app
    import afmforce.web.routes_analyze as routes
    from afmforce.datasets import path

    arrived, seen = threading.Event(), {}

    def warm_up():              # the warm-up ends after the upload has reached the server
        arrived.wait()
        seen["warm_end"] = time.monotonic()
        return []

    def analysis(*args, deadline, budget, **kw):
        seen["deadline"], seen["budget"] = deadline, budget
        return run_analysis(*args, deadline=deadline, budget=budget, **kw)

    run_analysis = routes.run_analysis
    monkeypatch.setattr(web_app, "warm_up_steps", warm_up)
    monkeypatch.setattr(routes, "run_analysis", analysis)
    c = make_client()
    sessions = c.app.state.sessions
    save_all = sessions.save_all

    def stored(*a, **k):
        out = save_all(*a, **k)
        arrived.set()
        return out

    monkeypatch.setattr(sessions, "save_all", stored)
    src = path("asylum-air")
    try:
        r = c.post("/api/analyze", files={"file": (src.name, src.read_bytes())})
    finally:
        arrived.set()           # the warm-up thread never outlives the test
    assert r.status_code == 200 and r.json()["results"][src.name]["pull_off_force"] < 0
    assert seen["deadline"] >= seen["warm_end"] + seen["budget"]
    assert c.get("/api/health").json()["warm"] is True


def test_sessions_expire_after_their_ttl(make_client, tmp_path):
    from afmforce.datasets import path

    c = make_client(session_ttl=3600)
    src = path("asylum-air")
    fid = c.post("/api/analyze", files={"file": (src.name, src.read_bytes())}).json()["files"][0]["id"]
    job = c.post("/api/fit", json={"velocities": [1e-6, 2e-6]}).json()["id"]
    c.post(f"/api/jobs/{job}/cancel")
    deadline = time.monotonic() + 300
    while c.get(f"/api/jobs/{job}").json()["state"] == "running" and time.monotonic() < deadline:
        time.sleep(0.1)
    sessions = c.app.state.sessions
    folders = list((tmp_path / "data" / "sessions").iterdir())
    assert len(folders) == 1
    assert sessions.expire(now=time.time() + 1800) == []                  # within the ttl: kept
    gone = sessions.expire(now=time.time() + 3601)
    assert gone == [folders[0].name] and not folders[0].exists()
    assert c.app.state.jobs.expire(gone, 3600) == [job]
    assert c.get("/api/files").json() == [] and c.get(f"/api/jobs/{job}").status_code == 404
    err = _error(c.post("/api/analyze", data={"file_id": fid}))
    assert "no uploaded file" in err["message"]
    cookie = c.get("/api/health").headers["set-cookie"]
    assert "Max-Age=3600" in cookie and "HttpOnly" in cookie and "SameSite=Strict" in cookie


def test_session_ttl_is_checked():
    from afmforce.errors import ParameterError
    from afmforce.web import Settings

    with pytest.raises(ParameterError, match="session-ttl"):
        Settings(session_ttl=1)


def test_a_chunked_upload_over_the_limit_gets_413(make_client):
    """Was: 400 (the multipart parser's error) when no Content-Length announced the size."""
    c = make_client(max_upload=10_000)

    def chunks():
        yield b"--b\r\ncontent-disposition: form-data; name=\"file\"; filename=\"x.ibw\"\r\n\r\n"
        for _ in range(100):
            yield b"x" * 1000
        yield b"\r\n--b--\r\n"

    r = c.post("/api/analyze", content=chunks(), headers={"content-type": "multipart/form-data; boundary=b"})
    err = _error(r, 413)
    assert err["type"] == "too_large" and "10,000" in err["message"]
    assert c.get("/api/health").status_code == 200


def test_serve_reads_the_new_options():
    from afmforce.cli.serve import session_ttl
    from afmforce.errors import ParameterError

    assert session_ttl("24h") == 86400 and session_ttl("30min") == 1800 and session_ttl("2d") == 172800
    assert session_ttl("600") == 600
    with pytest.raises(ParameterError, match="session-ttl"):
        session_ttl("soon")


def test_errors_of_fastapi_never_reach_the_client(client):
    err = _error(client.post("/api/fit", json={"velocities": [1e-6, 2e-6], "starts": "three"}))
    assert err["field"] == "starts" and err["type"] == "invalid_request"
    err = _error(client.post("/api/fit", json={"velocities": [1e-6, 2e-6], "bogus": 1}))
    assert err["field"] == "bogus"
    r = client.get("/api/jobs/nope")
    assert r.status_code == 404 and r.json()["error"]["type"] == "not_found"


def test_an_app_whose_lifespan_never_ran_does_not_wait_for_a_warm_up(tmp_path):
    """A ``TestClient`` used without ``with`` (or an ASGI server with its lifespan off) starts no warm-up:
    an analysis must not wait for one (it waited forever: the whole suite hung in test_declared_ranges
    after the warm-up wait was added). The request runs in a thread joined with a bound, so this test
    cannot hang the suite itself."""
    from fastapi.testclient import TestClient

    from afmforce.datasets import path

    app = create_app(Settings(data=tmp_path / "data", spare_job=False))
    client = TestClient(app, base_url="http://127.0.0.1")      # no __enter__: the lifespan does not run
    assert not app.state.warming.is_set() and not app.state.warm.is_set()
    src = path("asylum-air")
    answer = {}
    t = threading.Thread(target=lambda: answer.setdefault(
        "r", client.post("/api/analyze", files={"file": (src.name, src.read_bytes())})), daemon=True)
    t.start()
    t.join(300)
    assert "r" in answer, "the analysis request waited for a warm-up that never started"
    assert answer["r"].status_code == 200 and answer["r"].json()["files"]
