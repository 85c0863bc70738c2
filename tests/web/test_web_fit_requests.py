"""Fits and sweeps a client may start: bounded in number, refused before a process starts when
the data cannot answer."""

from __future__ import annotations

import pytest

fastapi = pytest.importorskip("fastapi")

from afmforce.web.limits import MAX_JOBS, MAX_SESSION_JOBS  # noqa: E402


@pytest.fixture
def recorded(client):
    """``client`` whose jobs are recorded as running without their process (the cap counts the
    records); returns the client and the ids started."""
    started: list = []

    def start(job):
        job.state = "running"
        started.append(job.id)

    client.app.state.jobs._start = start
    return client, started


def _as_session(client, n: int) -> None:
    client.cookies.clear()
    client.cookies.set("afmforce_session", f"{n:032d}")


def test_running_jobs_are_capped_per_session_and_per_server(recorded, workers):
    """Before: every POST /api/fit started a process, so a client looping over it started one per
    request until the machine's memory ran out. Now the session's third (the server's fifth) is
    refused with 429 and one readable line, and a cancelled job frees its slot."""
    client, started = recorded
    before = workers()
    body = {"velocities": [1e-6, 4e-6]}
    _as_session(client, 0)
    ids = [client.post("/api/fit", json=body).json()["id"] for _ in range(MAX_SESSION_JOBS)]
    r = client.post("/api/sweep", json={"grid": ["xi=0.001,0.01"]})
    assert r.status_code == 429, r.text
    err = r.json()["error"]
    assert err["type"] == "too_many_jobs" and f"a session may run {MAX_SESSION_JOBS}" in err["message"]
    client.app.state.jobs._jobs[ids[0]].state = "cancelled"       # what the watcher does on cancel
    assert client.post("/api/fit", json=body).status_code == 202
    answers = []
    for n in range(1, MAX_JOBS + 1):                               # other sessions: the server's cap
        _as_session(client, n)
        answers.append(client.post("/api/fit", json=body).status_code)
    assert answers.count(202) == MAX_JOBS - MAX_SESSION_JOBS and answers.count(429) == MAX_SESSION_JOBS
    # no process started (children an earlier test left may end meanwhile: at most as many as before)
    assert len(started) == MAX_JOBS + 1 and workers() <= before   # (one of them cancelled)


def test_virtual_curves_at_one_speed_are_refused_before_a_job_starts(recorded):
    """Before: {"velocities": [1e-6, 1e-6]} was accepted (202) and its job failed later."""
    client, started = recorded
    r = client.post("/api/fit", json={"velocities": [1e-6, 1e-6]})
    assert r.status_code == 422, r.text
    err = r.json()["error"]
    assert err["field"] == "velocities" and "cannot be determined from curves at one driving speed" in err["message"]
    assert not started
    assert client.post("/api/fit", json={"velocities": [1e-6, 1e-6], "free": ["hamaker"]}).status_code == 202


def test_a_fit_from_the_page_runs_with_afmforce_fit_s_defaults():
    """Before: a fit request without options ran 1 start (``afmforce fit``: 2) and the page's box
    for profile intervals was unchecked (Wald intervals; the CLI: profiles), its free parameters
    written in the script. Now the request model and the page's controls take fit_dynamic's
    defaults, as the CLI does."""
    import inspect

    from afmforce.cli.main import build_parser
    from afmforce.fit import fit_dynamic
    from afmforce.web.routes_fit import FitRequest
    from afmforce.web.schema import fit_defaults

    sig = inspect.signature(fit_dynamic).parameters
    cli = build_parser(None)._subparsers._group_actions[0].choices["fit"].parse_args(["a.txt"])
    request = FitRequest()
    assert request.starts == sig["starts"].default == cli.starts
    assert request.free == list(sig["free"].default) == cli.free.split(",")
    assert request.profile is (sig["profile"].default is None) is (not cli.no_profile) is True
    assert request.compare is sig["compare"].default is (not cli.no_compare) is True
    page = fit_defaults()       # GET /api/schema's "fit_defaults": what the page's boxes are set to
    assert page == {"free": request.free, "starts": request.starts, "profile": True, "compare": True}


@pytest.mark.parametrize("name", ["velocity", "sample_rate"])
def test_a_truth_that_sets_each_curve_s_drive_is_refused(recorded, name):
    """Before: {"truth": {"velocity": 1e-6}} was accepted (202) and its job failed with Python's
    "got multiple values for keyword argument 'velocity'"."""
    client, started = recorded
    r = client.post("/api/fit", json={"velocities": [1e-6, 4e-6], "truth": {name: 1e-6 if name == "velocity" else 1e4}})
    assert r.status_code == 422, r.text
    assert r.json()["error"]["field"] == f"truth.{name}" and "set by velocities" in r.json()["error"]["message"]
    assert not started
