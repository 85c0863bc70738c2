"""An approach whose far part climbs more steeply than its contact (the lever settling after the ramp's
start) is refused as a transient, not as "the curve starts in contact".

Found on a real JPK 2013 creep curve (matfiz/afm-curve-procesing ``dane_JPK/creep/force-save-2013.05.10-
14.38.05``, no licence stated): afmformats reads its approach rising from -2.48 nN to a flat -1.20 nN over
its first half (the lever settling), its contact a 0.2 nN rise at the end; the refusal said the curve
started in contact.
"""

from __future__ import annotations

import numpy as np
import pytest

from afmforce.analysis.pipeline import analyze
from afmforce.errors import AnalysisError
from afmforce.io.curve import RawCurve


def _settling_curve() -> RawCurve:
    n = 800
    z_app = np.linspace(0.0, 8e-6, n)                  # [m], towards the sample
    rng = np.random.default_rng(5)
    f_app = -1.3e-9 * np.exp(-z_app / 1.5e-6) + 2e-3 * np.clip(z_app - 7.9e-6, 0, None)  # settling, 0.2 nN contact
    z = np.r_[z_app, z_app[::-1]]
    f = np.r_[f_app, f_app[::-1]] + 3e-12 * rng.standard_normal(2 * n)
    seg = np.r_[np.zeros(n, np.int8), np.ones(n, np.int8)]
    meta = dict(spring_constant=0.06, sensitivity=60e-9, sample_rate=2000.0, velocity=2e-6,
                source_file="settling approach (test)")
    return RawCurve(time=np.arange(2 * n) / 2000.0, piezo_nominal=z.copy(), piezo_measured=z.copy(),
                    deflection_signal=f, segment=seg, metadata=meta, truth=None, deflection_unit="N")


def test_a_settling_transient_is_named_not_taken_for_a_contact():
    with pytest.raises(AnalysisError) as err:
        analyze(_settling_curve())
    msg = str(err.value)
    assert "transient or a drift rather than a contact" in msg and "starts in contact" not in msg


def test_real_jpk_2013_creep_curve_is_refused_as_a_transient():
    from afmforce.io import load
    from realdata import real_file

    c = load(real_file("jpk-force_matfiz_2013.05.10-14.38.05_creep-settling.jpk-force"))[0]
    with pytest.raises(AnalysisError, match="transient or a drift rather than a contact"):
        analyze(c)
