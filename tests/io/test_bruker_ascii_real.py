"""NanoScope Analysis ASCII exports of real curves in the variants instruments write (issue 32, item 3):
quoted header lines with CR CR LF line ends, a CSV with quoted cells and a blank line after every
line, and the processed force-vs-separation export (no spring constant needed, and said so).

The files are written by tests/data/make_bruker_ascii_real_variants.py from two real NanoScope binary
files; the expected values are decoded here again from those files' bytes and headers."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from afmforce.analysis.pipeline import analyze
from afmforce.io import find_format, load

DATA = Path(__file__).resolve().parents[1] / "data"
_spec = importlib.util.spec_from_file_location("gen_real", DATA / "make_bruker_ascii_real_variants.py")
gen = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(gen)
VLSB = 0.000375


def test_the_files_are_what_the_generator_writes(tmp_path, monkeypatch):
    monkeypatch.setattr(gen, "HERE", tmp_path)
    monkeypatch.setattr(gen, "SAPPHIRE", DATA / gen.SAPPHIRE.name)
    monkeypatch.setattr(gen, "EGEL", DATA / gen.EGEL.name)
    for path in gen.main():
        assert path.read_bytes() == (DATA / path.name).read_bytes(), path.name


def test_quoted_header_crcrlf_sapphire():
    path = DATA / "bruker-ascii_sapphire_quoted-crcrlf.txt"
    assert b'"\\Spring Constant: 0.0677954"\r\r\n' in path.read_bytes()  # the stale list is in the header
    assert find_format(path).identifier == "bruker-ascii"
    (c,) = load(path)
    assert c.metadata["spring_constant"] == 90.0  # the Deflection Error list's, not the stale 0.0678
    assert c.metadata["sensitivity"] == pytest.approx(72.76923e-9)
    assert (c.approach.sum(), c.retract.sum()) == (512, 512)
    raw = np.frombuffer((DATA / "bruker-nanoscope_sapphire_TAP525.001").read_bytes(), "<i2", count=1024,
                        offset=40960) * VLSB
    expected = np.concatenate([raw[:512][::-1], raw[512:]])  # both runs from the turning point
    np.testing.assert_allclose(c.deflection_signal, expected, atol=5e-7)
    assert c.metadata["sample_rate"] == pytest.approx(2 * 512 * 1.02796, rel=1e-5)  # \Scan rate, 512 + 512


def test_csv_quoted_cells_and_blank_lines():
    path = DATA / "bruker-ascii_egel_csv-blank-lines.csv"
    assert b'"\r\n\r\n"' in path.read_bytes()
    assert find_format(path).identifier == "bruker-ascii"
    (c,) = load(path)
    assert c.metadata["spring_constant"] == 0.1332 and c.metadata["sensitivity"] == pytest.approx(27.39e-9)
    assert c.deflection_unit == "m" and (c.approach.sum(), c.retract.sum()) == (256, 256)
    volts = np.frombuffer((DATA / "bruker-nanoscope_PyFMlab_Egel4_00025.spm").read_bytes(), "<i4", count=2048,
                          offset=80960) * VLSB
    ex, rt = volts[:1024][::-1], volts[1024:]
    base = np.median(ex[:200])
    expected = np.concatenate([ex[::4], rt[::4]]) - base
    np.testing.assert_allclose(c.deflection_signal, expected * 27.39e-9, atol=1e-14)
    z = c.piezo_nominal
    assert z[c.approach][-1] > z[c.approach][0]  # oriented towards the sample
    assert np.ptp(z) == pytest.approx(227.2211 * 13.203e-9 * 1023 / 1024, rel=1e-6)  # ramp x Zsens, 1st to last


def test_processed_force_vs_separation_needs_no_spring_constant():
    path = DATA / "bruker-ascii_egel_force-separation.txt"
    assert b"Spring Constant" not in path.read_bytes() and b"DeflSens" not in path.read_bytes()
    (c,) = load(path, require=("spring_constant", "sensitivity"))  # a force needs neither
    assert c.deflection_unit == "N" and "spring_constant" not in c.metadata
    assert c.metadata["position_is_separation"] and "force vs separation" in c.metadata["processed"]
    volts = np.frombuffer((DATA / "bruker-nanoscope_PyFMlab_Egel4_00025.spm").read_bytes(), "<i4", count=2048,
                          offset=80960) * VLSB
    ex, rt = volts[:1024][::-1], volts[1024:]
    force = (np.concatenate([ex[::4], rt[::4]]) - np.median(ex[:200])) * 27.39e-9 * 0.1332
    np.testing.assert_allclose(c.deflection_signal, force, atol=1e-14)
    r = analyze(c, steps=("adhesion",))
    assert any("processed export" in w and "no spring constant" in w for w in r.warnings)
    assert r.adhesion_force <= 0


def test_the_exports_sample_poisson_ratio_is_the_binary_files():
    """The export's quoted ``\\Sample Poisson's Ratio`` line (CR CR LF) is read into metadata ``poisson``
    as the binary file it came from states it (0.3, read here from the bytes); the gel's CSV export
    carries no such line, and no ratio is made up for it."""
    import re

    head = (DATA / gen.SAPPHIRE.name).read_bytes()[:40000].decode("latin-1")
    nu = float(re.search(r"\\Sample Poisson's Ratio:\s*([-+.\d]+)", head).group(1))
    (c,) = load(DATA / "bruker-ascii_sapphire_quoted-crcrlf.txt")
    assert c.metadata["poisson"] == nu == 0.3
    assert load(DATA / gen.SAPPHIRE.name)[0].metadata["poisson"] == nu
    (gel,) = load(DATA / "bruker-ascii_egel_csv-blank-lines.csv")
    assert "poisson" not in gel.metadata
