"""The web API (afmforce serve): the same numbers as the CLI and the library, and its security."""

from __future__ import annotations

import io
import json
import math
import time
from contextlib import redirect_stdout
from pathlib import Path

import numpy as np
import pytest

from afmforce.web.sessions import safe_suffix



def _file() -> Path:
    from afmforce.datasets import path

    return path("asylum-air")        # a real Asylum MFP-3D curve shipped with afmforce


def test_health(client):
    r = client.get("/api/health")
    assert r.status_code == 200 and r.json()["status"] == "ok"
    assert r.json()["token_required"] is False


def test_analyze_returns_what_the_cli_prints(client, tmp_path):
    from afmforce.cli.main import main

    src = _file()
    local = tmp_path / src.name
    local.write_bytes(src.read_bytes())
    out = io.StringIO()
    with redirect_stdout(out):
        assert main(["analyze", str(local), "--json"]) == 0
    cli = json.loads(out.getvalue())
    r = client.post("/api/analyze", files={"file": (src.name, src.read_bytes())})
    assert r.status_code == 200
    api = r.json()
    assert set(api["results"]) == set(cli["results"]) == {src.name}
    a, c = api["results"][src.name], cli["results"][src.name]
    assert a.pop("source") == src.name and Path(c.pop("source")).name == src.name
    assert a == c                      # every number, verdict and unit identical
    assert api["failed"] == cli["failed"] == []


def test_option_change_reruns_and_changes_the_fit(client):
    src = _file()
    first = client.post("/api/analyze", files={"file": (src.name, src.read_bytes())}).json()
    fid = first["files"][0]["id"]
    vdw0 = first["results"][src.name]["details"]["vdw"]
    assert vdw0["separation_max"] > 20e-9          # default window 30 nm
    again = client.post("/api/analyze", data={"file_id": fid, "option": "vdw.max_separation=20nm"}).json()
    vdw = again["results"][src.name]["details"]["vdw"]
    assert vdw["separation_max"] <= 20e-9 < vdw0["separation_max"]
    assert vdw["n_points"] < vdw0["n_points"]
    bad = client.post("/api/analyze", data={"file_id": fid, "option": "vdw.max_separation=-3nm"})
    assert bad.status_code == 422 and "max_separation" in bad.json()["error"]["message"]


def test_arrays_raw_signal_and_units(client):
    src = _file()
    r = client.post("/api/analyze", data={"example": "asylum-air", "arrays": "true", "max_points": "500"}).json()
    res = r["results"]["asylum-air"]
    assert len(res["force"]) <= 500 and len(res["force"]) == len(res["separation"])
    assert res["units"]["force"] == "N" and res["units"]["separation"] == "m"
    raw = r["raw"]["asylum-air"]
    assert raw["unit"] in ("V", "m", "N") and len(raw["signal"]) == len(raw["piezo"]) <= 500
    del src


@pytest.mark.parametrize("name", ["../../../../tmp/evil.ibw", "..\\..\\evil.ibw", "/etc/passwd", "a/../../b.ibw",
                                  "x.ibw\x00.txt", "...", ""])
def test_uploaded_names_never_reach_the_file_system(client, tmp_path, name):
    r = client.post("/api/analyze", files={"file": (name or "upload", b"not a force curve")})
    assert r.status_code in (200, 422)
    data = tmp_path / "data"
    for p in data.rglob("*"):
        rel = p.relative_to(data)
        assert rel.parts[0] in ("sessions", "jobs"), rel
        if p.is_file() and rel.parts[0] == "sessions":
            assert len(rel.parts) == 3 and (rel.name in ("index.json", "last-used") or
                                            rel.name.split(".")[0].isalnum() and len(rel.name.split(".")[0]) == 32)
    assert not (tmp_path / "evil.ibw").exists() and not Path("/tmp/evil.ibw").exists()
    if r.status_code == 200:   # a malformed file: an error for the page, no server path in it
        assert r.json()["failed"] and str(data) not in json.dumps(r.json())


def test_safe_suffix():
    assert safe_suffix("../../x.jpk-force") == ".jpk-force"
    assert safe_suffix("a.JPK-FORCE-MAP") == ".jpk-force-map"
    assert safe_suffix("x/..") == "" and safe_suffix("..") == "" and safe_suffix("noext") == ""
    assert safe_suffix("a.b/c") == "" and safe_suffix("x.i\x00bw") == ""


def test_upload_over_the_limit_gets_413(make_client):
    c = make_client(max_upload=1000)
    r = c.post("/api/analyze", files={"file": ("big.ibw", b"x" * 5000)})
    assert r.status_code == 413 and "1,000" in r.json()["error"]["message"]
    assert c.get("/api/health").status_code == 200


def test_token_required_beyond_loopback(make_client):
    c = make_client(host="0.0.0.0", token="s3cret-token")
    assert c.get("/api/health").status_code == 401
    assert c.get("/").status_code == 401
    assert c.get("/api/health", headers={"authorization": "Bearer wrong-token"}).status_code == 401
    assert c.get("/api/health", headers={"authorization": "Bearer s3cret-token"}).status_code == 200
    assert c.get("/?token=s3cret-token").status_code == 200          # the printed URL
    assert c.get("/api/health").status_code == 200                   # then the cookie carries it
    from afmforce.web.settings import Settings

    generated = Settings(host="0.0.0.0").resolved()
    assert generated.token and len(generated.token) >= 16 and "token=" in generated.url()
    assert Settings().resolved().token is None


