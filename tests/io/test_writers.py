"""The vendor map writers (issue 35, item 1): the virtual AFM's map written as JPK QI data and as a
Bruker NanoScope v9 force volume is read back, by afmforce's readers and by independent ones
(afmformats and nanite for JPK; the NanoScope header and samples decoded here by hand), with the
spring constant, sensitivity, grid, positions and curves that were written; the maps' curves read
one at a time equal the whole file's, for the written files and the real ones of the corpus."""

from __future__ import annotations

import re
import warnings
from pathlib import Path

import numpy as np
import pytest

from afmforce.errors import OutputExistsError, ParameterError
from afmforce.instrument.soft_map import SoftMapConfig, soft_map_curves, write_soft_map
from afmforce.io import load
from afmforce.io.map_curves import open_map
from afmforce.io.writers import write_jpk_qi, write_nanoscope_fv
from afmforce.io.writers.jpk_qi import DEFLECTION_STEP

CFG = SoftMapConfig(nx=4, ny=3, seed=5)  # not square: x and y cannot be swapped unseen
CORPUS = Path(__file__).resolve().parents[1] / "data" / "corpus"


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    folder = tmp_path_factory.mktemp("vendor")
    originals = {(c.metadata["map_x"], c.metadata["map_y"]): c for c in soft_map_curves(CFG)}
    return (write_soft_map(CFG, folder / "soft.jpk-qi-data", format="jpk-qi"),
            write_soft_map(CFG, folder / "soft.spm", format="bruker-fv"), originals)


def _check_grid(curves, originals, position_offset):
    assert len(curves) == CFG.nx * CFG.ny
    assert sorted((c.metadata["map_x"], c.metadata["map_y"]) for c in curves) == sorted(originals)
    for c in curves:
        md = c.metadata
        assert (md["map_nx"], md["map_ny"]) == (CFG.nx, CFG.ny)
        assert md["spring_constant"] == pytest.approx(CFG.spring_constant, rel=1e-12)
        assert md["sensitivity"] == pytest.approx(CFG.sensitivity, rel=1e-12)
        x, y = md["map_x"], md["map_y"]
        assert md["position_x"] == pytest.approx((x + position_offset) * CFG.step, abs=1e-15)
        assert md["position_y"] == pytest.approx((y + position_offset) * CFG.step, abs=1e-15)


@pytest.mark.parametrize("fmt", ["jpk-force", "jpk-zip"])
def test_jpk_qi_read_back(written, fmt):
    path, _, originals = written
    curves = load(path, format=fmt)
    _check_grid(curves, originals, 0.0)
    for c in curves:
        o = originals[c.metadata["map_x"], c.metadata["map_y"]]
        assert np.array_equal(c.segment, o.segment)
        assert np.abs(c.piezo_nominal - o.piezo_nominal).max() < 1e-13  # 32-bit encoder: 1e-14 m steps
        scale = CFG.sensitivity * CFG.spring_constant if fmt == "jpk-force" else 1.0
        assert c.deflection_unit == ("N" if fmt == "jpk-force" else "V")
        assert np.abs(c.deflection_signal / scale - o.deflection_signal).max() <= DEFLECTION_STEP
        app = o.time[o.segment == 0]
        assert c.metadata["sample_rate"] == pytest.approx(1 / np.diff(app).mean(), rel=1e-9)  # the approach's


def test_jpk_qi_read_by_afmformats_and_nanite(written):
    afmformats = pytest.importorskip("afmformats")
    path, _, originals = written
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        data = afmformats.load_data(path)  # afmformats' own detection and reader, not afmforce's
    assert len(data) == CFG.nx * CFG.ny
    for d in data:
        md = d.metadata
        assert (md["grid shape x"], md["grid shape y"]) == (CFG.nx, CFG.ny)
        assert md["spring constant"] == CFG.spring_constant and md["sensitivity"] == CFG.sensitivity
        o = originals[md["grid index x"], md["grid index y"]]
        assert md["position x"] == pytest.approx(md["grid index x"] * CFG.step, abs=1e-15)
        force = o.deflection_signal * CFG.sensitivity * CFG.spring_constant
        assert np.allclose(d["force"], force, rtol=0, atol=DEFLECTION_STEP * CFG.sensitivity * CFG.spring_constant)
        assert np.allclose(d["height (piezo)"], -o.piezo_nominal, rtol=0, atol=1e-13)
        assert np.array_equal(np.asarray(d["segment"]), o.segment)
    nanite = pytest.importorskip("nanite")
    group = nanite.load_group(path)
    assert len(group) == CFG.nx * CFG.ny and group[0].metadata["spring constant"] == CFG.spring_constant


def _header(path: Path) -> tuple[str, bytes]:
    raw = path.read_bytes()
    end = raw.index(b"\\*File list end")
    return raw[:end].decode("latin-1"), raw


