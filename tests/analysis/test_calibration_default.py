"""The calibration `afmforce analyze` uses by default: the file's stored InvOLS and k (docs/analysis.md,
"Which calibration"). The header values are read from the file's text here, not by afmforce; the
compliance slope's InvOLS is a reported diagnostic, and calibrates only without a stored one, when asked
(`calibration.source=fit`), or where the stored one is impossible (a hard, straight contact line on which
the deflection would outrun the position).

The file: a NanoScope ASCII export written by tests/data/make_bruker_example.py (hard contact, measured
Z sensor, DeflSens 45 nm/V, k 0.21 N/m); a placeholder or stale InvOLS is given with ``meta_override``.
"""

from __future__ import annotations

import warnings

import pytest

from afmforce.analysis.options import CalibrationOptions
from afmforce.analysis.pipeline import analyze
from afmforce.io import load
from realdata import DATA, bruker_synthetic_header

PATH = DATA / "bruker-nanoscope_synthetic.txt"


_header = bruker_synthetic_header   # (InvOLS [m/V], k [N/m]) from the header lines, by regular expression


def _analyse(factor: float | None = None, source: str = "auto"):
    sens, _ = _header()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        curve = load(PATH, meta_override=None if factor is None else {"sensitivity": sens * factor})[0]
        return analyze(curve, options=[CalibrationOptions(source=source)])


def test_stored_calibration_is_the_default():
    sens, k = _header()
    res = _analyse()
    assert res.calibration_source == "metadata"
    assert res.sensitivity_used == pytest.approx(sens, rel=1e-12) and res.spring_constant == pytest.approx(k)
    assert res.sensitivity_fit == pytest.approx(sens, rel=0.01)   # a hard contact: the slope agrees


def test_a_possible_mismatch_keeps_the_files_and_warns():
    """A stored InvOLS half the slope's (the deflection follows the position 0.5x: a soft sample, a changed
    alignment, a position that is not the tip-sample distance) is kept, with k, and said."""
    sens, k = _header()
    res = _analyse(0.5)
    assert res.calibration_source == "metadata"
    assert res.sensitivity_used == pytest.approx(sens * 0.5, rel=1e-12) and res.spring_constant == pytest.approx(k)
    assert res.sensitivity_fit == pytest.approx(sens, rel=0.01)
    w = [w for w in res.warnings if "compliance slope gives a calibration" in w]
    assert w and w[0].startswith("the compliance slope gives a calibration 2 x the file's")
    assert "the file's is used" in w[0] and not any("rescaled" in x for x in res.warnings)


def test_asking_for_the_refit_gives_the_refit_and_the_rescale():
    """`calibration.source=fit` on the same file: the slope's InvOLS, and the stored (thermal) k scaled by
    (stored / fitted)^2: (0.5)^2 here."""
    sens, k = _header()
    res = _analyse(0.5, source="fit")
    assert res.calibration_source == "fit" and res.sensitivity_used == res.sensitivity_fit
    assert res.sensitivity_used == pytest.approx(sens, rel=0.01)
    assert res.spring_constant == pytest.approx(k * (0.5 * sens / res.sensitivity_fit) ** 2, rel=1e-12)
    assert any("spring constant rescaled with the refitted sensitivity" in w for w in res.warnings)


def test_an_impossible_stored_sensitivity_is_refitted_with_a_warning():
    """A placeholder twice the true InvOLS: on the hard, straight contact the deflection would move 2x the
    position, which no contact allows; the slope is the only calibration the curve allows (the true 45 nm/V
    within 1 %), the file's k rescaled as a thermal one (x 4; force.thermal_k=false keeps it), and said. `metadata` keeps the placeholder, and the analysis
    then warns that the separation runs backwards in contact."""
    sens, k = _header()
    res = _analyse(2.0)
    assert res.calibration_source == "fit"
    assert res.sensitivity_used == pytest.approx(sens, rel=0.01)
    assert res.spring_constant == pytest.approx(k * (2 * sens / res.sensitivity_fit) ** 2, rel=1e-12)
    assert any("the file's sensitivity is impossible here" in w for w in res.warnings)
    # the deflections are the true ones; the k a thermal tune with the placeholder would have given is
    # rescaled, so the forces are k_rescaled / k times the true ones. This synthetic file's k is not a
    # thermal one: force.thermal_k=false keeps it and gives the true forces.
    true = _analyse()
    assert res.pull_off_force == pytest.approx(true.pull_off_force * res.spring_constant / k, rel=0.03)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        from afmforce.analysis.options import ForceOptions

        curve = load(PATH, meta_override={"sensitivity": sens * 2})[0]
        plain = analyze(curve, options=[ForceOptions(thermal_k=False)])
    assert plain.calibration_source == "fit" and plain.spring_constant == pytest.approx(k)
    assert plain.pull_off_force == pytest.approx(true.pull_off_force, rel=0.03)
    kept = _analyse(2.0, source="metadata")
    assert kept.calibration_source == "metadata" and kept.sensitivity_used == pytest.approx(2 * sens, rel=1e-12)
    assert any("runs backwards in contact" in w for w in kept.warnings)
