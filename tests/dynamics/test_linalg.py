"""The Newton linear algebra of the integrator: Schur-complement solves vs numpy.

The reduction forms the velocity block as ``xv = mu xq - bq``: its error is
relative to ``|bq|`` (a velocity residual, compared in the integrator with a
velocity tolerance ~1e-5 m/s), not to ``|xv|``; the bounds say so.
"""

import numpy as np
import pytest

from afmforce.dynamics._linalg import _schur_factor, _schur_factor_complex, _solve_complex, _solve_real
from afmforce.dynamics.models import MODEL_BEAM, MODEL_SPRING, jac


def _jacobians():
    rng = np.random.default_rng(3)
    for m in (1, 2):
        for _ in range(5):
            J = np.zeros((2 * m, 2 * m))
            J[:m, m:] = np.eye(m)
            J[m:, :] = rng.normal(scale=1e6, size=(m, 2 * m))
            yield J


def _check(x, ref, b):
    m = len(b) // 2
    dq, dv = np.abs(x[:m] - ref[:m]), np.abs(x[m:] - ref[m:])
    assert np.all(dq <= 1e-13 * np.abs(ref[:m]).max())
    assert np.all(dv <= 1e-13 * (np.abs(ref[m:]).max() + np.abs(b[:m]).max()))


@pytest.mark.parametrize("mu", [3.7e5, 1e9, 2.1])
def test_real_solve_equals_dense_solve(mu):
    for J in _jacobians():
        n = J.shape[0]
        b = np.random.default_rng(n).normal(size=n)
        S = np.zeros((2, 2))
        det = _schur_factor(J, mu, S)
        x = b.copy()
        _solve_real(J, mu, S, det, x)
        ref = np.linalg.solve(mu * np.eye(n) - J, b)
        _check(x, ref, b)


@pytest.mark.parametrize("mu", [2.68e5 - 3.05e5j, 1e9 + 4e8j])
def test_complex_solve_equals_dense_solve(mu):
    for J in _jacobians():
        n = J.shape[0]
        rng = np.random.default_rng(n + 1)
        b = rng.normal(size=n) + 1j * rng.normal(size=n)
        S = np.zeros((2, 2, 2))
        dr, di = _schur_factor_complex(J, mu.real, mu.imag, S)
        Sc = np.zeros((2, 2), dtype=complex)
        assert complex(dr, di) == pytest.approx(_schur_factor(J, mu, Sc), rel=1e-12)
        c = np.concatenate([b.real, b.imag])
        _solve_complex(J, mu.real, mu.imag, S, dr, di, c)
        ref = np.linalg.solve(mu * np.eye(n) - J, b)
        got = c[:n] + 1j * c[n:]
        _check(got, ref, b)


def test_model_jacobians_have_the_second_order_structure():
    """The reduction is only valid for J = [[0, I], [Jq, Jv]]: check both models."""
    from afmforce.dynamics import SimulationConfig
    from afmforce.dynamics.simulate import parameter_vector
    for model, n, y in ((MODEL_BEAM, 4, np.array([-1e-9, -2e-9, 1e-6, 2e-6])),
                        (MODEL_SPRING, 2, np.array([-1e-9, 1e-6]))):
        cfg = SimulationConfig(model="beam" if model == MODEL_BEAM else "spring")
        J = np.full((n, n), np.nan)
        assert jac(model, parameter_vector(cfg), -20e-9, 1e-7, y, J)
        m = n // 2
        np.testing.assert_array_equal(J[:m, :m], 0.0)
        np.testing.assert_array_equal(J[:m, m:], np.eye(m))


def test_singular_matrix_is_reported():
    J = np.zeros((4, 4))
    J[:2, 2:] = np.eye(2)
    S = np.zeros((2, 2))
    assert _schur_factor(J, 0.0, S) == 0.0
    assert _schur_factor_complex(J, 0.0, 0.0, np.zeros((2, 2, 2))) == (0.0, 0.0)
    J[2, 0] = np.inf
    assert _schur_factor(J, 1.0, S) == 0.0
    assert _schur_factor_complex(J, 1.0, 2.0, np.zeros((2, 2, 2))) == (0.0, 0.0)
