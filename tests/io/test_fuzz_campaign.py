"""Broken files from the mutation campaign (benchmarks/fuzz_readers.py), as seeded regression tests.

Each defect class the campaign found on the real files, before the fix, has its case here, built in the
test from a small file of tests/data (no stored mutants):

* a header number no instrument gives (k = 2^31-1 N/m, sensitivity 1e308 m/V, velocity 99999 m/s) was
  returned as metadata: now a FileFormatError naming the key and its declared range (``_fields.QUANTITIES``),
  and the user's value (``meta_override``) reads the file;
* a Bruker ASCII ``\\Scan rate: 1e308`` divided by zero (ZeroDivisionError, wrapped in a generic refusal);
* a JPK archive whose member fails its CRC or does not decompress, an HDF5 dataset h5py cannot decode:
  generic refusals "the reader stopped on BadZipFile/ReadJPKError/error/OSError": now "damaged ...";
* a truncated zip or HDF5 file: "content not recognised ... name its reader as format": now "cut short";
* a file of one family under another's ending: "renamed? give it its own ending".

The last test runs the campaign's own seeded mutations (truncations, header flips, numeric fields) of
three small files and checks every outcome: a curve with finite columns and in-range metadata, or an
AfmforceError whose one line names the file and is not a generic wrap of a foreign exception.
"""

from __future__ import annotations

import io
import re
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest

from afmforce._fields import QUANTITIES
from afmforce.errors import AfmforceError, FileFormatError
from afmforce.io import load

DATA = Path(__file__).resolve().parents[1] / "data"
sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
import fuzz_readers  # noqa: E402  the campaign's mutation generators: one definition

RAW = DATA / "afmforce-raw_jpk-cellhesion-spot3.txt"
BRUKER = DATA / "bruker-ascii_egel_csv-blank-lines.csv"
TAB = DATA / "afmformats-tab_asylum-sin-tip.tab"
JPK = DATA / "jpk_cellhesion_spot3.jpk-force"
H5 = DATA / "afmforce-hdf5_virtual-afm.h5"


def _edit(src: Path, pattern: bytes, value: bytes, dst: Path) -> Path:
    data = src.read_bytes()
    new, n = re.subn(pattern, lambda m: m.group(1) + value, data, count=1)
    assert n == 1, pattern
    dst.write_bytes(new)
    return dst


@pytest.mark.parametrize("src, pattern, key", [
    (RAW, rb"(# spring_constant: )[0-9.eE+-]+", "spring_constant"),
    (RAW, rb"(# sensitivity: )[0-9.eE+-]+", "sensitivity"),
    (BRUKER, rb"(\\Spring Constant: )[0-9.eE+-]+", "spring_constant"),
    (TAB, rb'("spring constant": )[0-9.eE+-]+', "spring_constant"),
    (TAB, rb'("sensitivity": )[0-9.eE+-]+', "sensitivity"),
])
@pytest.mark.parametrize("value", [b"2147483647", b"1e308", b"1e-30"])
def test_a_header_number_no_instrument_gives_is_refused_naming_the_key(src, pattern, key, value, tmp_path):
    path = _edit(src, pattern, value, tmp_path / ("m" + src.suffix))
    with pytest.raises(FileFormatError, match=rf"{key} = .* is out of range.*`{key}`"):
        load(path)
    right = load(src)[0].metadata[key]
    curves = load(path, meta_override={key: right})    # the user's value reads the damaged file
    assert curves[0].metadata[key] == right


@pytest.mark.parametrize("value", [b"0", b"-1", b"nan"])
def test_a_zero_or_negative_spring_constant_is_never_returned(value, tmp_path):
    for src, pattern in ((RAW, rb"(# spring_constant: )[0-9.eE+-]+"), (BRUKER, rb"(\\Spring Constant: )[0-9.eE+-]+")):
        path = _edit(src, pattern, value, tmp_path / ("k" + src.suffix))
        try:
            curves = load(path)
        except AfmforceError:
            continue
        k = curves[0].metadata.get("spring_constant")
        assert k is None or QUANTITIES["spring_constant"].contains(k), k


def test_a_damaged_scan_rate_is_refused_not_divided_by(tmp_path):
    path = _edit(BRUKER, rb"(\\Scan rate: )[0-9.eE+-]+", b"1e308", tmp_path / "rate.csv")
    with pytest.raises(FileFormatError, match=r"Scan rate 1e\+308 Hz.*`sample_rate`") as info:
        load(path)
    assert "ZeroDivisionError" not in str(info.value)
    assert load(path, meta_override={"sample_rate": 2000.0})[0].metadata["sample_rate"] == 2000.0