def test_nanoscope_fv_decoded_by_hand(written):
    """The header and the samples read with a few regular expressions and numpy, not afmforce's reader."""
    _, path, originals = written
    text, raw = _header(path)
    assert text.startswith("\\*Force file list\r\n\\Version: 0x0920B046") and "\\Start context: FVOL" in text
    assert int(re.search(r"\\Data length: (\d+)", text).group(1)) == raw.index(b"\\*Force") + \
        int(re.search(r"\\Data offset: (\d+)", text).group(1))  # the header's length: where the data start
    assert re.search(r"\\Samps/line: (\d+)\r\n\\Lines: (\d+)", text).groups() == (str(CFG.nx), str(CFG.ny))
    assert float(re.search(r"\\@Sens. DeflSens: V ([\d.eE+-]+)", text).group(1)) * 1e-9 == pytest.approx(CFG.sensitivity)
    assert float(re.search(r"\\Spring Constant: ([\d.eE+-]+)", text).group(1)) == CFG.spring_constant
    offsets = [int(v) for v in re.findall(r"\\Data offset: (\d+)", text)]
    lengths = [int(v) for v in re.findall(r"\\Data length: (\d+)", text)[1:]]
    scales = [float(v) for v in re.findall(r"\\@4:Z scale: V \[Sens\. \w+\] \(([\d.eE+-]+) V/LSB\)", text)]
    n = CFG.points
    assert lengths == [CFG.nx * CFG.ny * 2 * n * 4] * 2 and len(raw) == offsets[1] + lengths[1]
    defl = np.frombuffer(raw, "<i4", count=lengths[0] // 4, offset=offsets[0]).reshape(CFG.ny, CFG.nx, 2 * n)
    assert np.all(defl % 256 == 0)  # 16-bit counts shifted by 8 bits, as v9 stores them
    zsens = float(re.search(r"\\@Sens. ZsensSens: V ([\d.]+) nm/V", text).group(1)) * 1e-9
    zs = np.frombuffer(raw, "<i4", count=lengths[1] // 4, offset=offsets[1]).reshape(CFG.ny, CFG.nx, 2 * n)
    for (x, y), o in originals.items():
        volts = defl[y, x] / 256 * scales[0]
        assert np.array_equal(volts[:n][::-1], o.deflection_signal[:n])  # approach from the turning point
        assert np.array_equal(volts[n:], o.deflection_signal[n:])       # the virtual ADC's counts, exactly
        z = zs[y, x] / 256 * scales[1] * zsens
        assert np.abs(z[:n][::-1] - o.piezo_nominal[:n]).max() <= 0.5001 * scales[1] * zsens
    assert 0.5 * scales[1] * zsens < 0.1e-9  # the Z sensor's step: under 0.2 nm


def test_nanoscope_fv_read_back(written):
    _, path, originals = written
    curves = load(path)
    _check_grid(curves, originals, 0.5)  # NanoScope: the grid point's centre in the scanned square
    _, raw = _header(path)
    for c in curves:
        o = originals[c.metadata["map_x"], c.metadata["map_y"]]
        assert c.metadata["radius"] == pytest.approx(CFG.radius) and c.deflection_unit == "V"
        assert np.array_equal(c.deflection_signal, o.deflection_signal)
        assert np.abs(c.piezo_measured - o.piezo_nominal).max() < 0.1e-9
        assert c.metadata["velocity"] == pytest.approx(CFG.velocity, rel=5e-3)


def _same(a, b):
    for x, y in ((a.deflection_signal, b.deflection_signal), (a.piezo_nominal, b.piezo_nominal), (a.time, b.time),
                 (a.segment, b.segment)):
        assert np.allclose(x, y, rtol=1e-12, atol=0)
    assert (a.piezo_measured is None) == (b.piezo_measured is None)
    assert a.deflection_unit == b.deflection_unit
    for key in ("map_x", "map_y", "map_nx", "map_ny", "position_x", "position_y", "spring_constant", "sensitivity"):
        assert a.metadata.get(key) == b.metadata.get(key), key


@pytest.mark.parametrize("name, fmt", [
    ("soft.jpk-qi-data", "jpk-force"), ("soft.jpk-qi-data", "jpk-zip"), ("soft.spm", "bruker-nanoscope"),
    ("jpk-qi-data_2020.02.07.jpk-qi-data", "jpk-force"), ("jpk-force-map_HeLa_4x4.jpk-force-map", "jpk-force"),
    ("bruker-nanoscope_force-volume_v9.2_Egel2_00023.spm", "bruker-nanoscope")])
def test_curves_read_one_at_a_time_equal_the_whole_file(written, name, fmt):
    path = written[0].parent / name if name.startswith("soft") else CORPUS / name
    whole = load(path, format=fmt)
    reader = open_map(path, fmt)
    try:
        assert len(reader) == len(whole)
        for i in (0, len(whole) // 2, len(whole) - 1):
            _same(reader.read(i), whole[i])
    finally:
        reader.close()


def test_writers_refuse_what_they_cannot_write(written, tmp_path):
    import dataclasses

    first = next(soft_map_curves(CFG))
    with pytest.raises(ParameterError, match="volts"):
        write_jpk_qi([dataclasses.replace(first, deflection_unit="N")], tmp_path / "a.jpk-qi-data", shape=(1, 1),
                     step=1e-6)
    short = next(soft_map_curves(dataclasses.replace(CFG, points=200)))
    for writer, name in ((write_jpk_qi, "b.jpk-qi-data"), (write_nanoscope_fv, "b.spm")):
        with pytest.raises(ParameterError, match="points"):
            writer([first, dataclasses.replace(short, metadata={**short.metadata, "map_x": 1})], tmp_path / name,
                   shape=(1, 2), step=1e-6)
        assert not (tmp_path / name).exists()  # nothing half written
        with pytest.raises(ParameterError, match="two curves"):
            writer([first, first], tmp_path / name, shape=(1, 2), step=1e-6)
    with pytest.raises(OutputExistsError):
        write_soft_map(CFG, written[0], format="jpk-qi")
    with pytest.raises(ParameterError, match="format"):
        write_soft_map(CFG, tmp_path / "c.xyz", format="xyz")
