"""Speed of ``afmforce serve`` (issue 27): one command, ``python benchmarks/bench_web.py``.

1. Slider move -> redrawn Fig-5 trajectory, measured in the page itself (headless Debian
   Chromium via Playwright): from the slider's ``input`` event to the redrawn, painted plots
   (request, simulation, JSON, Plotly). Target: p95 < 150 ms on the 2-core machine. Baseline in
   the same run: the library's ``simulate()`` of the same configurations (ratio page / library).
2. Analysis re-run after an option change, a 10,000-point curve (virtual AFM, ``typical``
   preset, uploaded once): ``POST /api/analyze`` with ``file_id`` and a new option, wall time
   at the client. Target: < 1 s. Baseline: the library's ``analyze()`` of the same curve.
3. Load: 20 concurrent clients x 50 requests (as tests/web/test_web_load.py), errors and p95.

Options: ``--moves N`` (default 60), ``--reruns N`` (default 20), ``--no-browser``.
"""

from __future__ import annotations

import argparse
import socket
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))

CHROMIUM = "/usr/bin/chromium"
ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
        "--disable-background-networking", "--disable-component-update", "--disable-sync"]


def serve(data: Path):
    import uvicorn

    from afmforce.web import Settings, create_app

    sock = socket.socket()
    sock.bind(("127.0.0.1", 0))
    port = sock.getsockname()[1]
    app = create_app(Settings(port=port, data=data, spare_job=False))
    server = uvicorn.Server(uvicorn.Config(app, log_level="warning"))
    threading.Thread(target=server.run, kwargs={"sockets": [sock]}, daemon=True).start()
    while not server.started:
        time.sleep(0.05)
    return f"http://127.0.0.1:{port}/", server


def pct(a, q):
    return float(np.percentile(np.asarray(a), q))


def slider(url: str, moves: int) -> dict:
    import tempfile

    from playwright.sync_api import sync_playwright

    from afmforce.dynamics import simulate

    with sync_playwright() as p:
        ctx = p.chromium.launch_persistent_context(tempfile.mkdtemp(), executable_path=CHROMIUM, args=ARGS,
                                                   headless=True, viewport={"width": 1400, "height": 900})
        page = ctx.new_page()
        page.goto(url)
        page.wait_for_selector("body[data-ready='1']")
        page.click("button[data-view=simulate]")
        page.wait_for_function("(window.SIM_LATENCY || []).length >= 1", timeout=60_000)
        s = page.locator("[data-slider='xi']")
        lo, hi = float(s.get_attribute("min")), float(s.get_attribute("max"))
        values = np.linspace(lo + 0.02 * (hi - lo), hi, moves)
        xis = []
        for i, v in enumerate(values):
            n = page.evaluate("window.SIM_LATENCY.length")
            s.fill(repr(float(v)))
            page.wait_for_function(f"window.SIM_LATENCY.length > {n}", timeout=30_000)
            xis.append(float(page.locator(".field[data-name='xi'] input.val").input_value()))
        lat = page.evaluate("window.SIM_LATENCY.slice(1)")
        parts = np.array(page.evaluate("window.SIM_PARTS.slice(1)"))
        ctx.close()
    lib = []
    for xi in xis:
        t0 = time.perf_counter()
        simulate(xi=xi)
        lib.append((time.perf_counter() - t0) * 1e3)
    return {"page_ms": lat, "library_ms": lib, "parts_p50": np.median(parts, axis=0).tolist()}


