"""Issue 23, fast variant: the fit on the ``typical`` virtual AFM (two speeds, one seed).

The full study (four speeds, 20 seeds, profile intervals) is
``benchmarks/bench_fit_typical.py``. Here: two short curves (0.5 um/s at 5 kHz and
5 um/s at 10 kHz, -30 -> +10 nm) recorded with every artefact of the preset (piezo
hysteresis and creep, sensor steps and noise, fringes, white and 1/f noise, drift,
ADC). Before issue 23 such curves put A and xi several standard errors off (the
nominal channel, the A*R-xi valley, the 1/f noise); now the model describes them
(reduced chi-square below its threshold), the 1/f noise is measured, and A and xi lie
within three of their standard errors of the truth.
"""

from __future__ import annotations

import warnings

import pytest

from afmforce.dynamics import simulate
from afmforce.fit import fit_dynamic
from afmforce.instrument import build_instrument

A, XI = 5e-19, 0.005


@pytest.fixture(scope="module")
def typical_fit():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        trs = [simulate(velocity=v, xi=XI, sampling="average", start=-30e-9, turn=10e-9,
                        end=-60e-9, sample_rate=f) for v, f in ((0.5e-6, 5e3), (5e-6, 10e3))]
        curves = [build_instrument("typical").record(tr, seed=1) for tr in trs]
        return fit_dynamic(curves, "beam", free=("hamaker", "xi"), compare=False, profile=())


def test_typical_preset_is_described_and_recovered(typical_fit):
    r = typical_fit
    assert r.adequacy["adequate"] and 0.8 < r.redchi < r.adequacy["threshold"]
    a, x = r.parameters["hamaker"], r.parameters["xi"]
    assert abs(a.value - A) < 3 * a.stderr and a.stderr < 0.3 * A       # measured 1.27 +- 0.16
    assert abs(x.value - XI) < 3 * x.stderr and x.stderr < 0.5 * XI     # measured 1.48 +- 0.28
    # the 1/f noise of the preset (0.05 nm) is found and modelled
    assert all(0.025e-9 < c.pink < 0.1e-9 for c in r.curves)
    assert all(c.metadata["position_channel"] == "measured" for c in r._problem.ev.curves)
