"""The fit's ``soft="warn"`` path (a liquid fit: a curve the analysis calls a soft contact is
prepared with a note, not refused) on a curve that takes it: a Hertz contact on a soft sample
recorded by the virtual AFM. The demo's colloid curve in water that took this path before is hard
now (test_fit_real_files), which left the note untested.

The sample: E = 100 kPa (Poisson 0.5), tip radius 5 um, lever 0.1 N/m, turning at 20 nN; no
adhesion. Its contact's deflection per position, from Hertz's closed form F = 4/3 E* sqrt(R)
delta^1.5 (the sample's stiffness k_s = dF/d delta): between the chord over the whole contact,
F/k / (delta + F/k) = 0.595, and the tangent at the turn, k_s / (k + k_s) = 0.688. Below 0.7 the
analysis calls it soft (the tip indents); above 0.5 the fit's rigid-contact slope check lets it through.
"""

from __future__ import annotations

import math
import re
import warnings

import pytest

pytest.importorskip("afmforce.dynamics")

from afmforce.analysis.pipeline import analyze  # noqa: E402
from afmforce.errors import AnalysisError  # noqa: E402
from afmforce.fit.data import prepare_curves  # noqa: E402
from afmforce.instrument.soft_map import SoftMapConfig, soft_curve  # noqa: E402

E, NU, R, K, F = 1e5, 0.5, 5e-6, 0.1, 20e-9


def _curve():
    cfg = SoftMapConfig(nx=1, ny=1, radius=R, poisson=NU, spring_constant=K, setpoint=F, points=1000,
                        ramp=3e-6, velocity=10e-6, noise=0.02e-9)
    return soft_curve(cfg, E, 0.0, 0.0, seed=1)


def test_a_soft_contact_is_prepared_with_the_note_in_warn_and_refused_otherwise():
    hertz = 4.0 / 3.0 * E / (1 - NU ** 2) * math.sqrt(R)
    delta = (F / hertz) ** (2.0 / 3.0)
    k_s = 1.5 * hertz * math.sqrt(delta)
    chord, tangent = (F / K) / (delta + F / K), k_s / (K + k_s)
    assert chord == pytest.approx(0.595, abs=1e-3) and tangent == pytest.approx(0.688, abs=1e-3)
    curve = _curve()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ana = analyze(curve, steps=["kind"])
        assert ana.contact_kind == "soft"
        ratio = float(re.search(r"follows only ([0-9.]+) of the position", ana.contact_kind_reason).group(1))
        assert chord <= ratio <= tangent                         # the analysis reads Hertz's contact
        with pytest.raises(AnalysisError, match=r"^virtual-soft: soft contact \("):
            prepare_curves([curve], ["virtual-soft"])            # default: refuse (in air)
        fc = prepare_curves([curve], ["virtual-soft"], soft="warn")[0]
    notes = fc.metadata["preparation_notes"]
    soft = [n for n in notes if "soft contact" in n]
    assert soft == [f"virtual-soft: the analysis sees a soft contact ({ana.contact_kind_reason}); in a liquid "
                    "the drainage and double-layer forces the model has bend the approach like that, so the "
                    "curve is fitted and the fit's adequacy test judges it"]
    assert fc.mask.sum() > 100