def test_two_sessions_never_see_each_others_data(make_client):
    a, b = make_client(), make_client()
    src = _file()
    fid = a.post("/api/analyze", files={"file": (src.name, src.read_bytes())}).json()["files"][0]["id"]
    assert [f["id"] for f in a.get("/api/files").json()] == [fid]
    assert b.get("/api/files").json() == []
    r = b.post("/api/analyze", data={"file_id": fid})
    assert r.status_code == 422 and "no uploaded file" in r.json()["error"]["message"]
    job = a.post("/api/fit", json={"velocities": [1e-6, 4e-6], "truth": {"xi": 0.005}}).json()["id"]
    assert b.get(f"/api/jobs/{job}").status_code == 404
    assert b.get("/api/jobs").json() == []
    assert a.post(f"/api/jobs/{job}/cancel").status_code == 200     # cancel: the process is terminated
    deadline = time.monotonic() + 300
    while a.get(f"/api/jobs/{job}").json()["state"] == "running" and time.monotonic() < deadline:
        time.sleep(0.1)
    assert a.get(f"/api/jobs/{job}").json()["state"] == "cancelled"


def test_simulate_matches_the_library(client):
    from afmforce.dynamics import simulate

    r = client.post("/api/simulate?max_points=1000", json={"xi": 0.02, "velocity": 1e-6})
    assert r.status_code == 200
    body = r.json()
    ref = simulate(xi=0.02, velocity=1e-6)
    assert body["n_samples"] == len(ref)
    assert body["summary"]["jump_in"]["separation"] == pytest.approx(ref.events.jump_in_separation, rel=1e-9)
    assert body["summary"]["pull_off"]["force"] == pytest.approx(ref.events.pull_off_force, rel=1e-9)
    cols = body["columns"]
    assert len(cols["time"]) <= 1000 and body["units"]["deflection"] == "m"
    i = len(cols["time"]) // 2
    j = int(np.argmin(np.abs(ref.time - cols["time"][i])))
    assert cols["deflection"][i] == pytest.approx(ref.deflection[j], rel=1e-12, abs=1e-18)
    assert body["config"]["xi"] == 0.02


@pytest.mark.parametrize("cfg, word", [({"xi": -1}, "xi"), ({"nope": 1}, "unknown"),
                                       ({"sample_rate": 1e8, "velocity": 1e-9}, "samples")])
def test_simulate_bad_input_is_one_readable_error(client, cfg, word):
    r = client.post("/api/simulate", json=cfg)
    assert r.status_code == 422 and word in r.json()["error"]["message"]


def test_request_past_its_budget_is_cancelled(make_client):
    c = make_client(request_budget=1e-4)
    r = c.post("/api/simulate", json={"velocity": 1e-8})
    assert r.status_code == 504 and "budget" in r.json()["error"]["message"]
    assert r.json()["error"]["type"] == "past_budget"


def test_raw_export_reads_back(client, tmp_path):
    from afmforce.io import load

    r = client.post("/api/simulate/raw?preset=typical&seed=3", json={"velocity": 1e-6})
    assert r.status_code == 200 and "attachment" in r.headers["content-disposition"]
    path = tmp_path / "virtual.txt"
    path.write_bytes(r.content)
    curve = load(path)[0]
    assert curve.metadata["velocity"] == pytest.approx(1e-6)
    assert len(curve) > 100 and np.isfinite(curve.deflection_signal).all()


def test_sweep_job_runs_and_resumes_after_a_restart(make_client, tmp_path):
    from afmforce.sweep.simulation import simulate_run

    data = tmp_path / "sweepdata"
    c = make_client(data=data)
    job = c.post("/api/sweep", json={"grid": ["xi=0.01,0.1"], "sets": ["velocity=1um/s"],
                                     "executor": "serial"}).json()["id"]
    deadline = time.monotonic() + 300
    while (state := c.get(f"/api/jobs/{job}").json())["state"] == "running" and time.monotonic() < deadline:
        time.sleep(0.2)
    assert state["state"] == "done", state
    res = state["result"]
    assert res["n_runs"] == 2 and res["chunks_run"] >= 1
    col = res["columns"].index("min_apparent_deflection")
    xi = res["columns"].index("xi")
    for row in res["rows"]:
        direct = simulate_run(xi=row[xi], velocity=1e-6)["min_apparent_deflection"]
        assert row[col] == pytest.approx(direct, rel=1e-9)
    # a server stopped while the sweep ran: its record still says running; the next server resumes
    record = data / "jobs" / f"{job}.json"
    stored = json.loads(record.read_text())
    stored.update(state="running", result=None)
    record.write_text(json.dumps(stored))
    from afmforce.web import Settings, create_app

    c2 = make_client(app=create_app(Settings(data=data, spare_job=False)))
    c2.cookies.update(c.cookies)                     # the same browser
    deadline = time.monotonic() + 300
    while (state := c2.get(f"/api/jobs/{job}").json())["state"] == "running" and time.monotonic() < deadline:
        time.sleep(0.2)
    assert state["state"] == "done" and state["resumed"] == 1
    assert state["result"]["chunks_run"] == 0 and state["result"]["chunks_skipped"] >= 1
    assert math.isclose(state["result"]["rows"][0][col], res["rows"][0][col])


