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
