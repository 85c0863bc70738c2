"""A calibration file that gives a key twice is refused, naming the file and the key, on every face
(branch mapcap): json took the last value silently, so ``{"spring_constant": 0.1, ..., "spring_constant":
10}`` analysed with 10 N/m on the command line and the web alike; which one was meant cannot be told."""

from __future__ import annotations

import pytest

from afmforce.calibration.record import parse_calibration, read_calibration
from afmforce.cli.main import main
from afmforce.errors import FileFormatError

TWICE = b'{"afmforce_calibration": 1, "spring_constant": 0.1, "sensitivity": 5e-8, "spring_constant": 10}'


def test_the_library_refuses_a_key_given_twice(tmp_path):
    path = tmp_path / "calib.json"
    path.write_bytes(TWICE)
    with pytest.raises(FileFormatError, match=rf"{path}: the key 'spring_constant' is given twice"):
        read_calibration(path)
    once = TWICE.replace(b', "spring_constant": 10', b"")
    assert parse_calibration(once.decode(), "c.json") == {"spring_constant": 0.1, "sensitivity": 5e-8}
    nested = b'{"afmforce_calibration": 1, "spring_constant": 0.1, "fit": {"a": 1, "a": 2}}'
    with pytest.raises(FileFormatError, match="c.json: the key 'a' is given twice"):
        parse_calibration(nested.decode(), "c.json")


def test_the_command_line_refuses_it_in_one_line(tmp_path, capsys):
    path = tmp_path / "calib.json"
    path.write_bytes(TWICE)
    code = main(["analyze", "--example", "asylum-air", "--probe-calibration", str(path)])
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if line.strip() and not line.startswith("afmforce: first run")]
    assert code != 0 and "Traceback" not in err
    assert len(lines) == 1 and str(path) in lines[0] and "'spring_constant' is given twice" in lines[0], err


def test_the_web_refuses_it_naming_the_upload(client):
    r = client.post("/api/analyze", data={"example": "asylum-air"}, files={"calibration": ("twice.json", TWICE)})
    assert r.status_code == 422, r.text[:300]
    err = r.json()["error"]
    assert err["field"] == "calibration" and "twice.json" in err["message"], err
    assert "'spring_constant' is given twice" in err["message"]
