"""A physically impossible number is not a result (issue 32, item 6).

* A repulsive jump into contact or pull-off (both are attractions: F < 0 in afmforce's convention,
  ``JumpIn.force_after`` and ``PullOff.force`` = k x deflection, negative when the lever bends
  towards the surface): the jumps step is not applicable, the verdict names the contact region.
* A deflection signal beyond the photodiode ADC's range: no step gives a number, the verdict names
  the file's data scale (the real v9.2 force volume read 256 x too large reached 312-637 V).
* A hard contact whose compliance slope is more than 10 x off the file's sensitivity: no force.
* A force signal without a spring constant whose compliance slope (the k inferred) is no cantilever's
  (outside 1e-3..100 N/m): no force step, and the k is not reported.
* The stiff lever on sapphire (k = 90 N/m, shared/data/real README): the contact begins at the
  onset of the curved region (about 20 nm before the steep compliance line, 29 nm before the turning
  point, not the last 14 samples), so neither a +137 nN jump-in nor a +163 nN pull-off is reported
  (the pull-off found on the curved contact is refused by name), and no van der Waals fit is drawn.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from afmforce.analysis.jumps import JumpIn, PullOff
from afmforce.analysis.pipeline import analyze
from afmforce.analysis.regions import find_run_regions, run_indices, saturated_mask
from afmforce.analysis.plausibility import DETECTOR_RANGE, IMPOSSIBLE, K_UNDETERMINED, beyond_detector
from afmforce.analysis.steps.jumps import _repulsive
from afmforce.analysis.synthetic import static_curve
from afmforce.io import load

DATA = Path(__file__).resolve().parents[1] / "data"
SAPPHIRE = DATA / "bruker-nanoscope_sapphire_TAP525.001"
VOLUME = DATA / "bruker-nanoscope_force-volume_2x2_trimmed.spm"


def test_repulsive_jumps_are_named():
    nan = math.nan
    attractive = JumpIn(True, 10, nan, 1e-9, 0.0, -2e-9, 0.0, -2e-10, 30.0)
    repulsive = dataclasses.replace(attractive, deflection_after=1.5e-9, force_after=1.37e-7)
    no_pull = PullOff(False, -1, nan, nan, nan, nan, 0.0, False)
    assert _repulsive(attractive, no_pull, 1e-10) is None
    why = _repulsive(repulsive, no_pull, 1e-10)
    assert why.startswith(IMPOSSIBLE) and "+137 nN" in why and "suspect input: the contact region" in why
    pull = PullOff(True, 20, 0.0, 1.8e-9, 1.63e-7, 1.8e-9, 20.0, False)
    assert "pull-off is at +163 nN" in _repulsive(attractive, pull, 1e-10)
    assert _repulsive(repulsive, no_pull, 2e-9) is None  # within the tolerance (noise): not claimed


def test_sapphire_contact_at_the_curved_onset_and_no_repulsive_jumps():
    c = load(SAPPHIRE)[0]
    r = analyze(c)
    assert r.contact_kind == "hard" and r.spring_constant == 90.0
    # no repulsive jump-in or pull-off reported: the retract leaves its compliance line at a repulsive load
    # (a curl in contact), which is no pull-off; the pull-off is the attraction after it: the retract's dip
    for f in (r.jump_in_force, r.pull_off_force):
        assert not f > 0
    assert math.isnan(r.jump_in_force) and not r.verdict.startswith(IMPOSSIBLE)
    base0 = np.median(c.deflection_signal[c.approach][:300])
    dip = 90.0 * 72.76923e-9 * (c.deflection_signal[c.retract].min() - base0)
    assert r.pull_off_force == pytest.approx(dip, rel=0.3)
    # JKR with the file's 8 nm-class tip: gamma of several J/m^2, beyond any solid's: not a result, and why
    assert "surface_energy" in r.not_applicable and math.isnan(r.surface_energy)
    assert r.not_applicable["surface_energy"].startswith("not a surface energy") and "capillary" in \
        r.not_applicable["surface_energy"]
    # the contact begins at the onset of the curved region, about 20 nm before the steep (compliance) line
    assert 12e-9 < r.contact_onset_separation < 25e-9
    # no van der Waals law from a curve without attraction before contact: nothing kept, nothing drawn
    assert "vdw" not in r.details and math.isnan(r.hamaker_radius) and "A R" in r.not_applicable["vdw"]
    # the contact starts where the curved region does: 20-35 nm before the turning point, in the rise
    z = c.piezo_measured[c.approach]
    d = c.deflection_signal[c.approach]
    run = find_run_regions(c.piezo_measured, c.deflection_signal, run_indices(c.segment, 0), "approach",
                           saturated=saturated_mask(c.deflection_signal))
    split = run.split
    assert 20e-9 < z[-1] - z[split] < 35e-9
    base = np.median(d[:300])
    assert d[split] - base < 0.01 < d[-1] - base  # the onset is near the baseline, the end far above it
    # the adhesion (the retract's dip, no jump on a 90 N/m lever) stays: an attraction of about
    # k x DeflSens x (retract minimum - baseline) = 90 x 72.77 nm/V x (-0.0383 + 0.0098) V = -187 nN
    ret = c.deflection_signal[c.retract]
    expected = 90.0 * 72.76923e-9 * (ret.min() - base)
    assert r.adhesion_force < 0 and r.adhesion_force == pytest.approx(expected, rel=0.3)


def test_signal_beyond_the_adc_is_refused_with_its_suspect():
    c = load(VOLUME)[2]
    assert beyond_detector(c) is None
    misread = dataclasses.replace(c, deflection_signal=c.deflection_signal * 256)  # the 16-bit scale on int32
    why = beyond_detector(misread)
    assert why.startswith(IMPOSSIBLE) and f"+-{DETECTOR_RANGE:.3g} V" in why
    r = analyze(misread)
    assert r.verdict == why and "suspect input: the file's data scale" in r.verdict
    assert set(r.not_applicable) >= {"jumps", "adhesion", "indentation", "vdw"}
    assert math.isnan(r.adhesion_force) and math.isnan(r.youngs_modulus) and np.isnan(r.force).all()
    good = analyze(c)
    assert good.adhesion_force < 0 and not good.verdict.startswith(IMPOSSIBLE)


@pytest.mark.parametrize("factor", [20.0, 1 / 20])
def test_calibration_ten_times_off_on_a_hard_contact(factor):
    c = static_curve(seed=1)  # eq 2 with a spring, its sensitivity known (truth)
    true = c.truth["sensitivity"]
    ok = analyze(dataclasses.replace(c, metadata={**c.metadata, "sensitivity": true}))
    assert ok.contact_kind == "hard" and ok.pull_off_force < 0  # control: the right sensitivity
    r = analyze(dataclasses.replace(c, metadata={**c.metadata, "sensitivity": true * factor}))
    assert r.contact_kind == "hard"
    for step in ("jumps", "adhesion", "vdw", "surface_energy"):
        assert r.not_applicable[step].startswith(IMPOSSIBLE)
    assert f"{1 / factor:.3g} x the file's" in r.verdict and "suspect input: sensitivity" in r.verdict
    assert all(math.isnan(v) for v in (r.pull_off_force, r.jump_in_force, r.adhesion_force, r.hamaker_radius))


def _force_export(curve, position_scale: float = 1.0):
    """``curve`` as a processed export: force = k x its true deflection [N], no k or sensitivity stored."""
    t = curve.truth
    md = {key: v for key, v in curve.metadata.items() if key not in ("spring_constant", "sensitivity")}
    return dataclasses.replace(curve, deflection_signal=t["deflection"] * t["spring_constant"], deflection_unit="N",
                               piezo_nominal=curve.piezo_nominal * position_scale,
                               piezo_measured=curve.piezo_measured * position_scale, metadata=md, truth=None)


def test_spring_constant_inferred_from_the_slope_outside_any_lever_is_refused():
    c = static_curve(seed=1)  # k = 0.21 N/m, a hard contact: the force's contact slope is k
    ok = analyze(_force_export(c))
    assert ok.spring_constant == pytest.approx(0.21, rel=0.05)  # control: the slope's k is the lever's
    assert ok.pull_off_force < 0 and not ok.verdict.startswith(IMPOSSIBLE)
    # 1e4 x the travel: a slope of 2.1e-5 N/m, softer than any lever: no hard contact, k undetermined (not an
    # impossible number: the signal is a force, only not one that fixes k); 1e-3 x the travel: about 200 N/m,
    # stiffer than any lever, which a rigid contact's slope (the lever's) cannot be: impossible
    for scale, start, cause in (
            (1e4, K_UNDETERMINED, "the force signal has no hard contact: its compliance slope, 2.1e-05 N/m, is "
                                  "softer than any cantilever made (at least 0.001 N/m)"),
            (1e-3, IMPOSSIBLE, "the position is mis-scaled")):
        r = analyze(_force_export(c, scale))
        assert math.isnan(r.spring_constant)  # no lever is 2e-5 or 2e2 N/m: not reported
        assert r.verdict.startswith(start) and "spring_constant" in r.verdict
        assert cause in r.verdict
        for step in ("jumps", "adhesion", "vdw", "indentation"):
            assert r.not_applicable[step].startswith(start)
        assert all(math.isnan(v) for v in (r.pull_off_force, r.jump_in_force, r.adhesion_force, r.youngs_modulus))


def test_afm_workshop_force_without_a_hard_contact_leaves_k_undetermined():
    """The AFM Workshop export (shared/data/real): extend and retract Z-sense [nm] and force [nN], one
    segment each, no other column, no k. Read here without afmforce: the extend's force rises 20 pN over its
    last 300 nm of travel, where any lever (>= 1e-3 N/m) on a hard contact would rise >= 300 pN: the
    approach reaches no hard contact (a soft sample, or a rise before contact), so its slope (5.1e-5 N/m) is
    not the lever's and k is undetermined, not "physically impossible"."""
    from realdata import real_file

    path = real_file("afm-workshop_single.csv")
    lines = path.read_text().splitlines()
    head = next(i for i, ln in enumerate(lines) if ln.startswith("Extend Z-Sense"))
    assert lines[head].split(",") == ["Extend Z-Sense(nm)", "Extend Force(nN)", "Retract Z-Sense(nm)",
                                      "Retract Force(nN)"]                   # the four columns, no other
    rows = [ln.split(",") for ln in lines[head + 1:] if ln.strip()]
    assert all(len(r) <= 4 for r in rows)
    ext = np.array([[float(r[0]), float(r[1])] for r in rows if len(r) >= 2 and r[0].strip()])
    last = ext[:, 0] > ext[-1, 0] - 300.0                       # nm
    rise = (ext[last, 1].max() - ext[last, 1].min()) * 1e-9      # nN -> N
    assert rise < 0.1 * 1e-3 * 300e-9                            # a tenth of the softest lever's rise
    r = analyze(load(path)[0])
    assert r.verdict.startswith(K_UNDETERMINED) and IMPOSSIBLE not in r.verdict
    assert "no hard contact" in r.verdict and "5.13e-05 N/m" in r.verdict and "give spring_constant" in r.verdict
    assert math.isnan(r.spring_constant)


