"""Web requests shaped wrongly get a 4xx that says what to send, in words a user reads (branch fuzzfaces):
never pydantic's class names ("Expected UploadFile, received: <class 'str'>"), never a form body
echoed as bytes, never "inf um/s" for a finite number, never "got  (not a number)" for an empty field."""

from __future__ import annotations

import pytest


def test_a_file_part_without_a_file_name_says_so(client):
    r = client.post("/api/analyze", files={"file": ("", b"\x00\x01")})
    assert r.status_code == 422
    err = r.json()["error"]
    assert err["field"] == "file[0]" and "not a file" in err["message"] and "UploadFile" not in err["message"]


@pytest.mark.parametrize("url", ["/api/simulate", "/api/simulate/raw", "/api/fit", "/api/sweep"])
@pytest.mark.parametrize("how", ["form", "text"])
def test_a_body_that_is_not_json_says_to_send_json(client, url, how):
    r = (client.post(url, data={"velocity": "1"}) if how == "form" else
         client.post(url, content=b"velocity=1", headers={"content-type": "text/plain"}))
    assert r.status_code == 422
    message = r.json()["error"]["message"]
    assert "JSON object" in message and "application/json" in message and "b'" not in message


@pytest.mark.parametrize("body, fragment", [({"velocity": 1e308}, "1e+308 m/s is out of range"),
                                            ({"velocity": ""}, "got an empty value"),
                                            ({"velocity": "  "}, "got an empty value")])
def test_simulation_values_are_shown_as_given(client, body, fragment):
    r = client.post("/api/simulate?max_points=100", json=body)
    assert r.status_code == 422
    err = r.json()["error"]
    assert err["field"] == "velocity" and fragment in err["message"] and "inf" not in err["message"]


def test_an_empty_probe_value_is_said_empty(client):
    r = client.post("/api/analyze", data={"example": "workshop", "probe": "radius="})
    assert r.status_code == 422
    assert r.json()["error"] == {"type": "invalid_value", "field": "probe.radius",
                                 "message": "probe.radius expects a length, got an empty value; give one (e.g. 200nm)"}


def test_fit_starts_cap_is_the_library_cap(client):
    from afmforce.limits import MAX_STARTS

    r = client.post("/api/fit", json={"velocities": ["1um/s", "5um/s"], "starts": MAX_STARTS + 1})
    assert r.status_code == 422 and r.json()["error"]["field"] == "starts"
    assert f"less than or equal to {MAX_STARTS}" in r.json()["error"]["message"]


_FRESH = """
import sys, tempfile, threading
import afmforce.web.app as web_app
from fastapi.testclient import TestClient
MODULES = ("afmforce.units", "afmforce.dynamics", "afmforce.dynamics.trajectory", "afmforce.io",
           "afmforce.analysis.pipeline")
seen, done = {}, threading.Event()
def spy():          # the warm-up thread's first act (no compile here: only the order is tested)
    seen.update({m: m in sys.modules for m in MODULES})
    done.set()
    return []
web_app.warm_up_steps = spy
app = web_app.create_app(web_app.Settings(data=tempfile.mkdtemp(), spare_job=False))
with TestClient(app, base_url="http://127.0.0.1") as c:
    done.wait(60)
    r = c.post("/api/simulate", json={"start": "5um"})
print(r.status_code, sorted(m for m, ok in seen.items() if not ok) if seen else "no warm-up")
"""


def test_the_library_is_imported_before_the_warm_up_thread_and_the_first_request():
    """A request sent at start imported afmforce.dynamics while the warm-up thread did: a half-initialised
    module, 500 (KeyError 'afmforce.dynamics') in 1 run of 2. Checked in a fresh interpreter (imports are
    per process): the modules the warm-up and the requests import are loaded before its thread starts."""
    import os
    import subprocess
    import sys
    from pathlib import Path

    src = str(Path(__file__).parents[2] / "src")
    env = {**os.environ, "PYTHONPATH": src + os.pathsep + os.environ.get("PYTHONPATH", "")}
    out = subprocess.run([sys.executable, "-c", _FRESH], capture_output=True, text=True, env=env, timeout=600)
    assert out.stdout.strip().splitlines()[-1] == "422 []", out.stdout + out.stderr[-2000:]
