"""The page's analysis orients a curve stored with the inverted deflection sign as the library and the
command line do (tests/analysis/test_inverted_sign.py): calibration.source=fit gives the positive
sensitivity the virtual curve was made with, and the note says the signal was negated."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

fastapi = pytest.importorskip("fastapi")


def test_web_calibration_fit_orients_an_inverted_curve(client, tmp_path):
    from afmforce.analysis.synthetic import static_curve
    from afmforce.io.native.rawfile import write_raw

    plain = static_curve(sensitivity=50e-9, noise=0.05e-9, seed=1)
    inverted = dataclasses.replace(plain, deflection_signal=-np.asarray(plain.deflection_signal))
    path = write_raw(inverted, tmp_path / "inverted.txt")
    r = client.post("/api/analyze", files={"file": (path.name, path.read_bytes())},
                    data={"option": ["calibration.source=fit"]})
    assert r.status_code == 200, r.text
    row = r.json()["results"][path.name]
    assert row["calibration_source"] == "fit"
    assert row["sensitivity_fit"] == row["sensitivity_used"] == pytest.approx(50e-9, rel=0.01)
    assert any("sign is inverted" in w and "negated" in w for w in row["warnings"])
