"""Nanosurf .nid: force spectroscopy (single curves and maps) and thermal tunes.

Real files: a trimmed 2 x 2 map of Nanosurf's own FlexAFM example (NSFopen, MIT; tests/data,
``make_nid_trimmed.py``), the whole 10 x 10 map from
``shared/data/real`` (skipped when absent), and a real FlexAFM thermal tune
(``tests/data/spectra``). Expected values are read from the files here with ``configparser``,
``re`` and numpy (the scaling ``min + range (n / 2^32 + 1/2)`` of NSFopen), never from the reader.
"""

from __future__ import annotations

import configparser
import json
import math
import os
import re
from pathlib import Path

import numpy as np
import pytest

from afmforce.calibration import fit_thermal, read_spectrum, sader_rectangular
from afmforce.calibration.thermal import BOLTZMANN
from afmforce.cli.main import main
from afmforce.errors import FileFormatError
from afmforce.io import find_format, load

DATA = Path(__file__).resolve().parents[1] / "data"
MAP = DATA / "nanosurf-nid_spectroscopy-map_2x2_trimmed.nid"
THERMAL = DATA / "spectra" / "nanosurf-nid_thermal-tune_ACL-A.nid"
REAL = Path(os.environ.get("AFMFORCE_REAL_DATA", "/nonexistent"))
FULL_MAP = REAL / "nanosurf-nid_spectroscopy-map_10x10_Tap150Al.nid"


def _header(path: Path) -> configparser.ConfigParser:
    raw = path.read_bytes()
    cp = configparser.ConfigParser(strict=False, interpolation=None, delimiters=("=",))
    cp.optionxform = str
    cp.read_string(raw[:raw.index(b"\r\n#!")].decode("utf-8"))
    return cp


def _typed(text: str) -> float:
    return float(re.match(r"[DL]\[(.*)\]\*", text).group(1))


def _blocks(path: Path, cp) -> dict[str, np.ndarray]:
    """Every block as lines x points in its unit, decoded here with numpy from the file's end."""
    top = cp["DataSet"]
    names = [top[f"Gr{g}-Ch{c}"] for g in range(int(top["GroupCount"])) for c in range(int(top[f"Gr{g}-Count"]))
             if f"Gr{g}-Ch{c}" in top]
    raw = path.read_bytes()
    sizes = [int(cp[n]["Points"]) * int(cp[n]["Lines"]) * 4 for n in names]
    at, out = len(raw) - sum(sizes), {}
    for n, s in zip(names, sizes):
        h = cp[n]
        counts = np.frombuffer(raw[at:at + s], "<i4").astype(float)
        out[n] = (float(h["Dim2Min"]) + float(h["Dim2Range"]) * (counts / 2**32 + 0.5)).reshape(
            int(h["Lines"]), int(h["Points"]))
        at += s
    return out


def test_map_reads_as_its_header_and_data_say():
    cp = _header(MAP)
    curves = load(MAP)
    assert find_format(MAP).identifier == "nanosurf-nid"
    spec = cp["DataSet\\Parameters\\Spectroscopy"]
    k = _typed(cp["DataSet\\Calibration\\Cantilever"]["Prop0"])
    heads = {v.split(",")[1]: v.split(",") for k_, v in cp["DataSet\\Calibration\\Scanhead"].items()
             if re.match(r"In\d+$", k_)}
    invols = float(heads["TipSignalDC"][4]) / 10.0        # the deflection's metres over the +-10 V ADC
    assert float(heads["Channel0"][4]) / float(heads["TipSignalDC"][4]) == pytest.approx(k, rel=1e-5)
    blocks = _blocks(MAP, cp)
    assert len(curves) == int(cp["DataSet-0:0"]["Lines"]) == 4
    for i, c in enumerate(curves):
        md = c.metadata
        assert c.deflection_unit == "N" and md["reader"] == "nanosurf-nid"
        assert md["spring_constant"] == k == 2.72436
        assert md["sensitivity"] == pytest.approx(invols, rel=1e-12) and 20e-9 < invols < 500e-9
        assert md["sample_rate"] == _typed(spec["FwModDatapoints"]) / _typed(spec["FwModTime"]) == 1024.0
        assert md["velocity"] == pytest.approx(_typed(spec["FwModRange"]) / _typed(spec["FwModTime"]))
        n_app, n_ret = int(cp["DataSet-0:0"][f"LineDim{i}Points"]), int(cp["DataSet-1:0"][f"LineDim{i}Points"])
        np.testing.assert_array_equal(np.bincount(c.segment, minlength=2), [n_app, n_ret])
        app, ret = c.segment == 0, c.segment == 1
        np.testing.assert_array_equal(c.deflection_signal[app], blocks["DataSet-0:0"][i, :n_app])
        np.testing.assert_array_equal(c.deflection_signal[ret], blocks["DataSet-1:0"][i, :n_ret][::-1])  # time order
        np.testing.assert_array_equal(c.piezo_measured[app], blocks["DataSet-0:7"][i, :n_app])
        # the approach stops where the force reaches the header's threshold (FwModStopValue [N])
        assert c.deflection_signal[app][-1] == pytest.approx(_typed(spec["FwModStopValue"]), rel=0.02)
        # z grows towards the sample; the retract starts at the turning point; the measured travel
        # is the commanded ramp's (LineDim range, 1 um) within the Z sensor's calibration (25 %)
        z = c.piezo_measured
        assert z[app][-1] > z[app][0] and z[ret][0] > z[ret][-1]
        assert abs(z[ret][0] - z[app][-1]) < 5e-9
        ramp = float(cp["DataSet-0:0"][f"LineDim{i}Range"])
        assert np.ptp(z[app]) == pytest.approx(ramp, rel=0.25)
        assert np.ptp(c.piezo_nominal[app]) == pytest.approx(ramp, rel=1e-9)
        assert np.all(np.diff(c.time) > 0) and c.time[-1] == pytest.approx((n_app + n_ret - 1) / 1024)
    # the 2 x 2 grid, back and forth, at the map table's corners
    x0, x1, y0, y1, nx, ny = cp["DataSet\\SpecInfos\\SpecMapTable"]["Map0"].split(";")[:6]
    cells = [(c.metadata["map_x"], c.metadata["map_y"]) for c in curves]
    assert cells == [(0, 0), (1, 0), (1, 1), (0, 1)] and (int(nx), int(ny)) == (2, 2)
    assert [(c.metadata["position_x"], c.metadata["position_y"]) for c in curves] == [
        (float(x0), float(y0)), (float(x1), float(y0)), (float(x1), float(y1)), (float(x0), float(y1))]


