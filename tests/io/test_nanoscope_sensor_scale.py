"""The Z sensor (Height Sensor) of a NanoScope force file against the nominal ramp.

The sensor is read with Bruker's scale, counts x the channel's V/LSB (``\\@4:Z scale: V [Sens. ZsensSens]
(0.000375 V/LSB)``) x ``\\@Sens. ZsensSens`` [nm/V], as Bruker's Bede Pittenger gives it for the Height
Sensor of force curves (Nanoscale World forum, "Understanding raw data in header of force curve files",
2012: "163.0064*0.000375 nm/LSB"); the nominal ramp is ``Ramp size`` [V] x ``Zsens`` [nm/V]. On Bruker's own
closed-loop example (BioScope Resolve, PyPI ``nanoscope`` 1.2.300) the two agree within 3 %; on the BioScope
Catalyst files (NanoScope 9.1, PLSys and the pyfmrheo tutorial; ``Z Closed Loop: Off``) the sensor travels
1.18-1.35 x the ramp, and its steps against the ramp's grow along each run and differ between the runs at the
same place (approach near the turning point 1.22-1.42 x, retract just after it 1.01-1.03 x): an open-loop
piezo's hysteresis, a motion the sensor records and the ramp does not, which no constant scale could make.
The reader keeps the sensor (the measured position) and says how far it is from the ramp
(``position_note``, among the analysis's warnings), since the modulus depends on it (nominal / sensor
1.39-2.09 on these curves, afmforce and nanite alike on the same arrays: docs/formats.md)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from afmforce.analysis.state import prepare
from afmforce.io import load
from realdata import real_file  # noqa: E402  (tests/ is on sys.path: tests/conftest.py)
from test_nanoscope import _write  # noqa: E402

CORPUS = Path(__file__).resolve().parents[1] / "data" / "corpus"
CATALYST = ["bruker-nanoscope_v9.1_Catalyst_PLSys_cr00028.000", "bruker-nanoscope_v9.1_Catalyst_PLSys_cr00037.000",
            "bruker-nanoscope_v9.1_Catalyst_PLSys_cr00041.000", "bruker-nanoscope_v9.1_Catalyst_PLSys_cr00043.000",
            "bruker-nanoscope_v9.1_Catalyst_PLSys_cr00082.000", "bruker-nanoscope_v9.1_Catalyst_PLSys_cr00175.000",
            "bruker-nanoscope_v9.1_Catalyst_cr00000.000"]


def _sensor_by_hand(path: Path) -> tuple[np.ndarray, int]:
    """The Height Sensor [m] in storage order (each run from the turning point), decoded without afmforce:
    int16 counts at the channel's Data offset x its V/LSB x ZsensSens; and the samples of a run."""
    raw = path.read_bytes()
    head = raw[:raw.index(b"\\*File list end")].decode("latin-1")
    zss = float(re.search(r"\\@Sens\. ZsensSens: V ([\d.]+) nm/V", head).group(1)) * 1e-9
    for block in head.split("\\*Ciao force image list")[1:]:
        if "[ZSensor]" in block:
            at = int(re.search(r"\\Data offset: (\d+)", block).group(1))
            n = int(re.search(r"\\Data length: (\d+)", block).group(1))
            vlsb = float(re.search(r"Z scale: V \[Sens\. ZsensSens\] \(([\d.]+) V/LSB\)", block).group(1))
            return np.frombuffer(raw[at:at + n], "<i2") * vlsb * zss, n // 4
    raise AssertionError("no ZSensor channel")


def _steps(zm: np.ndarray, zn: np.ndarray) -> float:
    return abs(float(np.polyfit(zn, zm, 1)[0]))


@pytest.mark.parametrize("name", CATALYST)
def test_catalyst_height_sensor_is_brukers_scale_and_records_more_motion_than_the_ramp(name):
    path = real_file(name)
    stored, n = _sensor_by_hand(path)
    (c,) = load(path)
    app, ret = c.segment == 0, c.segment == 1
    zm, zn = c.piezo_measured, c.piezo_nominal
    # Bruker's scale, up to the sign the reader gives the position (growing towards the sample)
    np.testing.assert_allclose(np.abs(zm[app]), np.abs(stored[:n][::-1]), rtol=1e-12)
    np.testing.assert_allclose(np.abs(zm[ret]), np.abs(stored[n:]), rtol=1e-12)
    ratio = np.ptp(zm[app]) / np.ptp(zn[app])
    assert 1.15 < ratio < 1.40
    # not a scale: near the turning point the approach's steps are >= 1.2 x the ramp's, the retract's <= 1.06 x
    fifth = n // 5
    a, r = np.flatnonzero(app), np.flatnonzero(ret)
    assert _steps(zm[a[-fifth:]], zn[a[-fifth:]]) > 1.2 > 1.06 > _steps(zm[r[:fifth // 2]], zn[r[:fifth // 2]])
    assert _steps(zm[a[-fifth:]], zn[a[-fifth:]]) > 1.04 * _steps(zm[a[:fifth]], zn[a[:fifth]])  # it accelerates
    note = c.metadata["position_note"]
    assert f"{ratio:.3g} x the nominal ramp" in note and "open-loop piezo" in note
    assert note in prepare(c).warnings
    assert note not in prepare(c, channel="nominal").warnings   # said only where the sensor is used


def test_brukers_own_example_sensor_follows_the_ramp():
    """Bruker's ForceHold example (BioScope Resolve, NanoScope 9.3): the same scale gives the ramp within 3 %."""
    (c,) = load(CORPUS / "bruker-nanoscope_v9.30_Bruker-example_ForceHold.spm")
    app = c.segment == 0
    assert np.ptp(c.piezo_measured[app]) / np.ptp(c.piezo_nominal[app]) == pytest.approx(1.0, abs=0.03)
    assert "position_note" not in c.metadata


def _sensor_file(tmp_path: Path, name: str, z_app_nm: np.ndarray, z_ret_nm: np.ndarray) -> Path:
    """A synthetic force file (test_nanoscope._write: ramp 100 V x 10 nm/V = 1000 nm, sensor 0.0001 V/LSB x
    900 nm/V = 0.09 nm a count) whose sensor holds ``z_app_nm``/``z_ret_nm`` in time order."""
    n = z_app_nm.size
    counts = np.rint(np.r_[z_app_nm[::-1], z_ret_nm] / 0.09).astype(int)
    path = tmp_path / name
    _write(path, np.zeros(n, int), np.zeros(n, int), zsensor=counts)
    return path


def test_a_sensor_on_the_ramp_says_nothing_and_one_off_it_says_what(tmp_path):
    n = 200
    ramp = 1000.0 * (np.arange(n) + 1) / n          # the nominal approach [nm], time order
    back = 1000.0 - 1000.0 * np.arange(n) / n
    on = load(_sensor_file(tmp_path, "on.spm", ramp, back))[0]
    assert "position_note" not in on.metadata
    scaled = load(_sensor_file(tmp_path, "scaled.spm", 1.3 * ramp, 1.3 * back))[0].metadata["position_note"]
    assert "1.3 x the nominal ramp" in scaled and "a constant ratio" in scaled and "about 1.5 x as large" in scaled
    t = np.arange(n) / n                              # steps 1.1 -> 1.4 x the ramp's along the approach
    bent = 1000.0 * (1.1 * t + 0.15 * t * t) + 5.0
    note = load(_sensor_file(tmp_path, "bent.spm", bent, bent[::-1]))[0].metadata["position_note"]
    assert "open-loop piezo" in note and "1.25 x the nominal ramp" in note
