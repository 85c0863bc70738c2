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
from realdata import DATA, nanite_hertz_para, real_file  # noqa: E402  (tests/ is on sys.path: tests/conftest.py)

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


def _nanoscope_header(path: Path) -> str:
    raw = path.read_bytes()
    return raw[:raw.index(b"\x1a")].decode("latin-1")


def _value(text: str, pattern: str) -> float:
    return float(re.search(pattern, text).group(1))


def test_real_nanoscope_v6_multimode_file_reads_as_its_header_says():
    """A NanoScope 6.15 force file (MultiMode, controller IIIA: no height sensor, deflection only; from
    yogi-boi/tutorial_pyfmrheo_gren_draft, licence unstated: not kept), a header version never read here.
    Independent of afmforce: k and DeflSens from the header; the ramp is ``Ramp size`` [V] x ``Zsens`` [nm/V]
    (500 nm); 1024 samples per ``Scan rate`` cycle; the approach, a relative trigger of 0.1861 V, rises by it."""
    path = real_file("bruker-nanoscope_v6.15_MultiMode_hjkl.005")
    head = _nanoscope_header(path)
    assert "\\Version: 0x06150001" in head
    (c,) = load(path)
    assert c.metadata["spring_constant"] == _value(head, r"\\Spring Constant: ([\d.]+)")
    assert c.metadata["sensitivity"] == pytest.approx(_value(head, r"Sens\. DeflSens: V ([\d.]+)") * 1e-9, rel=1e-12)
    ramp = _value(head, r"@4:Ramp size: V \[Sens\. Zsens\] \([\d.]+ V/LSB\) ([\d.]+) V") * \
        _value(head, r"Sens\. Zsens: V ([\d.]+)") * 1e-9
    approach = c.segment == 0
    assert np.ptp(c.piezo_nominal[approach]) == pytest.approx(ramp * 511 / 512, rel=1e-4)  # 512 samples span 511 steps
    rate = 1024 * float(re.findall(r"\\Scan rate: ([\d.]+)", head)[-1])
    assert c.metadata["sample_rate"] == pytest.approx(rate, rel=1e-6)
    d = c.deflection_signal[approach]
    trigger = _value(head, r"Trig threshold Deflection: V \[Sens\. DeflSens\] \([\d.]+ V/LSB\) ([\d.]+) V")
    assert d[-1] - np.median(d[:100]) == pytest.approx(trigger, rel=0.06)


def test_real_nanoscope_v9_1_catalyst_modulus_agrees_with_nanite():
    """A NanoScope 9.1 BioScope Catalyst force file on a cell (same source, not kept): Deflection Error and
    Height Sensor channels, the header's tip radius 8 nm. nanite 4.2.3's Hertz paraboloid fit on the file
    parsed here without afmforce (int16 blocks x their V/LSB, DeflSens, ZsensSens, k; the approach stored
    turning point first) gives 11394 Pa; afmforce's default analysis gave 11337 Pa (0.5 %)."""
    pytest.importorskip("nanite")   # the bench extra: the reference fit

    from afmforce.analysis.pipeline import analyze

    path = real_file("bruker-nanoscope_v9.1_Catalyst_cr00000.000")
    raw = path.read_bytes()
    head = _nanoscope_header(path)
    k = _value(head, r"\\Spring Constant: ([\d.]+)")
    chans = {}
    for block in head.split("\\*Ciao force image list")[1:]:
        at, n = _value(block, r"\\Data offset: (\d+)"), _value(block, r"\\Data length: (\d+)")
        lsb = _value(block, r"Z scale: V \[.*?\] \(([\d.eE+-]+) V/LSB\)")
        chans[re.search(r"Image Data: S \[(\w+)\]", block).group(1)] = \
            np.frombuffer(raw[int(at):int(at + n)], "<i2") * lsb
    force = k * _value(head, r"Sens\. DeflSens: V ([\d.]+)") * 1e-9 * chans["DeflectionError"]
    z = chans["ZSensor"] * _value(head, r"Sens\. ZsensSens: V ([\d.]+)") * 1e-9
    half = force.size // 2
    force, z = np.r_[force[:half][::-1], force[half:]], np.r_[z[:half][::-1], z[half:]]
    radius = _value(head, r"\\Tip Radius: ([\d.]+)") * 1e-9
    e_nanite = nanite_hertz_para(force, z, radius, k)
    (c,) = load(path)
    assert c.metadata["radius"] == pytest.approx(radius, rel=1e-12)
    r = analyze(c)
    assert r.contact_kind == "soft"
    assert r.youngs_modulus == pytest.approx(e_nanite, rel=0.03)


