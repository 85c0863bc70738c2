"""Curves that never reached the surface, or stopped at once, are said to be so: never a contact, an
indentation or a rupture read from drift (public JPK files never tried before, see tests/data/README.md,
"Files tried").

* A JPK curve whose piezo ran out of range before the setpoint stores an extend of 1 to 3 samples of the
  thousands planned, and flags it (``force-scan-flags.z-end-out-of-range``, ``setpoint-out-of-range``):
  refused in one line naming the run, its samples and the file's flags (it was refused as "the measured
  position does not move ... check the position channel", which is not the cause).
* A JPK map curve flagged setpoint-out-of-range, flat within 0.03 nN over 30 um, was read as a soft
  contact 19 um deep, a fitted sensitivity of -6779 nm/V and a rupture at -29 um: the weaker contact test
  (a contact only the retract shows) now needs the approach to end above its free baseline line.
* A soft, relaxing sample's retract crosses zero force inside the approach's contact point: its dip and
  last rupture were given as negative distances (-28.7 nm on the corpus' JPK QI cell curve); they are
  measured from where the retract leaves its contact.
"""

from __future__ import annotations

import io
import math
import re
import zipfile
from pathlib import Path

import numpy as np
import pytest

from afmforce.analysis.pipeline import analyze
from afmforce.analysis.regions import RunRegions
from afmforce.analysis.state import MIN_RUN_SAMPLES
from afmforce.analysis.steps.contact import FALLBACK_RISE_SIGMAS, approach_end_rise
from afmforce.analysis.unbinding import retract_adhesion
from afmforce.errors import AnalysisError
from afmforce.io import load
from afmforce.io.jpk_zip import recording_flags

from realdata import SHARED  # noqa: E402  (tests/ is on sys.path: tests/conftest.py)

DATA = Path(__file__).resolve().parents[1] / "data"
NM = 1e-9


def _stopped_jpk(tmp_path: Path, keep: int) -> Path:
    """``jpk_cellhesion_spot3.jpk-force`` (afmformats, MIT) as the instrument writes a curve whose extend ran
    out of z range: its extend cut to ``keep`` samples of the 2000 planned, the two flags set (what nanite's
    ``fmt-jpk-fd_single_bad_2017-01-16_{2..5}`` files hold: 1 extend sample of 3750)."""
    src = zipfile.ZipFile(DATA / "jpk_cellhesion_spot3.jpk-force")
    out = io.BytesIO()
    with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as dst:
        for info in src.infolist():
            data = src.read(info.filename)
            if info.filename == "segments/0/segment-header.properties":
                text = data.decode("latin-1")
                text = re.sub(r"(force-segment-header\.num-points=)\d+", rf"\g<1>{keep}", text)
                text = re.sub(r"(channel\.\w+\.data\.num-points=)\d+", rf"\g<1>{keep}", text)
                for flag in ("z-end-out-of-range", "setpoint-out-of-range"):
                    text = text.replace(f"force-scan-flags.{flag}=false", f"force-scan-flags.{flag}=true")
                data = text.encode("latin-1")
            elif info.filename.startswith("segments/0/channels/"):
                data = data[: 2 * keep]        # short (2-byte) samples
            dst.writestr(info, data)
    path = tmp_path / "stopped.jpk-force"
    path.write_bytes(out.getvalue())
    return path


def test_jpk_extend_of_one_sample_is_refused_with_the_instruments_flags(tmp_path):
    (curve,) = load(_stopped_jpk(tmp_path, 1))
    assert int(np.count_nonzero(np.asarray(curve.segment) == 0)) == 1
    flags = curve.metadata["recording_flags"]
    assert "1 of 2000 samples recorded" in flags and "setpoint out of range" in flags
    with pytest.raises(AnalysisError) as err:
        analyze(curve)
    msg = str(err.value)
    assert "the approach holds only 1 sample" in msg and "(the retract 2000)" in msg
    assert "z end out of range" in msg and "position channel" not in msg and "\n" not in msg


