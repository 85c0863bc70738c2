"""``simulate()``: run one dynamic approach-retract cycle."""

from __future__ import annotations

import math
import time
import warnings
from typing import Callable

import numpy as np

from ..errors import SolverError
from . import radau as R
from .config import SimulationConfig
from .drive import approach_segment, initial_state, segments
from ._locate import sample_columns
from .events import Events, compliance_lines
from .guard import run_check
from .static import static_jump_in
from ..progress import Progress
from .load_friction import RING_AMPLITUDE, load_friction_controls  # noqa: F401  (re-exported)
from .registries import RINGING
from .models import (MODEL_BEAM, MODEL_IDS, O_DEFL, O_FY, O_FZ, O_H, O_THETA,
                     O_Y2, state_size)
from .trajectory import SolverStats, Trajectory
from ._params import (H_GUARD_FRACTION, _beam_fmax, _beam_template, free_frequency_max,  # noqa: F401 (re-exported)
                      parameter_vector)

__all__ = ["simulate", "DynamicsWarning", "H_GUARD_FRACTION", "VELOCITY_ATOL_FREQUENCY"]

#: The absolute tolerance on velocities is ``atol * 2 pi * VELOCITY_ATOL_FREQUENCY``
#: [Hz]: a velocity error counts like a position error over one period at this
#: frequency. 1 MHz lies above every mode that must be resolved (the free beam,
#: 4-65 kHz), so such modes are followed; see docs/dynamics.md for the
#: in-contact ringing.
VELOCITY_ATOL_FREQUENCY = 1e7   # upper bound only: see models.error_frequency
#: Velocity tolerance = atol * this * (the model's own rate, models.error_frequency).
#: 10: at 1 the Fig-5 cycle needs 2.3x the steps for no change of any event
#: (< 2 pm); at 100 a bouncing probe's turn-around is no longer resolved.
VELOCITY_TOLERANCE_FACTOR = 10.0
#: Relative tolerance on positions = rtol * this factor (0: positions are
#: controlled by atol alone; see docs/dynamics.md).
POSITION_RTOL_FACTOR = 0.0
#: First trial step at the start of every drive segment [s].
INITIAL_STEP = 1e-9
#: Steps between progress callbacks.
PROGRESS_CHUNK = 5000
#: Drive travel allowed per step: max(HMAX_FRACTION * h, HMAX_TRAVEL * z0).
HMAX_FRACTION = 0.1
HMAX_TRAVEL = 3.0


#: Inside the spike window the in-contact ringing is resolved until the running
#: spike maximum has not grown for this many contact-mode cycles (and this long
#: after contact), then damped (issue 16). 10, 30 and 100 give the same spike
#: height on the Fig 5/6 runs to 1e-4 nm (the full 2 ms window: the same again)
#: with 2.5-3.4x fewer steps than resolving the whole window; 30 keeps a margin
#: for a second, later ringing maximum.
SPIKE_QUIET_CYCLES = 30.0
#: Damping steps only where the contact stiffness -Fs'(h) exceeds this multiple
#: of k: well inside the repulsive wall, away from the pull-off fold (h = z0).
DAMP_KAPPA_RATIO = 100.0


class DynamicsWarning(UserWarning):
    """A simulation ran but its protocol did not do what was asked (no contact, no pull-off)."""


def _resolve_config(config, overrides) -> SimulationConfig:
    if config is None:
        return SimulationConfig(**overrides)      # flat names (raises on unknown ones)
    return config.replace(**overrides) if overrides else config


