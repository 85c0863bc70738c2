"""NanoScope Analysis ASCII exports (issue 24): every variant of the description, read against the
curve the generator wrote (tests/data/make_bruker_ascii_variants.py), sample for sample.

The expected numbers come from the generator's source curve in time order (static_curve), never from
the reader: deflection in the unit of the column chosen, position oriented to increase towards the
sample, time from the Time columns or the header's scan rate, k and InvOLS from the quoted header.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from afmforce.errors import FileFormatError
from afmforce.io import find_format, load

DATA = Path(__file__).resolve().parents[1] / "data"
_spec = importlib.util.spec_from_file_location("make_bruker_ascii_variants", DATA / "make_bruker_ascii_variants.py")
gen = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(gen)
SRC = gen.source()
N = int((SRC.segment == 0).sum())
VOLTS = np.round(SRC.deflection_signal, 7)
#: the deflection each file's reader output must hold, in time order: unit -> values [SI]
EXPECTED = {"V": VOLTS, "m": (VOLTS - gen.OFFSET) * gen.SENS, "N": (VOLTS - gen.OFFSET) * gen.SENS * gen.K}
UNIT = {"bruker-ascii_nm_retract-reversed.txt": "m", "bruker-ascii_pN_time-columns.txt": "N",
        "bruker-ascii_volts_reversed-time.txt": "V"}


def test_the_files_are_what_the_generator_writes(tmp_path, monkeypatch):
    monkeypatch.setattr(gen, "HERE", tmp_path)
    for path in gen.main():
        assert path.read_bytes() == (DATA / path.name).read_bytes(), path.name


@pytest.mark.parametrize("name", sorted(gen.VARIANTS))
def test_every_variant_reads_the_source_curve(name):
    path = DATA / name
    assert find_format(path).identifier == "bruker-ascii"
    (c,) = load(path)
    assert c.metadata["spring_constant"] == 0.34                       # "\Spring Constant: 0.34"
    assert c.metadata["sensitivity"] == pytest.approx(61.5e-9, rel=1e-12)  # "\@Sens. DeflSens: V 61.5 nm/V"
    assert c.deflection_unit == UNIT[name]
    np.testing.assert_array_equal(c.segment, SRC.segment)             # 180 extend then 180 retract rows
    # deflection in time order (a reversed retract is put back), to the 5-7 digits written
    np.testing.assert_allclose(c.deflection_signal, EXPECTED[UNIT[name]], rtol=0,
                               atol=1e-12 if UNIT[name] == "m" else 1e-11 * gen.K if UNIT[name] == "N" else 1e-7)
    z = c.piezo_measured if c.piezo_measured is not None else c.piezo_nominal
    np.testing.assert_allclose(z, SRC.piezo_measured, rtol=0, atol=1e-14)  # heights flipped where they decrease
    np.testing.assert_allclose(c.time, SRC.time, rtol=0, atol=1e-9)      # Time columns or \Scan rate
    assert c.metadata["sample_rate"] == pytest.approx(gen.RATE, rel=1e-6)
    assert c.metadata["velocity"] == pytest.approx(1e-6, rel=1e-6)     # 90 nm in 0.09 s


def _write(tmp_path, text: str, name="export.txt", encoding="utf-8") -> Path:
    path = tmp_path / name
    path.write_bytes(text.encode(encoding))
    return path


def _table(cols: dict[str, np.ndarray], quoted=True, lead="") -> str:
    head = gen.header(N)
    if not quoted:
        head = [h.strip('"') for h in head]
    n = max(len(v) for v in cols.values())
    rows = ["\t".join(f"{v[i]:.7f}" if i < len(v) else "" for v in cols.values()) for i in range(n)]
    return "\n".join(head + [lead + "\t".join(cols)] + rows) + "\n"


def _runs(sign=-1):
    return gen.columns(SRC, sign)


def test_retract_rows_reversed_without_time_or_deflection_hint(tmp_path):
    """The retract's direction comes from the piezo: a flat (zero) deflection gives no turning point."""
    r = _runs()
    flat = np.zeros(N)
    path = _write(tmp_path, _table({"Calc_Ramp_Ex_nm": r["Ex"]["Calc_Ramp_nm"], "Defl_nm_Ex": flat,
                                    "Calc_Ramp_Rt_nm": r["Rt"]["Calc_Ramp_nm"][::-1], "Defl_nm_Rt": flat + 1.0}))
    (c,) = load(path)
    np.testing.assert_allclose(c.piezo_nominal, SRC.piezo_measured, atol=1e-14)
    assert np.all(c.deflection_signal[c.segment == 1] == 1e-9)