def test_a_short_contact_with_a_time_base_is_not_called_timeless():
    """The NanoScope 6.15 file (1024 samples at 776.4 Hz) ends its approach with ~20 samples in contact: the
    oscillation verdict said "no time base" and the figure "no time base in the file". A run of 20 samples at
    1 kHz: no peak, too few samples, its Nyquist frequency 500 Hz (0.5 / the step); none at all says no time base."""
    from afmforce.analysis.oscillation import both_runs, find_peak

    t = np.arange(20) * 1e-3
    short = find_peak(t, np.sin(2 * np.pi * 100 * t), 1e-6, "approach")
    assert not short.found and short.nyquist == pytest.approx(500.0, rel=1e-9)
    origin, verdict, _ = both_runs(short, find_peak(t, np.cos(t), 1e-6, "retract"))
    assert origin == "none" and "no time base" not in verdict and "too few samples" in verdict
    timeless = find_peak(np.full(20, np.nan), np.zeros(20), 1e-6, "approach")
    assert "no time base" in both_runs(timeless, timeless)[1]


def test_real_nanoscope_v6_short_contact_is_not_called_timeless():
    from afmforce.analysis.pipeline import analyze

    (c,) = load(real_file("bruker-nanoscope_v6.15_MultiMode_hjkl.005"))
    verdict = analyze(c).details["oscillation"].verdict
    assert "no time base" not in verdict and "Nyquist 388.2 Hz" in verdict


def _optics11_hertz(path: Path, *, e_mod=20e3, radius=8e-6, k=0.032, travel=10e-6, contact=8e-6) -> None:
    """A SYNTHETIC Optics11 export (the 2020 layout: no Device line) of a Hertz contact, closed form: a sphere
    of ``radius`` on a sample of modulus ``e_mod`` (Poisson 0.5) under a lever ``k``; at each piezo position
    p > ``contact`` the bending d solves k d = 4/3 E/(1 - 0.25) sqrt(R) (p - contact - d)^1.5 (brentq)."""
    from scipy.optimize import brentq

    e_star = e_mod / 0.75
    p = np.concatenate([np.linspace(0, travel, 2000), np.full(1000, travel), np.linspace(travel, 0, 2000)[1:]])
    d = np.array([0.0 if x <= contact else brentq(
        lambda b, x=x: k * b - 4 / 3 * e_star * np.sqrt(radius) * max(x - contact - b, 0.0) ** 1.5, 0, x - contact)
        for x in p])
    d += np.random.default_rng(0).normal(0, 0.02e-9, p.size)
    table = np.column_stack([np.arange(p.size) * 1e-3, k * d * 1e6, (p - d) * 1e9, d * 1e9, p * 1e9, 0 * p])
    head = (f"Date\t28/02/2020\tTime\t17:00\tStatus\tOK\nsynthetic\nk (N/m)\t{k:.3f}\n\n"
            f"Tip radius (um)\t{radius * 1e6:.3f}\nCalibration factor\t2.054\n\n"
            f"D[Z1] (nm)\t0.000\tt[1] (s)\t0.000\nD[Z2] (nm)\t{travel * 1e9:.3f}\tt[2] (s)\t2.000\n"
            f"D[Z3] (nm)\t{travel * 1e9:.3f}\tt[3] (s)\t1.000\nD[Z4] (nm)\t0.000\tt[4] (s)\t2.000\n\n"
            "Time (s)\tLoad (uN)\tIndentation (nm)\tCantilever (nm)\tPiezo (nm)\tAuxiliary\n")
    path.write_text(head + "".join("\t".join(f"{v:.6f}" for v in row) + "\n" for row in table))


