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
        assert res.rupture_distance >= res.adhesion_distance > 0


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