def simulate(config: SimulationConfig | None = None, *,
             progress: Callable[[Progress], None] | None = None, check: str = "off",
             **overrides) -> Trajectory:
    """Simulate one approach-dwell-retract cycle (spec sections 3 and 5).

    Parameters
    ----------
    config : SimulationConfig, optional
        The run; default: the paper's Fig 5 (beam, xi = 0.1 kg/s, 0.1 um/s).
    progress : callable, optional
        Called now and then with a :class:`~afmforce.progress.Progress`
        (``done`` / ``total`` simulated time [s], ``unit="s"``).
    check : {"off", "auto", "always", "raise"}
        Convergence guard (:mod:`afmforce.dynamics.guard`): ``"auto"`` re-solves
        at 10x tighter tolerances when the run is in a risky regime (low
        damping ratio, stiff load-dependent friction) and warns with
        :class:`~afmforce.dynamics.guard.ConvergenceWarning` when a key event
        moved beyond its tolerance; ``"always"`` checks every run;
        ``"raise"`` checks and raises :class:`SolverError` instead. The
        differences are in ``solver.event_errors``. Default "off" (the CLI
        uses "auto").
    **overrides
        Changes to ``config`` (or to the default): flat names of
        :data:`~afmforce.dynamics.config.FLAT`, e.g. ``xi=0.01``, or whole
        parts, e.g. ``drive=Drive(velocity=1e-6)``.

    Returns
    -------
    Trajectory
        Sampled at ``config.sample_rate``, with events and solver statistics.

    Raises
    ------
    ParameterError
        Bad configuration (also: start already in contact).
    SolverError
        The integrator failed (step size underflow, step budget, non-finite
        state); never returns a truncated trajectory.

    Warns
    -----
    DynamicsWarning
        The approach never reached contact, or the retract ended in contact.

    See Also
    --------
    afmforce.dynamics.simulate_many : many configurations in one call (faster per run).
    """
    wall0 = time.perf_counter()
    run = _Run(_resolve_config(config, overrides))
    run.integrate(progress)
    return run.finish(check, wall0)


