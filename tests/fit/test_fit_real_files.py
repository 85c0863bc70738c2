"""Issue 23 items 2 and 4: the dynamic fit on real instrument files, prepared by the analysis steps.

Each real file either prepares for the fit with the calibration ``afmforce analyze`` uses (the same
number, checked against the analysis's own result and a plain least-squares contact slope), or is
refused once, with the property that stops it (a soft contact, no contact, no time axis) and what to
do. Preparation only (no model runs): fast. The fits' numbers are in docs/fit.md ("Real instrument
files").
"""

from __future__ import annotations

import dataclasses
import json
import warnings

import numpy as np
import pytest

from afmforce.analysis.pipeline import analyze
from afmforce.cli.main import main
from afmforce.errors import AnalysisError, MissingMetadataError
from afmforce.fit import prepare_curves
from afmforce.fit.core import base_config
from afmforce.fit.preprocess import preparation_warnings
from afmforce.io import load
from realdata import real_file

from fit_virtual import make_curves


def _load(name: str, **meta):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return load(real_file(name), meta_override=meta or None)


def _prepare(curve, name="c"):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return prepare_curves([curve], [name])[0]


def _analysed_and_prepared(name: str, calibration: str = "auto", options=None):
    """``(curve, analysis with the kind step, fit curve, its calibration)`` of a real file's first curve."""
    curve = _load(name)[0]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ana = analyze(curve, steps=["kind"], options=options)
        fc = prepare_curves([curve], [name], calibration=calibration)[0]
    return curve, ana, fc, fc.metadata["calibration"]


SOFT = ["ForceMetric_X60_3_x4_0100.ibw", "PyFMlab_20200904_Egel4-Z1.0_00025.spm",
        "jpk_cellhesion_spot3.jpk-force", "afmformats_jpk-sr_cell1-0008.jpk-force",
        "jpkfile_force-save-2016.06.15-13.17.08.jpk-force"]


@pytest.mark.parametrize("name", SOFT)
def test_soft_samples_refused_with_the_analysis_reason(name):
    """Gels, cells and an indented sample: the analysis calls the contact soft, the fit refuses it
    naming the contact, the rigid surfaces of its model and `afmforce analyze`."""
    curve = _load(name)[0]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ana = analyze(curve, steps=["kind"])
    assert ana.contact_kind == "soft"
    with pytest.raises(AnalysisError) as exc:
        _prepare(curve, name)
    msg = str(exc.value)
    assert msg.startswith(f"{name}: soft contact (") and ana.contact_kind_reason in msg
    assert "rigid surfaces" in msg and f"afmforce analyze {name}" in msg
    # a pause (dwell) segment is named too: a stress-relaxation record
    assert ("dwell/pause segment" in msg) == bool(np.any(np.asarray(curve.segment) >= 2))


def test_soft_looking_approach_in_a_liquid_is_fitted_with_a_note():
    """In a liquid (model viscosity above 1e-4 Pa s) drainage bends a fast colloid-probe approach
    like an indentation. The demo's 40 um/s curve in water has a rigid contact: the analysis called it
    soft until the kind step learnt to read a surface force's rise before a straight compliance line
    (steps/kind.py, the double-layer fix); it now calls it hard, the truth, and the fit prepares it with
    no soft-contact note and without ``soft="warn"``. A gel is still refused in a liquid, by the
    contact line's slope."""
    from afmforce.fit import virtual_curves
    from afmforce.fit.core import LIQUID_VISCOSITY
    from afmforce.paper.demo_liquid import LIQUID_DEMO

    assert base_config("beam").viscosity < LIQUID_VISCOSITY < LIQUID_DEMO["viscosity"]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        c = virtual_curves([40e-6], seed=1, noise=0.05e-9, drift_rms=0.5e-9,
                           sample_rates=[40e-6 / 1e-9], **LIQUID_DEMO)[0]
        assert analyze(c, steps=["kind"]).contact_kind == "hard"
        fc = prepare_curves([c], ["fast"])[0]
    assert not any("soft contact" in n for n in fc.metadata.get("preparation_notes", ()))
    assert fc.mask.sum() > 100
    gel = "PyFMlab_20200904_Egel4-Z1.0_00025.spm"
    with warnings.catch_warnings(), pytest.raises(AnalysisError, match="not ~1"):
        warnings.simplefilter("ignore")
        prepare_curves(_load(gel)[:1], [gel], soft="warn")


