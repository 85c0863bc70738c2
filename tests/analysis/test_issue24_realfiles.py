"""Issue 24 items 2 and 3 on the real files: segments by type, baselines, plausibility, figures, maps.

Each expected number comes from the file itself, computed here independently of the pipeline (the
raw signal's span, the force column of the file, a plain least-squares contact slope), or from the
physical ranges the warnings are about.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from afmforce.analysis.dynamic import diagnose_curve
from afmforce.analysis.drift import borrowed_line
from afmforce.analysis.options import CalibrationOptions, ForceOptions
from afmforce.analysis.pipeline import analyze
from afmforce.io import load
from realdata import real_file, wave_note  # noqa: E402  (tests/ is on sys.path: tests/conftest.py)

_CACHE: dict = {}


def _run(name: str, meta=None, options=None):
    key = (name, repr(meta), repr(options))
    if key not in _CACHE:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            curve = load(real_file(name), meta_override=meta)[0]
        _CACHE[key] = (curve, analyze(curve, options=options))
    return _CACHE[key]


def _runs(res):
    return (res.segment == 0) | (res.segment == 1)


def test_stress_relaxation_segments_by_type_and_force_within_the_signal():
    """JPK stress relaxation: pause, extend, 30 s pause, retract. Before: the approach's drift line was
    extrapolated in time over the 30 s dwell (force panel at -7000 nN for a +-210 nN signal)."""
    curve, res = _run("afmformats_jpk-sr_cell1-0008.jpk-force")
    seg = np.asarray(curve.segment)
    assert list(seg[np.r_[0, np.flatnonzero(np.diff(seg)) + 1]]) == [2, 0, 2, 1]  # the file's segment types
    m = _runs(res)
    span = float(np.ptp(np.asarray(curve.deflection_signal)[m]))  # [N]: the signal is a force
    f = res.force[m]
    assert np.ptp(f) <= 1.05 * span
    for s in (0, 1):  # each run's free end is its own zero (within 2 % of the span)
        run = np.flatnonzero(res.segment == s)
        far = run[np.argsort(curve.piezo_measured[run])[: run.size // 10]]  # farthest 10 % from the sample
        assert abs(float(np.median(res.force[far]))) < 0.02 * span
    dwell = res.segment == 2
    assert np.all(np.abs(res.force[dwell]) <= 1.05 * span)  # the dwell too: between the runs' baselines
    assert res.details["drift"].retract_line in ("offset", "approach slope", "position tilt", "separate")
    assert not any(w.startswith("the corrected force spans") for w in res.warnings)
    # contact point: stored nanite reference -137.19 um (fit_line_polynomial), tolerance 10 % of the indentation
    cp = res.details["contact_point"]
    assert abs(cp.position - (-137.194e-6)) < 0.1 * res.indentation


def test_bruker_gel_retract_baseline_is_its_own():
    """Bruker gel: the retract's free part is noisy (unbinding), so it borrowed the approach line and sat
    about 0.25 V (0.9 nN) below zero throughout; now its own offset."""
    curve, res = _run("PyFMlab_20200904_Egel4-Z1.0_00025.spm")
    run = np.flatnonzero(res.segment == 1)
    z = np.asarray(curve.piezo_nominal)[run]
    far = run[z < np.min(z) + 0.3 * np.ptp(z)]  # the retract's far 30 % (free)
    noise = res.details["drift"].noise * res.sensitivity * res.spring_constant
    assert abs(float(np.median(res.force[far]))) < max(0.1e-9, 10 * noise)
    assert res.details["drift"].retract_line == "offset"
    assert any("its own offset" in w for w in res.warnings)


def test_borrowed_line_picks_the_data_s_offset():
    rng = np.random.default_rng(3)
    t = np.linspace(10.0, 10.5, 400)
    s = -0.2 + 0.05 * rng.standard_normal(t.size)  # offset -0.2 and ringing noise 0.05
    name, off, slope, tilt = borrowed_line(t, s, None, 0.0, 0.01, 0.0, math.nan, 0.05)
    assert name in ("offset", "approach slope") and off == pytest.approx(-0.2, abs=0.02)
    same = 0.01 * t + 0.05 * rng.standard_normal(t.size)  # the approach line continued: kept
    assert borrowed_line(t, same, None, 0.0, 0.01, 0.0, math.nan, 0.05)[0] == "approach"


def test_cellhesion_contact_rupture_steps_and_oscillation_agree_with_the_figure():
    """2016 CellHesion: contact -36.5 um before (visible near -26 um), adhesion drawn 10 um inside the
    sample, rupture -1449 nm, the table's 351.5 Hz against the figure's "undetermined", steps unmarked."""
    from afmforce.plotting import plot_summary

    curve, res = _run("jpkfile_force-save-2016.06.15-13.17.08.jpk-force")
    assert -26.6e-6 < res.details["contact_point"].position < -25.7e-6
    assert abs(res.adhesion_distance) < 1e-6  # the deepest dip right after the contact, not 10 um inside
    # the last tether lets go near z = -35 um on the retract (a step of the raw signal): ~9 um from contact
    assert 7e-6 < res.rupture_distance < 11e-6
    assert res.unbinding_steps >= 1
    fig = plot_summary(res, curve)
    titles = [ax.get_title() for ax in fig.axes]
    labels = [t.get_text() for ax in fig.axes if ax.get_legend() for t in ax.get_legend().get_texts()]
    if math.isfinite(res.oscillation_frequency):
        assert any(f"{res.oscillation_frequency:.4g} Hz" in t for t in titles)
    assert any("unbinding step" in t for t in labels) and any("last rupture" in t for t in labels)
    assert "contact region, enlarged" in titles


def _asylum_air():
    """The Asylum SiN curve in air, independently: afmformats' force column (the file's calibration),
    the approach's contact line by plain least squares, and k and InvOLS from the wave note (igor2)."""
    import afmformats

    path = real_file("asylum-mfp3d_SiN-tip_air.ibw")
    note = wave_note(path)
    k, invols = float(note["SpringConstant"]), float(note["InvOLS"])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        dd = afmformats.load_data(path)[0]
    f_file = np.asarray(dd["force"])
    zs = -np.asarray(dd["height (measured)"])
    turn = 1008
    top = np.arange(turn - 40, turn)
    slope = np.polyfit(zs[top], f_file[top] / k, 1)[0]  # deflection per position with the file's InvOLS
    base = np.median(f_file[turn + 800:])
    return k, invols, slope, float(np.min(f_file[turn:]) - base)


