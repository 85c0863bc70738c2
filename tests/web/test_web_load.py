"""A bounded load test: 20 concurrent clients x 50 requests each on loopback, without an error.

Each client is a browser of its own (its own session cookie); one request in ten simulates a
short cycle, the others read the API (health, the session's files and jobs). The latencies are
printed (pytest -s); benchmarks/bench_web.py measures the speed targets.
"""

from __future__ import annotations

import threading
import time

import numpy as np

CLIENTS, REQUESTS = 20, 50


def test_20_clients_x_50_requests_without_an_error(live_server):
    import httpx

    errors: list[str] = []
    latencies: list[float] = []
    lock = threading.Lock()
    start = threading.Barrier(CLIENTS)

    def client(k: int) -> None:
        with httpx.Client(base_url=live_server, timeout=60) as c:
            start.wait()
            for i in range(REQUESTS):
                t0 = time.perf_counter()
                try:
                    if i % 10 == 0:
                        r = c.post("api/simulate?max_points=200", json={"velocity": 1e-5, "xi": 0.01 * (1 + k)})
                        ok = r.status_code == 200 and r.json()["n_samples"] > 0
                    elif i % 3 == 0:
                        r = c.get("api/files")
                        ok = r.status_code == 200 and r.json() == []       # a new session sees nothing
                    elif i % 3 == 1:
                        r = c.get("api/jobs")
                        ok = r.status_code == 200
                    else:
                        r = c.get("api/health")
                        ok = r.status_code == 200 and r.json()["status"] == "ok"
                    if not ok:
                        raise AssertionError(f"{r.status_code} {r.text[:200]}")
                except Exception as exc:
                    with lock:
                        errors.append(f"client {k} request {i}: {exc}")
                with lock:
                    latencies.append(time.perf_counter() - t0)

    deadline = time.monotonic() + 60        # the server loads the simulator at start (numba's cache)
    while not httpx.get(live_server + "api/health").json()["warm"] and time.monotonic() < deadline:
        time.sleep(0.1)
    t0 = time.perf_counter()
    threads = [threading.Thread(target=client, args=(k,)) for k in range(CLIENTS)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=300)
    wall = time.perf_counter() - t0
    assert not errors, errors[:5]
    assert len(latencies) == CLIENTS * REQUESTS
    lat = np.array(latencies) * 1e3
    print(f"\nload: {CLIENTS} clients x {REQUESTS} requests in {wall:.2f} s "
          f"({len(lat) / wall:.0f} req/s); latency p50 {np.percentile(lat, 50):.1f} ms, "
          f"p95 {np.percentile(lat, 95):.1f} ms, max {lat.max():.1f} ms; 0 errors")
