"""Inertia diagnostics (paper section 2.1, eqs 3-4, Fig 1 parameters)."""

import math

import numpy as np
import pytest

from afmforce.diagnostics import diagnose, inertia_parameter, inertial_lag, resonance_frequency
from afmforce.errors import ParameterError

K, M, R = 0.21, 1e-8, 100e-9


def test_resonance_fig1():
    f = resonance_frequency(K, M)
    assert f == pytest.approx(math.sqrt(K / M) / (2 * math.pi))
    assert f == pytest.approx(730, rel=0.01)  # paper: 0.73 kHz


@pytest.mark.parametrize("v, paper_R, paper_lag, lag_tol", [(10e-6, 2.2, 3.4e-9, 0.02), (1e-6, 0.2, 0.3e-9, 0.17)])
def test_eq3_eq4_fig1(v, paper_R, paper_lag, lag_tol):
    d = diagnose(spring_constant=K, mass=M, radius=R, velocity=v, resolution=0.5e-9, separation=5e-9)
    f = math.sqrt(K / M) / (2 * math.pi)
    # closed forms
    assert d.inertia_parameter == pytest.approx(v * d.force_gradient / (4 * f * K * 0.5e-9), rel=1e-12)
    assert d.inertial_lag == pytest.approx(v / (4 * f), rel=1e-12)
    # the paper's rounded values (one or two digits)
    assert d.inertia_parameter == pytest.approx(paper_R, rel=0.1)
    assert d.inertial_lag == pytest.approx(paper_lag, rel=lag_tol)
    assert d.inertia_measurable == (paper_R > 1)


def test_vectorised():
    v = np.array([1e-6, 5e-6, 10e-6])
    lag = inertial_lag(v, 730.0)
    assert lag.shape == (3,)
    assert lag[2] == inertial_lag(10e-6, 730.0)
    assert inertia_parameter(v, 0.067, 730.0, K, 0.5e-9).shape == (3,)


def test_diagnose_bad_input():
    with pytest.raises(ParameterError):
        diagnose(spring_constant=0, mass=M, radius=R, velocity=1e-6)
    with pytest.raises(ParameterError):
        diagnose(spring_constant=K, mass=-1, radius=R, velocity=1e-6)
    with pytest.raises(ParameterError):
        diagnose(spring_constant=K, mass=M, radius=R, velocity=0)
