"""Speed of ``afmforce serve`` (issue 27): one command, ``python benchmarks/bench_web.py``.

1. Slider move -> redrawn Fig-5 trajectory, measured in the page itself (headless Debian
   Chromium via Playwright): from the slider's ``input`` event to the redrawn, painted plots
   (request, simulation, JSON, Plotly). Target: p95 < 150 ms on the 2-core machine. Baseline in
   the same run: the library's ``simulate()`` of the same configurations (ratio page / library).
2. Analysis re-run after an option change, a 10,000-point curve (virtual AFM, ``typical``
   preset, uploaded once): ``POST /api/analyze`` with ``file_id`` and a new option, wall time
   at the client. Target: < 1 s. Baseline: the library's ``analyze()`` of the same curve.
3. Load: 20 concurrent clients x 50 requests (as tests/web/test_web_load.py), errors and p95.

Issue 33 item 7 (each in the page, headless Chromium, and the API alone, httpx):

4. Page load to interactive: a navigation to the moment the page has its controls built and its
   session restored (``window.READY_MS``, ``performance.now()`` from the navigation's start),
   a cold load (fresh browser profile) and warm reloads. Target: < 1 s.
5. Re-run after a calibration change (the spring constant typed in the analyse view) on the
   10,000-point curve of 2: from the field's ``change`` event to the painted plots
   (``window.AN_LATENCY``; parts: server, request + JSON, Plotly and tables, paint), and
   ``POST /api/analyze`` with ``file_id`` and ``probe=spring_constant=...`` alone. Target: < 300 ms.
6. A 16 x 16 force map (``afmforce.instrument.soft_map``, 300 + 300 points a curve): the upload
   analysed and its table, histogram and heat map drawn, then a re-run after a calibration change.
   Target: table and histograms < 2 s.

Options: ``--moves N`` (default 60), ``--reruns N`` (default 20), ``--no-browser``, ``--only
PART,...`` (slider, rerun, load, page-load, calibration, map).
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
    from afmforce.io import load

    path = virtual_10k()
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


def virtual_10k() -> Path:
    """A 10,001-point virtual-AFM curve (``typical`` preset) as a raw text file."""
    from afmforce.dynamics import simulate
    from afmforce.instrument.presets import get_preset
    from afmforce.io.native.rawfile import write_raw

    traj = simulate(velocity=1e-6, sample_rate=10_000 / (310e-9 / 1e-6))   # 310 nm of travel: 10,000 samples
    path = Path(tempfile.mkdtemp()) / "virtual-10k.txt"
    write_raw(get_preset("typical").record(traj, seed=1), path)
    return path


def soft_map_16() -> Path:
    """A 16 x 16 virtual QI map (300 + 300 points a curve) as an afmforce map file."""
    from afmforce.instrument.soft_map import SoftMapConfig, write_soft_map

    path = Path(tempfile.mkdtemp()) / "soft-16x16.afmforce-map.h5"
    write_soft_map(SoftMapConfig(nx=16, ny=16, points=300, step=50e-6 / 16), path)
    return path


def _browser(p):
    return p.chromium.launch_persistent_context(tempfile.mkdtemp(), executable_path=CHROMIUM, args=ARGS,
                                                headless=True, viewport={"width": 1400, "height": 900})


def page_load(url: str, n: int) -> dict:
    """Navigation start -> controls built and session restored (``window.READY_MS``) [ms]: the first
    load in a fresh profile (nothing cached), then ``n`` reloads."""
    from playwright.sync_api import sync_playwright

    cold, warm, parts = [], [], []
    with sync_playwright() as p:
        for k in range(2):      # two fresh profiles: two cold loads
            ctx = _browser(p)
            page = ctx.new_page()
            for i in range(1 + (n if k == 0 else 0)):
                if i == 0:
                    page.goto(url)
                else:
                    page.reload()
                page.wait_for_selector("body[data-ready='1']", timeout=60_000)
                t = page.evaluate("""() => { const nav = performance.getEntriesByType('navigation')[0];
                    return [window.READY_MS, nav.responseEnd, nav.domInteractive, nav.domContentLoadedEventEnd,
                            nav.transferSize]; }""")
                (cold if i == 0 else warm).append(t[0])
                parts.append(t)
            ctx.close()
    return {"cold_ms": cold, "warm_ms": warm, "parts_p50": np.median(np.array(parts)[:, 1:4], axis=0).tolist()}


def _analyse_in_page(page, path: Path, timeout: float = 120_000) -> None:
    n = page.evaluate("(window.AN_LATENCY || []).length")
    page.set_input_files("#an-files", str(path))
    page.click("#an-run")
    page.wait_for_function(f"(window.AN_LATENCY || []).length > {n}", timeout=timeout)


def _calibration_change(page, k: float, timeout: float = 60_000) -> None:
    n = page.evaluate("window.AN_LATENCY.length")
    box = page.locator("[data-probe='spring_constant'] input.val")
    box.fill(repr(k))
    box.dispatch_event("change")
    page.wait_for_function(f"window.AN_LATENCY.length > {n}", timeout=timeout)


def page_calibration(url: str, path: Path, n: int) -> dict:
    """The spring constant typed in the analyse view -> painted plots, on the 10,000-point curve."""
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        ctx = _browser(p)
        page = ctx.new_page()
        page.goto(url)
        page.wait_for_selector("body[data-ready='1']", timeout=60_000)
        _analyse_in_page(page, path)
        first = page.evaluate("window.AN_LATENCY.at(-1)")
        for i in range(n):
            _calibration_change(page, 0.1 + 0.01 * (i % 7))
        lat = page.evaluate(f"window.AN_LATENCY.slice(-{n})")
        parts = page.evaluate(f"window.AN_PARTS.slice(-{n})")
        ctx.close()
    return {"first_ms": first, "page_ms": lat, "parts_p50": np.median(np.array(parts), axis=0).tolist()}


def page_map(url: str, path: Path, n: int) -> dict:
    """A 16 x 16 map uploaded and analysed -> table, histogram and heat map drawn; then ``n`` re-runs
    after a calibration change. Also the time of drawing the table and histogram alone."""
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        ctx = _browser(p)
        page = ctx.new_page()
        page.goto(url)
        page.wait_for_selector("body[data-ready='1']", timeout=60_000)
        _analyse_in_page(page, path, timeout=300_000)
        rows = page.locator("#an-batch-table tr").count() - 1
        first = page.evaluate("window.AN_LATENCY.at(-1)")
        first_parts = page.evaluate("window.AN_PARTS.at(-1)")
        for i in range(n):
            _calibration_change(page, 0.1 + 0.01 * (i % 7), timeout=300_000)
        lat = page.evaluate(f"window.AN_LATENCY.slice(-{n})")
        parts = page.evaluate(f"window.AN_PARTS.slice(-{n})")
        table = page.evaluate("""() => { const out = [];
            for (let i = 0; i < 5; i++) { const t0 = performance.now(); drawBatch(); out.push(performance.now() - t0); }
            return out; }""")
        ctx.close()
    return {"rows": rows, "first_ms": first, "first_parts": first_parts, "page_ms": lat,
            "parts_p50": np.median(np.array(parts), axis=0).tolist(), "table_ms": table}


def api_calibration(url: str, path: Path, n: int, max_points: int = 1040) -> dict:
    """``POST /api/analyze`` with the stored upload and a new spring constant, arrays as the page asks
    them (the 1400-pixel-wide window's plots: 1040 samples; the arrays of the first curve only)."""
    import httpx

    with httpx.Client(base_url=url, timeout=300) as c:
        t0 = time.perf_counter()
        r = c.post("api/analyze", files={"file": (path.name, path.read_bytes())},
                   data={"arrays": "true", "max_points": str(max_points), "curve": ""})
        first = (time.perf_counter() - t0) * 1e3
        fid = r.json()["files"][0]["id"]
        ms, server, size = [], [], []
        for i in range(n):
            t0 = time.perf_counter()
            r = c.post("api/analyze", data={"file_id": fid, "probe": f"spring_constant={0.1 + 0.01 * (i % 7)}N/m",
                                            "arrays": "true", "max_points": str(max_points), "curve": ""})
            ms.append((time.perf_counter() - t0) * 1e3)
            assert r.status_code == 200 and r.json()["results"], r.text[:300]
            server.append(r.json()["wall_time"] * 1e3)
            size.append(len(r.content))
    return {"first_ms": first, "api_ms": ms, "server_ms": server, "bytes": float(np.median(size))}


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
    ap.add_argument("--only", default="slider,rerun,load,page-load,calibration,map")
    args = ap.parse_args()
    import os

    only = set(args.only.split(","))
    url, server = serve(Path(tempfile.mkdtemp()))
    import httpx

    while not httpx.get(url + "api/health").json()["warm"]:
        time.sleep(0.1)
    load = lambda: f"load average {os.getloadavg()[0]:.1f}"   # noqa: E731
    print(f"afmforce serve benchmark ({os.cpu_count()} cores, {load()}) at {url}")
    ok = True
    browser = not args.no_browser and Path(CHROMIUM).exists()
    if browser and "slider" in only:
        s = slider(url, args.moves)
        p95 = pct(s["page_ms"], 95)
        print(f"slider -> redrawn Fig-5 trajectory ({len(s['page_ms'])} moves of xi, in Chromium): "
              f"p50 {pct(s['page_ms'], 50):.0f} ms, p95 {p95:.0f} ms (target < 150 ms); library simulate() "
              f"p50 {pct(s['library_ms'], 50):.1f} ms: page/library {pct(s['page_ms'], 50) / pct(s['library_ms'], 50):.1f}x")
        on_server, fetch, draw, paint = s["parts_p50"]
        print(f"  p50 parts: server {on_server:.0f} ms, request + JSON {fetch:.0f} ms, Plotly {draw:.0f} ms, "
              f"paint {paint:.0f} ms")
        ok &= p95 < 150
    if browser and "page-load" in only:
        pl = page_load(url, 10)
        print(f"page load to interactive (Chromium; {load()}): cold {', '.join(f'{v:.0f}' for v in pl['cold_ms'])} ms, "
              f"reload p50 {pct(pl['warm_ms'], 50):.0f} ms, max {max(pl['warm_ms']):.0f} ms (target < 1000 ms)")
        print("  p50 parts: response end {:.0f} ms, DOM interactive {:.0f} ms, DOMContentLoaded {:.0f} ms".format(*pl["parts_p50"]))
        ok &= max(pl["cold_ms"] + pl["warm_ms"]) < 1000
    if "calibration" in only:
        path = virtual_10k()
        a = api_calibration(url, path, args.reruns)
        print(f"re-run after a calibration change, 10,001 points, API ({args.reruns} runs; {load()}): "
              f"p50 {pct(a['api_ms'], 50):.0f} ms, max {max(a['api_ms']):.0f} ms (server p50 "
              f"{pct(a['server_ms'], 50):.0f} ms), {a['bytes'] / 1e3:.0f} kB; first analysis {a['first_ms']:.0f} ms")
        if browser:
            c = page_calibration(url, path, args.reruns)
            print(f"re-run after a calibration change, 10,001 points, in Chromium ({load()}): p50 "
                  f"{pct(c['page_ms'], 50):.0f} ms, p95 {pct(c['page_ms'], 95):.0f} ms, max {max(c['page_ms']):.0f} ms "
                  f"(target < 300 ms); first analysis {c['first_ms']:.0f} ms")
            print("  p50 parts: server {:.0f} ms, request + JSON {:.0f} ms, plots and tables {:.0f} ms, paint {:.0f} ms"
                  .format(*c["parts_p50"]))
            ok &= pct(c["page_ms"], 95) < 300
    if "map" in only:
        path = soft_map_16()
        a = api_calibration(url, path, max(3, args.reruns // 5))
        print(f"16 x 16 map, API ({load()}): first analysis {a['first_ms']:.0f} ms; re-run after a calibration "
              f"change p50 {pct(a['api_ms'], 50):.0f} ms (server {pct(a['server_ms'], 50):.0f} ms), "
              f"{a['bytes'] / 1e3:.0f} kB")
        if browser:
            m = page_map(url, path, max(3, args.reruns // 5))
            print(f"16 x 16 map in Chromium ({m['rows']} rows; {load()}): upload to table, histogram and heat map "
                  f"{m['first_ms']:.0f} ms (server {m['first_parts'][0]:.0f} ms, page {m['first_parts'][2]:.0f} ms); "
                  f"re-run after a calibration change p50 {pct(m['page_ms'], 50):.0f} ms, max {max(m['page_ms']):.0f} ms "
                  f"(target < 2000 ms); table + histogram alone p50 {pct(m['table_ms'], 50):.0f} ms")
            print("  re-run p50 parts: server {:.0f} ms, request + JSON {:.0f} ms, plots and tables {:.0f} ms, paint {:.0f} ms"
                  .format(*m["parts_p50"]))
            ok &= max(m["page_ms"] + [m["first_ms"]]) < 2000
    if "rerun" in only:
        r = rerun(url, args.reruns)
        print(f"analysis re-run after an option change ({r['points']}-point curve, {args.reruns} runs): "
              f"p50 {pct(r['api_ms'], 50):.0f} ms, max {max(r['api_ms']):.0f} ms (target < 1000 ms); library "
              f"analyze() p50 {pct(r['library_ms'], 50):.0f} ms: API/library "
              f"{pct(r['api_ms'], 50) / pct(r['library_ms'], 50):.2f}x")
        ok &= max(r["api_ms"]) < 1000
    if "load" in only:
        lt = load_test(url)
        print(f"load: 20 clients x 50 requests in {lt['wall_s']:.1f} s, {lt['errors']} errors, "
              f"p50 {pct(lt['ms'], 50):.0f} ms, p95 {pct(lt['ms'], 95):.0f} ms")
        ok &= lt["errors"] == 0
    server.should_exit = True
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
