"""The compiled batch core agrees with the pipeline and with the generator's truth."""

from __future__ import annotations

import numpy as np
import pytest

from afmforce.analysis.batch import analyze_batch
from afmforce.analysis.synthetic import static_curve
from afmforce.errors import ParameterError
from afmforce.analysis.options import SmoothOptions
from afmforce.analysis.pipeline import analyze


@pytest.fixture(scope="module")
def stack():
    curves = [static_curve(noise=0.05e-9, drift=d, offset=o, seed=s)
              for s, d, o in [(1, 0.0, 0.3), (2, 0.01, 0.1), (3, -0.02, 0.5), (4, 0.005, -0.2)]]
    n_app = int(np.sum(curves[0].segment == 0))
    z = np.stack([c.piezo_measured for c in curves])
    s = np.stack([c.deflection_signal for c in curves])
    return curves, curves[0].time, z, s, n_app


@pytest.mark.parametrize("parallel", [False, True])
def test_batch_matches_truth_and_pipeline(stack, parallel):
    curves, t, z, s, n_app = stack
    res = analyze_batch(t, z, s, n_app, parallel=parallel)
    assert res.ok.all()
    for i, c in enumerate(curves):
        truth = c.truth
        assert res.sensitivity[i] == pytest.approx(truth["sensitivity"], rel=0.01)  # beta
        assert abs(res.jump_in_index[i] - truth["jump_in_index"]) <= 1
        assert abs(res.pull_off_index[i] - truth["pull_off_index"]) <= 1
        assert res.jump_in_separation[i] == pytest.approx(truth["separation"][truth["jump_in_index"]], abs=0.3e-9)
        pipe = analyze(c, steps=["shift", "jumps"], options=[SmoothOptions(window=1)])
        assert res.sensitivity[i] == pytest.approx(pipe.sensitivity_fit, rel=2e-3)
        assert res.shift[i] == pytest.approx(pipe.shift, abs=0.2e-9)
        assert res.jump_in_index[i] == pipe.details["jumps"].jump_in.index
        assert res.pull_off_deflection[i] == pytest.approx(pipe.details["jumps"].pull_off.deflection, rel=0.01)


def test_batch_flags_a_curve_without_contact(stack):
    curves, t, z, s, n_app = stack
    flat = np.full_like(s[:1], 0.3) + 1e-3 * np.random.default_rng(0).standard_normal(s[:1].shape)
    res = analyze_batch(t, z[:1], flat, n_app)
    assert res.jump_in_index[0] == -1 and res.pull_off_index[0] == -1


def test_batch_checks_shapes(stack):
    curves, t, z, s, n_app = stack
    with pytest.raises(ParameterError):
        analyze_batch(t, z, s[:, :-1], n_app)
    with pytest.raises(ParameterError):
        analyze_batch(t, z, s, 3)
