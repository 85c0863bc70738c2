"""Settings files are read bounded (faces audit, 2026-11-29): ``afmforce sweep --config /dev/zero``
filled the memory until the kernel killed it (67 s, exit 137); a settings file of any size was read
whole. Now every settings file (sweep and instrument TOML, calibration JSON) is read up to
:data:`afmforce.limits.CONFIG_BYTES` and a larger one refused in one line."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from afmforce._files import read_settings
from afmforce.cli.main import main
from afmforce.errors import FileFormatError
from afmforce.limits import CONFIG_BYTES

CURVE = str(Path(__file__).parents[1] / "data" / "asylum-mfp3d_SiN-tip_air.ibw")


@pytest.fixture
def big(tmp_path):
    """A settings file past the cap that its parser would take: TOML and JSON comments/whitespace."""
    path = tmp_path / "big.toml"
    path.write_text("# a comment line\n" * (CONFIG_BYTES // 17 + 10) + '[grid]\nxi = "0.001:0.1:3"\n')
    return path


@pytest.mark.parametrize("argv", [
    ["sweep", "--serial", "--config", "{big}"],
    ["simulate", "--instrument", "typical", "--instrument-config", "{big}", "--raw", "r.txt"],
    ["analyze", CURVE, "--probe-calibration", "{big}"],
    ["simulate", "--probe-calibration", "{big}"],
])
def test_a_settings_file_past_the_cap_is_one_line(capsys, tmp_path, monkeypatch, big, argv):
    monkeypatch.chdir(tmp_path)
    code = main([a.format(big=big) for a in argv])
    err = capsys.readouterr().err.strip().splitlines()
    err = [e for e in err if not e.startswith("afmforce: first run")]
    assert code == 1 and len(err) == 1, err
    assert f"more than {CONFIG_BYTES:,} bytes" in err[0]
    assert not list(tmp_path.glob("sweeps*")) and not (tmp_path / "r.txt").exists()


@pytest.mark.skipif(not os.path.exists("/dev/zero"), reason="no /dev/zero")
def test_a_device_that_never_ends_is_refused():
    with pytest.raises(FileFormatError, match="more than"):
        read_settings("/dev/zero", "a TOML sweep file")


def test_a_file_within_the_cap_is_read_whole(tmp_path):
    path = tmp_path / "s.toml"
    text = "# x\n" * 1000 + '[set]\nxi = "0.01kg/s"\n'
    path.write_text(text)
    assert read_settings(path, "a TOML sweep file") == text
