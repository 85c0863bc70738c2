"""The small dense solver shared by the compiled fits (afmforce._linalg_small), against LAPACK."""

from __future__ import annotations

import numpy as np
import pytest

from afmforce._linalg_small import solve_small, solve_small_in_place


def _well_conditioned(rng, n):
    """A random n x n system with condition number below ~50: Q diag(s) Q'^T, s in [1, 50]."""
    q1, _ = np.linalg.qr(rng.standard_normal((n, n)))
    q2, _ = np.linalg.qr(rng.standard_normal((n, n)))
    s = rng.uniform(1.0, 50.0, n)
    scale = 10.0 ** rng.uniform(-12, 12)  # the fits' normal equations span many decades
    return scale * (q1 * s) @ q2.T, rng.standard_normal(n) * 10.0 ** rng.uniform(-12, 12)


@pytest.mark.parametrize("n", [1, 2, 3, 4, 5, 6])
def test_solve_small_agrees_with_numpy_on_random_systems(n):
    rng = np.random.default_rng(20 + n)
    for _ in range(50):
        A, b = _well_conditioned(rng, n)
        ref = np.linalg.solve(A, b)
        A0, b0 = A.copy(), b.copy()
        x = solve_small(A, b)
        assert np.array_equal(A, A0) and np.array_equal(b, b0)         # its inputs are not changed
        # backward stable: the error is cond(A) * eps relative to the solution (cond < 50)
        assert np.linalg.norm(x - ref) <= 1e-12 * np.linalg.norm(ref)
        M, y = A.copy(), b.copy()
        assert solve_small_in_place(M, y)
        assert np.array_equal(y, x)                                     # the same elimination


def test_solve_small_pivots():
    """A zero on the diagonal needs the row exchange (no pivoting would divide by zero)."""
    A = np.array([[0.0, 2.0, 1.0], [1.0, 1.0, 0.0], [3.0, 0.0, 1.0]])
    b = np.array([3.0, 2.0, 4.0])
    assert np.allclose(solve_small(A, b), np.linalg.solve(A, b), rtol=1e-14, atol=0)
    assert np.allclose(A @ solve_small(A, b), b, rtol=1e-14, atol=1e-15)


@pytest.mark.parametrize("A", [np.array([[1.0, 2.0], [2.0, 4.0]]),           # rank 1
                               np.zeros((3, 3)),
                               np.array([[np.nan, 1.0], [1.0, np.nan]])])
def test_a_singular_system_says_so(A):
    b = np.ones(A.shape[0])
    assert np.isnan(solve_small(A, b)).all()
    assert not solve_small_in_place(A.copy(), b.copy())


def test_an_edit_of_the_shared_solver_changes_its_callers_stamp(tmp_path):
    """The contact's adhesive_lm and the analysis' _wls_small and lm_fit call this module's kernels
    from other files; numba stamps a cached kernel with its own file only, so afmforce's stamp
    (afmforce._jitcache: every source a kernel may reach) must cover this file, or an edit here would
    leave the callers' caches running the old elimination."""
    import shutil

    from afmforce._jitcache import PACKAGE, kernel_source_files, sources_digest

    pkg = tmp_path / "afmforce"
    shutil.copytree(PACKAGE, pkg, ignore=shutil.ignore_patterns("__pycache__", "*.nbi", "*.nbc"))
    assert pkg / "_linalg_small.py" in kernel_source_files(pkg)
    before = sources_digest(pkg)
    (pkg / "_linalg_small.py").write_text((pkg / "_linalg_small.py").read_text() + "\n# an edit\n")
    assert sources_digest(pkg) != before
