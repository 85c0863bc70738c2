"""When the data cannot determine the slip length, the fit says so (no tight interval).

Virtual-AFM curves of a 5 um colloid probe in water (the set of ``test_liquid_fit.py``: 10 and
40 um/s, approach from 100 nm, 0.05 nm noise), the truth known. Vinogradova's factor is
``f* ~ 1 - 2b/h`` far out (b acts like a shift of separation: determined) and
``f* ~ (h/3b) ln(6b/h)`` for h << b (a slow logarithm traded against the spring constant: barely).

* b = 1 um, far beyond the 100 nm fitted, k free: before, the Wald interval (``profile=()``) was
  [0, 0.90 um] -- an upper bound that excluded the truth; now it is reported undetermined, and the
  profile interval (the default) is open above: [0.20 um, no upper end].
* b = 0.02 nm, much smaller than every separation: an upper bound, no lower end, containing it.
* b = 4 nm (control): two-sided and covering the truth.
"""

import math
import sys
import warnings
from pathlib import Path


from afmforce.fit import fit_dynamic, virtual_curves

sys.path.insert(0, str(Path(__file__).parent))
from test_liquid_fit import LIQ, SPEEDS  # noqa: E402

FIXED = {k: v for k, v in LIQ.items() if k not in ("start", "turn", "end", "model", "spring_constant")}


def _fit(slip, free=("slip_length", "spring_constant"), profile=None):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        curves = virtual_curves(SPEEDS, seed=4, noise=0.05e-9, drift_rms=0.5e-9,
                                sample_rates=[v / 2e-9 for v in SPEEDS], slip_length=slip, **LIQ)
        return fit_dynamic(curves, model="spring", free=free, fixed=FIXED, jump_window=0.3e-3, compare=False,
                           profile=profile if profile is not None else ("slip_length",))


def test_slip_far_beyond_the_separations_is_not_bounded_above():
    b = _fit(1e-6).parameters["slip_length"]
    assert b.interval_method == "profile" and b.interval[1] is None and "no upper end" in b.note
    assert b.interval[0] is not None and b.interval[0] <= 1e-6 and b.interval[0] < 0.5e-6


def test_slip_far_beyond_the_separations_is_undetermined_without_a_profile():
    b = _fit(1e-6, profile=()).parameters["slip_length"]
    assert b.interval == (None, None) and b.interval_method == "undetermined"
    assert "slip_length: undetermined" in b.note and "not small against the separations" in b.note


def test_slip_much_smaller_than_the_separations_is_an_upper_bound():
    b = _fit(0.02e-9, free=("slip_length",)).parameters["slip_length"]
    assert b.interval[0] is None and "no lower end" in b.note
    assert 0.02e-9 <= b.interval[1] < 0.5e-9


def test_slip_within_the_range_is_determined_without_a_profile():
    b = _fit(4e-9, profile=()).parameters["slip_length"]
    assert b.interval_method == "wald" and b.note == ""
    lo, hi = b.interval
    assert lo < 4e-9 < hi and hi - lo < 3e-9 and math.isfinite(b.stderr)