def test_map_file_each_curve_and_one_json_refusal(capsys):
    """A force map (4 cells): every curve is a fit curve (FILE#i); the first soft one stops the fit
    with one JSON object."""
    path = real_file("afmformats_jpk-fd_map2x2_extracted.jpk-force-map")
    assert main(["fit", str(path), "--free", "hamaker", "--json"]) == 1
    out = capsys.readouterr().out
    d = json.loads(out)
    assert out.count("\n") == 1 and list(d) == ["error"]
    assert d["error"]["message"].startswith(f"{path.name}#1: soft contact")


def test_asylum_air_prepared_with_the_files_calibration_as_the_analysis():
    """The MFP-3D SiN curve (hard contact, measured ZSnsr): the fit's preprocessing takes the calibration
    `afmforce analyze` uses, by default the file's (InvOLS 44.99 nm/V, k 1.1841 N/m of the wave note, read
    with igor2): with it the deflection follows the position 0.47x in contact, so the fit refuses the
    curve as not rigid, naming the calibration, instead of refitting the InvOLS behind the user's back."""
    from realdata import wave_note

    name = "asylum-mfp3d_SiN-tip_air.ibw"
    note = wave_note(real_file(name))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        curve = _load(name)[0]
        ana = analyze(curve)
    from afmforce.fit.preprocess import analysis_inputs

    inp = analysis_inputs(curve, name, np.flatnonzero(np.asarray(curve.segment) == 0))
    assert ana.calibration_source == "metadata" and inp.source == "file"
    assert inp.factor == pytest.approx(ana.details["calibration"].factor, rel=1e-12)
    assert inp.spring_constant == ana.spring_constant == pytest.approx(float(note["SpringConstant"]), rel=1e-12)
    assert inp.file_sensitivity == pytest.approx(float(note["InvOLS"]), rel=1e-12)
    assert not any("rescaled" in n or "calibrates" in n for n in inp.notes)
    assert 0.4 < inp.slope < 0.55                  # the file's calibration: far below 1 in contact
    with pytest.raises(AnalysisError, match=r"slope 0\.4\d+, not ~1 \(calibrated: file\).*`calibration` fit"):
        _prepare(curve, name)


def test_asylum_air_refit_asked_for_as_the_analysis():
    """`calibration="fit"`, as `afmforce analyze --calibration fit`: the compliance slope calibrates (the
    deflection follows the position 0.47x with the file's InvOLS) and the thermal k is rescaled, the
    same numbers as the analysis asked the same."""
    from afmforce.analysis.options import CalibrationOptions

    name = "asylum-mfp3d_SiN-tip_air.ibw"
    curve, ana, fc, cal = _analysed_and_prepared(name, calibration="fit",
                                                 options=[CalibrationOptions(source="fit")])
    assert ana.contact_kind == "hard" and ana.calibration_source == "fit"
    assert cal["source"] == "recalibrated"
    factor = ana.details["calibration"].factor
    assert cal["factor"] == pytest.approx(factor, rel=1e-12)
    # independently: a plain least-squares line through the deepest 20 approach samples (in contact)
    app = np.flatnonzero(np.asarray(curve.segment) == 0)[-20:]
    k = curve.metadata["spring_constant"]
    slope = np.polyfit(np.asarray(curve.piezo_measured)[app],
                       np.asarray(curve.deflection_signal)[app] / k, 1)[0]
    assert 0.4 < slope < 0.55                      # far below 1 with the file's calibration
    assert cal["factor"] == pytest.approx(1.0 / (k * slope), rel=0.05)
    assert cal["contact_slope"] == pytest.approx(1.0, rel=1e-9)
    assert np.ptp(fc.deflection) == pytest.approx(np.ptp(np.asarray(curve.deflection_signal)[
        np.asarray(curve.segment) == 0]) * factor, rel=1e-12)
    notes = preparation_warnings([fc], base_config("beam"))
    s = ana.details["calibration"]
    assert any(f"{s.sensitivity_fit * 1e9:.4g} nm/V instead of the file's 44.99 nm/V" in w for w in notes)
    # the file's thermal k rescaled as the analysis does (x (44.99 / 96.3)^2), and that lever is not
    # the model's (0.1387 N/m): said, with the keys (`k0`, `model`: the CLI renders --k0, --model)
    k = 1.1841 * (44.99e-9 / s.sensitivity_fit) ** 2
    assert cal["spring_constant"] == pytest.approx(k, rel=1e-6)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert cal["spring_constant"] == pytest.approx(analyze(curve, steps=["kind", "force"], options=[
            CalibrationOptions(source="fit")]).spring_constant, rel=1e-12)
    assert any(f"spring constant is {k:.4g} N/m" in w and "(`k0` " in w and "`model` spring" in w for w in notes)