def test_a_map_is_planned_curve_by_curve_from_its_header():
    """The batch engine (analyze of a folder, --fast-map) sees one item per curve of a .nid map."""
    from afmforce.sweep.files import plan_curves

    refs = plan_curves([MAP])
    assert [(r.index, r.format) for r in refs] == [(i, "nanosurf-nid") for i in range(4)]


@pytest.mark.skipif(not FULL_MAP.is_file(), reason="shared real data not present")
def test_the_whole_map_runs_back_and_forth():
    """The contact heights (z where the approach stopped) of the 10 x 10 map lie on a smooth surface
    only if odd rows run backwards: a plane fits them within 5 nm rms that way, 13 nm row by row."""
    curves = load(FULL_MAP)
    assert len(curves) == 100
    h = np.array([c.piezo_measured[c.segment == 0][-1] for c in curves])
    xs = np.array([c.metadata["map_x"] for c in curves])
    ys = np.array([c.metadata["map_y"] for c in curves])

    def rms(x, y):
        a = np.c_[x, y, np.ones_like(x)]
        return float(np.std(h - a @ np.linalg.lstsq(a, h, rcond=None)[0]))

    assert sorted(zip(xs, ys)) == sorted((i, j) for i in range(10) for j in range(10))
    assert rms(xs, ys) < 5e-9 < 10e-9 < rms(np.arange(100) % 10, np.arange(100) // 10)


def test_truncated_and_image_only_files_are_refused_cleanly(tmp_path):
    data = MAP.read_bytes()
    short = tmp_path / "short.nid"
    short.write_bytes(data[:-1000])
    with pytest.raises(FileFormatError, match="truncated"):
        load(short)
    head = tmp_path / "head.nid"
    head.write_bytes(data[:5000])
    with pytest.raises(FileFormatError, match="short.nid|head.nid"):
        load(head)
    # an image-only .nid written here in the container's layout (one 4 x 2 block)
    image = tmp_path / "image.nid"
    text = ("[DataSet]\r\nVersion=2\r\nGroupCount=1\r\nGr0-Name=Scan forward\r\nGr0-ID=0\r\nGr0-Count=1\r\n"
            "Gr0-Ch0=DataSet-0:0\r\n\r\n[DataSet-0:0]\r\nVersion=2\r\nPoints=4\r\nLines=2\r\nFrame=Scan forward\r\n"
            "Dim2Name=Z-Axis\r\nDim2Unit=m\r\nDim2Range=1e-06\r\nDim2Min=-5e-07\r\nSaveMode=Binary\r\nSaveBits=32\r\n"
            "SaveSign=Signed\r\nSaveOrder=Intel\r\n\r\n")
    image.write_bytes(text.encode() + b"\r\n#!" + np.arange(8, dtype="<i4").tobytes())
    with pytest.raises(FileFormatError, match="holds images .*no force curve"):
        load(image)
    with pytest.raises(FileFormatError, match="thermal tune, no force curve"):
        load(THERMAL)


def test_analyze_as_a_user_types_it(capsys):
    """``afmforce analyze FILE --json``: the file's k and InvOLS used; the adhesion is the retract's
    dip below its far baseline, read here from the Spec backward block (within 1 nN)."""
    cp = _header(MAP)
    blocks = _blocks(MAP, cp)
    code = main(["analyze", str(MAP), "--json"])
    out, err = capsys.readouterr()
    assert code == 0, err
    results = json.loads(out)["results"]
    assert list(results) == [f"{MAP.name}#{i}" for i in range(4)]
    for i, r in enumerate(results.values()):
        assert _find(r, "spring_constant") == 2.72436
        n = int(cp["DataSet-1:0"][f"LineDim{i}Points"])
        row = blocks["DataSet-1:0"][i, :n]
        dip = float(np.median(row[:200]) - row.min())          # the far end is stored first
        adhesion = _find(r, "adhesion_force")
        assert 1e-9 < dip < 30e-9
        assert abs(abs(adhesion) - dip) < 1e-9, (adhesion, dip)


def _find(obj, key):
    if isinstance(obj, dict):
        if key in obj and isinstance(obj[key], (int, float)):
            return obj[key]
        for v in obj.values():
            found = _find(v, key)
            if found is not None:
                return found
    if isinstance(obj, list):
        for v in obj:
            found = _find(v, key)
            if found is not None:
                return found
    return None


# -- the thermal tune -------------------------------------------------------------------------

def _info(path: Path) -> dict[str, str]:
    return dict(_header(path)["DataSet-Info"])


def test_thermal_tune_reads_and_fits_as_its_header_says():
    """The spectrum's scale is the header's: its peak equals the tune's 'Peak Value' (772 fm/sqrt(Hz))
    within 2 % (one noisy bin); the fit in the tune's window finds its f0 within 0.1 % (two bins of
    38 Hz) and Q within 15 % (442 by Nanosurf's fit of the amplitude; ours is the likelihood fit of the
    power, whose Q moves with the window by this much); and equipartition of the fit equals
    equipartition of Nanosurf's own f0, Q and peak (pi/2 f0 A^2/Q) within 10 %."""
    info = _info(THERMAL)
    f_vendor = float(re.match(r"([\d.]+)kHz", info["Frequency:"]).group(1)) * 1e3
    q_vendor = float(info["Q Factor:"])
    peak = float(re.match(r"([\d.]+)fm", info["Peak Value:"]).group(1)) * 1e-15
    lo, hi = (float(re.match(r"([\d.]+)kHz", info[k]).group(1)) * 1e3 for k in ("Peak fit min", "Peak fit max"))
    temperature = float(re.match(r"([\d.]+)", info["Cantilever temperature"]).group(1)) + 273.15
    sp = read_spectrum(THERMAL)
    assert sp.unit == "m^2/Hz" and sp.temperature == pytest.approx(temperature) and sp.window == (lo, hi)
    assert sp.frequency[1] - sp.frequency[0] == pytest.approx(float(info["Resolution"].split()[0]), rel=1e-4)
    near = (sp.frequency > f_vendor - 2e3) & (sp.frequency < f_vendor + 2e3)
    assert math.sqrt(sp.psd[near].max()) == pytest.approx(peak, rel=0.02)
    fit = fit_thermal(sp.frequency, sp.psd, temperature=temperature, correction=1.0, f_range=(lo, hi))
    assert fit.resonance_frequency == pytest.approx(f_vendor, rel=1e-3)
    assert fit.quality_factor == pytest.approx(q_vendor, rel=0.15)
    k_vendor_fit = BOLTZMANN * temperature / (math.pi / 2 * f_vendor * peak**2 / q_vendor)
    assert fit.spring_constant == pytest.approx(k_vendor_fit, rel=0.10)


def test_the_files_spring_constant_agrees_with_sader_not_equipartition():
    """The header's 'Spring Constant' (27.13 N/m) is not equipartition of the stored spectrum (that
    gives 9-11 N/m: the spectrum's metres rest on a deflection sensitivity the file does not store);
    it agrees with Sader's k of the tune's f0 and Q for the lever type's nominal plan view (ACL-A:
    225 x 40 um, as NSFopen's spring-constant example takes it): 25.3 N/m, within 10 % (air's
    density and viscosity, nominal sizes)."""
    info = _info(THERMAL)
    assert info["Cantilever type"] == "ACL-A"
    k_file = float(info["Spring Constant:"].split()[0])
    f0 = float(re.match(r"([\d.]+)kHz", info["Frequency:"]).group(1)) * 1e3
    sader = sader_rectangular(225e-6, 40e-6, f0, float(info["Q Factor:"]), "air")
    assert sader.spring_constant == pytest.approx(k_file, rel=0.10)


def test_calibrate_thermal_as_a_user_types_it(capsys):
    code = main(["calibrate", "thermal", str(THERMAL), "--json"])
    out, err = capsys.readouterr()
    assert code == 0, err
    d = json.loads(out)
    assert d["sources"]["window"] == "file" and d["sources"]["temperature"] == "file"
    assert d["resonance_frequency"] == pytest.approx(179.8e3, rel=1e-3)
    assert d["file_spring_constant"] == 27.13
    # chi 0.817 of 8.9-11 N/m: a stiff tapping lever (ACL: 20-95 N/m nominal) calibrated on a
    # sensitivity the tune does not record; plausible in magnitude, a third of the file's Sader k
    assert 5.0 < d["spring_constant"] < 15.0 and d["spring_constant_se"] < 0.05 * d["spring_constant"]


def _write_nid(path: Path, frames: list[tuple[str, str, str, np.ndarray, float, float]], info: str) -> None:
    """A one-curve .nid in the container's layout (our writer): per frame (name, channel, unit,
    values, ramp start, ramp span); int32 counts n = (v - min) / range 2^32 - 2^31."""
    groups = list(dict.fromkeys(f[0] for f in frames))
    top = ["[DataSet]", "Version=2", f"GroupCount={len(groups)}"]
    for g, name in enumerate(groups):
        top += [f"Gr{g}-Name={name}", f"Gr{g}-ID=1", f"Gr{g}-Count={sum(f[0] == name for f in frames)}"]
    sections, blobs = [], []
    for j, (name, channel, unit, values, start, span) in enumerate(frames):
        g, c = groups.index(name), [f for f in frames if f[0] == name].index(frames[j])
        top.append(f"Gr{g}-Ch{c}=DataSet-{g}:{c}")
        low, rng = float(values.min()) - 1e-9, float(np.ptp(values)) + 2e-9
        sections += [f"[DataSet-{g}:{c}]", "Version=3", f"Points={len(values)}", "Lines=1", f"Frame={name}",
                     "Dim0Name=Z-Axis", "Dim0Unit=m", f"Dim2Name={channel}", f"Dim2Unit={unit}",
                     f"Dim2Range={rng!r}", f"Dim2Min={low!r}", f"LineDim0Min={start!r}", f"LineDim0Range={span!r}",
                     f"LineDim0Points={len(values)}", "SaveMode=Binary", "SaveBits=32", "SaveSign=Signed",
                     "SaveOrder=Intel", ""]
        blobs.append(np.round((values - low) / rng * 2**32 - 2**31).astype("<i4").tobytes())
    text = "\r\n".join(top + ["", "[DataSet-Info]", info, ""] + sections)
    path.write_bytes(text.encode() + b"\r\n#!" + b"".join(blobs))


def test_a_single_curve_with_a_pause_in_metres(tmp_path):
    """One curve (no map): approach, forward pause, retract in time order (segments 0, 2, 1); a
    deflection in m kept in m; no Z sensor: the commanded ramp is z; the sample rate from the
    [DataSet-Info] 'Modulation time' and 'Data points' (older files)."""
    z = np.linspace(0.0, 100e-9, 100)
    app = np.where(z > 80e-9, (z - 80e-9) * 0.9, 0.0)
    pause = np.full(20, app[-1]) - np.linspace(0, 1e-9, 20)
    back = np.where(z > 85e-9, (z - 85e-9) * 0.9, 0.0)[::2]     # stored far end first, as Nanosurf does
    path = tmp_path / "single.nid"
    _write_nid(path, [("Spec forward", "Deflection", "m", app, 1e-6, 100e-9),
                      ("Spec fwd pause", "Deflection", "m", pause, 1.1e-6, 0.0),
                      ("Spec backward", "Deflection", "m", back, 1e-6, 100e-9)],
               "Modulation time=0.5 s\r\nData points=100\r\nHead type=CoreAFM")
    (c,) = load(path)
    assert c.deflection_unit == "m" and c.piezo_measured is None and "map_x" not in c.metadata
    assert c.metadata["sample_rate"] == 200.0 and c.metadata["instrument"] == "Nanosurf CoreAFM"
    np.testing.assert_array_equal(c.segment, [0] * 100 + [2] * 20 + [1] * 50)
    step = 100e-9 * 2**-32 * 2                                    # a count of the widest block
    np.testing.assert_allclose(c.deflection_signal, np.concatenate([app, pause, back[::-1]]), atol=step)
    np.testing.assert_allclose(c.piezo_nominal[:100], 1e-6 + z, rtol=1e-12)
    np.testing.assert_allclose(c.piezo_nominal[120:], (1e-6 + np.linspace(0, 100e-9, 50))[::-1], rtol=1e-12)
    np.testing.assert_allclose(np.diff(c.time), 1 / 200.0)