def _flip_in_member(src: Path, suffix: str) -> bytes:
    """The archive with one byte of the first member ending in ``suffix`` flipped (its CRC then fails)."""
    data = bytearray(src.read_bytes())
    with zipfile.ZipFile(io.BytesIO(bytes(data))) as z:
        info = next(i for i in z.infolist() if i.filename.endswith(suffix) and i.compress_size > 8)
    start = info.header_offset + 30 + len(info.filename.encode()) + len(info.extra)
    data[start + info.compress_size // 2] ^= 0x10
    return bytes(data)


@pytest.mark.parametrize("member", [".dat", "segment-header.properties"])
def test_a_zip_member_that_fails_its_checksum_is_named_damaged(member, tmp_path):
    path = tmp_path / "crc.jpk-force"
    path.write_bytes(_flip_in_member(JPK, member))
    with pytest.raises(FileFormatError, match="damaged") as info:
        load(path)
    assert "could not read it" not in str(info.value)       # not the generic wrap of BadZipFile/ReadJPKError


@pytest.mark.parametrize("src", [JPK, H5])
@pytest.mark.parametrize("fraction", [0.05, 0.5, 0.95])
def test_a_cut_archive_says_cut_short_not_unrecognised(src, fraction, tmp_path):
    data = src.read_bytes()
    path = tmp_path / ("cut" + src.suffix)
    path.write_bytes(data[:int(len(data) * fraction)])
    with pytest.raises(FileFormatError) as info:
        load(path)
    text = str(info.value)
    assert "cut short" in text or "truncated" in text, text
    assert "content not recognised" not in text


@pytest.mark.parametrize("src, ending", [(JPK, ".txt"), (DATA / "asylum-mfp3d_SiN-tip_air.ibw", ".csv"),
                                         (H5, ".tab")])
def test_a_file_under_another_family_ending_is_named_renamed(src, ending, tmp_path):
    path = tmp_path / ("renamed" + ending)
    path.write_bytes(src.read_bytes())
    with pytest.raises(FileFormatError, match=r"renamed\? give it its own ending \(.*" + re.escape(src.suffix)):
        load(path)


def _outcome(path: Path) -> str | None:
    """None when ``load`` keeps afmforce's promise for this file, else what is wrong."""
    try:
        curves = load(path, timeout=20.0)
    except AfmforceError as exc:
        text = str(exc)
        if "\n" in text.strip() or path.name not in text:
            return f"message not one line naming the file: {text[:200]}"
        if "could not read it" in text and re.search(r"\((?:BadZipFile|error|OSError|ZeroDivisionError|"
                                                     r"ReadJPKError)\b|stopped on (?:ReadJPKError|OSError)", text):
            return f"generic wrap of a damage exception: {text[:200]}"
        return None
    except Exception as exc:  # noqa: BLE001  the defect the test hunts
        return f"{type(exc).__name__}: {str(exc)[:200]}"
    problems = fuzz_readers._plausibility(curves)
    problems = [p for p in problems if "constant deflection" not in p]   # flat garbage is finite, in range
    return "; ".join(problems) or None


@pytest.mark.parametrize("src", [RAW, BRUKER, JPK], ids=lambda p: p.name)
def test_seeded_campaign_mutations_of_small_files(src, tmp_path):
    cases = fuzz_readers.mutations(src, seed=sum(src.name.encode()))
    cases = [c for c in cases if c[0] != "ending"][:60]   # truncations, header flips, fields, zip members
    assert len(cases) >= 30
    bad = []
    for kind, detail, blob, ending in cases:
        path = tmp_path / ("m" + ending)
        path.write_bytes(blob)
        problem = _outcome(path)
        assert path.read_bytes() == blob   # input never modified
        if problem:
            bad.append(f"{kind} {detail}: {problem}")
    assert not bad, bad


@pytest.mark.parametrize("src", [TAB, BRUKER, DATA / "chiaro-txt_AEBP1_Indentation_002_thinned.txt"],
                         ids=lambda p: p.suffix)
def test_a_text_table_cut_inside_its_last_number_is_refused(src, tmp_path):
    data = src.read_bytes().rstrip(b"\r\n")
    whole = tmp_path / ("whole" + src.suffix)
    whole.write_bytes(data)                       # complete, without the final line break: read as before
    assert sum(map(len, load(whole))) == sum(map(len, load(src)))
    cut = tmp_path / ("cut" + src.suffix)
    cut.write_bytes(data[:-3])                    # the last value loses its last digits (1.2345e-09 -> 1.2345e-)
    with pytest.raises(FileFormatError, match="ends inside its last line.*copy it again"):
        load(cut)
