"""The position channel reaches the web as it reaches the command line, from one declaration.

Faces audit 2026-11-29: ``afmforce analyze --channel nominal`` existed, the web's analyse form and
``POST /api/analyze`` had no such field (a file with a measured and a nominal position was always read on
the measured one). Now the flag, the form field, the schema's control and the OpenAPI enum are all
:data:`afmforce._fields.ANALYSIS_CHOICES` (the test walks it: a setting added there reaches every face)."""

from __future__ import annotations

import io
import json
from contextlib import redirect_stdout

import pytest

from afmforce._fields import ANALYSIS_CHOICES
from afmforce.cli.main import build_parser, main
from afmforce.io.curve import POSITION_CHANNELS

EXAMPLE = "jpk-calibration"      # a real JPK file with a measured and a nominal height channel


def _cli(*flags) -> dict:
    out = io.StringIO()
    with redirect_stdout(out):
        assert main(["analyze", "--example", EXAMPLE, "--json", *flags]) == 0
    (res,) = json.loads(out.getvalue())["results"].values()
    return res


def _action(parser, dest):
    sub = next(a for a in parser._actions if a.dest == "command").choices["analyze"]
    return next(a for a in sub._actions if a.dest == dest)


@pytest.mark.parametrize("name", list(ANALYSIS_CHOICES))
def test_every_declared_setting_reaches_every_face(client, name):
    spec = ANALYSIS_CHOICES[name]
    flag = _action(build_parser(), name)
    assert tuple(flag.choices) == spec.choices and flag.default == spec.default and spec.help in flag.help
    schema = {f["name"]: f for f in client.get("/api/schema").json()["analysis_settings"]}
    assert schema[name]["choices"] == list(spec.choices) and schema[name]["default"] == spec.default
    assert schema[name]["help"] == spec.help and schema[name]["kind"] == "choice"
    doc = client.get("/openapi.json").json()
    form = doc["paths"]["/api/analyze"]["post"]["requestBody"]["content"]["multipart/form-data"]["schema"]
    body = doc["components"]["schemas"][form["$ref"].rsplit("/", 1)[-1]]["properties"]
    assert body[name]["enum"] == list(spec.choices) and body[name]["default"] == spec.default
    r = client.post("/api/analyze", data={"example": EXAMPLE, name: "bogus"})
    assert r.status_code == 422 and r.json()["error"]["field"] == name
    assert all(c in r.json()["error"]["message"] for c in spec.choices)


def test_the_io_layer_reads_the_same_declaration():
    assert POSITION_CHANNELS == ANALYSIS_CHOICES["channel"].choices


def test_the_web_reads_the_channel_asked_for_as_the_cli_does(client):
    auto, nominal = _cli(), _cli("--channel", "nominal")
    assert auto["shift"] != pytest.approx(nominal["shift"], rel=0.1)      # 16.4 nm measured, -47.1 nm nominal
    for flags, data in (((), {}), (("--channel", "nominal"), {"channel": "nominal"})):
        r = client.post("/api/analyze", data={"example": EXAMPLE, **data})
        assert r.status_code == 200, r.text
        (web,) = r.json()["results"].values()
        want = _cli(*flags)
        assert web["shift"] == pytest.approx(want["shift"], rel=1e-12), flags
        for key in ("spring_constant", "sensitivity_used", "contact_kind"):
            assert web[key] == want[key] or web[key] == pytest.approx(want[key], rel=1e-12), (flags, key)


# ---- the page: the control is listed and its value is sent ----------------------------------------------
# the `page` fixture: tests/web/conftest.py (headless Chromium on the live server)


def test_the_page_lists_the_channel_and_sends_it(page):
    spec = ANALYSIS_CHOICES["channel"]
    shown = page.eval_on_selector_all("[data-setting='channel'] select option", "os => os.map(o => o.value)")
    assert shown == list(spec.choices)
    assert page.locator("[data-setting='channel'] select").input_value() == spec.default
    page.select_option("#an-example", EXAMPLE)
    with page.expect_request(lambda r: r.url.endswith("/api/analyze")) as first:
        page.click("#an-run")
    assert 'name="channel"' not in (first.value.post_data or "")      # the default: not sent
    page.wait_for_function("typeof AN !== 'undefined' && AN.payload && Object.keys(AN.payload.results).length", timeout=120_000)
    with page.expect_request(lambda r: r.url.endswith("/api/analyze")) as second:
        page.select_option("[data-setting='channel'] select", "nominal")
    body = second.value.post_data or ""
    assert 'name="channel"\r\n\r\nnominal' in body, body[:400]
    page.wait_for_function("() => { const r = Object.values(AN.payload.results)[0]; return r && r.shift < 0; }",
                           timeout=120_000)
    shift = page.evaluate("Object.values(AN.payload.results)[0].shift")
    assert shift == pytest.approx(_cli("--channel", "nominal")["shift"], rel=1e-12)
    assert not page.errors
