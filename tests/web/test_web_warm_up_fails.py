"""A warm-up step that raises is logged (a warning with its reason) and the server keeps serving.

Before, the analysis step's exceptions were swallowed silently and any other step's went to the
thread's excepthook (a traceback on stderr) and skipped the steps after it."""

from __future__ import annotations

import logging
import time

import pytest

pytest.importorskip("fastapi")

import afmforce.dynamics  # noqa: E402
import afmforce.web.app as web_app  # noqa: E402


def _broken(monkeypatch):
    def integrator(*a, **k):
        raise RuntimeError("no compiled integrator here")

    def analysis():
        raise OSError("the shipped curve is gone")

    monkeypatch.setattr(afmforce.dynamics, "simulate", integrator)
    monkeypatch.setattr(web_app, "_warm_analysis", analysis)


def test_each_failing_step_is_a_warning_with_its_reason_and_the_others_run(monkeypatch, caplog):
    _broken(monkeypatch)
    with caplog.at_level(logging.WARNING, logger="afmforce.web"):
        failed = web_app.warm_up_steps()
    logged = [r.getMessage() for r in caplog.records if r.name == "afmforce.web" and r.levelno == logging.WARNING]
    assert logged == failed and len(failed) == 2
    assert "the integrator failed (RuntimeError: no compiled integrator here)" in failed[0]
    assert "the analysis failed (OSError: the shipped curve is gone)" in failed[1]


def test_the_server_serves_after_a_failed_warm_up(monkeypatch, caplog, make_client):
    _broken(monkeypatch)
    with caplog.at_level(logging.WARNING, logger="afmforce.web"):
        client = make_client()
        deadline = time.monotonic() + 300
        while not client.get("/api/health").json()["warm"] and time.monotonic() < deadline:
            time.sleep(0.1)
        health = client.get("/api/health")
    assert health.status_code == 200 and health.json()["warm"] is True
    assert sum("warm-up of" in r.getMessage() for r in caplog.records) == 2
    assert client.get("/api/schema").status_code == 200 and client.get("/").status_code == 200


def test_a_spare_job_process_whose_warm_up_fails_logs_it_and_waits_for_its_job(monkeypatch, caplog):
    """The spare job process (``tasks.standby``) died of its warm-up's exception, a traceback on the
    server's stderr; it now logs it and waits for its job (here: it leaves, its parent being gone)."""
    import queue

    from afmforce.web.tasks import standby

    _broken(monkeypatch)
    with caplog.at_level(logging.WARNING, logger="afmforce.web"):
        assert standby(queue.Queue(), queue.Queue(), parent=-1, warm=True) is None
    assert [r.getMessage() for r in caplog.records if r.name == "afmforce.web"] == [
        "warm-up of a spare job process failed (RuntimeError: no compiled integrator here); it takes its job unwarmed"]
