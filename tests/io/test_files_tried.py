"""Public files never read here before (tests/data/README.md, "Files tried"): what they revealed.

Each test asserts against values read without afmforce (the header text with a regular expression,
the raw table with numpy) or against nanite 4.2.3. Files whose licence is GPL or unstated are not in
tests/data: they are looked for in ``AFMFORCE_REAL_DATA`` (tests/realdata.py) and skipped where absent;
each fix is also tested on an MIT file here, changed in a temporary folder the way the real file differs.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from afmforce.io import find_format, load
from realdata import DATA, real_file  # noqa: E402  (tests/ is on sys.path: tests/conftest.py)

CHIARO_MIT = DATA / "chiaro-txt_AEBP1_Indentation_002_thinned.txt"


def _table(path: Path) -> tuple[dict[str, float], np.ndarray]:
    """An Optics11 export read with numpy alone: ``k``, ``R`` [m] and the numeric table."""
    lines = path.read_bytes().decode("latin-1").splitlines()
    top = next(i for i, ln in enumerate(lines) if ln.startswith("Time (s)\tLoad"))
    text = "\n".join(lines[:top])
    head = {"k": float(re.search(r"k \(N/m\)\t([\d.]+)", text).group(1)),
            "R": float(re.search(r"Tip radius \(.m\)\t([\d.]+)", text).group(1)) * 1e-6}
    table = np.array([[float(v) for v in ln.split("\t")] for ln in lines[top + 1:] if ln.strip()])
    return head, table


@pytest.mark.parametrize("device", [None, b"Piuma"])
def test_optics11_export_without_a_chiaro_device_line_is_read(tmp_path, device):
    """Optics11 exports of 2020 write no ``Device:`` line and a Piuma's says ``Device:<TAB>Piuma``: both were
    refused as 'content not recognised'; the MIT Chiaro file changed that way reads as it did, bit for bit."""
    raw = CHIARO_MIT.read_bytes()
    assert b"Device:\tChiaro" in raw
    changed = raw.replace(b"Device:\tChiaro", b"Device:\t" + device) if device else re.sub(
        rb"Device:\tChiaro\r?\n", b"", raw)
    path = tmp_path / "export.txt"
    path.write_bytes(changed)
    assert find_format(path).identifier == "chiaro-txt"
    (got,), (ref,) = load(path), load(CHIARO_MIT)
    np.testing.assert_array_equal(got.deflection_signal, ref.deflection_signal)
    np.testing.assert_array_equal(got.piezo_nominal, ref.piezo_nominal)
    np.testing.assert_array_equal(got.segment, ref.segment)
    assert got.metadata["instrument"] == (device.decode() if device else "Optics11 indenter")


@pytest.mark.parametrize("name", ["optics11-piuma_V3.5.0_NanoPrepare_test2.txt",
                                  "optics11-chiaro_2020_NanoPrepare_PEGFN_X1Y1.txt"])
def test_real_optics11_exports_read_as_their_headers_say(name):
    """CellMechLab/NanoPrepare testdata (GPL-3.0): a Piuma V3.5.0 export and a Chiaro export of 2020, both
    refused before. k and the tip radius as the header states them (read with a regex), the force the Load
    column [uN] exactly, and the profile's hold at the deepest step a dwell."""
    path = real_file(name)
    head, table = _table(path)
    (c,) = load(path)
    assert c.metadata["spring_constant"] == head["k"]
    assert c.metadata["radius"] == pytest.approx(head["R"], rel=1e-12)
    np.testing.assert_allclose(c.deflection_signal, table[:, 1] * 1e-6, rtol=0, atol=0)
    assert np.any(c.segment == 2)  # the displacement profile's hold at the deepest step is a dwell


def test_igor_wave_without_the_asylum_note_is_refused_in_one_line(tmp_path):
    """igor2's test waves (``win-double.ibw``, ``mac-zeroPointWave.ibw``: plain waves Igor wrote, no Asylum
    note) were refused as "afmformats cannot read it (KeyError: 'ImagingMode')". The MIT Asylum curve with
    its note blanked (same length, read back with igor2) is now refused naming what is missing."""
    from igor2 import binarywave

    from afmforce.errors import FileFormatError

    src = DATA / "asylum-mfp3d_SiN-tip_air.ibw"
    raw = src.read_bytes()
    note = binarywave.load(str(src))["wave"]["note"]
    at = raw.find(note)
    assert at > 0 and b"SpringConstant" in note
    path = tmp_path / "plain.ibw"
    path.write_bytes(raw[:at] + b" " * len(note) + raw[at + len(note):])
    assert binarywave.load(str(path))["wave"]["note"].strip() == b""
    with pytest.raises(FileFormatError) as err:
        load(path)
    msg = str(err.value)
    assert "\n" not in msg and "KeyError" not in msg
    assert "ImagingMode, SpringConstant, InvOLS" in msg and "afmforce raw text" in msg


@pytest.mark.parametrize("name, words", [
    ("sample_0.h5-jpk", "JPK HDF5 file (.h5-jpk"),
    ("sample_0.asd", "high-speed AFM movie"),
    ("sample_0_1.topostats", "TopoStats file"),
    ("sample_0.top", "WSxM image (.top)"),
])
def test_image_families_of_afmreader_are_named_not_unknown(tmp_path, name, words):
    """AFMReader 0.0.7's test images (sdist tests/resources, GPL-3.0: not kept) of these endings got
    "unknown file type; supported endings: ..."; each is now named with what to give instead. The
    content does not matter to the refusal by ending: HDF5's or the ASD's first bytes stand in."""
    from afmforce.errors import FileFormatError
    from afmforce.io import is_supported

    path = tmp_path / name
    path.write_bytes(b"\x89HDF\r\n\x1a\n" + b"\0" * 64)
    with pytest.raises(FileFormatError) as err:
        load(path)
    msg = str(err.value)
    assert "\n" not in msg and "unknown file type" not in msg and words in msg
    assert not is_supported(path)
