"""A thermal spectrum file with a bin that is no power (NaN, infinite, negative) is refused as
damaged, naming the bin; before, the fit dropped the bin silently: the peak bin of the shipped
virtual spectrum replaced by NaN, inf or -1e-20 gave k = 195.83 instead of 197.06 mN/m and no word."""

from __future__ import annotations

import pytest

from afmforce.calibration import fit_thermal
from afmforce.calibration.spectrum import read_spectrum
from afmforce.datasets import thermal_example as example_path
from afmforce.errors import FileFormatError


def _with_bin(tmp_path, value: str, at: float):
    src = example_path("virtual-air").read_text(encoding="utf-8").splitlines()
    rows = [i for i, line in enumerate(src) if line[:1].isdigit()]
    freqs = [float(src[i].split(",")[0]) for i in rows]
    i = rows[min(range(len(freqs)), key=lambda j: abs(freqs[j] - at))]
    f = src[i].split(",")[0]
    src[i] = f"{f},{value}"
    path = tmp_path / "damaged.psd"
    path.write_text("\n".join(src) + "\n", encoding="utf-8")
    return path, float(f), rows.index(i) + 1


@pytest.mark.parametrize("value", ["nan", "inf", "-1e-20"])
@pytest.mark.parametrize("at", [263.7, 20009.8])     # outside and at the peak (f0 = 20 kHz)
def test_a_bin_that_is_no_power_is_refused_with_its_place(tmp_path, value, at):
    path, f, n = _with_bin(tmp_path, value, at)
    with pytest.raises(FileFormatError) as err:
        read_spectrum(path)
    msg = str(err.value)
    assert msg.startswith(f"{path}: 1 spectrum bin(s) are not a power")
    assert f"at {f:.6g} Hz, bin {n})" in msg and "damaged" in msg


def test_the_shipped_spectra_still_read_and_give_their_k():
    """The example files are unchanged by the check: k as `afmforce calibrate thermal` prints it."""
    for name, k in (("virtual-air", 0.19706), ("jpk-water", 0.045056)):
        s = read_spectrum(example_path(name))
        fit = fit_thermal(s.frequency, s.displacement_psd(), temperature=s.temperature,
                          correction=s.correction if s.correction is not None else 1.0)
        assert fit.spring_constant == pytest.approx(k, rel=2e-4), name


def test_the_cli_says_one_error_line(tmp_path, capsys):
    from afmforce.cli.main import main

    path, _, _ = _with_bin(tmp_path, "nan", 20009.8)
    before = path.read_bytes()
    assert main(["calibrate", "thermal", str(path)]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(f"error: {path}: 1 spectrum bin(s)")
    assert path.read_bytes() == before


@pytest.mark.parametrize("key, value, says", [
    ("temperature", "abc K", "header 'temperature' must be a finite number, got 'abc K'"),    # was ValueError
    ("temperature", "", "header 'temperature' must be a finite number, got ''"),             # was IndexError
    ("temperature", "nan K", "header 'temperature' must be a finite number, got 'nan K'"),
    ("correction", "1e400", "header 'correction' must be a finite number, got '1e400'"),
    ("averages", "inf", "header 'averages' must be a finite number, got 'inf'"),            # was OverflowError
    ("averages", "-3", "header 'averages' must be a whole number >= 1, got '-3'"),            # was taken as -3
])
def test_a_damaged_header_value_is_a_file_format_error(tmp_path, key, value, says):
    lines = example_path("virtual-air").read_text(encoding="utf-8").splitlines()
    lines = [f"# {key}: {value}" if line.startswith(f"# {key}:") else line for line in lines]
    path = tmp_path / "header.psd"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    with pytest.raises(FileFormatError) as err:
        read_spectrum(path)
    assert str(err.value).startswith(f"{path}: {says}: the file is damaged")


@pytest.mark.parametrize("value, shown", [("-5 nm/V", "-5e-09"), ("0 nm/V", "0")])
def test_a_jpk_file_with_a_sensitivity_that_is_no_invols_is_refused(tmp_path, value, shown):
    """Before: InvOLS -5 nm/V was used (k 219.66 mN/m, squared away), 0 nm/V said 'fewer than 8 bins'."""
    lines = example_path("jpk-water").read_text(encoding="utf-8").splitlines()
    lines = [f"# sensitivity: {value}" if line.startswith("# sensitivity:") else line for line in lines]
    path = tmp_path / "bad.tnd"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    with pytest.raises(FileFormatError) as err:
        read_spectrum(path)
    assert str(err.value) == (f"{path}: its sensitivity is {shown}, not a positive number: the file is damaged; "
                              "correct that header line")
