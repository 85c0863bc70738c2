"""The disk a session and the server may fill with uploads is bounded (``--session-storage``,
``--server-storage``): the next upload past a total gets 413 ``storage_full`` with one line saying
what to do, nothing is written, nothing stored is evicted, and deleting files or a session's expiry
frees the space at once."""

from __future__ import annotations

import time

import pytest

fastapi = pytest.importorskip("fastapi")

from afmforce.errors import ParameterError  # noqa: E402
from afmforce.web import Settings  # noqa: E402
from afmforce.web.guard import SESSION_COOKIE  # noqa: E402
from afmforce.web.sessions import Sessions, StorageFull  # noqa: E402


def upload(client, *sizes, name="curve.txt"):
    """POST /api/analyze with files of these sizes (bytes that no reader reads: listed as failed)."""
    files = [("file", (f"{i}{name}", b"x" * n)) for i, n in enumerate(sizes)]
    return client.post("/api/analyze", files=files)


def seed(client, size, name="stored.txt"):
    """Store ``size`` bytes in the client's session as its uploads are stored, without analysing them."""
    client.get("/api/files")                            # the cookie: the session
    return client.app.state.sessions.save(client.cookies[SESSION_COOKIE], name, b"s" * size)


def stored_files(client):
    return client.get("/api/files").json()


def test_a_session_past_its_total_is_refused_and_keeps_its_files(make_client):
    client = make_client(session_storage=1000, server_storage=100_000)
    seed(client, 600)
    before = stored_files(client)
    assert [f["size"] for f in before] == [600]
    refused = upload(client, 500)                       # 600 + 500 > 1000
    assert refused.status_code == 413
    error = refused.json()["error"]
    assert error["type"] == "storage_full" and "\n" not in error["message"]
    assert "600 bytes" in error["message"] and "1,000 bytes" in error["message"]
    assert "delete" in error["message"] and "new session" in error["message"]
    assert stored_files(client) == before               # nothing evicted, nothing added
    state = client.get("/api/session").json()
    assert state["stored"] == 600 and state["max_stored"] == 1000
    sessions = client.app.state.sessions
    assert sessions.stored_bytes() == 600
    seed(client, 400)                                   # exactly the total is allowed
    assert sessions.stored_bytes() == 1000
    assert upload(client, 1).status_code == 413
    for f in stored_files(client):                      # deleting frees the space at once
        assert client.delete(f"/api/files/{f['id']}").status_code == 200
    assert sessions.stored_bytes() == 0
    assert upload(client, 900).status_code != 413       # an upload through the page's request
    assert [f["size"] for f in stored_files(client)] == [900]


def test_the_files_of_one_request_are_stored_all_or_none(make_client):
    client = make_client(session_storage=1000, server_storage=100_000)
    assert upload(client, 400, 400, 400).status_code == 413
    assert stored_files(client) == [] and client.app.state.sessions.stored_bytes() == 0
    assert not client.app.state.sessions.keys()         # a refused session made no folder either


def test_the_servers_total_counts_every_session_and_an_expired_one_frees_it(make_client):
    first = make_client(session_storage=1000, server_storage=1500)
    second = make_client(session_storage=1000, server_storage=1500)   # same app, another cookie
    assert first.app is second.app
    seed(first, 1000)
    refused = upload(second, 600)                       # its own 0 + 600 <= 1000, the server's 1600 > 1500
    assert refused.status_code == 413
    message = refused.json()["error"]["message"]
    assert "server" in message and "1,000 bytes" in message and "1,500 bytes" in message
    assert stored_files(second) == [] and [f["size"] for f in stored_files(first)] == [1000]
    seed(second, 500)                                   # 1500: exactly the total
    assert upload(second, 1).status_code == 413
    sessions = first.app.state.sessions
    gone = sessions.expire(now=time.time() + sessions.ttl + 60)   # both sessions unused past the ttl
    assert len(gone) == 2 and sessions.stored_bytes() == 0
    seed(second, 1000)
    assert [f["size"] for f in stored_files(second)] == [1000]


def test_a_replaced_asylum_wave_frees_the_bytes_it_replaces(tmp_path):
    sessions = Sessions(tmp_path, session_bytes=1000, server_bytes=1000)
    sessions.save("s", "Map1Point0000Defl.ibw", b"x" * 700)
    sessions.save("s", "Map1Point0000Defl.ibw", b"y" * 800)    # the same wave again: replaces it
    assert sessions.stored_bytes("s") == 800 and len(sessions.files("s")) == 1
    with pytest.raises(StorageFull, match="more would pass the 1,000 bytes a session may store"):
        sessions.save("s", "Map1Point0000ZSnsr.ibw", b"z" * 300)
    assert sessions.stored_bytes("s") == 800 and len(sessions.files("s")) == 1


def test_the_totals_are_settings_and_flags(capsys):
    from afmforce.cli.main import main
    from afmforce.web.settings import parse_size

    assert Settings().session_storage == 2_000_000_000 and Settings().server_storage == 20_000_000_000
    assert parse_size("1.5GB", "--server-storage") == 1_500_000_000
    with pytest.raises(ParameterError, match="--session-storage"):
        Settings(session_storage=0)
    with pytest.raises(ParameterError, match="--server-storage"):
        Settings(server_storage=-5)
    assert main(["serve", "--session-storage", "lots"]) == 2      # refused before anything listens
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error: --session-storage 'lots'")
