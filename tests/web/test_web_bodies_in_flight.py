"""Request bodies count against the session's storage while they are received (branch mapcap).

Starlette spools an upload to its temporary folder before any route runs, so two sessions' large
uploads, or one session's many at once, filled the disk before the session's storage was counted
(the route refused them afterwards, their bytes already written). Now the guard middleware reserves
each body's bytes (its ``Content-Length``, or a chunked body's as it grows) against the session's
storage with the session's other bodies in flight, and all bodies together against
``afmforce.limits.SERVER_BODIES_IN_FLIGHT``: refused before a byte is read."""

from __future__ import annotations

import asyncio
import json

import pytest

from afmforce.limits import SERVER_BODIES_IN_FLIGHT, SERVER_MAX_UPLOAD
from afmforce.web import Settings
from afmforce.web.guard import SESSION_COOKIE, Guard

SID = "s" * 40


def test_an_upload_past_the_sessions_storage_is_refused_before_it_is_spooled(make_client, monkeypatch):
    """Before: Starlette spooled the 2 MB upload, then the route answered 413 (its bytes written first).
    (Each body's first 64 kB, its multipart framing, are not counted.)"""
    import starlette.formparsers as formparsers

    spooled = []
    real = formparsers.SpooledTemporaryFile
    monkeypatch.setattr(formparsers, "SpooledTemporaryFile", lambda *a, **k: spooled.append(1) or real(*a, **k))
    client = make_client(session_storage=1_000_000)
    r = client.post("/api/analyze", files={"file": ("big.txt", b"1 2\n" * 500_000)})
    assert r.status_code == 413 and r.json()["error"]["type"] == "storage_full", r.text[:300]
    assert "1 MB a session may store" in r.json()["error"]["message"] and spooled == []
    ok = client.post("/api/analyze", files={"file": ("small.txt", b"1 2\n" * 10)})
    assert ok.status_code != 413 and spooled, ok.text[:300]          # a body that fits is received as before
    assert Settings().max_upload == SERVER_MAX_UPLOAD and SERVER_BODIES_IN_FLIGHT == 5 * SERVER_MAX_UPLOAD


async def _run(guard, bodies):
    """Send ``bodies`` (path, session, chunks, announce the length) through ``guard`` at once; its app reads
    each body whole, then answers when every request has started. -> ([(status, json)], paths read)."""
    gate = asyncio.Event()
    started = []

    async def app(scope, receive, send):
        while (await receive()).get("more_body"):
            pass
        started.append(scope["path"])
        await gate.wait()
        await send({"type": "http.response.start", "status": 200, "headers": []})
        await send({"type": "http.response.body", "body": b"{}"})

    guard.app = app

    async def one(path, sid, chunks, announce):
        sent = []
        queue = [{"type": "http.request", "body": c, "more_body": i < len(chunks) - 1} for i, c in enumerate(chunks)]

        async def receive():
            return queue.pop(0) if queue else {"type": "http.disconnect"}

        async def send(message):
            sent.append(message)

        headers = [(b"host", b"127.0.0.1"), (b"cookie", f"{SESSION_COOKIE}={sid}".encode())]
        if announce:
            headers.append((b"content-length", str(sum(map(len, chunks))).encode()))
        scope = {"type": "http", "method": "POST", "path": path, "headers": headers, "query_string": b""}
        await guard(scope, receive, send)
        status = sent[0]["status"]
        body = b"".join(m.get("body", b"") for m in sent[1:])
        return status, json.loads(body)

    tasks = [asyncio.create_task(one(*b)) for b in bodies]
    for _ in range(50):
        await asyncio.sleep(0)
    gate.set()
    return await asyncio.gather(*tasks), started


def _guard(stored=0, storage=1000, max_flight=10_000):
    room = (lambda sid, adding: f"this session keeps {stored}; {adding} more would pass {storage}"
            if stored + adding > storage else None)
    return Guard(None, token=None, max_body=5000, room=room, max_flight=max_flight, framing=0)


@pytest.mark.parametrize("announce", [True, False])
def test_a_sessions_bodies_in_flight_count_together(announce, monkeypatch):
    """Two bodies of 600 bytes at once in a session that may store 1000: the second is 413 storage_full
    (chunked: as it grows, checked each 100 bytes here, each 8 MB in the server); after both ended, one
    fits again (nothing stays reserved)."""
    from afmforce.web import guard as guard_module

    monkeypatch.setattr(guard_module, "_STEP", 100)
    guard = _guard()
    results, started = asyncio.run(_run(guard, [("/a", SID, [b"x" * 300] * 2, announce),
                                                ("/b", SID, [b"x" * 300] * 2, announce)]))
    statuses = sorted(s for s, _ in results)
    assert statuses == [200, 413] and started in (["/a"], ["/b"]), results
    refused = next(body for s, body in results if s == 413)["error"]
    assert refused["type"] == "storage_full" and "would pass 1000" in refused["message"]
    assert guard._flight == {} and guard._flight_total == 0
    again, _ = asyncio.run(_run(guard, [("/c", SID, [b"x" * 600], announce)]))
    assert again[0][0] == 200


def test_all_sessions_bodies_in_flight_are_bounded():
    guard = _guard(max_flight=1000, storage=10_000)
    results, _ = asyncio.run(_run(guard, [("/a", "a" * 40, [b"x" * 600], True), ("/b", "b" * 40, [b"x" * 600], True)]))
    assert sorted(s for s, _ in results) == [200, 429]
    assert next(b for s, b in results if s == 429)["error"]["type"] == "busy"

