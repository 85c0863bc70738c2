"""The creep-compliance curves of the corpus (CellHesion 200, 30-35 um z range, 10 nN relative setpoint):
afmforce's indentation against nanite 4.2.3 on the same curve, read without afmforce.

The brain curve (``jpk-force_creep-compliance_brain.jpk-force``) is indented 13.5 um: possible, since its
approach travels 30.0 um (height measured 47.40 -> 17.41 um), the force starts to rise near the middle of
it (11.23 nN baseline at 32.4 um, 11.47 nN at 29.4 um) and the lever bends only 162 nm (9.87 nN over
k = 0.061 N/m) while the piezo moves another ~13.7 um: a very soft sample. nanite's contact point
(fit_line_polynomial) gives 13.33 um (deviation_from_baseline 13.90 um). The SPM 6.1 text export of the
same session (``jpk-txt_spm6.1_creep-compliance_JPK01466_index7.txt``) is another curve: 1.67 um
(nanite 1.71 um); it is a gel-like curve of 1.7 um, not the brain's 13.5 um.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from afmforce.analysis.pipeline import analyze
from afmforce.io import load

CORPUS = Path(__file__).resolve().parents[1] / "data" / "corpus"
BRAIN = CORPUS / "jpk-force_creep-compliance_brain.jpk-force"
TEXT = CORPUS / "jpk-txt_spm6.1_creep-compliance_JPK01466_index7.txt"

nanite = pytest.importorskip("nanite")


def _nanite_indentation(force, height, retract, time, k) -> float:
    """nanite's indentation at the end of the approach [m]: the tip position below its contact point."""
    md = {"spring constant": k, "sensitivity": 1.0, "path": "creep", "enum": 0, "imaging mode": "force-distance",
          "duration": float(time[-1]), "point count": int(force.size)}
    idnt = nanite.Indentation(data={"force": force, "height (measured)": height, "segment": retract, "time": time},
                              metadata=md)
    idnt.apply_preprocessing(["compute_tip_position", "correct_force_offset", "correct_tip_offset"],
                             options={"correct_tip_offset": {"method": "fit_line_polynomial"}})
    app = ~np.asarray(idnt["segment"], bool)
    return -float(np.min(idnt["tip position"][app]))


def _text_segments(path: Path) -> tuple[list[tuple[list[str], np.ndarray]], float]:
    """The JPK text export read by hand: (columns, rows) per segment, and the spring constant."""
    segs, rows, cols, k = [], [], None, None
    for line in path.read_text().splitlines():
        if line.startswith("#"):
            if rows:
                segs.append((cols, np.array(rows)))
                rows = []
            if line.startswith("# columns:"):
                cols = line.split(":", 1)[1].split()
            elif line.startswith("# springConstant:"):
                k = float(line.split(":", 1)[1])
            continue
        if line.strip():
            rows.append([float(x) for x in line.split()])
    if rows:
        segs.append((cols, np.array(rows)))
    return segs, k


def test_brain_creep_indentation_agrees_with_nanite_and_fits_the_z_range():
    afmformats = pytest.importorskip("afmformats")
    data = afmformats.load_data(BRAIN)[0]
    seg = np.asarray(data["segment"])
    keep = seg != 1                                   # extend and retract (the pause is the creep)
    force, height = np.asarray(data["force"])[keep], np.asarray(data["height (measured)"])[keep]
    k = float(data.metadata["spring constant"])
    assert k == pytest.approx(0.061)
    ref = _nanite_indentation(force, height, seg[keep] == 2, np.asarray(data["time"])[keep], k)
    assert ref == pytest.approx(13.33e-6, rel=0.02)
    app = seg == 0
    travel = float(np.ptp(np.asarray(data["height (measured)"])[app]))
    bend = (float(np.max(np.asarray(data["force"])[app])) - float(np.median(np.asarray(data["force"])[app][:300]))) / k
    assert travel == pytest.approx(30.0e-6, rel=0.01) and bend == pytest.approx(162e-9, rel=0.02)
    res = analyze(load(BRAIN)[0])
    assert res.contact_kind == "soft"
    assert res.indentation == pytest.approx(ref, rel=0.05)               # 13.55 um
    assert 0 < res.indentation < travel - bend                             # what the z range allows


def test_text_export_creep_indentation_agrees_with_nanite():
    segs, k = _text_segments(TEXT)
    (ca, a), _, (cr, r) = segs                         # extend, pause, retract
    col = lambda c, x, n: x[:, c.index(n)]  # noqa: E731
    force = np.r_[col(ca, a, "vDeflection"), col(cr, r, "vDeflection")]    # [N]: calibrationSlot force
    height = np.r_[col(ca, a, "measuredHeight"), col(cr, r, "measuredHeight")]
    retract = np.r_[np.zeros(len(a), bool), np.ones(len(r), bool)]
    time = np.r_[col(ca, a, "seriesTime"), col(cr, r, "seriesTime")]
    ref = _nanite_indentation(force, height, retract, time, k)
    assert ref == pytest.approx(1.708e-6, rel=0.02)
    res = analyze(load(TEXT)[0])
    assert res.indentation == pytest.approx(ref, rel=0.05)               # 1.67 um