def test_an_interferometric_hertz_contact_stiffer_than_the_lever_is_an_indentation(tmp_path):
    """A 20 kPa sample under an 8 um sphere on a 0.032 N/m lever: the contact is 3-4 x stiffer than the lever,
    so the deflection follows 0.76 of the piezo along a nearly straight line (late/early slope 1.22). It was
    called "hard" (the default least stiffness 0.7 allows for an InvOLS 30 % off) and no modulus was fitted;
    the Optics11 reader says the deflection is interferometric, so the contact is soft and E is the closed
    form's 20 kPa."""
    from afmforce.analysis import options as O
    from afmforce.analysis.pipeline import analyze

    path = tmp_path / "hertz.txt"
    _optics11_hertz(path)
    (c,) = load(path)
    assert c.metadata["deflection_interferometric"] is True
    r = analyze(c, options=[O.IndentationOptions(model="hertz_paraboloid")])
    assert r.contact_kind == "soft"
    assert r.youngs_modulus == pytest.approx(20e3, rel=0.01)
    hard = analyze(c, options=[O.KindOptions(min_stiffness=0.7 + 1e-9)])  # the user's own threshold still rules
    assert hard.contact_kind == "hard"


def test_real_chiaro_gel_exports_are_soft_and_agree_with_nanite():
    """The 2020 Chiaro export of a PEG gel (GPL, skipped where absent), 8 um sphere: "hard", no modulus, before.
    nanite 4.2.3's Hertz paraboloid fit on the export's own columns (Load, Piezo) gives 22273 Pa; afmforce 22046
    Pa (the Chiaro software's own fit in the header: 19926 Pa, over a range it does not state)."""
    import warnings

    nanite = pytest.importorskip("nanite")   # the bench extra: the reference fit

    from afmforce.analysis.pipeline import analyze

    path = real_file("optics11-chiaro_2020_NanoPrepare_PEGFN_X1Y1.txt")
    head, table = _table(path)
    piezo, force = table[:, 4] * 1e-9, table[:, 1] * 1e-6
    seg = np.arange(piezo.size) > int(np.argmax(piezo))
    md = {"spring constant": head["k"], "sensitivity": 1.0, "path": "x", "enum": 0, "imaging mode": "force-distance",
          "duration": 1.0, "point count": piezo.size}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        idnt = nanite.Indentation(data={"force": force, "height (measured)": -piezo, "segment": seg,
                                        "time": table[:, 0]}, metadata=md)
        idnt.apply_preprocessing(["compute_tip_position", "correct_force_offset", "correct_tip_offset"],
                                 options={"correct_tip_offset": {"method": "fit_line_polynomial"}})
        p = idnt.get_initial_fit_parameters(model_key="hertz_para")
        p["R"].set(value=head["R"])
        p["nu"].set(value=0.5)
        idnt.fit_model(model_key="hertz_para", params_initial=p, weight_cp=0, range_x=(0, 0),
                       range_type="absolute", segment="approach")
    e_nanite = idnt.fit_properties["params_fitted"]["E"].value
    r = analyze(load(path)[0])
    assert r.contact_kind == "soft"
    assert r.youngs_modulus == pytest.approx(e_nanite, rel=0.03)


