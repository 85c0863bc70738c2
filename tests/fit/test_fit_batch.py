"""The fit's batched forward model: predict_many / Problem.prefetch equal separate runs."""

import numpy as np

from afmforce.fit.core import base_config
from afmforce.fit.data import prepare_curves
from afmforce.fit.model import Evaluator
from afmforce.fit.problem import Problem
from fit_virtual import make_curves


def test_batched_predictions_and_jacobian_equal_separate_runs():
    curves = prepare_curves(make_curves(0.05, seed=4, speeds=(1e-6, 4e-6)))
    base = base_config("beam")
    ev = Evaluator(curves, base, "dynamic", True)
    values = {"xi": 0.05, "hamaker": base.hamaker}
    reqs = [(0, values, 0.0), (1, values, 0.1e-9), (0, {**values, "xi": 0.08}, 0.0),
            (1, values, -60e-9)]                 # the last starts in contact: None
    ev.threads = 2
    many = ev.predict_many(reqs)
    one = [ev.predict(*r) for r in reqs]
    assert many[3] is None and one[3] is None and ev.failures == 2
    for a, b in zip(many[:3], one[:3]):
        np.testing.assert_array_equal(a, b)
    assert not np.array_equal(many[0], many[2])   # xi changes the curve

    prob = Problem(ev, ("xi", "hamaker"))
    x = prob.pack(values, [0.0, 0.0])
    J_batched = prob.jacobian(x)
    n_batched = ev.simulations
    ev2 = Evaluator(curves, base, "dynamic", True)
    ev2.threads = 1
    prob2 = Problem(ev2, ("xi", "hamaker"))
    prob2.prefetch = lambda requests: None        # the unbatched path: one run per request
    np.testing.assert_array_equal(J_batched, prob2.jacobian(x))
    assert n_batched - 8 == 2 * (1 + 2 + 1)       # base, two parameters, shift: per curve
