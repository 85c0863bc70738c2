"""InvOLS from the compliance line (issue 34): the real JPK calibration curve in raw volts, and
a virtual curve whose InvOLS is known."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from afmforce.analysis.invols import measure_invols
from afmforce.io import load

DATA = Path(__file__).resolve().parents[1] / "data"


def test_jpk_calibration_curve_matches_a_numpy_line_and_is_flagged():
    """numpy.polyfit of the 6 deepest approach samples (the pipeline's compliance region): the
    same slope within its standard error; the retract line is twice as steep and the region
    holds 6 samples, so the InvOLS is reported undetermined rather than as 934 +- 79 nm/V."""
    c = load(DATA / "jpk_calibration-curve_raw-volts.jpk-force")[0]
    r = measure_invols(c)
    app = c.segment == 0
    z, s = c.piezo_measured[app], c.deflection_signal[app]
    order = np.argsort(z)
    slope = np.polyfit(z[order][-6:], s[order][-6:], 1)[0]
    assert r.n_points == 6
    assert r.sensitivity == pytest.approx(1 / slope, rel=0.02)
    assert abs(r.sensitivity - 1 / slope) < r.sensitivity_se
    assert r.sensitivity_retract < 0.6 * r.sensitivity_approach
    assert not r.determined and "not determined" in r.verdict


def test_virtual_curve_gives_its_invols():
    """The virtual AFM file stores 50 nm/V; its compliance line gives it back within 2 %."""
    c = load(DATA / "afmforce-hdf5_virtual-afm.h5")[0]
    r = measure_invols(c)
    assert r.determined and r.file_sensitivity == pytest.approx(50e-9)
    assert r.sensitivity == pytest.approx(50e-9, rel=0.02)


def test_soft_contact_is_no_calibration():
    """A cell (JPK CellHesion, soft; the file's 70 nm/V): the slope is the sample's, the runs
    disagree, and the verdict says it is twice the file's InvOLS and why that may be."""
    c = load(DATA / "jpk_cellhesion_spot3.jpk-force")[0]
    r = measure_invols(c)
    assert not r.determined and r.file_sensitivity == pytest.approx(70e-9, rel=1e-4)
    assert "x the file's 70 nm/V" in r.verdict and "soft sample" in r.verdict


def test_no_contact_is_an_analysis_error():
    """The approach never reaches the surface: no line, a clear error (not a KeyError)."""
    from afmforce.errors import AnalysisError

    c = load(DATA / "jpk_calibration-curve_raw-volts.jpk-force")[0]
    away = c.segment == 0
    far = type(c)(**{**c.__dict__, "deflection_signal": np.where(away, c.deflection_signal[0], c.deflection_signal[0])})
    with pytest.raises(AnalysisError):
        measure_invols(far)


def test_soft_contact_whose_runs_agree_is_still_no_calibration():
    """An Asylum curve on a soft sample (the deflection follows 0.435 of the position in contact) whose
    approach and retract lines agree: before, a "determined" InvOLS of 468 nm/V, 2.3 x the file's 203.6."""
    c = load(DATA / "corpus" / "asylum-ibw_U3_3_p10004.ibw")[0]
    r = measure_invols(c)
    assert r.file_sensitivity == pytest.approx(203.64e-9, rel=1e-4)  # the wave note's InvOLS
    assert abs(r.sensitivity_approach / r.sensitivity_retract - 1) < 0.10  # the runs agree ...
    assert not r.determined and "the contact is soft" in r.verdict  # ... but the slope is not the lever's


def test_cli_prints_no_interval_for_an_undetermined_invols(capsys):
    from afmforce.cli.main import main

    assert main(["calibrate", "invols", "--example"]) == 0
    out = capsys.readouterr().out
    row = next(ln for ln in out.splitlines() if ln.strip().startswith("InvOLS"))
    assert "undetermined" in row and "+-" not in row and "934.45 nm/V" in row  # the 6-sample line, no interval
    assert main(["calibrate", "invols", "--example", "--json"]) == 0
    import json

    d = json.loads(capsys.readouterr().out)
    assert d["determined"] is False and d["sensitivity_se"] is None