def test_raw_volts_calibration_curve_gets_the_analysis_sensitivity():
    """JPK calibration curve in raw volts, no sensitivity: the analysis's compliance-slope
    sensitivity, with its own warning (6 contact samples) and the fit's note (no jump-in)."""
    name = "jpk_calibration-curve_raw-volts.jpk-force"
    curve, ana, fc, cal = _analysed_and_prepared(name)
    assert cal["source"] == "compliance" and cal["unit"] == "V"
    assert cal["sensitivity"] == pytest.approx(ana.sensitivity_fit, rel=1e-12)
    assert cal["sensitivity"] == pytest.approx(934.5e-9, rel=1e-3)
    notes = preparation_warnings([fc], base_config("beam"))
    assert any("934.5 nm/V from the slope" in w and "(`sensitivity`)" in w for w in notes)   # CLI: --meta
    assert any("fitted on only 6 contact samples" in w for w in notes)
    assert any("no significant jump into contact" in w for w in notes)


def test_the_fit_jump_in_is_the_analysis_jump_in():
    """One preprocessing: on virtual curves the fit's first sample after the jump-in is the sample
    after the analysis's jump-in (step ``jumps``)."""
    curves = make_curves(0.005, seed=3, speeds=(1e-6, 4e-6), spacing=0.5e-9)
    fcs = prepare_curves(curves)
    for c, fc in zip(curves, fcs):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            ji = analyze(c, steps=["jumps"]).details["jumps"].jump_in
        assert ji.found
        assert fc.jump_index == ji.index + 1 - np.flatnonzero(np.asarray(c.segment) == 0)[0]
        assert fc.metadata["calibration"]["source"] == "file"


def test_no_contact_refused():
    """The JPK curve whose approach never pushes (k removed from the file, given here)."""
    curve = _load("afmformats_jpk-fd_single-modified_2023.jpk-force", spring_constant=12.0)[0]
    with pytest.raises(AnalysisError, match="no contact reached.*the fit needs curves that reach contact"):
        _prepare(curve, "jpk")


def test_files_without_time_refused_for_their_contact_first(capsys):
    """AFM Workshop and NT-MDT exports carry the sample index, not the time (the speed read off the
    ramp would be in metres per sample: 0.001 um/s before). Their samples are soft: the contact is
    what stops the fit, said before the missing time (a sample rate would not help); the missing time
    alone: test_sample_index_time_rescaled_with_the_given_rate."""
    meta = ["--meta", "spring_constant=0.1N/m", "--meta", "sensitivity=50nm/V"]
    for name in ("afm-workshop_single.csv", "ntmdt_gel-in-water.txt",
                 "afmformats_afm-workshop-fd_single_2018-08-01.csv"):
        assert main(["fit", str(real_file(name)), "--free", "hamaker", "--json", *meta]) == 1
        msg = json.loads(capsys.readouterr().out)["error"]["message"]
        assert msg.startswith(f"{name}: soft contact (") and "--sample-rates" not in msg


def test_force_without_spring_constant_implausible_slope_refused():
    """AFM Workshop force [N] without k: its compliance slope, the k of a rigid contact, is 5e-5 N/m
    (a plain least-squares line through the deepest approach samples says the same): no cantilever
    is that soft, so the contact is not rigid (with k = 0.1 N/m it follows the position 0.0005x)."""
    curve = _load("afm-workshop_single.csv")[0]
    app = np.flatnonzero(np.asarray(curve.segment) == 0)[-30:]
    k_slope = np.polyfit(np.asarray(curve.piezo_nominal)[app], np.asarray(curve.deflection_signal)[app], 1)[0]
    assert 1e-5 < k_slope < 1e-4
    with pytest.raises(AnalysisError, match=r"compliance slope.*is 5\.\d+e-05 N/m.*\(`spring_constant`\)"):
        _prepare(curve, "aws")


def test_missing_calibration_named_with_the_fit_flags(capsys):
    """The loader's `--spring-constant` is the model's lever in `afmforce fit`: the fit asks for
    --meta instead."""
    path = real_file("ntmdt_gel-in-water.txt")
    assert main(["fit", str(path), "--free", "hamaker", "--json"]) == 2
    msg = json.loads(capsys.readouterr().out)["error"]["message"]
    assert "--meta spring_constant=VALUE --meta sensitivity=VALUE" in msg


