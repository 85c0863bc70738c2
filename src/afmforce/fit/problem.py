"""The least-squares problem of a joint fit: parameter vector, residuals, block Jacobian.

The vector holds the free global parameters (in units of their registry
``scale``) and then the per-curve zero of position ``shift_i`` (in nm). A
global parameter changes every curve; ``shift_i`` only curve *i*, so the
forward-difference Jacobian costs one simulation per curve per global
parameter plus one per curve for the shifts (not ``n_par x n_curves``).
"""

from __future__ import annotations

import numpy as np

from .model import Evaluator
from .params import PARAMETERS

__all__ = ["Problem", "SHIFT_SCALE", "SHIFT_STEP", "local_fit"]

#: Shifts are handled in nm inside the optimiser.
SHIFT_SCALE = 1e-9
#: Forward-difference step of a shift [m].
SHIFT_STEP = 0.02e-9


class Problem:
    """Residuals and Jacobian of the joint fit.

    Parameters
    ----------
    evaluator : Evaluator
    free : tuple of str
        Free global parameters (registry names).
    fixed : dict
        Values of global parameters held fixed [SI] (override the base config).
    """

    def __init__(self, evaluator: Evaluator, free: tuple[str, ...], fixed: dict | None = None):
        self.ev = evaluator
        self.free = tuple(free)
        self.fixed = dict(fixed or {})
        self.n_curves = len(evaluator.curves)
        self._cache: dict = {}

    # --- vector <-> values ----------------------------------------------------------
    @property
    def names(self) -> list[str]:
        return list(self.free) + [f"shift_{i}" for i in range(self.n_curves)]

    def scale(self) -> np.ndarray:
        return np.array([PARAMETERS[n].scale for n in self.free] + [SHIFT_SCALE] * self.n_curves)

    def unpack(self, x: np.ndarray) -> tuple[dict, np.ndarray]:
        """Scaled vector -> (SI values of the globals incl. fixed ones, shifts [m])."""
        x = np.asarray(x, float) * self.scale()
        g = len(self.free)
        values = {**self.fixed, **{n: float(v) for n, v in zip(self.free, x[:g])}}
        return values, x[g:]

    def pack(self, values: dict, shifts) -> np.ndarray:
        g = [values[n] for n in self.free]
        return np.concatenate([g, np.asarray(shifts, float)]) / self.scale()

    # --- residuals -------------------------------------------------------------------
    def curve_prediction(self, i: int, values: dict, shift: float):
        key = (i, tuple(sorted(values.items())), float(shift))
        if key not in self._cache:
            if len(self._cache) > 64 * self.n_curves:
                self._cache.clear()
            self._cache[key] = self.ev.predict(i, values, float(shift))
        return self._cache[key]

    def prefetch(self, requests) -> None:
        """Simulate every ``(i, values, shift)`` not yet cached in one batched call."""
        todo, keys = [], set()
        for i, values, shift in requests:
            key = (i, tuple(sorted(values.items())), float(shift))
            if key not in keys:
                keys.add(key)
                if key not in self._cache:
                    todo.append((key, (i, values, float(shift))))
        if not todo:
            return
        if len(self._cache) + len(todo) > 64 * self.n_curves:   # keep what is asked for now
            self._cache = {k: v for k, v in self._cache.items() if k in keys}
        for (key, _), pred in zip(todo, self.ev.predict_many([r for _, r in todo])):
            self._cache[key] = pred

    def projections(self, values: dict, shifts, replace: tuple | None = None) -> tuple:
        """Per curve ``(residual, linear coefficients)``, fringe signal [m] and the shared fringe
        coefficients [m] at ``values, shifts`` (:meth:`Evaluator.project_all`).

        ``replace = (i, shift)`` evaluates curve ``i`` at another shift (a Jacobian column):
        with fringes shared by the curves every curve's residual may change.
        """
        shifts = np.array(shifts, float)
        if replace is not None:
            shifts[replace[0]] = replace[1]
        self.prefetch([(i, values, shifts[i]) for i in range(self.n_curves)])
        preds = [self.curve_prediction(i, values, shifts[i]) for i in range(self.n_curves)]
        return self.ev.project_all(preds, shifts)

    def curve_residuals(self, x: np.ndarray) -> list[np.ndarray]:
        """The weighted residual of each curve at ``x`` (noise units)."""
        values, shifts = self.unpack(x)
        return [p[0] for p in self.projections(values, shifts)[0]]

    def residual(self, x: np.ndarray) -> np.ndarray:
        return np.concatenate(self.curve_residuals(x))

    def chi2(self, x: np.ndarray) -> float:
        r = self.residual(x)
        return float(r @ r)

    def jacobian(self, x: np.ndarray) -> np.ndarray:
        """Forward-difference Jacobian of :meth:`residual` w.r.t. the scaled vector."""
        values, shifts = self.unpack(x)
        requests = [(i, values, shifts[i]) for i in range(self.n_curves)]
        steps = {}
        for name in self.free:       # every perturbed run of this Jacobian in one batch
            p = PARAMETERS[name]
            h = p.step(values[name])
            if values[name] + h > p.upper:
                h = -h
            steps[name] = h
            requests += [(i, {**values, name: values[name] + h}, shifts[i])
                         for i in range(self.n_curves)]
        requests += [(i, values, shifts[i] + SHIFT_STEP) for i in range(self.n_curves)]
        self.prefetch(requests)
        base = np.concatenate([p[0] for p in self.projections(values, shifts)[0]])
        J = np.zeros((base.size, len(self.free) + self.n_curves))
        for j, name in enumerate(self.free):
            h = steps[name]
            r2 = np.concatenate([p[0] for p in self.projections(
                {**values, name: values[name] + h}, shifts)[0]])
            J[:, j] = (r2 - base) / (h / PARAMETERS[name].scale)
        g = len(self.free)
        for i in range(self.n_curves):
            r2 = np.concatenate([p[0] for p in self.projections(
                values, shifts, (i, shifts[i] + SHIFT_STEP))[0]])
            J[:, g + i] = (r2 - base) / (SHIFT_STEP / SHIFT_SCALE)
        return J

    def linear_coefficients(self, x: np.ndarray) -> list[np.ndarray]:
        """Per curve ``(offset [m], drift [m/s], ...)`` at ``x``."""
        values, shifts = self.unpack(x)
        return [p[1] for p in self.projections(values, shifts)[0]]

    def fringe_amplitude(self, x: np.ndarray) -> tuple[float, float]:
        """Amplitude of the shared periodic fringes at ``x`` and its standard error [m] (0, 0
        without them; the other parameters held at ``x``)."""
        values, shifts = self.unpack(x)
        c = np.asarray(self.projections(values, shifts)[2], float)
        amp = float(np.hypot(*c))
        if amp == 0.0:
            return 0.0, 0.0
        return amp, float(np.sqrt(max(c @ self.ev.fringe_cov @ c, 0.0)) / amp)

    def predictions(self, x: np.ndarray) -> list[np.ndarray | None]:
        """Model deflection of every curve incl. offset, drift and fringes [m] at ``x``."""
        values, shifts = self.unpack(x)
        proj, fringes, _ = self.projections(values, shifts)
        out = []
        for i in range(self.n_curves):
            m = self.curve_prediction(i, values, shifts[i])
            out.append(None if m is None else m + self.ev.baseline(i, proj[i][1]) + fringes[i])
        return out


def local_fit(problem: Problem, x0: np.ndarray, max_nfev: int = 40):
    """Bounded least squares from ``x0`` with lmfit (scipy ``least_squares``, TRF).

    Returns ``(x, lmfit result)``; ``x`` is the scaled parameter vector.
    """
    import lmfit

    params = lmfit.Parameters()
    names = problem.names
    for name, v in zip(names, x0):
        if name in PARAMETERS:
            p = PARAMETERS[name]
            lo, hi = p.lower / p.scale, p.upper / p.scale
            params.add(name, value=float(np.clip(v, lo, hi)), min=lo, max=hi)
        else:
            params.add(name, value=float(v))

    def vec(p):
        return np.array([p[n].value for n in names])

    res = lmfit.minimize(lambda p: problem.residual(vec(p)), params, method="least_squares",
                         jac=lambda p, *a, **k: problem.jacobian(vec(p)), x_scale="jac",
                         max_nfev=max_nfev, scale_covar=True)
    return vec(res.params), res