def test_runs_shorter_than_the_contact_split_needs_are_refused(tmp_path):
    (curve,) = load(_stopped_jpk(tmp_path, MIN_RUN_SAMPLES - 1))
    with pytest.raises(AnalysisError, match=f"holds only {MIN_RUN_SAMPLES - 1} sample"):
        analyze(curve)
    (curve,) = load(_stopped_jpk(tmp_path, 4 * MIN_RUN_SAMPLES))   # short, but enough: no refusal for length
    res = analyze(curve)
    assert any("the file flags its recording" in w for w in res.warnings)


def test_recording_flags_read_from_a_segment_header():
    props = {"force-segment-header.force-scan-flags.z-end-out-of-range": "true",
             "force-segment-header.force-scan-flags.setpoint-out-of-range": "true\r",
             "force-segment-header.force-scan-flags.aborted": "false",
             "force-segment-header.settings.segment-settings.num-points": "3750"}
    assert recording_flags(props, 1) == ("1 of 3750 samples recorded, z end out of range (the piezo reached "
                                         "the end of its travel), setpoint out of range (the setpoint was not "
                                         "reached)")
    assert recording_flags({**props, "force-segment-header.force-scan-flags.z-end-out-of-range": "false",
                            "force-segment-header.force-scan-flags.setpoint-out-of-range": "false"}, 1) == ""
    # a flagged extend that recorded all its samples says the flags only
    assert recording_flags(props, 3750).startswith("z end out of range")


def _regions(z, s, far):
    n = z.size
    return RunRegions("approach", np.arange(n), int(far.sum()), ~far, far, ~far, np.zeros(n, bool),
                      float(np.std(np.diff(s[far])) / math.sqrt(2)))


def test_approach_end_rise_tells_a_push_from_drift():
    """A lever pressed on the surface ends the approach above its free baseline line; one that drifted
    down (the map curves flagged setpoint-out-of-range) ends on or below it."""
    rng = np.random.default_rng(1)
    z = np.linspace(0, 1e-6, 1000)
    far = z < 0.8e-6
    noise = 0.2 * NM * rng.standard_normal(z.size)
    pushed = np.where(far, 0.0, (z - 0.8e-6) * 0.05) + noise        # 10 nm over the last 200 nm: 50 sigma
    assert approach_end_rise(z, pushed, _regions(z, pushed, far)) > 30
    drift = 2 * NM * np.sin(z / 0.3e-6) - (z * 2e-3) + noise           # a wandering, falling baseline
    assert approach_end_rise(z, drift, _regions(z, drift, far)) < FALLBACK_RISE_SIGMAS


def test_retract_leaving_contact_inside_the_approach_contact_point_gives_positive_distances():
    """A retract crossing zero force 80 nm inside the approach's contact point (a relaxing cell), its dip's
    floor from 20 to 30 nm and its last rupture at 30 nm from there: 20-30 nm and 30 nm, not about -55 and
    -50 nm."""
    x = np.arange(130.0, -1050.0, -1.0) * NM          # position from the approach's contact point
    xr = x - 80 * NM                                   # ... and from where the retract leaves its contact
    d = np.where(xr > -20 * NM, xr, -20 * NM)          # in contact, then the dip to -20 nm
    d = np.where(xr <= -30 * NM, 0.0, d) + 0.1 * NM * np.random.default_rng(0).standard_normal(x.size)
    n = x.size
    run = RunRegions("retract", np.arange(n), int(np.argmax(xr <= -20 * NM)), xr > 0, xr < -500 * NM,
                     xr > 10 * NM, np.zeros(n, bool), 0.1 * NM)
    res = retract_adhesion(d, x, run, 0.02)
    assert res.found
    assert 19 * NM <= res.distance <= 31 * NM          # the deepest sample of the dip's floor (20-30 nm)
    assert res.rupture_distance == pytest.approx(30 * NM, abs=2 * NM)
    # the same retract with its contact at the approach's (no shift applies): the same, within a sample
    run0 = RunRegions("retract", np.arange(n), run.split, run.contact, run.zero_force, run.compliance,
                      run.saturated, run.noise)
    res0 = retract_adhesion(d, xr, run0, 0.02)
    assert res0.rupture_distance == pytest.approx(res.rupture_distance, abs=1.5 * NM)  # one sample: 1 nm