def test_asylum_air_uses_the_files_calibration_by_default():
    """The file's stored InvOLS and thermal k are the default, as nanite, JPK DP and Asylum's software use
    them: k 1.1841 N/m and InvOLS 44.99 nm/V of the wave note. Before, a hard contact whose line followed the
    position 0.47 x refitted the InvOLS to 96.4 nm/V and rescaled k to 0.258 N/m, with a warning only, while
    `afmforce calibrate invols` said the same 2.14 x may be a soft sample, a changed laser alignment or a
    position channel that is not the tip-sample distance. The refit stays a reported diagnostic."""
    k, invols, slope, pull_file = _asylum_air()
    assert (k, invols) == (1.1841, 4.499e-08)
    _, res = _run("asylum-mfp3d_SiN-tip_air.ibw")
    assert res.calibration_source == "metadata"
    assert res.sensitivity_used == pytest.approx(invols, rel=1e-12) and res.sensitivity == res.sensitivity_used
    assert res.spring_constant == pytest.approx(k, rel=1e-12)
    assert res.pull_off_force == pytest.approx(pull_file, rel=0.03)    # the file's forces
    assert res.sensitivity_fit == pytest.approx(invols / slope, rel=0.03)   # the refit, reported beside
    mismatch = [w for w in res.warnings if "x the file's" in w and "compliance slope" in w]
    assert mismatch and f"{1 / slope:.2g}" in mismatch[0] and "the file's is used" in mismatch[0]
    assert not any("rescaled" in w for w in res.warnings)
    assert not res.dynamic and res.dynamic_assessed and "likely capillary" in res.verdict
    hw = [w for w in res.warnings if w.startswith("Hamaker constant")]
    assert hw and "outside the physical range" in hw[0]
    # `calibration` metadata (the file's always) gives the same numbers here
    _, meta = _run("asylum-mfp3d_SiN-tip_air.ibw", options=[CalibrationOptions(source="metadata")])
    assert (meta.spring_constant, meta.pull_off_force) == (res.spring_constant, res.pull_off_force)


def test_asylum_air_refit_when_asked_rescales_the_thermal_k():
    """`calibration` fit (asked for): the compliance slope calibrates and the thermal k goes as 1/InvOLS^2,
    so forces scale by file's/fitted (k x (slope)^2, deflections / slope); the lines then stand vertical
    (pulled off at h ~ 0). force.thermal_k=false keeps the file's k (forces doubled, -27 nN)."""
    k, invols, slope, pull_file = _asylum_air()
    _, res = _run("asylum-mfp3d_SiN-tip_air.ibw", options=[CalibrationOptions(source="fit")])
    assert res.calibration_source == "fit"
    assert res.sensitivity_used == res.sensitivity_fit == pytest.approx(invols / slope, rel=0.03)
    assert res.spring_constant == pytest.approx(k * slope**2, rel=0.06)
    assert res.pull_off_force == pytest.approx(pull_file * slope, rel=0.05)
    assert any("rescaled with the refitted sensitivity" in w for w in res.warnings)
    h_pull = res.separation[np.argmin(np.where(res.segment == 1, res.force, np.inf))]
    assert abs(h_pull) < 3e-9
    _, kept = _run("asylum-mfp3d_SiN-tip_air.ibw",
                   options=[CalibrationOptions(source="fit"), ForceOptions(thermal_k=False)])
    assert kept.spring_constant == pytest.approx(k, rel=1e-12)
    assert kept.pull_off_force == pytest.approx(pull_file / slope, rel=0.05)


