"""Real curves made hostile the ways files go wrong: a position that stands still, runs the other way or
is read in the wrong unit, a spring constant or sensitivity no lever has, a modulus no material has.

Each gives one readable refusal (an AfmforceError naming what is wrong and what to give) or the correct
result: the same numbers as the intact curve. The curves are the shared Asylum SiN tip in air (a hard
contact, measured ZSnsr and nominal Raw positions) and the Bruker gel (a soft contact with a modulus).
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from afmforce.analysis.options import ProbeCalibration
from afmforce.analysis.pipeline import analyze
from afmforce.analysis.plausibility import IMPOSSIBLE, MODULUS_RANGE, impossible_modulus
from afmforce.analysis.state import prepare
from afmforce.errors import AfmforceError, AnalysisError
from afmforce.io import load
from afmforce.io.native.rawfile import write_raw

DATA = Path(__file__).resolve().parents[1] / "data"


@pytest.fixture(scope="module")
def sin():
    return load(DATA / "asylum-mfp3d_SiN-tip_air.ibw")[0]


@pytest.fixture(scope="module")
def gel():
    return load(DATA / "bruker-nanoscope_PyFMlab_Egel4_00025.spm")[0]


def _numbers(r):
    return (r.contact_kind, r.spring_constant, r.sensitivity_used, r.adhesion_force, r.pull_off_force,
            r.jump_in_separation)


def test_position_stored_as_distance_from_the_sample_is_turned_round(sin):
    """z falling on the approach (a distance from the sample): the same numbers as the intact curve, with a
    note. Before, the hard contact's stale-sensitivity check (the refit default until the file's calibration
    became the default) saw another slope: k 1.184 instead of 0.258 N/m."""
    ref = analyze(sin)
    flipped = dataclasses.replace(sin, piezo_nominal=-np.asarray(sin.piezo_nominal),
                                  piezo_measured=-np.asarray(sin.piezo_measured))
    res = analyze(flipped)
    assert _numbers(res) == _numbers(ref)
    assert any("turned round" in w for w in res.warnings)
    assert not any("turned round" in w for w in ref.warnings)


def test_position_that_stands_still_is_refused(sin):
    still = dataclasses.replace(sin, piezo_nominal=np.full(len(sin), 1e-6), piezo_measured=np.full(len(sin), 1e-6))
    with pytest.raises(AnalysisError, match="position does not move during the approach.*`channel`"):
        analyze(still)


def test_stuck_position_sensor_gives_way_to_the_nominal_position(sin):
    """A ZSnsr channel that stands still (sensor off): the piezo's nominal position, as --channel nominal."""
    stuck = dataclasses.replace(sin, piezo_measured=np.full(len(sin), 2e-6))
    res = analyze(stuck)
    assert _numbers(res) == _numbers(analyze(sin, channel="nominal"))
    assert any("nominal (piezo) position is used" in w for w in res.warnings)
    with pytest.raises(AnalysisError, match="measured .sensor. position does not move"):
        analyze(stuck, channel="measured")  # the user's choice is not overridden


def test_position_in_the_wrong_unit_is_refused(sin):
    """ZSnsr in nm read as metres: 2 um of travel becomes 2 km; no scanner moves a millimetre."""
    nm = dataclasses.replace(sin, piezo_nominal=np.asarray(sin.piezo_nominal) * 1e9,
                             piezo_measured=np.asarray(sin.piezo_measured) * 1e9)
    with pytest.raises(AnalysisError, match="wrong position scale"):
        analyze(nm)


@pytest.mark.parametrize("key,value", [("spring_constant", math.inf), ("spring_constant", -1.0),
                                       ("spring_constant", 0.0), ("spring_constant", 1e30),
                                       ("sensitivity", math.inf), ("sensitivity", -45e-9), ("sensitivity", 1.0)])
def test_calibration_no_lever_has_is_refused(sin, key, value):
    """Before: k = inf raised a bare ZeroDivisionError; a negative or infinite sensitivity was reported as used."""
    md = dict(sin.metadata, **{key: value})
    with pytest.raises(AnalysisError, match=rf"outside .*; give `{key}`"):
        analyze(dataclasses.replace(sin, metadata=md))
    # the user's value replaces the file's bad one, except the spring constant that made this file's forces
    # (in N: its deflection is force / the file's k)
    assert sin.deflection_unit == "N"
    fixed = dataclasses.replace(sin, metadata=md)
    if key == "sensitivity":
        res = analyze(fixed, probe=ProbeCalibration(sensitivity=sin.metadata[key]))
        assert _numbers(res) == _numbers(analyze(sin, probe=ProbeCalibration(sensitivity=sin.metadata[key])))
    else:
        with pytest.raises(AnalysisError, match="spring constant"):
            analyze(fixed, probe=ProbeCalibration(spring_constant=sin.metadata[key]))