def _piuma_hertz(path: Path, contact: float, *, e_mod=338.0, radius=32.5e-6, k=0.24, travel=10e-6) -> None:
    """A SYNTHETIC Piuma export (closed-form Hertz as in :func:`_optics11_hertz`), the load zeroed at the first
    sample as the instrument does; ``contact`` < 0: the sphere already presses on the sample when the record
    starts (NanoPrepare's ``new.txt``: the Piuma's and nanite's free-contact Hertz fits put it before the data)."""
    from scipy.optimize import brentq

    e_star = e_mod / 0.75
    p = np.concatenate([np.linspace(0, travel, 1000), np.full(500, travel), np.linspace(travel, 0, 1000)[1:]])
    d = np.array([0.0 if x <= contact else brentq(
        lambda b, x=x: k * b - 4 / 3 * e_star * np.sqrt(radius) * max(x - contact - b, 0.0) ** 1.5, 0, x - contact)
        for x in p])
    d = d - d[0] + np.random.default_rng(0).normal(0, 0.05e-9, p.size)
    table = np.column_stack([np.arange(p.size) * 1e-3, k * d * 1e6, (p - d) * 1e9, d * 1e9, p * 1e9, 0 * p])
    head = (f"Date\t16/01/2024\tTime\t19:01:15\tStatus\tOK\nsynthetic\nk (N/m)\t{k:.3f}\n"
            f"Tip radius (um)\t{radius * 1e6:.3f}\n\nDevice:\tPiuma\n\n"
            f"D[Z1] (nm)\t{travel * 1e9:.3f}\tt[1] (s)\t1.000\nD[Z2] (nm)\t{travel * 1e9:.3f}\tt[2] (s)\t0.500\n"
            "D[Z3] (nm)\t0.000\tt[3] (s)\t1.000\n\n"
            "Time (s)\tLoad (uN)\tIndentation (nm)\tCantilever (nm)\tPiezo (nm)\tAuxiliary\n")
    path.write_text(head + "".join("\t".join(f"{v:.6f}" for v in row) + "\n" for row in table))


CLIMBS = "the baseline line fitted before contact climbs"


def test_an_approach_that_starts_in_contact_is_said_to_be_uncertain(tmp_path):
    """Closed form, 338 Pa under a 32.5 um sphere on a 0.24 N/m lever. Contact 3 um into the record: no warning
    and E within 1 % of 338 Pa. Contact 2 um before the record starts: the "free" part is a slow contact, the
    drift line fitted to it took away most of the load and E came out half (170 Pa) with a tight interval and no
    word; now a warning says the contact point, force and modulus are uncertain (numbers unchanged)."""
    from afmforce.analysis.pipeline import analyze

    good, bad = tmp_path / "good.txt", tmp_path / "bad.txt"
    _piuma_hertz(good, 3e-6)
    _piuma_hertz(bad, -2e-6)
    r = analyze(load(good)[0])
    assert r.youngs_modulus == pytest.approx(338.0, rel=0.01)
    assert not any(CLIMBS in w for w in r.warnings)
    r = analyze(load(bad)[0])
    assert r.youngs_modulus < 0.6 * 338.0  # what the drift line leaves: the reason for the warning
    assert any(CLIMBS in w for w in r.warnings)


def test_real_files_that_press_from_their_first_samples_are_warned():
    """The Piuma export (GPL, skipped where absent) and the MIT JPK stress-relaxation cell (``cell1-0008``: its
    extend starts after a pause in contact): both rise from their first approach samples, read with numpy on
    the reader's arrays (a fifth of the extend gains more than a tenth of the whole rise, where a free baseline
    stays flat), and both get the warning; the ForceMetric curves in air (a free baseline) do not."""
    from afmforce.analysis.pipeline import analyze

    paths = [DATA / "afmformats_jpk-sr_cell1-0008.jpk-force"]
    piuma = DATA.parent / "no-such-file"
    try:
        piuma = real_file("optics11-piuma_V3.5.0_NanoPrepare_test2.txt")
    except pytest.skip.Exception:
        pass
    paths += [piuma] if piuma.is_file() else []
    for path in paths:
        (c,) = load(path)
        d = c.deflection_signal[c.segment == 0]
        fifth = d.size // 5
        assert d[fifth] - d[:10].mean() > 0.1 * (d[-1] - d[:10].mean())
        assert any(CLIMBS in w for w in analyze(c).warnings), path.name
    (c,) = load(DATA / "asylum-mfp3d_ForceMetric_X60_3_x4_0100.ibw")
    assert not any(CLIMBS in w for w in analyze(c).warnings)
