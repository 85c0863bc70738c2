"""NanoScope Analysis exports as they come off real instruments (issue 32, item 3), the four Fodis
files of the corpus: a whole ``"\\?Force file list"`` header quoted line by line with CR CR LF line
ends, and three exports of one plotted run (a unit row ``nm  nN``, no header: processed force).

Expected values are read by eye from the files' text (quoted below) and decoded here with numpy."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from afmforce.analysis.pipeline import analyze
from afmforce.io import find_format, load

CORPUS = Path(__file__).resolve().parents[1] / "data" / "corpus"


def test_quoted_question_mark_header_with_crcrlf():
    path = CORPUS / "bruker-ascii_fodis_ScanAsyst-glass.txt"
    raw = path.read_bytes()
    assert raw.startswith(b'"\\?Force file list"\r\r\n')
    assert find_format(path).identifier == "bruker-ascii"
    (c,) = load(path)
    md = c.metadata
    # "\Spring Constant: 0.337691" (every force image list), "\@Sens. DeflSens: V 46.81180 nm/V",
    # "\Scan rate: 1.00469" ramps/s, "\Samps/line: 512 512"
    assert md["spring_constant"] == 0.337691
    assert md["sensitivity"] == pytest.approx(46.81180e-9, rel=1e-12)
    assert md["sample_rate"] == pytest.approx(1.00469 * 1024, rel=1e-9)
    assert c.deflection_unit == "m" and (c.approach.sum(), c.retract.sum()) == (512, 512)
    # the first data row: Defl_nm_Ex -13.48180, Defl_nm_Rt 7.513523, PF_Z_Sensor_nm_Ex -1847.625, _Rt -867.0
    assert c.deflection_signal[0] == pytest.approx(-13.48180e-9) and c.deflection_signal[512] == pytest.approx(7.513523e-9)
    z = c.piezo_nominal
    assert abs(z[0]) == pytest.approx(1847.625e-9) and abs(z[512]) == pytest.approx(867.0e-9)
    assert z[c.approach][-1] > z[c.approach][0]  # oriented towards the sample
    # the exported force column is k x deflection: the file's own check of the spring constant
    rows = np.array([ln.split("\t")[:4] for ln in raw.decode("latin-1").split("\r\n") if ln[:1] and ln[0] in "-0123456789"],
                    dtype=float)
    assert np.median(rows[:, 2] / rows[:, 0]) * 1e-3 == pytest.approx(0.337691, rel=1e-3)


@pytest.mark.parametrize("name, run, units, n", [
    ("bruker-ascii_fodis_ScanAsyst-glass_retract.txt", "retract", (1e-6, 1e-9), 512),
    ("bruker-ascii_fodis_extracted.txt", "approach", (1e-9, 1e-9), 2048),
    ("bruker-ascii_fodis_mica-GA6_baseline-corrected.txt", "retract", (1e-9, 1e-12), 1024),
])
def test_one_run_export_with_a_unit_row(name, run, units, n):
    path = CORPUS / name
    table = np.loadtxt(path, skiprows=1, encoding="latin-1")
    assert find_format(path).identifier == "bruker-ascii"
    (c,) = load(path, require=("spring_constant", "sensitivity"))  # a force needs neither
    assert c.deflection_unit == "N" and "spring_constant" not in c.metadata
    assert c.metadata["single_run"] == run and "the export does not name it" in c.metadata["processed"]
    assert len(c.time) == n and np.all(c.segment == (0 if run == "approach" else 1))
    np.testing.assert_allclose(c.deflection_signal, table[:, 1] * units[1], rtol=1e-12)
    np.testing.assert_allclose(np.abs(c.piezo_nominal), np.abs(table[:, 0] * units[0]), rtol=1e-12)
    force, z = c.deflection_signal, c.piezo_nominal
    contact = np.argmax(force)  # the position increases towards the contact (largest force)
    assert z[contact] >= np.median(z)
    other = "retract" if run == "approach" else "approach"   # one run: the other's steps not available
    assert analyze(c).not_applicable["shift"] == f"not available: no {other} run"  # (tests/analysis/test_single_run.py)


def test_the_retract_export_is_the_whole_exports_retract_columns():
    """The same curve exported twice: the one-run export (um, nN) equals PF_Z_Sensor_nm_Rt and Defl_pN_Rt."""
    (whole,) = load(CORPUS / "bruker-ascii_fodis_ScanAsyst-glass.txt")
    (rt,) = load(CORPUS / "bruker-ascii_fodis_ScanAsyst-glass_retract.txt")
    k = whole.metadata["spring_constant"]
    np.testing.assert_allclose(rt.deflection_signal, whole.deflection_signal[whole.retract] * k, rtol=2e-6, atol=2e-15)
    np.testing.assert_allclose(rt.piezo_nominal, whole.piezo_nominal[whole.retract], rtol=1e-6, atol=1e-13)
