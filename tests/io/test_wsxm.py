"""WSxM (Nanotec) ``.curves`` force curves: the reader against the file read WITHOUT afmforce.

The real file is pycroscopy/SciFiDatasets' ``WSxM1DReader_spectrocurve_0001_Normalforce.f.curves``
(MIT; ``tests/data/corpus``): 5 curves of 512 + 512 points on a 25 nm Z ramp, Normal force in V, a
5.33904 N/m lever. The numbers asserted here come from the file's text headers (plain ``re``) and its
binary blocks located by those headers (``numpy.frombuffer`` at the offsets computed here), not from
the reader. Its ``..._Amplitude.f.curves`` sibling (``tests/data/wsxm``, same series, dynamic-mode
amplitude) must be refused with a message that names the channel.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest

from afmforce.errors import FileFormatError
from afmforce.io import find_format, load
from afmforce.io.wsxm import load_wsxm_curves

DATA = Path(__file__).resolve().parents[1] / "data"
FILE = DATA / "corpus" / "wsxm-curves_spectrocurve_0001_Normalforce.f.curves"
AMPLITUDE = DATA / "wsxm" / "WSxM1DReader_spectrocurve_0001_Amplitude.f.curves"


def _blocks(raw: bytes):
    """(header text, data start, points, lines) of every curve block, found with ``re`` alone."""
    top = int(re.search(rb"Image header size: (\d+)", raw).group(1))
    text = raw[:top].decode("latin-1")
    rows = int(re.search(r"Number of rows: (\d+)", text).group(1))
    cols = int(re.search(r"Number of columns: (\d+)", text).group(1))
    assert re.search(r"Image Data Type: double", text)
    at, out = top + rows * cols * 8, []
    while at < len(raw):
        size = int(re.search(rb"Image header size: (\d+)", raw[at:at + 100]).group(1))
        head = raw[at:at + size].decode("latin-1")
        n = int(re.search(r"Number of points: (\d+)", head).group(1))
        lines = int(re.search(r"Number of lines: (\d+)", head).group(1))
        out.append((head, at + size, n, lines))
        at += size + n * lines * 16
    assert at == len(raw)  # the blocks tile the file exactly
    return text, out


RAW = FILE.read_bytes()
TOP, BLOCKS = _blocks(RAW)


def test_detected_and_read_with_the_header_values():
    assert find_format(FILE).identifier == "wsxm-curves"
    curves = load(FILE)
    k = float(re.search(r"Force constant: ([\d.]+) N/m", TOP).group(1))
    assert k == 5.33904 and len(BLOCKS) == 5 == len(curves)
    for c, (head, start, n, lines) in zip(curves, BLOCKS):
        assert lines == 2 and n == 512 and "First Forward: Yes" in head
        md = c.metadata
        assert md["reader"] == "wsxm-curves" and md["spring_constant"] == k and "sensitivity" not in md
        assert md["curve_index"] == int(re.search(r"Index of this Curve: (\d+)", head).group(1))
        assert c.deflection_unit == "V" and re.search(r"Y axis unit: V\s", head)
        assert np.bincount(c.segment).tolist() == [n, n] and np.all(c.segment[:n] == 0)
        ms = float(re.search(r"Forward plot total time: ([\d.]+) ms", head).group(1))
        assert md["sample_rate"] == pytest.approx(n / (ms * 1e-3), rel=1e-12)
        # the controller's own numbers agree: Sampling frequency / Samples/point = 15000 / 117 Hz
        assert md["sample_rate"] == pytest.approx(15000 / 117, rel=1e-3)
        # the data: (Z [nm], Normal force [V]) pairs, forward line then backward line, both on ascending Z
        pairs = np.frombuffer(RAW, "<f8", count=n * lines * 2, offset=start).reshape(lines, n, 2)
        np.testing.assert_array_equal(c.piezo_nominal[:n], pairs[0, :, 0] * 1e-9)
        np.testing.assert_array_equal(c.deflection_signal[:n], pairs[0, :, 1])
        np.testing.assert_array_equal(c.piezo_nominal[n:], pairs[1, ::-1, 0] * 1e-9)  # retract in time order
        np.testing.assert_array_equal(c.deflection_signal[n:], pairs[1, ::-1, 1])
        x, y = re.search(r"Acquisition point: \(([-\d.]+) nm, ([-\d.]+) nm\)", head).groups()
        assert (md["position_x"], md["position_y"]) == (float(x) * 1e-9, float(y) * 1e-9)
        assert np.all(np.diff(c.time) > 0) and c.time[-1] == pytest.approx(2 * ms * 1e-3, rel=1e-2)


def test_units_and_ranges_are_those_of_an_afm_force_curve():
    for c in load(FILE):
        n = int(np.sum(c.segment == 0))
        z = c.piezo_nominal
        assert z[n - 1] - z[0] == pytest.approx(25e-9, rel=1e-3)  # X axis -10 .. 15 nm
        assert np.all(np.abs(c.deflection_signal) < 10.0)  # within the +-10 V of the photodiode ADC
        assert c.metadata["velocity"] == pytest.approx(25e-9 / 3.993, rel=1e-3)
        # in contact the deflection rises with z (z towards the sample, deflection up positive) ...
        assert np.polyfit(z[n - 100:n], c.deflection_signal[n - 100:n], 1)[0] > 0
        # ... and the retract pulls off at a smaller z than the approach jumps in (adhesion hysteresis)
        assert z[n + np.argmin(c.deflection_signal[n:])] < z[np.argmin(c.deflection_signal[:n])]


def test_amplitude_curves_are_refused_naming_the_channel():
    raw = AMPLITUDE.read_bytes()
    assert re.search(rb"Y axis text: Amplitude", raw)
    with pytest.raises(FileFormatError, match=r"channel 'Amplitude' \[V\], not a deflection.*'Normal force' file"):
        load(AMPLITUDE)


def _rewrite(raw: bytes, edit) -> bytes:
    """The file with every curve header passed through ``edit`` and its declared size recomputed."""
    _, blocks = _blocks(raw)
    out = bytearray(raw[:blocks[0][1] - len(blocks[0][0])])
    for head, start, n, lines in blocks:
        new = edit(head)
        for _ in range(3):  # the size counts its own digits
            new = re.sub(r"Image header size: \d+", f"Image header size: {len(new.encode('latin-1'))}", new)
        out += new.encode("latin-1") + raw[start:start + n * lines * 16]
    return bytes(out)


def test_a_deflection_in_nm_and_the_conversion_factor_sign(tmp_path):
    path = tmp_path / "nm.f.curves"
    path.write_bytes(_rewrite(RAW, lambda h: h.replace("Conversion Factor 00: 1 V", "Conversion Factor 00: 20 nm")
                              .replace("Conversion Offset 00: 0 V", "Conversion Offset 00: 0 nm")
                              .replace("Y axis unit: V", "Y axis unit: nm")
                              .replace("Channel is inverted: No", "Channel is inverted: Yes")))
    ref, got = load(FILE)[0], load(path)[0]
    assert got.deflection_unit == "m"
    np.testing.assert_allclose(got.deflection_signal, -20e-9 * ref.deflection_signal, rtol=1e-15)
    bad = tmp_path / "mixed.f.curves"
    bad.write_bytes(_rewrite(RAW, lambda h: h.replace("Y axis unit: V", "Y axis unit: nm")))
    with pytest.raises(FileFormatError, match="Y axis is in 'nm' but its conversion factor gives 'V'"):
        load_wsxm_curves(bad)


def test_a_backward_line_stored_in_time_order_is_not_reversed_again(tmp_path):
    raw = bytearray(RAW)
    for _, start, n, _ in BLOCKS:
        bwd = np.frombuffer(RAW, "<f8", count=2 * n, offset=start + 16 * n).reshape(n, 2)
        raw[start + 16 * n:start + 32 * n] = bwd[::-1].tobytes()
    path = tmp_path / "time-order.f.curves"
    path.write_bytes(bytes(raw))
    for a, b in zip(load(FILE), load(path)):
        np.testing.assert_array_equal(a.piezo_nominal, b.piezo_nominal)
        np.testing.assert_array_equal(a.deflection_signal, b.deflection_signal)


@pytest.mark.parametrize("cut", [100, 3000, 3225 + 1000, BLOCKS[0][1] - 500, BLOCKS[0][1] + 4000,
                                 BLOCKS[2][1] + 16384, len(RAW) - 8])
def test_truncated_copies_give_a_clean_error(tmp_path, cut):
    path = tmp_path / "cut.f.curves"
    path.write_bytes(RAW[:cut])
    with pytest.raises(FileFormatError, match="truncated|damaged") as err:
        load_wsxm_curves(path)  # the reader's own words, not the registry's wrapping of a crash
    assert str(path) in str(err.value)
    with pytest.raises(FileFormatError):
        load(path)


@pytest.mark.parametrize("old, new, words", [
    (b"Image header size: 3225", b"Image header size: 9999999", "truncated or damaged"),
    (b"Number of points: 512", b"Number of points: 5x2", "not a whole number"),
    (b"Image Data Type: double", b"Image Data Type: dooble", "not one WSxM writes"),
    (b"Number of lines: 2", b"Number of lines: 3", "pairs|truncated"),
    (b"X axis unit: nm", b"X axis unit: Hz", "not a length"),
    (b"[Header end]", b"[Header and]", "Header end"),
    (b"Image header size: 3225", b"Image header size: 3224", "not a ramp|non-finite|damaged"),  # data 1 byte off
])
def test_garbled_copies_give_a_clean_error(tmp_path, old, new, words):
    assert old in RAW
    path = tmp_path / "garbled.f.curves"
    path.write_bytes(RAW.replace(old, new, 1))
    with pytest.raises(FileFormatError, match=words):
        load_wsxm_curves(path)


def test_afmforce_analyze_as_a_user_types_it(tmp_path, capsys):
    from afmforce.cli.main import main

    before = RAW
    assert main(["analyze", str(FILE), "--json"]) == 0
    results = json.loads(capsys.readouterr().out)["results"]
    assert len(results) == 5
    for i, res in enumerate(results.values()):
        assert res["deflection_unit"] == "V" and res["spring_constant"] == 5.33904
        # the sensitivity is fitted on the hard contact; independently: 1 / slope of the last 100 approach points
        c = load(FILE)[i]
        slope = np.polyfit(c.piezo_nominal[412:512], c.deflection_signal[412:512], 1)[0]
        assert res["sensitivity_fit"] == pytest.approx(1 / slope, rel=0.05)
        assert 3e-9 < res["sensitivity_fit"] < 8e-9
        # adhesion of a stiff lever in air: tens of nN, attractive; jump-in smaller than pull-off
        assert -100e-9 < res["pull_off_force"] < -10e-9
        assert res["pull_off_force"] < res["jump_in_force"] < 0
    assert FILE.read_bytes() == before
    # without the file's spring constant: no forces, and the analysis says which number is missing
    nok = tmp_path / "nok.f.curves"
    nok.write_bytes(RAW.replace(b"Force constant", b"Force konstant", 1))
    assert main(["analyze", str(nok), "--json"]) == 0
    res = next(iter(json.loads(capsys.readouterr().out)["results"].values()))
    assert res["spring_constant"] is None and res["pull_off_force"] is None
    assert any("spring constant" in w for w in res["warnings"])
    # the amplitude file: one line saying why (the analysis' "failed:" of a file), no traceback, non-zero exit
    assert main(["analyze", str(AMPLITUDE)]) != 0
    err = capsys.readouterr().err.strip()
    assert err.startswith(("failed:", "error:")) and len(err.splitlines()) == 1
    assert "'Amplitude'" in err and "Normal force" in err and "Traceback" not in err


def test_mutated_headers_are_read_or_refused_in_the_readers_words(tmp_path):
    """Bytes of the headers (where every length and count lives) overwritten at random: the reader
    either reads the file or raises its FileFormatError, never another exception."""
    rng = np.random.default_rng(7)
    spans = [(0, 3225)] + [(start - len(head), start) for head, start, _, _ in BLOCKS]
    path = tmp_path / "mutated.f.curves"
    refused = 0
    for _ in range(60):
        raw = bytearray(RAW)
        a, b = spans[rng.integers(len(spans))]
        for at in rng.integers(a, b, size=rng.integers(1, 4)):
            raw[at] = int(rng.choice(list(b"0123456789:[] \r\nx-.")))
        path.write_bytes(bytes(raw))
        try:
            curves = load_wsxm_curves(path)
        except FileFormatError as exc:
            refused += 1
            assert str(path) in str(exc)
        else:
            assert curves and all(np.all(np.isfinite(c.deflection_signal)) for c in curves)
    assert refused > 0