def test_diagnosis_names_capillarity_in_air_and_keeps_dynamics_in_liquid():
    common = dict(velocity=4e-7, spring_constant=0.26, resonance_frequency=2.3e4, resolution=1e-11,
                  force_gradient=0.16, jump_in_separation=6e-9, static_jump_in_separation=4e-9)
    air = diagnose_curve(**common, friction="not detected", quality_factor=139.0)
    assert not air.dynamic and "likely capillary" in air.verdict
    liquid = diagnose_curve(**common, friction="not assessed", quality_factor=3.0)
    # inertia excluded (eq 3: 0.27 < 1) leaves friction, which coincident lines cannot exclude (Figs 5-6)
    assert liquid.dynamic and "friction (inertia excluded" in liquid.verdict


def test_implausible_spring_constant_and_sensitivity_are_flagged():
    _, ws = _run("afm-workshop_single.csv")  # k inferred from the slope of a soft contact: 5.1e-5 N/m
    assert math.isnan(ws.spring_constant)  # no lever's: flagged, and not reported (issue 32, item 6)
    assert any(w.startswith("spring constant 5.13e-05 N/m") and "outside" in w for w in ws.warnings)
    assert "spring constant undetermined" in ws.verdict and "spring_constant" in ws.verdict
    _, cal = _run("jpk_calibration-curve_raw-volts.jpk-force")  # 6 samples in contact at 205 Hz
    n = cal.details["compliance"].approach.n_points
    assert n < 20
    assert any(f"fitted on only {n} contact samples" in w for w in cal.warnings)
    assert any("runs backwards" in w for w in cal.warnings)  # the retract line with the approach's InvOLS


def test_map_image_axes_in_um_and_title_inside_the_figure():
    import pandas as pd

    from afmforce.analysis.maps import map_images
    from afmforce.plotting.maps import plot_map

    name = "a_rather_long_force_map_file_name_from_the_instrument_2026.jpk-force-map"
    rows = pd.DataFrame({"file": [name] * 2, "map_x": [0, 9], "map_y": [0, 9], "map_nx": [10, 10], "map_ny": [10, 10],
                         "map_width": [6e-4, 6e-4], "map_height": [3e-4, 3e-4], "adhesion_force": [-1e-10, -2e-10]})
    (image,) = map_images(rows, "adhesion")
    ax = plot_map(image)
    assert ax.get_xlabel() == "x [µm]" and ax.get_xlim() == pytest.approx((0.0, 600.0))
    assert ax.get_ylim() == pytest.approx((0.0, 300.0))
    fig = ax.figure
    fig.draw_without_rendering()
    box, title = fig.bbox, ax.title.get_window_extent()
    assert box.x0 <= title.x0 and title.x1 <= box.x1  # not clipped
    (plain,) = map_images(rows.drop(columns=["map_width", "map_height"]), "adhesion")
    assert "index" in plot_map(plain).get_xlabel()


def test_hard_pull_off_is_no_unbinding_step_cell_curves_keep_theirs():
    """Asylum SiN in air: the pull-off jump and the lever's settling after it were counted (and marked) as one
    unbinding step; the dip ends in that one jump (deepest point to last rupture within 3 nm), so 0 steps.
    The JPK cell curves keep theirs (the counts before and after the change: spot3 1 at 57 nm, the 2016
    CellHesion curve 2, the first map curve 1)."""
    from afmforce.plotting import plot_summary

    curve, hard = _run("asylum-mfp3d_SiN-tip_air.ibw")
    ad = hard.details["adhesion"]
    assert hard.contact_kind == "hard" and ad.found and hard.details["jumps"].pull_off.found
    # the whole recovery is the one jump: the last rupture is the pull-off (on a hard contact given as the
    # separation there, analysis.tethers; this retract's contact line lies 15.6 nm off the approach's)
    assert abs(ad.rupture_distance - hard.separation[ad.index]) < 3e-9 and ad.tethers == ()
    assert hard.unbinding_steps == 0 and ad.steps == ()
    fig = plot_summary(hard, curve)
    labels = [t.get_text() for ax in fig.axes if ax.get_legend() for t in ax.get_legend().get_texts()]
    assert not any("unbinding step" in t for t in labels)
    expected = {"jpk_cellhesion_spot3.jpk-force": 1, "jpkfile_force-save-2016.06.15-13.17.08.jpk-force": 2,
                "afmformats_jpk-fd_map2x2_extracted.jpk-force-map": 1}
    for name, n in expected.items():
        _, soft = _run(name)
        assert soft.contact_kind == "soft" and soft.unbinding_steps == n, name
        assert all(0 < s.distance <= soft.rupture_distance + 5e-9 for s in soft.details["adhesion"].steps)
    _, spot3 = _run("jpk_cellhesion_spot3.jpk-force")
    # 57 nm from the approach's contact point; the distances count from where the retract leaves its contact
    # (detach_position inside the contact point on this relaxing cell: tests/analysis/test_unreached_surface.py)
    ad3 = spot3.details["adhesion"]
    assert ad3.steps[0].distance - ad3.detach_position == pytest.approx(57e-9, abs=5e-9)