def test_sample_index_time_rescaled_with_the_given_rate():
    """A virtual curve whose time column is the sample index: refused without a rate; with it the
    fit's time, speed and mask are those of the curve with its real time."""
    c = make_curves(0.005, seed=3, speeds=(1e-6, 4e-6), spacing=0.5e-9)[0]
    fs = c.metadata["sample_rate"]
    meta = {k: v for k, v in c.metadata.items() if k not in ("sample_rate", "velocity")}
    idx = dataclasses.replace(c, time=np.arange(len(c.time), dtype=float),
                              metadata={**meta, "time_is_sample_index": True})
    with pytest.raises(MissingMetadataError, match="stores no time"):
        _prepare(idx)
    ref = _prepare(c)
    got = prepare_curves([idx], sample_rates=[fs])[0]
    np.testing.assert_allclose(got.time, ref.time, rtol=1e-9, atol=1e-15)
    assert got.velocity == pytest.approx(ref.velocity, rel=1e-3)
    assert got.jump_index == ref.jump_index and np.array_equal(got.mask, ref.mask)


def test_paper_preset_backlash_and_a_jump_below_the_noise():
    """The ``paper`` virtual AFM (5 nm position steps, 37 nm backlash, 0.3 nm noise) over a short
    drive: the retract's sensor barely moves in contact, so its compliance line is degenerate; the
    analysis (and with it the fit) goes on with the approach's line, saying so (before: the
    analysis failed). The jump-in (0.9-1.5 nm, below 5 step noises) is still left out where the
    trajectory's truth has it."""
    from afmforce.dynamics import simulate
    from afmforce.instrument import build_instrument

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        tr = simulate(velocity=2e-6, xi=0.005, sampling="average", start=-40e-9, turn=20e-9, end=-60e-9)
    for seed in (1, 3):
        c = build_instrument("paper").record(tr, seed=seed)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            ana = analyze(c, steps=["calibration"])
        assert any("the retract run has no compliance line" in w for w in ana.warnings)
        assert not ana.details["compliance"].retract.found and ana.details["compliance"].approach.found
        fc = _prepare(c)
        app = np.flatnonzero(np.asarray(c.segment) == 0)
        true_j = int(np.flatnonzero(np.asarray(c.truth["separation"])[app] < 0.3e-9)[0])
        assert fc.metadata["calibration"]["jump_found"] is False
        assert fc.jump_index == true_j and not fc.mask[true_j - 2: true_j + 2].any()


def test_asylum_air_fit_via_the_cli_warns_like_the_analysis(capsys):
    """`afmforce fit FILE --free hamaker --json` on the MFP-3D SiN curve in air: with the file's calibration
    (the default) the contact is not rigid, refused naming --calibration fit; with it, one JSON object with
    the analysis's calibration per curve; the jump-in in air is a capillary one, far beyond van der
    Waals: both the fit and the analysis (its vdW step) put A above the physical range and say so."""
    from afmforce.analysis.plausibility import HAMAKER_RANGE

    name = "asylum-mfp3d_SiN-tip_air.ibw"
    path = real_file(name)
    assert main(["fit", str(path), "--free", "hamaker", "--json"]) == 1    # the file's calibration: not rigid
    err = json.loads(capsys.readouterr().out)["error"]["message"]
    assert "not ~1 (calibrated: file)" in err and "--calibration fit" in err
    assert main(["fit", str(path), "--free", "hamaker", "--no-profile", "--no-compare", "--json",
                 "--calibration", "fit"]) == 0
    out = capsys.readouterr().out
    d, end = json.JSONDecoder().raw_decode(out)
    assert end == len(out.rstrip())                  # one JSON object, nothing else on stdout
    assert d["calibration"][name]["source"] == "recalibrated"
    a = d["parameters"]["hamaker"]["value"]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ana = analyze(_load(name)[0])
    hw = [w for w in ana.warnings if w.startswith("Hamaker constant")]   # the pull-off's radius
    assert hw and "outside the physical range" in hw[0]
    assert a > HAMAKER_RANGE[1] and float(hw[0].split()[2]) > HAMAKER_RANGE[1]
    assert any(w.startswith(f"Hamaker constant {a:.3g} J (with the model's radius 100 nm")
               and "capillary meniscus" in w for w in d["warnings"])


