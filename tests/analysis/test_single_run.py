"""A curve of one run (an export of the retract or of the approach alone) is analysed: the quantities of
the run it holds, each step that needs the missing run reported "not available: no <run> run"
(docs/analysis.md, "Curves of one run"), never an error for the whole curve nor a made-up number.

Checked independently: the adhesion (the deepest retract force below the retract's own free
baseline) against numpy on the file's columns read as plain text; the unbinding steps and the last
rupture against a synthetic retract whose ruptures are placed by hand.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from afmforce.analysis.pipeline import analyze
from afmforce.io import load
from afmforce.io.curve import RawCurve

CORPUS = Path(__file__).resolve().parents[1] / "data" / "corpus"
NO_APPROACH, NO_RETRACT = "not available: no approach run", "not available: no retract run"


def _columns(name: str) -> tuple[np.ndarray, np.ndarray]:
    """Position and force columns as the text holds them (the export's units: a unit row first)."""
    table = np.loadtxt(CORPUS / name, skiprows=1, encoding="latin-1")
    return table[:, 0], table[:, 1]


def test_retract_only_export_gives_the_adhesion_numpy_finds():
    """NanoScope's baseline-corrected retract (pN, nm): the deepest force below a straight baseline fitted
    (np.polyfit) through the far 40 % of the run equals the analysis's adhesion within the baseline's noise."""
    name = "bruker-ascii_fodis_mica-GA6_baseline-corrected.txt"
    z, f = _columns(name)
    far = slice(int(0.6 * z.size), z.size)  # the far end of the retract (contact at the start)
    residual = f - np.polyval(np.polyfit(z[far], f[far], 1), z)
    noise = 1.4826 * np.median(np.abs(residual[far] - np.median(residual[far])))
    expected = residual.min() * 1e-12                                       # pN -> N
    (curve,) = load(CORPUS / name)
    res = analyze(curve)
    assert res.adhesion_force == pytest.approx(expected, abs=2 * noise * 1e-12)
    assert res.adhesion_force < -10 * noise * 1e-12                        # a real dip, far above the noise
    # the deepest point is the one numpy finds (within the analysis's running window of a few samples)
    assert abs(res.details["adhesion"].index - int(np.argmin(residual))) <= 3   # one run: sample = row
    assert res.rupture_distance >= res.adhesion_distance > 0
    for step in ("kind", "shift", "vdw", "friction", "indentation", "jumps"):
        assert res.not_applicable[step] == NO_APPROACH
    # no contact kind without the approach: no hard contact's pull-off jump told from an unbinding step
    assert np.isnan(res.jump_in_force) and np.isnan(res.pull_off_force) and res.contact_kind == ""
    assert np.isnan(res.shift)
    said = [w for w in res.warnings if w.startswith("the curve holds the retract run only: " + NO_APPROACH)]
    assert len(said) == 1 and "kind" in said[0] and "jumps" in said[0]    # once, in every output


def test_the_retract_export_gives_the_whole_curves_retract_quantities():
    """The same ScanAsyst glass curve exported whole (both runs) and as its retract alone: the adhesion is
    measured from the retract's own baseline either way, so its noise, depth and verdict agree (the
    one-run export is the whole export's retract columns, to its 7 printed digits)."""
    (whole,) = load(CORPUS / "bruker-ascii_fodis_ScanAsyst-glass.txt")
    (alone,) = load(CORPUS / "bruker-ascii_fodis_ScanAsyst-glass_retract.txt")
    a, b = analyze(whole), analyze(alone)
    assert b.adhesion_noise == pytest.approx(a.adhesion_noise, rel=1e-3)
    assert b.adhesion_verdict == a.adhesion_verdict            # here: a dip of 3.9 noise sigmas, below 5
    assert np.isnan(b.adhesion_force) == np.isnan(a.adhesion_force)


def _synthetic_retract(k: float = 0.05, noise: float = 0.02e-9, seed: int = 3) -> tuple[RawCurve, list[float]]:
    """A retract of one run (deflection in m): the compliance line d = z in contact (z > 0), then a tether
    plateau at -3 nm that lets go in two steps (to -1.5 nm at 100 nm from contact, to 0 at 200 nm)."""
    n = 3000
    z = np.linspace(60e-9, -500e-9, n)            # grows towards the sample; the retract moves away
    d = np.where(z > -3e-9, np.maximum(z, -3e-9), np.where(z > -100e-9, -3e-9, np.where(z > -200e-9, -1.5e-9, 0.0)))
    d = d + np.random.default_rng(seed).normal(0.0, noise, n)
    curve = RawCurve(time=np.arange(n) * 1e-4, piezo_nominal=z, deflection_signal=d,
                     segment=np.ones(n, np.int8), deflection_unit="m",
                     metadata={"spring_constant": k, "single_run": "retract", "source_file": "synthetic"})
    return curve, [100e-9, 200e-9]


def test_synthetic_retract_counts_the_ruptures_placed_by_hand():
    curve, ruptures = _synthetic_retract()
    res = analyze(curve)
    assert res.adhesion_force == pytest.approx(-3e-9 * 0.05, rel=0.05)      # the plateau: -0.15 nN
    steps = res.details["adhesion"].steps
    assert res.unbinding_steps == len(steps) == 2
    for step, at in zip(steps, ruptures):                 # each step 1.5 nm x k, where it was placed
        assert step.distance == pytest.approx(at, abs=5e-9)
        assert step.force == pytest.approx(1.5e-9 * 0.05, rel=0.1)
    assert res.rupture_distance == pytest.approx(ruptures[-1], abs=5e-9)
    assert res.not_applicable["kind"] == NO_APPROACH


def test_approach_only_export_gives_the_approach_and_no_pull_off():
    """NanoScope's extend export: the contact kind and the contact point come from the approach; the
    retract's quantities are not available, with the reason, and NaN."""
    (curve,) = load(CORPUS / "bruker-ascii_fodis_extracted.txt")
    res = analyze(curve)
    assert res.contact_kind in ("hard", "soft") and "kind" not in res.not_applicable
    for step in ("adhesion", "shift", "friction", "surface_energy"):
        assert res.not_applicable[step] == NO_RETRACT
    assert np.isnan(res.pull_off_force) and np.isnan(res.adhesion_force) and res.unbinding_steps == 0
    assert not any("no pull-off found" in w for w in res.warnings)   # none looked for: no retract run
    z = np.asarray(curve.piezo_nominal)
    cp = res.details["contact_point"].position       # the soft contact point, on the recorded approach
    assert z.min() < cp < z.max()
    # the modulus from the approach, as nanite fits it, once the lever's k and the tip's radius are given
    from afmforce.analysis.options import ProbeCalibration
    given = analyze(curve, probe=ProbeCalibration(spring_constant=0.1, radius=20e-9))
    assert "indentation" not in given.not_applicable and given.youngs_modulus > 0


def test_a_two_segment_less_curve_that_is_no_export_of_one_run_is_still_refused():
    """One segment without the reader's word that the file holds one run: an unsplit whole curve, refused."""
    curve, _ = _synthetic_retract()
    bare = RawCurve(time=curve.time, piezo_nominal=curve.piezo_nominal, deflection_signal=curve.deflection_signal,
                    segment=curve.segment, deflection_unit="m", metadata={"spring_constant": 0.05})
    from afmforce.errors import AnalysisError
    with pytest.raises(AnalysisError, match="split the curve at its turning point"):
        analyze(bare)


def test_batch_summary_and_figures_of_one_run_curves(tmp_path):
    """`afmforce analyze FOLDER` over the three one-run exports: no failure, one summary row each, the
    retract's adhesion in its column, the approach export's NaN there."""
    import pandas as pd

    from afmforce.cli.main import main

    folder = tmp_path / "in"
    folder.mkdir()
    names = ["bruker-ascii_fodis_mica-GA6_baseline-corrected.txt", "bruker-ascii_fodis_extracted.txt",
             "bruker-ascii_fodis_ScanAsyst-glass_retract.txt"]
    for n in names:
        (folder / n).write_bytes((CORPUS / n).read_bytes())
    assert main(["analyze", str(folder), "--out", str(tmp_path / "out")]) == 0
    (summary,) = (tmp_path / "out").glob("batch-*/summary.csv")
    table = pd.read_csv(summary)
    assert len(table) == 3
    row = {Path(str(f)).name: r for f, r in zip(table[[c for c in table.columns if "file" in c][0]], table.to_dict("records"))}
    adhesion = [c for c in table.columns if c.startswith("adhesion_force")][0]
    assert row[names[0]][adhesion] < 0 and np.isnan(row[names[1]][adhesion])
    assert len(list((tmp_path / "out").glob("*.afmforce.png"))) == 3


def test_the_web_analyses_a_retract_export(tmp_path):
    """The web's /api/analyze on the retract export: the CLI's numbers, the missing run's steps with the reason."""
    pytest.importorskip("fastapi")
    from fastapi.testclient import TestClient

    from afmforce.web import Settings, create_app

    name = "bruker-ascii_fodis_mica-GA6_baseline-corrected.txt"
    with TestClient(create_app(Settings(data=tmp_path / "data", spare_job=False)), base_url="http://127.0.0.1") as c:
        r = c.post("/api/analyze", files={"file": (name, (CORPUS / name).read_bytes())})
    assert r.status_code == 200, r.text
    api = r.json()["results"][name]
    assert api["adhesion_force"] == pytest.approx(analyze(load(CORPUS / name)[0]).adhesion_force, rel=1e-9)
    assert api["not_applicable"]["kind"] == NO_APPROACH