def test_openapi_documents_the_api(client):
    paths = client.get("/openapi.json").json()["paths"]
    for p in ("/api/health", "/api/analyze", "/api/simulate", "/api/fit", "/api/sweep", "/api/jobs/{job_id}"):
        assert p in paths


def test_serve_command_prints_its_url_and_a_generated_token(tmp_path):
    """``afmforce serve --host 0.0.0.0``: a token is generated, printed and required."""
    import os
    import re
    import subprocess
    import sys

    import httpx

    src = Path(__file__).resolve().parents[2] / "src"
    env = {**os.environ, "PYTHONPATH": str(src)}
    proc = subprocess.Popen([sys.executable, "-m", "afmforce.cli.main", "serve", "--host", "0.0.0.0", "--port", "0",
                             "--data", str(tmp_path / "d")], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            text=True, env=env)
    try:
        line = proc.stdout.readline()
        m = re.search(r"http://127\.0\.0\.1:(\d+)/\?token=(\S+)", line)
        assert m, line
        assert "token:" in proc.stdout.readline()
        base = f"http://127.0.0.1:{m.group(1)}/"
        assert httpx.get(base + "api/health", timeout=30).status_code == 401
        r = httpx.get(base + "api/health", headers={"authorization": f"Bearer {m.group(2)}"}, timeout=30)
        assert r.status_code == 200 and r.json()["token_required"] is True
    finally:
        proc.terminate()
        proc.wait(timeout=30)


def test_the_page_needs_no_network(client):
    """Everything the page loads comes from this server: no http(s) URL in it, Plotly served locally."""
    import re

    from afmforce.web.routes_main import STATIC

    page = client.get("/")
    assert page.status_code == 200
    for name in ("index.html", "app.js", "style.css"):
        text = (STATIC / name).read_text(encoding="utf-8")
        assert not re.search(r"https?://|//cdn|@import", text), name
    srcs = re.findall(r'(?:src|href)="([^"]+)"', page.text)
    # Plotly.js is added by the page's script once the page is ready (app.js: plotlyLoaded)
    srcs += re.findall(r'src: "([^"]+)"', (STATIC / "app.js").read_text(encoding="utf-8"))
    assert "static/plotly.min.js" in srcs
    for src in srcs:
        assert client.get("/" + src).status_code == 200, src
    js = client.get("/static/plotly.min.js")
    assert js.status_code == 200 and len(js.content) > 1_000_000 and b"plotly" in js.content[:2000].lower()
    assert client.get("/static/..%2Fapp.py").status_code == 404
    assert client.get("/docs").status_code == 404          # Swagger UI would load from a CDN


def test_force_map_image_has_axes_in_um_and_names_its_curves(client):
    """The 2x2 corner extract of a 10x10 JPK map (600 um square; tests/data): pixels at the corners."""
    path = Path(__file__).resolve().parents[1] / "data" / "afmforce-map_jpk-map2x2.h5"
    r = client.post("/api/analyze", files={"file": (path.name, path.read_bytes())}, data={"arrays": "true"})
    assert r.status_code == 200 and len(r.json()["results"]) == 4
    m = next(m for m in r.json()["maps"] if m["quantity"] == "adhesion")
    assert m["axes"] == "um" and len(m["x_um"]) == 10 and len(m["y_um"]) == 10
    # the stage positions the file stores (two curves per column or row: their mean, on a line)
    assert m["x_um"][0] == pytest.approx((31.97265625 + 31.85546875) / 2, rel=1e-9)
    assert m["x_um"][9] == pytest.approx(571.8359375, rel=1e-9)
    assert m["y_um"][0] == pytest.approx((-753.53515625 - 753.90625) / 2, rel=1e-9)
    assert m["y_um"][9] == pytest.approx(-213.73046875, rel=1e-9)
    assert m["curves"][0][0] == f"{path.name}#0" and m["curves"][9][9] == f"{path.name}#2"
    assert m["curves"][5][5] is None and m["z"][5][5] is None
    adhesion = -r.json()["results"][f"{path.name}#0"]["adhesion_force"]
    assert m["z"][0][0] == pytest.approx(adhesion, rel=1e-12)


def test_requests_from_other_sites_are_refused(client):
    """Another web site's page cannot drive the local server (CSRF), nor a rebound DNS name."""
    evil = client.post("/api/simulate", json={}, headers={"origin": "http://evil.example"})
    assert evil.status_code == 403 and "cross-site" in evil.json()["error"]["message"]
    assert client.get("/api/health", headers={"host": "evil.example:8765"}).status_code == 403
    same = client.get("/api/health", headers={"origin": "http://127.0.0.1"})
    assert same.status_code == 200