def test_impossible_sensitivity_on_one_virtual_curve_recalibrated():
    """Two virtual curves in volts with the file's 50 nm/V; the laser of the second was realigned
    (its signal 1.6x larger for the same deflection): with the file's sensitivity its deflection would
    outrun the position 1.6x in contact, which no contact allows, so the analysis's rule (the one case
    `auto` refits a stored sensitivity) gives it the compliance slope's calibration (the truth,
    31.25 nm/V, within 2 %), and the fit says the curves' calibrations differ."""
    # 40 nm in contact: the analysis recalibrates only a contact line it finds straight
    c1, c2 = make_curves(0.005, seed=3, speeds=(1e-6, 4e-6), spacing=0.5e-9, turn=40e-9)
    s = 50e-9

    def volts(c, gain):
        return dataclasses.replace(c, deflection_signal=np.asarray(c.deflection_signal) / s * gain,
                                   deflection_unit="V", metadata={**c.metadata, "sensitivity": s})

    ref = prepare_curves([volts(c2, 1.0)])[0]
    fc1, fc2 = prepare_curves([volts(c1, 1.0), volts(c2, 1.6)])
    cal = fc2.metadata["calibration"]
    assert fc1.metadata["calibration"]["source"] == "file" and cal["source"] == "recalibrated"
    assert cal["sensitivity"] == pytest.approx(s / 1.6, rel=0.02)     # the truth: 31.25 nm/V
    np.testing.assert_allclose(fc2.deflection, ref.deflection * cal["sensitivity"] * 1.6 / s, rtol=1e-12)
    assert fc2.jump_index == ref.jump_index and np.array_equal(fc2.mask, ref.mask)
    notes = preparation_warnings([fc1, fc2], base_config("beam"))
    assert any(w.startswith("the curves' sensitivities differ") for w in notes)
    assert any("the file's is impossible on this hard contact" in w and fc2.name in w for w in notes)


def test_calibration_words_are_the_analysis_words():
    """The fit's `calibration` is the analysis's `calibration.source` (one rule): `metadata` (and `file`,
    its former word) keeps the file's sensitivity even where a hard contact's line calls it impossible;
    `auto` refits only that impossible case (gain 1.6: the deflection would outrun the position), and keeps
    the file's where the deflection follows the position less than 1 (gain 0.625: possible on a soft
    sample or with a changed alignment); `fit` refits both. Truth: 50 nm/V / gain."""
    from afmforce.analysis.options import CALIBRATION_SOURCES, CalibrationOptions

    c1, c2 = make_curves(0.005, seed=3, speeds=(1e-6, 4e-6), spacing=0.5e-9, turn=40e-9)
    s = 50e-9

    def volts(gain):
        return dataclasses.replace(c2, deflection_signal=np.asarray(c2.deflection_signal) / s * gain,
                                   deflection_unit="V", metadata={**c2.metadata, "sensitivity": s})

    v2, low = volts(1.6), volts(0.625)
    auto = prepare_curves([v2])[0]
    kept = prepare_curves([v2], calibration="file")[0]
    meta = prepare_curves([v2], calibration="metadata")[0]
    assert auto.metadata["calibration"]["source"] == "recalibrated"
    assert kept.metadata["calibration"]["source"] == meta.metadata["calibration"]["source"] == "file"
    assert kept.metadata["calibration"]["factor"] == pytest.approx(s, rel=1e-12)
    np.testing.assert_allclose(kept.deflection, np.asarray(v2.deflection_signal)[: kept.n] * s,
                               rtol=1e-12)
    np.testing.assert_array_equal(kept.deflection, meta.deflection)
    low_auto, low_fit = (prepare_curves([low], calibration=c)[0].metadata["calibration"] for c in ("auto", "fit"))
    assert low_auto["source"] == "file" and low_auto["factor"] == pytest.approx(s, rel=1e-12)
    assert low_fit["source"] == "recalibrated" and low_fit["sensitivity"] == pytest.approx(s / 0.625, rel=0.02)
    # the analysis decides the same for each word (one rule)
    for word in CALIBRATION_SOURCES:
        for curve in (v2, low):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                ana = analyze(curve, steps=["kind"], options=[CalibrationOptions(source=word)])
                fc = prepare_curves([curve], calibration=word)[0]
            assert fc.metadata["calibration"]["factor"] == pytest.approx(ana.details["calibration"].factor,
                                                                         rel=1e-12), (word, curve is v2)
    from afmforce.errors import ParameterError
    from afmforce.fit import fit_dynamic

    with pytest.raises(ParameterError, match="calibration must be"):
        fit_dynamic([v2], "beam", free=("hamaker",), calibration="stale")