def rerun(url: str, n: int) -> dict:
    import httpx

    from afmforce.analysis.pipeline import analyze
    from afmforce.dynamics import simulate
    from afmforce.instrument.presets import get_preset
    from afmforce.io import load
    from afmforce.io.native.rawfile import write_raw

    traj = simulate(velocity=1e-6, sample_rate=10_000 / (310e-9 / 1e-6))   # 310 nm of travel: 10,000 samples
    curve = get_preset("typical").record(traj, seed=1)
    path = Path(tempfile.mkdtemp()) / "virtual-10k.txt"
    write_raw(curve, path)
    points = len(load(path)[0])
    with httpx.Client(base_url=url, timeout=120) as c:
        fid = c.post("api/analyze", files={"file": (path.name, path.read_bytes())}).json()["files"][0]["id"]
        api = []
        for i in range(n):
            opt = f"vdw.max_separation={15 + i % 10}nm"
            t0 = time.perf_counter()
            r = c.post("api/analyze", data={"file_id": fid, "option": opt, "arrays": "true"})
            api.append((time.perf_counter() - t0) * 1e3)
            assert r.status_code == 200 and r.json()["results"], r.text[:300]
    from afmforce.analysis.options import VdwOptions

    lib = []
    loaded = load(path)[0]
    for i in range(n):
        t0 = time.perf_counter()
        analyze(loaded, options=(VdwOptions(max_separation=(15 + i % 10) * 1e-9),))
        lib.append((time.perf_counter() - t0) * 1e3)
    return {"points": points, "api_ms": api, "library_ms": lib}


def load_test(url: str) -> dict:
    import httpx

    errors, lat, lock = [], [], threading.Lock()

    def client(k):
        with httpx.Client(base_url=url, timeout=60) as c:
            for i in range(50):
                t0 = time.perf_counter()
                try:
                    r = (c.post("api/simulate?max_points=200", json={"velocity": 1e-5}) if i % 10 == 0
                         else c.get("api/health"))
                    if r.status_code != 200:
                        raise RuntimeError(r.status_code)
                except Exception as exc:
                    with lock:
                        errors.append(str(exc))
                with lock:
                    lat.append((time.perf_counter() - t0) * 1e3)

    t0 = time.perf_counter()
    threads = [threading.Thread(target=client, args=(k,)) for k in range(20)]
    [t.start() for t in threads]
    [t.join() for t in threads]
    return {"wall_s": time.perf_counter() - t0, "ms": lat, "errors": len(errors)}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--moves", type=int, default=60)
    ap.add_argument("--reruns", type=int, default=20)
    ap.add_argument("--no-browser", action="store_true")
    args = ap.parse_args()
    import os

    url, server = serve(Path(tempfile.mkdtemp()))
    import httpx

    while not httpx.get(url + "api/health").json()["warm"]:
        time.sleep(0.1)
    print(f"afmforce serve benchmark ({os.cpu_count()} cores, load average "
          f"{os.getloadavg()[0]:.1f}) at {url}")
    ok = True
    if not args.no_browser and Path(CHROMIUM).exists():
        s = slider(url, args.moves)
        p95 = pct(s["page_ms"], 95)
        print(f"slider -> redrawn Fig-5 trajectory ({len(s['page_ms'])} moves of xi, in Chromium): "
              f"p50 {pct(s['page_ms'], 50):.0f} ms, p95 {p95:.0f} ms (target < 150 ms); library simulate() "
              f"p50 {pct(s['library_ms'], 50):.1f} ms: page/library {pct(s['page_ms'], 50) / pct(s['library_ms'], 50):.1f}x")
        on_server, fetch, draw, paint = s["parts_p50"]
        print(f"  p50 parts: server {on_server:.0f} ms, request + JSON {fetch:.0f} ms, Plotly {draw:.0f} ms, "
              f"paint {paint:.0f} ms")
        ok &= p95 < 150
    r = rerun(url, args.reruns)
    print(f"analysis re-run after an option change ({r['points']}-point curve, {args.reruns} runs): "
          f"p50 {pct(r['api_ms'], 50):.0f} ms, max {max(r['api_ms']):.0f} ms (target < 1000 ms); library "
          f"analyze() p50 {pct(r['library_ms'], 50):.0f} ms: API/library "
          f"{pct(r['api_ms'], 50) / pct(r['library_ms'], 50):.2f}x")
    ok &= max(r["api_ms"]) < 1000
    lt = load_test(url)
    print(f"load: 20 clients x 50 requests in {lt['wall_s']:.1f} s, {lt['errors']} errors, "
          f"p50 {pct(lt['ms'], 50):.0f} ms, p95 {pct(lt['ms'], 95):.0f} ms")
    ok &= lt["errors"] == 0
    server.should_exit = True
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
