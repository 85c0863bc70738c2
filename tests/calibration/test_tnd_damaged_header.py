"""A JPK thermal-noise file whose temperature, correction factor or sensitivity line holds no
number is refused, naming the line; before, the value was dropped and the default taken (a
temperature of 'abc' silently became 295 K in k = kT/<x^2>, printed only as '(default)').
An absent or empty line still means "not stored" (the default, as before)."""

from __future__ import annotations

from pathlib import Path

import pytest

from afmforce.calibration.spectrum import read_spectrum
from afmforce.errors import FileFormatError

TND = Path(__file__).resolve().parents[1] / "data" / "jpk-tnd_PFQNM-water_thermal-noise_0-80kHz.tnd"


def _with_line(tmp_path, key: str, value: str | None) -> Path:
    lines = TND.read_text(encoding="utf-8").splitlines()
    out = []
    for line in lines:
        if line.startswith(f"# {key}:"):
            if value is None:
                continue
            line = f"# {key}: {value}"
        out.append(line)
    path = tmp_path / "damaged.tnd"
    path.write_text("\n".join(out) + "\n", encoding="utf-8")
    return path


@pytest.mark.parametrize("key,value", [("settings.temperature", "abc"), ("settings.temperature", "nan ℃"),
                                       ("cantilever.correction factor", "nan"), ("sensitivity", "x nm/V")])
def test_a_stored_value_that_is_no_number_is_refused(tmp_path, key, value):
    path = _with_line(tmp_path, key, value)
    with pytest.raises(FileFormatError, match=f"the header's '{key}' is"):
        read_spectrum(path)


def test_absent_or_empty_lines_are_not_stored_and_the_file_reads():
    """The file's own values, read from its text: 25.0 C, 0.9000, 11.0399 nm/V."""
    sp = read_spectrum(TND)
    assert sp.temperature == pytest.approx(25.0 + 273.15, rel=1e-12)
    assert sp.correction == pytest.approx(0.9, rel=1e-12)
    assert sp.sensitivity == pytest.approx(11.0399e-9, rel=1e-12)


@pytest.mark.parametrize("value", [None, ""])
def test_a_missing_temperature_is_none(tmp_path, value):
    sp = read_spectrum(_with_line(tmp_path, "settings.temperature", value))
    assert sp.temperature is None and sp.correction == pytest.approx(0.9)


@pytest.mark.parametrize("value,kelvin", [("298.15 K", 298.15), ("298.15", 298.15), ("25.0 °C", 298.15),
                                          ("77.0 °F", None), ("25.0 mK", None)])
def test_the_temperature_unit_is_read_or_the_line_refused(tmp_path, value, kelvin):
    """Kelvin and Celsius as written; any other unit is refused (before, '77.0 °F' read as 77 K: k 3.9 x low)."""
    path = _with_line(tmp_path, "settings.temperature", value)
    if kelvin is None:
        with pytest.raises(FileFormatError, match="kelvin or degrees Celsius"):
            read_spectrum(path)
    else:
        assert read_spectrum(path).temperature == pytest.approx(kelvin, rel=1e-12)
