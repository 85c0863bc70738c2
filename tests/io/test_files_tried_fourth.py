"""Public files of the fourth round (tests/data/README.md, "Files tried"): what they showed wrong.

A SoftMech export (CellMechLab/softmech ``tools/h1000_curve.csv``, MIT, kept unchanged as
``tests/data/refused/softmech_h1000_average-curve.csv``: an averaged F-z curve with columns ``Z(m),F_avg(N),
F_std(N)``) was taken for an AFM Workshop CSV export, because afmformats' recipe claims every ``.csv`` by its
ending, and refused with afmformats' parser error ("Could not parse metadata correctly"). The AFM Workshop
reader now asks for the line its files begin with (``Force-Distance Curve``, afmformats' own docstring and
every AFM Workshop file in tests/data) before the column line, and says so when named with ``--format``.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from afmforce.errors import FileFormatError
from afmforce.io import find_format, load

DATA = Path(__file__).resolve().parents[1] / "data"
SOFTMECH = DATA / "refused" / "softmech_h1000_average-curve.csv"


def _softmech_header(path: Path) -> Path:
    """SoftMech's other export (its ``tools/test.csv``): '#' header lines, then tab-separated numbers."""
    rows = [f"{i * 1e-9:.6e}\t{i * 1e-12:.6e}\t{1e-12:.6e}" for i in range(50)]
    path.write_text("#SoftMech export data\n#Average F-d curve\n#Direction:V\n#Elastic constant [N/m]: 0.032\n"
                    "#Columns: Indentation <F> SigmaF\n#\n#DATA\n" + "\n".join(rows) + "\n")
    return path


@pytest.mark.parametrize("make", [lambda tmp: SOFTMECH, lambda tmp: _softmech_header(tmp / "softmech.csv")],
                         ids=["softmech-real", "softmech-header"])
def test_a_csv_of_another_program_is_not_taken_for_afm_workshop(tmp_path, make):
    path = make(tmp_path)
    assert path.read_text(encoding="latin-1").splitlines()[0] != "Force-Distance Curve"
    with pytest.raises(FileFormatError) as err:
        find_format(path)
    msg = str(err.value)
    assert "content not recognised" in msg and "afmformats" not in msg and "\n" not in msg
    with pytest.raises(FileFormatError) as err:
        load(path, format="afm-workshop-csv")
    msg = str(err.value)
    first = path.read_text(encoding="latin-1").splitlines()[0]
    assert "not an AFM Workshop CSV export" in msg and repr(first) in msg and "afmformats" not in msg


def test_every_afm_workshop_file_here_is_still_detected():
    files = [p for p in DATA.rglob("*.csv") if p.read_bytes().lstrip().startswith(b"Force-Distance Curve")]
    assert len(files) >= 7
    for path in files:
        assert find_format(path).identifier == "afm-workshop-csv", path


# --- an Igor wave of another program holding an image ----------------------------------------------------

#: Omicron MATRIX's Igor export of an STM current image (pycroscopy/SciFiDatasets, MIT, unchanged): a 256 x 58
#: wave whose note begins "SPM Image" and names MATRIX V4.3.5; it was refused as "this Asylum .ibw holds an image".
MATRIX_IBW = DATA / "refused" / "omicron-matrix_stm-image_ScV6Sn6_I-backward.ibw"


def test_an_igor_image_of_another_program_is_not_called_asylum():
    from igor2 import binarywave

    wave = binarywave.load(str(MATRIX_IBW))["wave"]
    assert wave["wData"].shape == (256, 58)
    note = wave["note"].decode("latin-1")
    assert "MATRIX version" in note and not any(f"{k}:" in note for k in ("ImagingMode", "SpringConstant", "InvOLS"))
    with pytest.raises(FileFormatError) as err:
        load(MATRIX_IBW)
    msg = str(err.value)
    assert "Asylum .ibw" not in msg and "Igor binary wave (its note is not the Asylum software's" in msg
    assert "256 x 58 pixels, 1 channel" in msg and "\n" not in msg