def test_slope_of_a_separation_or_a_soft_contact_is_not_the_levers_spring_constant():
    c = static_curve(seed=1)
    export = _force_export(c)
    sep = dataclasses.replace(export, metadata={**export.metadata, "position_is_separation": True})
    r = analyze(sep)
    assert math.isnan(r.spring_constant) and r.pull_off_force < 0  # the forces are the file's, and stay
    assert any("not reported: the position is the tip-sample separation" in w for w in r.warnings)
    # a real soft contact in force units without k (AFM Workshop CSV; the slope gives 2.7 N/m)
    r = analyze(load(DATA / "corpus" / "afm-workshop_single_2020-02-14.csv")[0])
    assert r.contact_kind == "soft" and math.isnan(r.spring_constant) and math.isnan(r.youngs_modulus)
    assert "the contact is soft" in r.not_applicable["indentation"]
    assert any("2.7 N/m from the compliance slope not reported" in w for w in r.warnings)


def test_negative_indentation_is_not_reported():
    """The Asylum force-map curve whose wave note keeps an uncalibrated InvOLS (100 nm/V): read
    independently (igor2), its deflection rises more than the ZSnsr position travels over the
    approach's last 60 samples, so no indentation (z travel less deflection rise) can be positive;
    the audit found -1.59 nm reported as the curve's indentation."""
    from igor2 import binarywave

    path = DATA / "corpus" / "asylum-ibw_no-date_ForceMap.ibw"
    wave = binarywave.load(str(path))["wave"]
    defl, zsnsr = wave["wData"][:, 1], wave["wData"][:, 2]
    end = 224   # Indexes 0,224,...: the approach ends at sample 224 (wave note)
    assert defl[end] - defl[end - 60] > zsnsr[end] - zsnsr[end - 60] > 0
    r = analyze(load(path)[0])
    assert r.contact_kind == "soft"
    assert math.isnan(r.indentation)
    why = [w for w in r.warnings if "negative indentation" in w]
    assert why and why[0].startswith(IMPOSSIBLE) and "suspect input: sensitivity" in why[0]