class _Run:
    """One cycle split into its three phases, so that :func:`simulate_many` can run the
    compiled middle one (:meth:`integrate`, no Python objects touched, the GIL released)
    on several threads while this thread prepares and finishes the others."""

    def __init__(self, cfg: SimulationConfig) -> None:
        self.wall0 = time.perf_counter()
        self.cfg = cfg
        self.model = model = MODEL_IDS[cfg.model]
        self.n = n = state_size(model)
        self.p = p = parameter_vector(cfg)
        self.y = initial_state(cfg)
        atol = np.full(n, cfg.atol)
        atol[n // 2:] = cfg.atol * 2.0 * math.pi * VELOCITY_ATOL_FREQUENCY
        rtolv = np.full(n, cfg.rtol)
        rtolv[: n // 2] = cfg.rtol * POSITION_RTOL_FACTOR
        self.atol, self.rtolv = atol, rtolv
        self.app = approach_segment(cfg)
        plan = segments(cfg)
        self.t_total_max = t_total_max = plan[-1].t_end
        self.dt = 1.0 / cfg.sample_rate
        self.nbuf = nbuf = int(math.floor(t_total_max * cfg.sample_rate * (1.0 + 1e-12))) + 1
        self.averaged = cfg.sampling == "average"
        self.ybuf = np.zeros((nbuf, n + 1)) if self.averaged else np.full((nbuf, n), np.nan)
        self.s_next = np.zeros(1, dtype=np.int64)
        self.ev = ev = np.full(R.E_SIZE, np.nan)
        ev[R.E_IN_CONTACT] = 0.0
        ev[R.E_H_CONTACT] = cfg.contact_separation
        ev[R.E_SPIKE_WINDOW] = cfg.spike_window
        ev[R.E_SPIKE_CYCLES] = SPIKE_QUIET_CYCLES
        ev[R.E_JUMP_FACTOR] = cfg.jump_factor
        self.h_s, self.z_s, _ = static_jump_in(cfg.force_constant, cfg.radius, cfg.hamaker, cfg.z0)
        ev[R.E_H_STATIC] = self.h_s if math.isfinite(self.h_s) else -math.inf
        self.vfac_scale, ring_amp = load_friction_controls(cfg)
        ev[R.E_RING_AMP] = ring_amp
        self.work = np.zeros(R.W_SIZE)
        self.Q = np.zeros((n, 3))
        self.y_old = np.zeros(n)
        self.J = np.zeros((n, n))
        self.stats = np.zeros(R.S_SIZE, dtype=np.int64)
        self.hmax_dz = HMAX_TRAVEL * cfg.z0
        self.damp_cycles = RINGING[cfg.ringing].damp_cycles
        if cfg.turn_force is not None:
            # the load an instrument triggers on: k z2, not the ringing contact force Fz
            self.term = (R.TERM_DEFLECTION, cfg.turn_force / cfg.force_constant)
        elif cfg.turn_deflection is not None:
            self.term = (R.TERM_DEFLECTION, cfg.turn_deflection)
        else:
            self.term = (R.TERM_NONE, 0.0)
        self.f_max = f_max = (_beam_fmax(cfg.cantilever, cfg.m_joint, cfg.m_base)
                              if model == MODEL_BEAM else free_frequency_max(p, model))
        self.budget = cfg.max_steps if cfg.max_steps is not None else max(
            2_000_000, int(60.0 * f_max * t_total_max))

    def _integrator_args(self, seg, term_kind, term_level, chunk) -> tuple:
        """The arguments of :func:`.radau.integrate_segment` for the drive segment ``seg``
        (its records as plain tuples; the arrays are this run's, updated in place; the
        records that do not change between segments are built once per run)."""
        fixed = self.__dict__.get("_fixed_records")
        if fixed is None or fixed[0] != chunk:
            cfg = self.cfg
            fixed = self._fixed_records = (
                chunk,
                R.tolerance_record(cfg.rtol, self.rtolv, self.atol),
                R.control_record(HMAX_FRACTION, self.hmax_dz, self.damp_cycles,
                                 DAMP_KAPPA_RATIO, self.budget, chunk),
                R.sampling_record(0.0, self.dt, self.averaged, self.s_next, self.ybuf),
                R.state_record(self.y, self.ev, self.work, self.Q, self.y_old, self.J,
                               self.stats))
        return (self.model, self.p,
                R.drive_record(seg.kind, seg.t_start, seg.z_start, seg.velocity, seg.t_end,
                               term_kind, term_level)) + fixed[1:]

    def _segment(self, seg, term_kind, term_level, t_total, progress):
        work, s_next, stats = self.work, self.s_next, self.stats
        work[R.W_T] = seg.t_start
        work[R.W_H] = INITIAL_STEP
        work[R.W_H_OLD] = 0.0
        work[R.W_ERR_OLD] = 0.0
        work[R.W_HAS_SOL] = 0.0
        work[R.W_HAVE_JAC] = 0.0
        work[R.W_VFAC] = VELOCITY_TOLERANCE_FACTOR * self.vfac_scale
        first = int(s_next[0])
        chunk = PROGRESS_CHUNK if progress is not None else 2**62
        args = self._integrator_args(seg, term_kind, term_level, chunk)
        while True:
            status = R.integrate_segment(*args)
            if status == R.PAUSED:
                progress(Progress(done=min(float(work[R.W_T]), t_total), total=t_total, unit="s",
                                  what="simulate"))
                continue
            break
        if status < 0:
            t = work[R.W_T]
            where = (f"at t = {t:.6g} s, z = {seg.position(t) * 1e9:.4g} nm in the "
                     f"{('approach', 'retract', 'dwell')[seg.kind]} after {stats[R.S_STEPS]} steps")
            if status == R.MAX_STEPS:
                advice = (f"the step budget max_steps = {self.budget} is spent; raise max_steps "
                          f"(this run follows modes up to {self.f_max / 1e3:.3g} kHz over "
                          f"{t_total:.4g} s; a tighter rtol/atol needs more steps, not fewer)")
            else:
                advice = "a tighter rtol/atol may get past it"
            raise SolverError(f"integration failed ({R.STATUS[status]}) {where}; {advice}")
        return status, first, int(s_next[0])

    def integrate(self, progress=None) -> "_Run":
        """Run the integrator over every drive segment (raises :class:`SolverError`)."""
        cfg, app = self.cfg, self.app
        labels = []
        status, a, b = self._segment(app, *self.term, self.t_total_max, progress)
        labels.append((app.kind, a, b))
        self.turned_at_load = status == R.TERMINAL
        if self.turned_at_load:
            t_turn = float(self.ev[R.E_TERM_T])
            plan = segments(cfg, t_turn, float(app.position(t_turn)))
        else:
            plan = segments(cfg)
        t_total = plan[-1].t_end
        for seg in plan[1:]:
            _, a, b = self._segment(seg, R.TERM_NONE, 0.0, t_total, progress)
            labels.append((seg.kind, a, b))
        if progress is not None:
            progress(Progress(done=t_total, total=t_total, unit="s", what="simulate"))
        self.labels, self.plan = labels, plan
        return self

    def finish(self, check: str = "off", wall0: float | None = None) -> Trajectory:
        """The trajectory, events, warnings and convergence check of an integrated run."""
        cfg, model, ev, stats, plan = self.cfg, self.model, self.ev, self.stats, self.plan
        labels, n = self.labels, self.n
        if self.averaged:
            # every grid time up to the end; windows at the ends are clipped to the run
            n_samp = min(self.nbuf, int(math.floor(plan[-1].t_end * cfg.sample_rate
                                                   * (1.0 + 1e-12))) + 1)
            Y = self.ybuf[:n_samp, :n] / self.ybuf[:n_samp, n:]
            bounds = [seg.t_end for seg in plan[:-1]]
            sample_seg = np.searchsorted(np.asarray(bounds), np.arange(n_samp) * self.dt,
                                         side="left")
            labels = [(seg.kind, int(np.searchsorted(sample_seg, i)),
                       int(np.searchsorted(sample_seg, i, side="right")))
                      for i, seg in enumerate(plan)]
        else:
            n_samp = int(self.s_next[0])
            Y = self.ybuf[:n_samp]
        lab = np.array([(a, b, kind) for kind, a, b in labels], dtype=np.int64).reshape(-1, 3)
        seg = np.array([(s.t_start, s.z_start, s.velocity) for s in plan]).reshape(-1, 3)
        tt, zd, seg_code, obs, finite = sample_columns(
            model, self.p, Y, self.dt, lab[:, 0], lab[:, 1], lab[:, 2].astype(np.int8),
            seg[:, 0], seg[:, 1], seg[:, 2])
        if not finite:
            raise SolverError("the sampled trajectory contains non-finite values; "
                              "try a tighter rtol/atol")
        beta = cfg.calibration_factor
        deflection = obs[:, O_DEFL]
        if model == MODEL_BEAM:
            angle = obs[:, O_THETA]
            apparent = beta * angle
        else:
            angle = np.full(n_samp, np.nan)
            apparent = deflection.copy()
        separation = obs[:, O_H]

        events = _events(cfg, ev, plan, beta, model, zd, apparent, separation, seg_code,
                         self.h_s, self.z_s)
        if not math.isfinite(events.contact_time):
            warnings.warn(
                f"the approach never reached contact (h < {cfg.contact_separation * 1e9:.3g} nm) "
                f"before turning at z = {events.turn_position * 1e9:.4g} nm; raise turn",
                DynamicsWarning, stacklevel=3)
        elif ev[R.E_IN_CONTACT] == 1.0:
            warnings.warn(
                f"the retract ended in contact at z = {cfg.end * 1e9:.4g} nm (no pull-off); "
                "lower end", DynamicsWarning, stacklevel=3)
        if cfg.turn_force is not None or cfg.turn_deflection is not None:
            if not self.turned_at_load:
                what = "turn_force" if cfg.turn_force is not None else "turn_deflection"
                warnings.warn(f"{what} was not reached before the turn limit "
                              f"z = {cfg.turn * 1e9:.4g} nm; turned there", DynamicsWarning,
                              stacklevel=3)

        def _resolve(tight):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                return simulate(tight).events

        event_errors, check_note = run_check(check, cfg, events, _resolve)
        wall = time.perf_counter() - (self.wall0 if wall0 is None else wall0)
        solver = SolverStats(
            status="success", method="Radau IIA (order 5), compiled, analytic Jacobian",
            steps=int(stats[R.S_STEPS]), accepted=int(stats[R.S_ACCEPTED]),
            rejected=int(stats[R.S_REJECTED]), rhs_evaluations=int(stats[R.S_NFEV]),
            jacobian_evaluations=int(stats[R.S_NJEV]), lu_decompositions=int(stats[R.S_NLU]),
            damping_steps=int(stats[R.S_DAMPED]), newton_failures=int(stats[R.S_NEWTON_FAIL]),
            wall_time=wall, event_errors=event_errors, check=check_note)
        return Trajectory(
            time=tt, piezo_position=zd, deflection=deflection, apparent_deflection=apparent,
            separation=separation, apparent_separation=apparent - zd, angle=angle,
            lateral_position=obs[:, O_Y2], normal_force=obs[:, O_FZ], friction_force=obs[:, O_FY],
            segment=seg_code, calibration_factor=beta, spring_constant=cfg.force_constant,
            config=cfg, events=events, solver=solver)


def _events(cfg, ev, plan, beta, model, zd, apparent, separation, seg_code, h_s, z_s) -> Events:
    contact = math.isfinite(ev[R.E_CONTACT_T])
    left = math.isfinite(ev[R.E_JUMP_T])
    fast = math.isfinite(ev[R.E_FAST_T]) and (not contact or ev[R.E_FAST_T] <= ev[R.E_CONTACT_T])
    where = (f"left the static branch (h < h_s = {h_s * 1e9:.4g} nm) at "
             f"z = {ev[R.E_JUMP_Z] * 1e9:.4g} nm; static instability at z = {z_s * 1e9:.4g} nm"
             if left else "")
    if not contact:
        jumped, note = None, "no contact: the approach turned before the surfaces touched"
    elif fast:
        jumped, note = True, f"jump-in: {where}; then dh/dt < -{cfg.jump_factor:g} dz/dt"
    else:
        jumped, note = False, ("no jump: crept into contact (dh/dt never fell below "
                               f"-{cfg.jump_factor:g} dz/dt before contact)"
                               + (f"; {where}" if left else ""))
    turn = plan[0]
    offset, slope = (math.nan, math.nan)
    if contact:
        offset, slope = compliance_lines(zd, apparent, separation, seg_code,
                                         cfg.contact_separation, ev[R.E_CONTACT_Z],
                                         turn.z_end, beta if model == MODEL_BEAM else math.nan)
    if model == MODEL_BEAM:
        min_app, min_app_z = beta * ev[R.E_MIN_THETA], ev[R.E_MIN_THETA_Z]
        spike, spike_t, spike_z = beta * ev[R.E_SPIKE_THETA], ev[R.E_SPIKE_T], ev[R.E_SPIKE_Z]
        if cfg.spike_window == 0.0:         # not asked for: no window, no spike
            spike = spike_t = spike_z = math.nan
    else:
        min_app, min_app_z = ev[R.E_MIN_DEFL], ev[R.E_MIN_DEFL_Z]
        spike = spike_t = spike_z = math.nan
    f = float
    return Events(
        jumped=jumped, jump_in_note=note,
        jump_in_time=f(ev[R.E_JUMP_T]), jump_in_position=f(ev[R.E_JUMP_Z]),
        jump_in_separation=f(ev[R.E_JUMP_H]),
        static_jump_in_position=f(z_s), static_jump_in_separation=f(h_s),
        contact_time=f(ev[R.E_CONTACT_T]), contact_position=f(ev[R.E_CONTACT_Z]),
        pull_off_time=f(ev[R.E_PULL_T]), pull_off_position=f(ev[R.E_PULL_Z]),
        pull_off_force=f(ev[R.E_MIN_FZ]) if contact else math.nan,
        min_deflection=f(ev[R.E_MIN_DEFL]), min_deflection_position=f(ev[R.E_MIN_DEFL_Z]),
        min_apparent_deflection=f(min_app), min_apparent_deflection_position=f(min_app_z),
        spike_height=f(spike), spike_time=f(spike_t), spike_position=f(spike_z),
        hysteresis_offset=f(offset), compliance_slope=f(slope),
        turn_time=f(turn.t_end), turn_position=f(turn.z_end))