def test_jpk_qi_cell_curves_adhesion_from_where_the_retract_leaves_contact():
    """The corpus' JPK QI cell curves (afmformats, MIT; curve 0's last rupture was -28.7 nm): the dip's
    distance equals numpy's on afmformats' columns (force and measured height of the retract, less the
    line through its far 30 %: from the first sample below that line to the deepest), and the last rupture
    lies beyond the dip."""
    import afmformats

    path = DATA / "corpus" / "jpk-qi-data_2020.02.07.jpk-qi-data"
    for dd, curve in zip(afmformats.load_data(path), load(path)):
        i = np.flatnonzero(np.asarray(dd["segment"]) == 1)
        h, f = np.asarray(dd["height (measured)"])[i], np.asarray(dd["force"])[i]
        far = slice(int(0.7 * i.size), None)
        u = f - np.polyval(np.polyfit(h[far], f[far], 1), h)
        expected = h[int(np.argmin(u))] - h[int(np.argmax(u < 0))]
        res = analyze(curve)
        assert res.adhesion_distance == pytest.approx(expected, abs=2 * NM)
        # (a retract that comes back gradually, with no step, has no rupture: its return lies beyond the dip)
        last = res.rupture_distance if np.isfinite(res.rupture_distance) else res.adhesion_return_distance
        assert np.isfinite(res.rupture_distance) or "gradually" in res.adhesion_verdict
        assert last >= res.adhesion_distance > 0


NANITE = "AFM-analysis/nanite tests/data (GPL-3.0: not redistributed here; put them in AFMFORCE_REAL_DATA)"


@pytest.mark.parametrize("name", ["fmt-jpk-fd_map_bad_2013-05-27_1.jpk-force-map",
                                  "fmt-jpk-fd_map_bad_2013-05-27_2.jpk-force-map"])
def test_nanite_map_curves_that_never_touched_are_no_contact(name):
    path = SHARED / name
    if not path.is_file():
        pytest.skip(f"{name} not in {SHARED}: {NANITE}")
    (curve,) = load(path)
    res = analyze(curve)
    assert res.contact_kind == "none"
    assert "setpoint out of range" in " ".join(res.warnings) or "drift" in " ".join(res.warnings)


# --- impossible calibration and indentation numbers (NSFopen 1.1.18's `spec.nid`, a FluidFM cell curve) ---

def _line(slope: float):
    from afmforce.analysis.compliance import ComplianceLine

    return ComplianceLine(0.0, slope, 0.0, abs(slope) * 0.01, 1e-12, 100, 0.0, 1e-6, 0.0, 1e-9)


def test_a_falling_compliance_line_gives_no_sensitivity():
    """A contact line the deflection falls along (the cell curve's: -38470 nm/V) is no compliance line: no
    fitted sensitivity; the file's calibration stays; asked to calibrate from it, a refusal naming the value."""
    from afmforce.analysis.compliance import ComplianceResult, calibrate

    meta = {"sensitivity": 55.17e-9, "spring_constant": 0.902264}
    falling = ComplianceResult(_line(-1.0e-4), _line(-1.2e-4), "N")     # N per m: falls as the tip pushes in
    cal = calibrate(falling, meta)
    assert math.isnan(cal.sensitivity_fit) and cal.source == "metadata"
    assert cal.factor == pytest.approx(1 / 0.902264)                      # the file's: force / k
    with pytest.raises(AnalysisError, match="sensitivity"):
        calibrate(falling, {}, source="fit")
    # a rising line: the sensitivity it gives = file's x (k / slope), as before
    rising = ComplianceResult(_line(0.902264 / 2), _line(0.902264 / 2), "N")
    assert calibrate(rising, meta).sensitivity_fit == pytest.approx(2 * 55.17e-9)


def test_indentation_undetermined_when_its_contact_point_interval_spans_half_of_it():
    from afmforce.analysis.contact_point import SoftContactPoint
    from afmforce.analysis.steps.kind import UNDETERMINED_INDENTATION_RATIO, indentation_determined

    def cp(width, indentation=1e-6):
        return SoftContactPoint("power_local", 10, 0.0, 0.0, 0.0, indentation, 1.75, 0.0, width)

    assert indentation_determined(cp(0.1e-6))
    assert not indentation_determined(cp(1.01 * UNDETERMINED_INDENTATION_RATIO * 1e-6))
    assert not indentation_determined(cp(0.0, indentation=-5e-9))   # the deflection rose more than z moved


