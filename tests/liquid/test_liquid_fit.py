"""The dynamic fit in a liquid (issue 25): slip length and spring constant in situ, slip verdict.

Curves from the virtual AFM (fit/virtual.py); the recovery over 20 experiments made by the
independent scipy reference solver is benchmarks/bench_liquid.py."""

import warnings

import pytest

from afmforce.errors import ParameterError
from afmforce.fit import PARAMETERS, fit_dynamic, virtual_curves

SPEEDS = [10e-6, 40e-6]
LIQ = dict(model="spring", spring_constant=0.1, mass=1e-11, radius=5e-6, geometry="sphere-flat",
           hamaker=5e-21, viscosity=0.89e-3, lever_drag=1e-5, start=-100e-9, turn=40e-9, end=-100e-9)


def _fit(slip):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        cur = virtual_curves(SPEEDS, seed=4, noise=0.05e-9, drift_rms=0.5e-9,
                             sample_rates=[v / 2e-9 for v in SPEEDS], slip_length=slip, **LIQ)
    import dataclasses
    cur = [dataclasses.replace(c, metadata={**c.metadata, "spring_constant": 0.108}) for c in cur]
    # the file's k is 8 % off; the free spring constant starts from it
    fixed = {k: v for k, v in LIQ.items() if k not in ("start", "turn", "end", "model", "spring_constant")}
    return fit_dynamic(cur, model="spring", free=("slip_length", "spring_constant"), fixed=fixed,
                       profile=("slip_length",), jump_window=0.3e-3)


def test_slip_length_and_spring_constant_in_situ():
    res = _fit(4e-9)
    b = res.parameters["slip_length"]
    assert b.value == pytest.approx(4e-9, abs=0.5e-9)
    assert b.interval[0] <= 4e-9 <= b.interval[1] and b.interval_method == "profile"
    assert res.parameters["spring_constant"].value == pytest.approx(0.1, rel=0.02)
    assert res.slip_detected is True and res.slip_p_value < 0.01
    d = res.to_dict()
    assert d["slip_detected"] is True and "dynamic, no slip" in d["comparison"]["chi2"]
    assert res.friction_detected is False      # the spring has no friction: not tested


def test_registry_and_speed_dependence():
    assert {"slip_length", "spring_constant", "lever_drag", "surface_potential", "debye_length",
            "hamaker"} <= set(PARAMETERS)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        cur = virtual_curves([10e-6, 10e-6], seed=1, sample_rates=[1e4, 1e4], slip_length=2e-9, **LIQ)
    with pytest.raises(ParameterError, match="slip_length"):
        fit_dynamic(cur, model="spring", free=("slip_length",), jump_window=0.3e-3)


def test_plan_slip_scales_with_the_target():
    from afmforce.fit.plan_slip import plan_slip
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        p = plan_slip(target=0.05e-9, speeds=(10e-6, 40e-6), n_curves=2, slip_length=4e-9,
                      **{k: v for k, v in LIQ.items()})
    assert set(p.best_speeds) <= {10e-6, 40e-6} and p.half_width > 0
    # information grows with the samples per nm: the half-width scales as 1/sqrt(points)
    assert p.points_per_nm_needed == pytest.approx(max(p.points_per_nm * (p.half_width / 0.05e-9) ** 2,
                                                       100 / 140), rel=1e-12)
    with pytest.raises(ParameterError, match="slip length"):
        plan_slip(target=0.5e-9, **{**LIQ, "slip_length": 0.0})


def test_the_model_lever_is_the_files_unless_given():
    # issue 34: the spring constant comes from the files (a free one starts there too)
    from afmforce.dynamics import SimulationConfig
    from afmforce.fit.core import lever_from_files

    class C:      # only the metadata matters here
        def __init__(self, k):
            self.metadata = {"spring_constant": k}
    curves = [C(0.108), C(0.108)]
    base = SimulationConfig(model="spring", spring_constant=0.2)
    assert lever_from_files(base, curves).spring_constant == 0.108
    assert lever_from_files(base, curves, "model") is base
    assert lever_from_files(base, [C(None)]) is base
    beam = SimulationConfig(model="beam", k0=0.1)
    got = lever_from_files(beam, curves)
    assert got.force_constant == pytest.approx(0.108, rel=1e-12)     # eq 13 scales with k0