def test_an_asylum_image_is_still_called_asylum(tmp_path):
    """The PFM images of SciFiDatasets carry the Asylum note: ``tests/io/test_refused_images.py`` reshapes the
    Asylum curve's wave (its note kept) into an image; the same here, on the line's wording."""
    import struct

    raw = bytearray((DATA / "asylum-mfp3d_SiN-tip_air.ibw").read_bytes())
    raw[64 + 68:64 + 84] = struct.pack("<4i", 96, 63, 1, 0)
    path = tmp_path / "image.ibw"
    path.write_bytes(bytes(raw))
    with pytest.raises(FileFormatError) as err:
        load(path)
    assert "this Asylum .ibw holds an image (96 x 63 pixels" in str(err.value)


# --- families met this round that no reader claims: named, not "unknown file type" -----------------------

@pytest.mark.parametrize("name, content, words", [
    ("pp_cell_01.016.mat", b"MATLAB 5.0 MAT-file, Platform: MACI64" + b"\0" * 100, "MATLAB data file"),
    ("grid.3ds", b'Grid dim="30 x 30"\r\nSweep Signal="Bias (V)"\r\n', "Nanonis grid spectroscopy"),
    ("image.sxm", b":NANONIS_VERSION:\n2\n", "Nanonis image"),
    ("chip.gsf", b"Gwyddion Simple Field 1.0\nXRes = 300\n", "Gwyddion Simple Field"),
    ("film.axz", b"\x1f\x8b\x08\x00" + b"\0" * 32, "Anasys"),
])
def test_families_of_this_round_are_refused_by_name(tmp_path, name, content, words):
    """jpsferreira/AFM_curve_analysis' and jhaydak3/AFM_ML's `.mat` curves, SciFiDatasets' Nanonis `.3ds`,
    Gwyddion `.gsf` and Anasys `.axz` got "unknown file type; supported endings: ..." (the signatures here
    are those files' first bytes)."""
    from afmforce.io import is_supported

    path = tmp_path / name
    path.write_bytes(content)
    with pytest.raises(FileFormatError) as err:
        load(path)
    msg = str(err.value)
    assert words in msg and "unknown file type" not in msg and "\n" not in msg
    assert not is_supported(path)


# --- a Git LFS pointer in place of the file --------------------------------------------------------------

#: bicarlsen/jpk_reader's ``data/qi_data/qi_data-sm.jpk-qi-data`` (commit e9486d4, MIT) as a clone without Git
#: LFS holds it: 130 bytes of pointer text (PyFMlab_DyNaMo's QI file and gnezd/ARDF_read's map are stored so too).
POINTER = (b"version https://git-lfs.github.com/spec/v1\n"
           b"oid sha256:90852b6e5a4652961a429a6e01ac8463e3d419443d2bf1e0412fa2b0aae504fa\nsize 73741\n")


@pytest.mark.parametrize("name, fmt", [("qi-data-sm.jpk-qi-data", None), ("ForceMap001.ARDF", None),
                                       ("curve.ibw", None), ("fv_00001.spm", "bruker-nanoscope"),
                                       ("spectroscopy.nid", None), ("notes.dat", None)])
def test_a_git_lfs_pointer_says_the_file_was_not_downloaded(tmp_path, name, fmt):
    """Before: "content not recognised as any of: JPK force curve ...; name its reader as --format" (and for
    the .ibw "not an Igor binary wave (version field 30309)"), which sends the user after the wrong cause."""
    assert len(POINTER) == 130
    path = tmp_path / name
    path.write_bytes(POINTER)
    with pytest.raises(FileFormatError) as err:
        load(path, format=fmt)
    msg = str(err.value)
    assert "Git LFS pointer" in msg and "73,741-byte file" in msg and "git lfs pull" in msg and "\n" not in msg
    assert "content not recognised" not in msg