SPEC = "nsfopen-1.1.18_spec.nid"  # PyPI NSFopen 1.1.18 sdist, NSFopen/example/spec.nid (MIT; 5.4 MB)


def test_fluidfm_cell_curves_give_no_negative_sensitivity_nor_an_undetermined_indentation():
    """Nanosurf FlexAFM 2015 (software 3.4), a FluidFM lever (k 0.902 N/m) on cells, 10 curves triggered at
    10 nN over up to 42 um: no fitted sensitivity <= 0; an indentation only where its contact point is
    fixed within half of it; none beyond the approach's travel."""
    path = SHARED / SPEC
    if not path.is_file():
        pytest.skip(f"{SPEC} not in {SHARED} (too large for tests/data): pip download --no-deps NSFopen==1.1.18")
    for curve in load(path)[:2]:
        z = np.asarray(curve.piezo_nominal)[np.asarray(curve.segment) == 0]
        try:
            res = analyze(curve)
        except AnalysisError:
            continue
        assert not res.sensitivity_fit <= 0
        cp = res.details["contact_point"]
        if math.isfinite(res.indentation):
            assert cp.position_high - cp.position_low <= 0.5 * res.indentation
            assert res.indentation < np.ptp(z)


def test_a_dip_inside_the_contact_point_with_no_contact_before_it_has_no_distances():
    """A retract cut short (PyJibe's `invalid_dataset.jpk-force`: 53 of 5000 retract samples, its last
    rupture was -26.8 nm): it starts below its baseline, inside the approach's contact point, and jumps
    back 30 nm before it. The adhesion stands; its distance, the last rupture's: undetermined, not negative."""
    x = np.arange(60.0, -1000.0, -1.0) * NM
    d = np.where(x > 30 * NM, -20 * NM, 0.0) + 0.1 * NM * np.random.default_rng(2).standard_normal(x.size)
    n = x.size
    run = RunRegions("retract", np.arange(n), 0, x > 0, x < -500 * NM, x > 10 * NM, np.zeros(n, bool), 0.1 * NM)
    res = retract_adhesion(d, x, run, 0.02)
    assert res.found and res.force == pytest.approx(-20 * NM * 0.02, rel=0.05)
    assert math.isnan(res.distance) and math.isnan(res.rupture_distance)
    assert "undetermined" in res.verdict


def test_map_curves_carry_their_flags_and_good_ones_none(tmp_path):
    """Maps and QI data are read through afmformats, which drops the flags: the readers add them. The
    corpus' 2 x 2 map (triggered extends: 1627 of 12030 samples, flagged z-start-out-of-range only) and its
    QI data carry none; a map curve whose extend is flagged z-end and setpoint out of range carries both."""
    for name in ("jpk-force-map_2x2.jpk-force-map", "jpk-qi-data_2020.02.07.jpk-qi-data"):
        assert all("recording_flags" not in c.metadata for c in load(DATA / "corpus" / name))
    src = zipfile.ZipFile(DATA / "corpus" / "jpk-force-map_2x2.jpk-force-map")
    out = tmp_path / "flagged.jpk-force-map"
    with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as dst:
        for info in src.infolist():
            data = src.read(info.filename)
            if info.filename == "index/0/segments/0/segment-header.properties":
                text = data.decode("latin-1")
                for flag in ("z-end-out-of-range", "setpoint-out-of-range"):
                    assert f"force-scan-flags.{flag}=false" in text
                    text = text.replace(f"force-scan-flags.{flag}=false", f"force-scan-flags.{flag}=true")
                data = text.encode("latin-1")
            dst.writestr(info, data)
    flags = [c.metadata.get("recording_flags") for c in load(out)]
    assert "setpoint out of range" in flags[0] and "z end out of range" in flags[0]
    assert flags[1:] == [None, None, None]