def test_modulus_no_material_has_is_not_a_result(gel):
    ref = analyze(gel)
    assert MODULUS_RANGE[0] < ref.youngs_modulus < MODULUS_RANGE[1]  # the gel's, a few kPa
    # the softest lever and sensitivity that can be typed scale the forces down ~4e5 x: E far below 1 Pa
    res = analyze(gel, probe=ProbeCalibration(spring_constant=1e-4, sensitivity=1e-10))
    assert math.isnan(res.youngs_modulus)
    assert res.not_applicable["indentation"].startswith(IMPOSSIBLE)
    assert impossible_modulus(ref.youngs_modulus) is None and impossible_modulus(math.nan) is None
    assert "5e+13 Pa" in impossible_modulus(5e13)


def test_cli_batch_reports_a_still_position_and_goes_on(tmp_path, sin, capsys):
    from afmforce.cli.main import main

    md = {k: sin.metadata[k] for k in ("spring_constant", "sensitivity", "sample_rate")}
    still = dataclasses.replace(sin, piezo_nominal=np.full(len(sin), 1e-6), piezo_measured=np.full(len(sin), 1e-6),
                                metadata=md)
    write_raw(still, tmp_path / "still.txt")
    (tmp_path / "good.ibw").write_bytes((DATA / "asylum-mfp3d_SiN-tip_air.ibw").read_bytes())
    code = main(["analyze", str(tmp_path), "--serial"])
    out = capsys.readouterr()
    assert code == 1 and "Traceback" not in out.err
    bad = [ln for ln in out.err.splitlines() if "still.txt" in ln]
    assert len(bad) == 1 and "does not move" in bad[0]
    assert "good.ibw" in out.out


def test_errors_are_afmforce_errors():
    assert issubclass(AnalysisError, AfmforceError)


@pytest.mark.parametrize("name", ["asylum-mfp3d_SiN-tip_air.ibw", "bruker-nanoscope_PyFMlab_Egel4_00025.spm",
                                  "bruker-nanoscope_sapphire_TAP525.001",   # quantised: its noise is one quantum
                                  "corpus/asylum-ibw_ForceMetric_X60_3_x4_0146.ibw"])
def test_inverted_deflection_sign_is_refused(name):
    """A deflection stored with the other sign (falling as the tip presses on the sample) would give a
    soft result with a wrong adhesion: prepare warns (not a refusal: an approach that stops before
    contact, held by an attraction, looks the same; tests/fit/test_fit_bad_input.py), and the analysis,
    whose compliance line then falls, negates the signal and analyses it again. The
    intact curves get none, among them one whose approach ends below its baseline without the rise (the
    0146 corpus curve); its negated copy rises as a pressed lever does, so it gets none either."""
    curve = load(DATA / name)[0]
    said = lambda st: any("sign is inverted" in w for w in st.warnings)  # noqa: E731
    assert not said(prepare(curve))                                  # the file as read: no warning
    negated = dataclasses.replace(curve, deflection_signal=-np.asarray(curve.deflection_signal))
    if "0146" in name:
        assert not said(prepare(negated))
        return
    assert said(prepare(negated))
    # the analysis orients it (its compliance line falls: tests/analysis/test_inverted_sign.py): the
    # numbers of the file as read, a positive sensitivity from the slope, and a note saying so
    res, ref = analyze(negated), analyze(curve)
    assert any("sign is inverted" in w and "negated" in w for w in res.warnings)
    fit, fit_ref = res.details["calibration"].sensitivity_fit, ref.details["calibration"].sensitivity_fit
    assert fit == pytest.approx(fit_ref, rel=1e-9) and fit > 0   # (the summary's is NaN on a soft contact)
    assert res.sensitivity_fit == pytest.approx(ref.sensitivity_fit, rel=1e-9, nan_ok=True)
    assert res.contact_kind == ref.contact_kind
    assert res.adhesion_force == pytest.approx(ref.adhesion_force, rel=1e-9, nan_ok=True)
