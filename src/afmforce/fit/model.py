"""Model predictions for prepared curves: the dynamic model, its static limit, residuals.

The dynamic model of curve *i* is :func:`afmforce.dynamics.simulate` with the
curve's own speed and sample rate, started at the true position of its first
sample (``position[0] - shift_i``) and turned one sample after its last, so the
simulated samples fall at the data's times. The linear nuisance parameters
(baseline offset and drift slope of each curve) are eliminated by weighted
linear least squares inside the residual (variable projection, Golub & Pereyra
1973): the optimiser sees only the nonlinear ones, and the Jacobian of the
projected residual gives the marginal covariance of those.
"""

from __future__ import annotations

import math
import warnings
from typing import Sequence

import numpy as np

from ..errors import AfmforceError, ParameterError
from .data import FitCurve

__all__ = ["Evaluator", "MODEL_KINDS", "FAILED_RESIDUAL"]

#: ``dynamic``: simulate(); ``static``: the quasi-static, friction-free curve (no inertia, no drainage).
MODEL_KINDS = ("dynamic", "static")
#: Residual (in noise units) given to every sample of a curve whose simulation failed.
FAILED_RESIDUAL = 1e3


class Evaluator:
    """Predict and compare curves for given global parameters and shifts.

    Parameters
    ----------
    curves : list of FitCurve
    base : SimulationConfig
        Model and every fixed parameter; speed, sample rate and drive range
        are set per curve.
    kind : {"dynamic", "static"}
    drift : bool
        Fit a linear drift (slope in time) per curve besides the offset.
    """

    def __init__(self, curves: Sequence[FitCurve], base, kind: str = "dynamic",
                 drift: bool = True) -> None:
        if kind not in MODEL_KINDS:
            raise ParameterError(f"model kind must be one of {MODEL_KINDS}, got {kind!r}")
        self.curves = list(curves)
        self.base = base
        self.kind = kind
        self.drift = drift
        self.simulations = 0
        self.failures = 0
        self.last_error = ""
        #: integrator threads of the batched runs (None: one per core; see simulate_many)
        self.threads: int | None = None

    # --- predictions -------------------------------------------------------------
    def predict(self, i: int, values: dict, shift: float) -> np.ndarray | None:
        """Model apparent deflection [m] at the samples of curve ``i`` (None: the model failed)."""
        return self.predict_many([(i, values, shift)])[0]

    def _config(self, i: int, values: dict, shift: float):
        c = self.curves[i]
        dz = c.velocity / c.sample_rate
        start = float(c.position[0] - shift)
        turn = start + c.velocity * float(c.time[-1]) + dz
        return self.base.replace(**values, velocity=c.velocity, sample_rate=c.sample_rate,
                                 start=start, turn=turn, end=turn - 1e-9, turn_force=None,
                                 turn_deflection=None, dwell=0.0, retract_velocity=None)

    def _failed(self, exc: AfmforceError) -> None:
        self.failures += 1
        self.last_error = str(exc)

    def predict_many(self, requests: Sequence[tuple[int, dict, float]]) -> list[np.ndarray | None]:
        """:meth:`predict` for many ``(curve index, values, shift)`` at once.

        The dynamic model runs them in one :func:`afmforce.dynamics.simulate_many`
        call (a Jacobian's perturbed runs, the curves of one residual); the
        results equal separate :meth:`predict` calls.
        """
        self.simulations += len(requests)
        if self.kind == "static":
            return [self._static(self.curves[i], values, shift) for i, values, shift in requests]
        from ..dynamics import DynamicsWarning
        from ..dynamics.batch import simulate_many

        out: list = [None] * len(requests)
        cfgs, where = [], []
        for k, (i, values, shift) in enumerate(requests):
            try:
                cfgs.append(self._config(i, values, shift))
                where.append(k)
            except AfmforceError as exc:   # start in contact: a bad trial point
                self._failed(exc)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", DynamicsWarning)
            runs = simulate_many(cfgs, on_error="return", threads=self.threads,
                                 reduce=lambda tr: (tr.time, tr.segment, tr.apparent_deflection))
        for k, r in zip(where, runs):
            if isinstance(r, AfmforceError):   # solver failure: a bad trial point
                self._failed(r)
                continue
            t, seg, app_defl = r
            app = seg == 0
            out[k] = np.interp(self.curves[requests[k][0]].time, t[app], app_defl[app])
        return out

    def _static(self, c: FitCurve, values: dict, shift: float) -> np.ndarray:
        from ..forces import vdw_force

        cfg = self.base.replace(**values) if values else self.base
        k, R, A, z0 = cfg.force_constant, cfg.radius, cfg.hamaker, cfg.z0
        h = np.geomspace(0.5 * z0, 5e-6, 4000)
        f = np.asarray(vdw_force(h, R, A, z0))
        zz = f / k - h
        z2 = f / k
        # stable branches: outer (largest h with Fs' = k and above), inner (contact)
        dz = np.diff(zz)
        unstable = np.flatnonzero(dz > 0)          # z increases with h: unstable part
        z = c.position - shift
        if unstable.size == 0:                     # no instability: single branch
            order = np.argsort(zz)
            return np.interp(z, zz[order], z2[order])
        i_in, i_out = unstable[0], unstable[-1] + 1
        zin, yin = zz[: i_in + 1][::-1], z2[: i_in + 1][::-1]     # z increasing
        zout, yout = zz[i_out:][::-1], z2[i_out:][::-1]
        z_jump = zz[i_out]
        return np.where(z < z_jump, np.interp(z, zout, yout), np.interp(z, zin, yin))

    # --- residuals ---------------------------------------------------------------
    def design(self, i: int) -> np.ndarray:
        c = self.curves[i]
        cols = [np.ones(c.n)] + ([c.time] if self.drift else [])
        return np.column_stack(cols)

    def project(self, i: int, model: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
        """Weighted residual of curve ``i`` on its mask, offset/drift eliminated.

        Returns ``(residual, coefficients)``: residual in noise units, coefficients
        ``(offset [m], drift [m/s])`` (drift 0 when not fitted).
        """
        c = self.curves[i]
        m = c.mask
        if model is None or not np.all(np.isfinite(model[m])):
            return np.full(int(m.sum()), FAILED_RESIDUAL), np.array([math.nan, math.nan])
        X = self.design(i)[m] / c.sigma
        b = (c.deflection[m] - model[m]) / c.sigma
        coef, *_ = np.linalg.lstsq(X, b, rcond=None)
        r = b - X @ coef
        return r, np.append(coef, 0.0)[:2]

    def residual(self, i: int, values: dict, shift: float) -> np.ndarray:
        return self.project(i, self.predict(i, values, shift))[0]

    def n_linear(self) -> int:
        """Linear nuisance parameters eliminated per curve."""
        return 2 if self.drift else 1