def test_mixed_units_choose_the_one_every_run_has_and_duplicates_keep_the_first(tmp_path):
    r = _runs()
    cols = {"Defl_V_Ex": r["Ex"]["Defl_V"], "Defl_nm_Ex": r["Ex"]["Defl_nm"], "Defl_nm_Rt": r["Rt"]["Defl_nm"],
            "Height_Sensor_nm_Ex": r["Ex"]["Height_Sensor_nm"], "Height_Sensor_nm_Rt": r["Rt"]["Height_Sensor_nm"]}
    (c,) = load(_write(tmp_path, _table(cols)))
    assert c.deflection_unit == "m"                     # Rt has no volts: nm for both
    np.testing.assert_allclose(c.deflection_signal, EXPECTED["m"], atol=1e-15)
    dup = {"Defl_nm_Ex": r["Ex"]["Defl_nm"], "Defl_nm_Rt": r["Rt"]["Defl_nm"],
           "Calc_Ramp_Ex_nm": r["Ex"]["Calc_Ramp_nm"], "Calc_Ramp_Rt_nm": r["Rt"]["Calc_Ramp_nm"]}
    text = _table(dup).replace("Calc_Ramp_Rt_nm\n", "Calc_Ramp_Rt_nm\tDefl_nm_Ex\n")
    text = "\n".join(ln + ("\t99" if ln and ln[0] in "-0123456789" else "") for ln in text.split("\n"))
    (c,) = load(_write(tmp_path, text, "dup.txt"))
    assert c.deflection_signal.max() < 1e-7             # the second Defl_nm_Ex (99 nm) is ignored


def test_extend_run_only(tmp_path):
    r = _runs()
    (c,) = load(_write(tmp_path, _table({"Defl_pN_Ex": r["Ex"]["Defl_pN"], "Calc_Ramp_Ex_nm": r["Ex"]["Calc_Ramp_nm"]})))
    assert set(np.unique(c.segment)) == {0} and c.deflection_unit == "N"
    np.testing.assert_allclose(c.piezo_nominal, SRC.piezo_measured[:N], atol=1e-14)
    assert c.metadata["sample_rate"] == pytest.approx(gen.RATE)  # the scan rate counts both runs
    with pytest.raises(FileFormatError, match="only retract"):
        load(_write(tmp_path, _table({"Defl_pN_Rt": r["Rt"]["Defl_pN"], "Calc_Ramp_Rt_nm": r["Rt"]["Calc_Ramp_nm"]}),
                    "rt.txt"))


def test_utf16_unquoted_and_trailing_blank_header(tmp_path):
    r = _runs(+1)
    cols = {"Calc_Ramp_Ex_nm": r["Ex"]["Calc_Ramp_nm"], "Calc_Ramp_Rt_nm": r["Rt"]["Calc_Ramp_nm"],
            "Defl_V_Ex": r["Ex"]["Defl_V"], "Defl_V_Rt": r["Rt"]["Defl_V"]}
    for quoted in (True, False):
        path = _write(tmp_path, _table(cols, quoted=quoted).replace("\n", "\r\n"), f"u{quoted}.txt", "utf-16")
        assert find_format(path).identifier == "bruker-ascii"
        (c,) = load(path)
        np.testing.assert_allclose(c.deflection_signal, VOLTS, atol=1e-7)
        np.testing.assert_allclose(c.piezo_nominal, SRC.piezo_measured, atol=1e-14)


@pytest.mark.parametrize("cols,message", [
    ({"Calc_Ramp_Ex_nm": [1.0, 2.0], "Calc_Ramp_Rt_nm": [2.0, 1.0]}, "no deflection column"),
    ({"Defl_V_Ex": [1.0, 2.0], "Defl_nm_Rt": [2.0, 1.0], "Calc_Ramp_Ex_nm": [1.0, 2.0],
      "Calc_Ramp_Rt_nm": [2.0, 1.0]}, "in the same unit"),
    ({"Defl_V_Ex": [1.0, 2.0], "Defl_V_Rt": [2.0, 1.0]}, "no position column"),
])
def test_missing_columns_are_named(tmp_path, cols, message):
    path = _write(tmp_path, _table({k: np.array(v) for k, v in cols.items()}))
    with pytest.raises(FileFormatError, match=message):
        load(path)
