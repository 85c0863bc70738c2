"""``GET /static/{name}`` answers 404 for every name that is not one of the page's files -- a name too
long for the file system or with a NUL byte included (before: 500, ``OSError: File name too long`` /
``ValueError: embedded null byte`` from ``Path.is_file``)."""

from __future__ import annotations

import pytest

pytest.importorskip("fastapi")


@pytest.mark.parametrize("name", ["a" * 3000, "x%00y", "%00", "..%2Fapp.py", "%2e%2e", ".hidden", "nope.js",
                                  "app.js%00.png", "%E2%80%AE" * 200])
def test_a_name_that_is_no_static_file_is_404_never_500(make_client, name):
    client = make_client()
    from fastapi.testclient import TestClient

    c = TestClient(client.app, base_url="http://127.0.0.1", raise_server_exceptions=False)
    r = c.get(f"/static/{name}")
    assert r.status_code == 404, (r.status_code, r.text[:200])
    assert r.json()["error"]["type"] == "not_found"


def test_the_pages_files_are_still_served(client):
    from afmforce.web.routes_main import STATIC

    for path in STATIC.iterdir():
        r = client.get(f"/static/{path.name}")
        assert r.status_code == 200 and r.content == path.read_bytes(), path.name
