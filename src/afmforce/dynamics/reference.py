"""A plain scipy implementation of the same equations, for cross-checks.

Written independently of the compiled vector field: numpy, the force laws of
:mod:`afmforce.forces` and the beam matrices of
:class:`~afmforce.cantilever.InclinedCantilever` (spec sections 3 and 5), and
``scipy.integrate.solve_ivp`` with an analytic Jacobian, one call per drive
segment, with solve_ivp's own event location. The lever damping of issue 23 (a quality
factor) is built here from its definition: the undamped free modes by scipy's generalised
eigensolver, Rayleigh's alpha and beta by a linear solve of ``zeta_i = alpha / (2 w_i) +
beta w_i / 2``. It is slow (pure Python per
step) and meant for tests on short windows at tight tolerances and for the
benchmark (``benchmarks/bench_dynamics.py``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..forces import (double_layer_force, double_layer_force_gradient, lever_drag_force,
                      slip_drainage_force, vdw_force, vdw_force_gradient)
from ..surface_laws import total_force
from .config import SimulationConfig
from .drive import initial_state, segments
from .static import surface_jump_in

__all__ = ["ReferenceSolution", "reference_solve", "ReferenceModel"]


def rayleigh_damping(K, M, q1, q2=None) -> np.ndarray:
    """``C = alpha M + beta K`` giving the two undamped free modes of (M, K) the quality
    factors q1, q2 (q2 None: q1; q1 None: the first mode undamped); zeros for both None
    (the paper's undamped model)."""
    if q1 is None and q2 is None:
        return np.zeros_like(K)
    from scipy.linalg import eigh

    w = np.sqrt(eigh(K, M, eigvals_only=True))
    zeta = np.array([0.0 if q is None else 0.5 / q for q in (q1, q1 if q2 is None else q2)])
    alpha, beta = np.linalg.solve(np.column_stack([0.5 / w, 0.5 * w]), zeta)
    return alpha * M + beta * K


class ReferenceModel:
    """The equations of motion in numpy: ``f(t, y)`` and ``df/dy`` for one drive segment."""

    def __init__(self, cfg: SimulationConfig):
        self.cfg = cfg
        s, probe, fr = cfg.surface, cfg.probe, cfg.friction
        self.R, self.A, self.z0, self.eta = s.paper_radius, s.hamaker, s.z0, s.viscosity
        self.surface = s
        # the surface force laws (issue 31): (R_eff, parameter values) when one acts, else None
        self.laws = (s.radius_eff, s.law_values) if s.laws else None
        if cfg.model == "spring":
            self.beam = False
            self.k, self.m = probe.spring_constant, probe.mass
            q = probe.quality_factor
            self.c = 0.0 if q is None else self.m * math.sqrt(self.k / self.m) / q
            return
        self.beam = True
        c = cfg.cantilever
        th0 = c.theta0
        L1 = c.L1
        T = np.array([[1.0, 0.0], [-1.5 / L1, 1.0 / L1]])     # d(x, theta)/d(q_alpha, q_beta)
        self.Adyn = -T.T @ c.beam_stiffness @ T
        self.minv = np.array([1.0 / (probe.m_joint + probe.m_base / 4.0), 3.0 / probe.m_base])
        self.dh = np.array([math.cos(th0), c.a]) @ T             # dh/dq (eqs 24, 25)
        self.dy = np.array([math.sin(th0), c.b]) @ T             # dy2/dq (eqs 26, 27)
        self.dth = np.array([0.0, 1.0]) @ T                     # dtheta/dq
        self.C = rayleigh_damping(-self.Adyn, np.diag(1.0 / self.minv), probe.quality_factor,
                                  probe.quality_factor_2)
        if fr.law == "none":
            self.xi, self.zeta = 0.0, 0.0
        elif fr.law == "viscous":
            self.xi, self.zeta = fr.xi, 0.0
        else:
            self.xi, self.zeta = fr.xi, fr.zeta

    def _dl(self, h, law):
        s = self.surface
        if s.double_layer == "none":
            return 0.0
        return float(law(h, s.radius, s.surface_potential, s.debye_length, s.surface_potential_2,
                         s.permittivity, s.double_layer, s.geometry))

    def _laws(self, h):
        """(F, F') of the surface force laws of :mod:`afmforce.surface_laws` (their numpy forms)."""
        f, df = total_force(h, *self.laws)
        return float(f), float(df)

    def _drag(self, h, hd):
        s = self.surface
        return float(slip_drainage_force(h, hd, s.radius, s.viscosity, s.slip_length, s.geometry)) \
            + float(lever_drag_force(h, hd, s.lever_drag, s.lever_height))

    def _forces(self, h, hd):
        fz = float(vdw_force(h, self.R, self.A, self.z0)) + self._dl(h, double_layer_force) \
            + self._drag(h, hd)
        if self.laws is not None:
            fz += self._laws(h)[0]
        return fz

    def separation(self, y, z, v):
        """(h, dh/dt) for state y at drive position z and speed v."""
        if not self.beam:
            return y[0] - z, y[1] - v
        return self.dh @ y[:2] - z, self.dh @ y[2:] - v

    def fun(self, t, y, z_of_t, v):
        z = z_of_t(t)
        h, hd = self.separation(y, z, v)
        fz = self._forces(h, hd)
        if not self.beam:
            return np.array([y[1], (-self.k * y[0] + fz - self.c * y[1]) / self.m])
        yd = self.dy @ y[2:]
        fy = -(self.xi + self.zeta * fz**2) * yd
        acc = self.minv * (self.Adyn @ y[:2] + fz * self.dh + fy * self.dy - self.C @ y[2:])
        return np.concatenate([y[2:], acc])

    def jac(self, t, y, z_of_t, v):
        z = z_of_t(t)
        h, hd = self.separation(y, z, v)
        dfs = float(vdw_force_gradient(h, self.R, self.A, self.z0)) + self._dl(
            h, double_layer_force_gradient)
        if self.laws is not None:
            dfs += self._laws(h)[1]
        dd = 1e-6 * h      # drainage and drag: linear in h', differentiated numerically in h
        dfz_dh = dfs + (self._drag(h + dd, hd) - self._drag(h - dd, hd)) / (2.0 * dd)
        dfz_dhd = self._drag(h, 1.0)
        if not self.beam:
            return np.array([[0.0, 1.0], [(-self.k + dfz_dh) / self.m,
                                          (dfz_dhd - self.c) / self.m]])
        fz = self._forces(h, hd)
        yd = self.dy @ y[2:]
        xi_eff = self.xi + self.zeta * fz**2
        dfy_dfz = -2.0 * self.zeta * fz * yd
        # generalised force G = A q + Fz dh + Fy dy
        dG_dq = self.Adyn + np.outer(self.dh + dfy_dfz * self.dy, self.dh) * dfz_dh
        dG_dv = np.outer(self.dh + dfy_dfz * self.dy, self.dh) * dfz_dhd - xi_eff * np.outer(
            self.dy, self.dy) - self.C
        J = np.zeros((4, 4))
        J[0, 2] = J[1, 3] = 1.0
        J[2:, :2] = self.minv[:, None] * dG_dq
        J[2:, 2:] = self.minv[:, None] * dG_dv
        return J

    def observables(self, Y, z, v):
        """deflection z2, angle theta, separation h for states Y (rows), positions z."""
        Y = np.atleast_2d(Y)
        if not self.beam:
            return Y[:, 0], np.full(len(Y), np.nan), Y[:, 0] - z
        z2 = Y[:, :2] @ self.dh
        return z2, Y[:, :2] @ self.dth, z2 - z


@dataclass(frozen=True)
class ReferenceSolution:
    """Result of :func:`reference_solve` (SI; NaN where an event did not occur).

    Attributes
    ----------
    time, piezo_position, deflection, angle, separation : ndarray
        Samples on the requested grid (up to ``t_stop``).
    jump_in_time, jump_in_position : float
        First ``h < h_s`` (static instability separation) on the approach.
    contact_time, contact_position : float
        First ``h < contact_separation`` on the approach.
    pull_off_position : float
        First ``h > contact_separation`` on the retract.
    min_deflection, min_apparent_deflection : float
        Before contact, from the dense output on a fine grid.
    nfev, steps : int
        Work of solve_ivp.
    """

    time: np.ndarray
    piezo_position: np.ndarray
    deflection: np.ndarray
    angle: np.ndarray
    separation: np.ndarray
    jump_in_time: float
    jump_in_position: float
    contact_time: float
    contact_position: float
    pull_off_position: float
    min_deflection: float
    min_apparent_deflection: float
    nfev: int
    steps: int


def reference_solve(cfg: SimulationConfig | None = None, *, rtol: float = 1e-8,
                    atol: float = 1e-15, t_stop: float | None = None,
                    sample_times=None, fine_points: int = 20001, **overrides) -> ReferenceSolution:
    """Solve a cycle (or its beginning, up to ``t_stop``) with scipy's Radau.

    Parameters
    ----------
    cfg : SimulationConfig
        The run (a turn at a load is not supported here).
    rtol, atol : float
        solve_ivp tolerances; ``atol`` [m] on positions, ``atol * 2 pi 1e7``
        [m/s] on velocities (as in :func:`afmforce.dynamics.simulate`).
    t_stop : float, optional
        Stop at this time [s] (short windows).
    sample_times : array_like, optional
        Times at which to return samples.
    fine_points : int
        Dense-output points per segment used for the minima before contact.
    """
    from scipy.integrate import solve_ivp

    cfg = cfg if cfg is not None else SimulationConfig()
    if overrides:
        cfg = cfg.replace(**overrides)
    model = ReferenceModel(cfg)
    y = initial_state(cfg)
    n = y.size
    atol_v = np.full(n, atol)
    atol_v[n // 2:] = atol * 2 * math.pi * 1e7
    beta = cfg.calibration_factor if model.beam else 1.0
    hc = cfg.contact_separation
    h_s = surface_jump_in(cfg.force_constant, cfg.surface)[0]
    plan = segments(cfg)
    t_stop = plan[-1].t_end if t_stop is None else t_stop
    ts_req = None if sample_times is None else np.asarray(sample_times, float)
    out = {k: [] for k in ("t", "z", "d", "th", "h")}
    ev = dict(jump_t=math.nan, jump_z=math.nan, contact_t=math.nan, contact_z=math.nan,
              pull_z=math.nan, min_d=math.nan, min_app=math.nan)
    nfev = steps = 0
    for seg in plan:
        if seg.t_start >= t_stop:
            break
        t1 = min(seg.t_end, t_stop)
        v = seg.velocity
        zf = seg.position

        def g_contact(t, y, zf, v):
            return model.separation(y, zf(t), v)[0] - hc

        def g_jump(t, y, zf, v):      # leaves the static branch: h < h_s
            return model.separation(y, zf(t), v)[0] - h_s

        events = [g_contact, g_jump]
        for g in events:
            g.direction = 0
        g_contact.direction = -1 if seg.kind == 0 else 1
        g_jump.direction = -1
        sol = solve_ivp(model.fun, (seg.t_start, t1), y, method="Radau", jac=model.jac,
                        rtol=rtol, atol=atol_v, dense_output=True, events=events,
                        args=(zf, v), first_step=1e-9)
        if sol.status < 0:
            raise RuntimeError(f"reference solve failed: {sol.message}")
        nfev += sol.nfev
        steps += sol.t.size - 1
        tc = sol.t_events[0]
        if seg.kind == 0:
            if tc.size and math.isnan(ev["contact_t"]):
                ev["contact_t"], ev["contact_z"] = tc[0], float(zf(tc[0]))
            tj = sol.t_events[1]
            tj = tj[tj < (tc[0] if tc.size else np.inf)]
            if tj.size:
                ev["jump_t"], ev["jump_z"] = tj[0], float(zf(tj[0]))
            t_end_pre = tc[0] if tc.size else t1
            tf = np.linspace(seg.t_start, t_end_pre, fine_points)
            tf = np.union1d(tf, sol.t[sol.t <= t_end_pre])
            d, th, _ = model.observables(sol.sol(tf).T, zf(tf), v)
            ev["min_d"] = float(d.min())
            ev["min_app"] = float((beta * th).min()) if model.beam else float(d.min())
        elif seg.kind == 1 and tc.size and math.isnan(ev["pull_z"]):
            ev["pull_z"] = float(zf(tc[0]))
        if ts_req is not None:
            m = (ts_req >= seg.t_start) & (ts_req <= t1)
            if seg is not plan[0]:
                m &= ts_req > seg.t_start
            tt = ts_req[m]
            if tt.size:
                Y = sol.sol(tt).T
                d, th, h = model.observables(Y, zf(tt), v)
                out["t"].append(tt)
                out["z"].append(zf(tt))
                out["d"].append(d)
                out["th"].append(th)
                out["h"].append(h)
        y = sol.y[:, -1]
    cat = (lambda k: np.concatenate(out[k]) if out[k] else np.empty(0))
    return ReferenceSolution(
        time=cat("t"), piezo_position=cat("z"), deflection=cat("d"), angle=cat("th"),
        separation=cat("h"), jump_in_time=ev["jump_t"], jump_in_position=ev["jump_z"],
        contact_time=ev["contact_t"], contact_position=ev["contact_z"],
        pull_off_position=ev["pull_z"], min_deflection=ev["min_d"],
        min_apparent_deflection=ev["min_app"], nfev=nfev, steps=steps)
