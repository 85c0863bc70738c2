"""Fixtures of the web tests: an in-process client and a live server on a free loopback port."""

from __future__ import annotations

import os
import shutil
import socket
import threading
import time
from pathlib import Path

import pytest

fastapi = pytest.importorskip("fastapi")

from afmforce.web import Settings, create_app  # noqa: E402


@pytest.fixture
def make_client(tmp_path):
    """``make_client(**settings) -> TestClient`` (a fresh cookie jar each call: a new session)."""
    from fastapi.testclient import TestClient

    apps = {}

    def make(app=None, **kw):
        if app is None:
            kw.setdefault("spare_job", False)      # no warm job process per test app (CPU)
            key = tuple(sorted(kw.items()))
            if key not in apps:
                apps[key] = create_app(Settings(data=kw.pop("data", tmp_path / "data"), **kw))
            app = apps[key]
        client = TestClient(app, base_url="http://127.0.0.1")
        client.__enter__()
        made.append(client)
        return client

    made: list = []
    yield make
    for c in made:
        c.__exit__(None, None, None)


@pytest.fixture
def client(make_client):
    return make_client()


@pytest.fixture(scope="module")
def live_server(tmp_path_factory):
    """``http://127.0.0.1:PORT/`` of a real uvicorn server in a thread (stopped after the module)."""
    import uvicorn

    data = tmp_path_factory.mktemp("web-data")
    sock = socket.socket()
    sock.bind(("127.0.0.1", 0))
    port = sock.getsockname()[1]
    app = create_app(Settings(port=port, data=data))
    server = uvicorn.Server(uvicorn.Config(app, log_level="warning", timeout_graceful_shutdown=2))
    thread = threading.Thread(target=server.run, kwargs={"sockets": [sock]}, daemon=True)
    thread.start()
    deadline = time.monotonic() + 30
    while not server.started and time.monotonic() < deadline:
        time.sleep(0.05)
    assert server.started, "the server did not start"
    yield f"http://127.0.0.1:{port}/"
    server.should_exit = True
    thread.join(timeout=10)


def worker_processes() -> int:
    """Child processes of this test process, but multiprocessing's resource tracker (one helper per
    interpreter, started with the first job process and kept: not a worker) and the suite's
    background compile (tests/conftest.py, its own process group)."""
    import psutil

    warmup = int(os.environ.get("AFMFORCE_TEST_WARMUP_PGID", "-1"))
    n = 0
    for p in psutil.Process().children(recursive=True):
        try:
            if "resource_tracker" in " ".join(p.cmdline()) or os.getpgid(p.pid) == warmup:
                continue
        except (psutil.Error, OSError):
            continue
        except psutil.Error:
            continue
        n += 1
    return n


@pytest.fixture(scope="session")
def workers():
    """``workers() -> int``: the worker processes alive under this test process now."""
    return worker_processes


#: Debian's headless Chromium of the page tests (tests/web/test_web_e2e.py and the control tests), its flags
CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                 "--disable-background-networking", "--disable-component-update", "--disable-sync"]


def _browser_missing() -> str | None:
    try:
        import playwright.sync_api  # noqa: F401
    except ImportError:
        return "playwright is not installed (pip install playwright)"
    if not Path(CHROMIUM).exists():
        return "Debian's chromium is not installed (apt-get install -y chromium)"
    return None


@pytest.fixture(scope="module")
def page(live_server, tmp_path_factory):
    """A headless Chromium page on the live server, ready (``body[data-ready='1']``), its script errors in
    ``page.errors``. Skipped without playwright or chromium (failed where ``AFMFORCE_REQUIRE_E2E=1``, as
    ``.ci/run`` sets it)."""
    why = _browser_missing()
    if why:
        if os.environ.get("AFMFORCE_REQUIRE_E2E") == "1":
            pytest.fail(why)
        pytest.skip(why)
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        ctx = p.chromium.launch_persistent_context(str(tmp_path_factory.mktemp("chromium-profile")),
                                                   executable_path=CHROMIUM, args=CHROMIUM_ARGS, headless=True,
                                                   viewport={"width": 1400, "height": 900})
        pg = ctx.new_page()
        pg.errors = []
        pg.on("pageerror", lambda e: pg.errors.append(str(e)))
        pg.goto(live_server)
        pg.wait_for_selector("body[data-ready='1']", timeout=30_000)
        yield pg
        ctx.close()
