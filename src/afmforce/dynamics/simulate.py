"""``simulate()``: run one dynamic approach-retract cycle."""

from __future__ import annotations

import math
import time
from bisect import bisect_left, bisect_right
import warnings
from typing import Callable

import numpy as np

from ..errors import SolverError
from ..progress import Progress
from . import _helper
from . import radau as R
from .config import SimulationConfig
from .drive import segments
from ._sampling import sample_columns
from .events import Events, fit_compliance
from .guard import lever_damping_check, risky, run_check
from .models import MODEL_BEAM, N_OBS, O_DEFL, O_FY, O_FZ, O_H, O_THETA, O_Y2
from .trajectory import SolverStats, Trajectory
from ._setup import _control, _record, _seg_columns, _seg_kinds, _seg_table, _setup
# re-exported (tests, docs and earlier imports name them here)
from ._setup import (DAMP_KAPPA_RATIO, HMAX_FRACTION, HMAX_TRAVEL,  # noqa: F401
                     POSITION_RTOL_FACTOR, VELOCITY_ATOL_FREQUENCY, VELOCITY_TOLERANCE_FACTOR)
from .load_friction import RING_AMPLITUDE, load_friction_controls  # noqa: F401
from ._params import (H_GUARD_FRACTION, _beam_fmax, _beam_template,  # noqa: F401
                      free_frequency_max, parameter_vector)

__all__ = ["simulate", "DynamicsWarning", "H_GUARD_FRACTION", "VELOCITY_ATOL_FREQUENCY"]

#: First trial step at the start of every drive segment [s].
INITIAL_STEP = 1e-9
#: Steps between progress callbacks.
PROGRESS_CHUNK = 5000
#: Inside the spike window the in-contact ringing is resolved until the running
#: spike maximum has not grown for this many contact-mode cycles (and this long
#: after contact), then damped (issue 16). 10, 30 and 100 give the same spike
#: height on the Fig 5/6 runs to 1e-4 nm (the full 2 ms window: the same again)
#: with 2.5-3.4x fewer steps than resolving the whole window; 30 keeps a margin
#: for a second, later ringing maximum.
SPIKE_QUIET_CYCLES = 30.0
#: ``SolverStats.method``.
METHOD = "Radau IIA (order 5), compiled, analytic Jacobian"


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
    compiled middle one (:meth:`integrate`: one integrator call per drive segment, the
    sampled columns and the compliance fits, all releasing the GIL, with some microseconds
    of Python between them) on several threads while this thread prepares and finishes the others."""

    def __init__(self, cfg: SimulationConfig) -> None:
        self.wall0 = time.perf_counter()
        self.cfg = cfg
        self.setup = s = _setup(cfg)
        n = s.n
        self.y = s.y0.copy()
        self.ev = s.ev0.copy()
        self.ev[R.E_SPIKE_CYCLES] = SPIKE_QUIET_CYCLES   # not cached: tests may patch it
        # the zeroed work arrays as views of two blocks (fewer allocations: a short call's
        # Python, issue 35.5; each view is C-contiguous, as the compiled calls are typed)
        counters = np.zeros(R.S_SIZE + 1, dtype=np.int64)
        self.s_next, self.stats = counters[:1], counters[1:]
        w = R.W_SIZE
        scratch = np.zeros(w + 4 * n + n * n)
        self.work = scratch[:w]
        self.state = (self.y, self.ev, self.work, scratch[w:w + 3 * n].reshape(n, 3),
                      scratch[w + 3 * n:w + 4 * n], scratch[w + 4 * n:].reshape(n, n), self.stats)
        # the sample buffer and the sampled columns, allocated here: simulate_many prepares
        # runs in its own thread and integrates them on others, and large arrays allocated
        # there came back from glibc as fresh pages (a page fault per 4 kB: 0.1 ms and 40 %
        # of the batch's speed-up lost); averaged: sums from 0; point samples: every row up
        # to s_next is written (._sampling.sample_step), so np.empty
        nb = s.nbuf
        self.ybuf = np.zeros((nb, n + 1)) if s.averaged else np.empty((nb, n))
        # time, z, apparent deflection and separation: rows of one block
        f = np.empty((4, nb))
        self.out = (f[0], f[1], np.empty(nb, dtype=np.int8), np.empty((nb, N_OBS)), f[2], f[3])

    def integrate(self, progress=None) -> "_Run":
        """Run the integrator over every drive segment, then sample the result (raises
        :class:`SolverError`)."""
        _helper.start()             # first call, empty numba cache: compile on two cores
        s = self.setup
        ybuf = self.ybuf
        fixed = (s.tolerances, s.control if progress is None else _control(s, PROGRESS_CHUNK),
                 (0.0, s.dt, s.averaged, self.s_next, ybuf), self.state)
        rows = [self._segment(s.records[0], s.t_total_max, progress, fixed, s.plan[0])]
        self.turned_at_load = turned = rows[0][0] == R.TERMINAL
        if turned:
            t_turn = float(self.ev[R.E_TERM_T])
            plan = segments(self.cfg, t_turn, float(s.plan[0].position(t_turn)))
            records = [_record(seg) for seg in plan]
            seg_table = _seg_table(plan)
        else:
            plan, records, seg_table = s.plan, s.records, s.seg_table
        t_total = plan[-1].t_end
        for j in range(1, len(plan)):
            rows.append(self._segment(records[j], t_total, progress, fixed, plan[j]))
        if progress is not None:
            progress(Progress(done=t_total, total=t_total, unit="s", what="simulate"))
        self.t_turn, self.z_turn = plan[0].t_end, plan[0].z_end
        self.columns = self._sample(ybuf, plan, rows, seg_table)
        return self

    def _sample(self, ybuf, plan, rows, seg_table) -> tuple:
        """The sampled columns and compliance lines (two compiled calls that release the
        GIL, writing into the buffers of ``__init__``): ``(time, z, segment code,
        observables, apparent deflection, apparent
        separation, all finite, hysteresis offset, compliance slope)``."""
        s = self.setup
        if s.averaged:
            # every grid time up to the end; windows at the ends are clipped to the run
            n_samp = min(s.nbuf, int(math.floor(plan[-1].t_end * s.rate * (1.0 + 1e-12))) + 1)
            bounds = [seg.t_end for seg in plan[:-1]]
            sample_seg = np.searchsorted(np.asarray(bounds), np.arange(n_samp) * s.dt,
                                         side="left")
            labels = [(int(np.searchsorted(sample_seg, i)),
                       int(np.searchsorted(sample_seg, i, side="right")), seg.kind)
                      for i, seg in enumerate(plan)]
        else:
            n_samp = int(self.s_next[0])
            labels = None                       # built from rows where a fit needs them
            lab = np.array(rows, dtype=np.int64)[:, 1:]
        if labels is not None:
            lab = np.array(labels, dtype=np.int64)
        if seg_table is s.seg_table:        # the plan of the setup (not turned at a load)
            kinds, columns = s.seg_kinds, s.seg_columns
        else:
            kinds, columns = _seg_kinds(plan), _seg_columns(seg_table)
        finite = sample_columns(s.kmodel, s.p, ybuf, n_samp, s.averaged, s.dt, lab[:, 0],
                                lab[:, 1], kinds, *columns, s.beam, s.beta, *self.out)
        # the first n_samp rows; a copy where they are well short of the buffer (a run
        # that turned early at a load), so that the trajectory does not hold the rest
        tt, zd, code, obs, apparent, apparent_sep = self.out
        if 4 * n_samp < 3 * s.nbuf:
            tt, zd, code, obs, apparent, apparent_sep = [a[:n_samp].copy() for a in self.out]
        elif n_samp < s.nbuf:
            tt, zd, code, obs, apparent, apparent_sep = [a[:n_samp] for a in self.out]
        offset = slope = math.nan
        if finite and math.isfinite(self.ev[R.E_CONTACT_T]):
            if labels is None:
                labels = [(a, b, seg.kind) for (_, a, b), seg in zip(rows, plan)]
            z_c = float(self.ev[R.E_CONTACT_Z])
            a, b = _rows_between(zd, labels, plan, z_c, self.z_turn)
            offset, slope = fit_compliance(zd[a:b], apparent[a:b], obs[a:b, O_H], code[a:b],
                                           self.cfg.contact_separation, z_c, self.z_turn,
                                           s.beta if s.beam else math.nan)
        return tt, zd, code, obs, apparent, apparent_sep, finite, offset, slope

    def _segment(self, record, t_total, progress, fixed, seg):
        """Integrate one drive segment (``record``: its :func:`.radau.drive_record`); returns
        (status, first sample, end sample)."""
        work, s_next = self.work, self.s_next
        work[R.W_T] = seg.t_start
        work[R.W_H] = INITIAL_STEP
        work[R.W_H_OLD] = 0.0
        work[R.W_ERR_OLD] = 0.0
        work[R.W_HAS_SOL] = 0.0
        work[R.W_HAVE_JAC] = 0.0
        work[R.W_VFAC] = self.setup.vfac
        first = int(s_next[0])
        args = (self.setup.kmodel, self.setup.p, record) + fixed
        while True:
            status = R.integrate_segment(*args)
            if status == R.PAUSED:
                progress(Progress(done=min(float(work[R.W_T]), t_total), total=t_total, unit="s",
                                  what="simulate"))
                continue
            break
        if status < 0:
            self._raise(status, seg, t_total)
        return status, first, int(s_next[0])

    def _raise(self, status, seg, t_total):
        t = self.work[R.W_T]
        where = (f"at t = {t:.6g} s, z = {seg.position(t) * 1e9:.4g} nm in the "
                 f"{('approach', 'retract', 'dwell')[seg.kind]} after {self.stats[R.S_STEPS]} steps")
        if status == R.MAX_STEPS:
            advice = (f"the step budget max_steps = {self.setup.budget} is spent; raise max_steps "
                      f"(this run follows modes up to {self.setup.f_max / 1e3:.3g} kHz over "
                      f"{t_total:.4g} s; a tighter rtol/atol needs more steps, not fewer)")
        else:
            advice = "a tighter rtol/atol may get past it"
        raise SolverError(f"integration failed ({R.STATUS[status]}) {where}; {advice}")

    def finish(self, check: str = "off", wall0: float | None = None) -> Trajectory:
        """The trajectory, events, warnings and convergence check of an integrated run."""
        cfg, s, ev, stats = self.cfg, self.setup, self.ev, self.stats
        tt, zd, seg_code, obs, apparent, apparent_sep, finite, offset, slope = self.columns
        if not finite:
            raise SolverError("the sampled trajectory contains non-finite values; "
                              "try a tighter rtol/atol")
        beta = s.beta
        why = _risky(cfg) if check == "off" else ""
        deflection = obs[:, O_DEFL]
        angle = obs[:, O_THETA] if s.beam else np.full(tt.shape[0], np.nan)
        events = _events(cfg, ev, self.t_turn, self.z_turn, beta, s.model, offset, slope,
                         s.h_s, s.z_s)
        if not math.isfinite(events.contact_time):
            warnings.warn(
                f"the approach never reached contact (h < {cfg.solver.contact_separation * 1e9:.3g} "
                f"nm) before turning at z = {events.turn_position * 1e9:.4g} nm; raise turn",
                DynamicsWarning, stacklevel=3)
        elif ev[R.E_IN_CONTACT] == 1.0:
            warnings.warn(
                f"the retract ended in contact at z = {cfg.end * 1e9:.4g} nm (no pull-off); "
                "lower end" + (f"; or, with this little damping ({why}), the solve lost the "
                               "energy of a probe that bounces in contact: run with "
                               "check='auto' to find out" if why else ""),
                DynamicsWarning, stacklevel=3)
        if s.term[0] != R.TERM_NONE and not self.turned_at_load:
            what = "turn_force" if cfg.turn_force is not None else "turn_deflection"
            warnings.warn(f"{what} was not reached before the turn limit "
                          f"z = {cfg.turn * 1e9:.4g} nm; turned there", DynamicsWarning,
                          stacklevel=3)

        def _resolve(tight):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                return simulate(tight).events

        if check == "off" and not s.stiff_load:
            # unchecked: say so, and why a check would matter where the regime is risky
            event_errors, check_note = {}, "not checked" + (
                f" (risky regime: {why}; check='auto' compares a 10x tighter solve)" if why else "")
        else:
            event_errors, check_note = run_check(check, cfg, events, _resolve)
            check_note += lever_damping_check(check, cfg, events, _resolve)   # issue 23
        wall = time.perf_counter() - (self.wall0 if wall0 is None else wall0)
        st = stats.tolist()
        solver = _frozen(SolverStats, {
            "status": "success", "method": METHOD, "steps": st[R.S_STEPS], "accepted": st[R.S_ACCEPTED],
            "rejected": st[R.S_REJECTED], "rhs_evaluations": st[R.S_NFEV],
            "jacobian_evaluations": st[R.S_NJEV], "lu_decompositions": st[R.S_NLU],
            "damping_steps": st[R.S_DAMPED], "newton_failures": st[R.S_NEWTON_FAIL],
            "wall_time": wall, "event_errors": event_errors, "check": check_note})
        return _frozen(Trajectory, {
            "time": tt, "piezo_position": zd, "deflection": deflection, "apparent_deflection": apparent,
            "separation": obs[:, O_H], "apparent_separation": apparent_sep, "angle": angle,
            "lateral_position": obs[:, O_Y2], "normal_force": obs[:, O_FZ], "friction_force": obs[:, O_FY],
            "segment": seg_code, "calibration_factor": s.beta, "spring_constant": s.k, "config": cfg,
            "events": events, "solver": solver})


#: risky() by the identity of (probe, surface, friction), what it reads (-> those and it).
_WHY: dict = {}


def _risky(cfg) -> str:
    """:func:`.guard.risky` of ``cfg``, once per (probe, surface, friction) objects (2 us of a
    short call, issue 35.5; configurations built from flat names share the default parts)."""
    probe, surface, friction = cfg.probe, cfg.surface, cfg.friction
    key = (id(probe), id(surface), id(friction))
    hit = _WHY.get(key)
    if hit is not None and hit[0] is probe and hit[1] is surface and hit[2] is friction:
        return hit[3]
    why = risky(cfg)
    if len(_WHY) >= 256:
        _WHY.clear()
    _WHY[key] = (probe, surface, friction, why)
    return why


def _neg(x):
    return -x


def _rows_between(zd, labels, plan, lo, hi) -> tuple[int, int]:
    """The rows ``[a, b)`` that hold every sample with ``lo <= z <= hi`` of the approach and
    retract segments (``labels``: their rows; ``z`` is monotone along a segment, so
    bisection finds them): the compliance fits read samples in ``[contact, turn]`` only, and
    reading these rows instead of all (Fig 5: ~4,600 of 31,001) gives the same sums in the
    same order, bitwise (issue 35.5)."""
    a, b = len(zd), 0
    for (first, last, kind), seg in zip(labels, plan):
        if kind == R.DWELL or last <= first:
            continue
        if seg.velocity > 0.0:
            i, j = bisect_left(zd, lo, first, last), bisect_right(zd, hi, first, last)
        elif seg.velocity < 0.0:
            i = bisect_left(zd, -hi, first, last, key=_neg)
            j = bisect_right(zd, -lo, first, last, key=_neg)
        else:
            i, j = first, last
        if j > i:
            a, b = min(a, i), max(b, j)
    return (a, b) if b > a else (0, 0)


def _nan1(x) -> float:
    """``float(x)``, every NaN the one ``math.nan``."""
    x = float(x)
    return x if x == x else math.nan


def _events(cfg, ev, t_turn, z_turn, beta, model, offset, slope, h_s, z_s) -> Events:
    # Python floats (the same values), read once; every NaN is the one math.nan, so that
    # events of identical runs compare equal (dataclass == compares fields by identity first)
    nan = math.nan
    e = [x if x == x else nan for x in ev.tolist()]
    jump_t, jump_z, jump_h = e[R.E_JUMP_T], e[R.E_JUMP_Z], e[R.E_JUMP_H]
    contact_t, fast_t = e[R.E_CONTACT_T], e[R.E_FAST_T]
    min_defl, min_defl_z = e[R.E_MIN_DEFL], e[R.E_MIN_DEFL_Z]
    spike_t, spike_z = e[R.E_SPIKE_T], e[R.E_SPIKE_Z]
    contact = math.isfinite(contact_t)
    left = math.isfinite(jump_t)
    fast = math.isfinite(fast_t) and (not contact or fast_t <= contact_t)
    solver = cfg.solver
    if not contact:
        jumped, note = None, "no contact: the approach turned before the surfaces touched"
    else:
        where = (f"left the static branch (h < h_s = {h_s * 1e9:.4g} nm) at "
                 f"z = {jump_z * 1e9:.4g} nm; static instability at z = {z_s * 1e9:.4g} nm"
                 if left else "")
        if fast:
            jumped, note = True, f"jump-in: {where}; then dh/dt < -{solver.jump_factor:g} dz/dt"
        else:
            jumped, note = False, ("no jump: crept into contact (dh/dt never fell below "
                                   f"-{solver.jump_factor:g} dz/dt before contact)"
                                   + (f"; {where}" if left else ""))
    if model == MODEL_BEAM:
        min_app, min_app_z = _nan1(beta * e[R.E_MIN_THETA]), e[R.E_MIN_THETA_Z]
        if solver.spike_window == 0.0:      # not asked for: no window, no spike
            spike = spike_t = spike_z = nan
        else:
            spike = _nan1(beta * e[R.E_SPIKE_THETA])
    else:
        min_app, min_app_z = min_defl, min_defl_z
        spike = spike_t = spike_z = nan
    return _frozen(Events, {
        "jumped": jumped, "jump_in_note": note,
        "jump_in_time": jump_t, "jump_in_position": jump_z, "jump_in_separation": jump_h,
        "static_jump_in_position": _nan1(z_s), "static_jump_in_separation": _nan1(h_s),
        "contact_time": contact_t, "contact_position": e[R.E_CONTACT_Z],
        "pull_off_time": e[R.E_PULL_T], "pull_off_position": e[R.E_PULL_Z],
        "pull_off_force": e[R.E_MIN_FZ] if contact else nan,
        "min_deflection": min_defl, "min_deflection_position": min_defl_z,
        "min_apparent_deflection": min_app, "min_apparent_deflection_position": min_app_z,
        "spike_height": spike, "spike_time": spike_t, "spike_position": spike_z,
        "hysteresis_offset": _nan1(offset), "compliance_slope": _nan1(slope),
        "turn_time": _nan1(t_turn), "turn_position": _nan1(z_turn)})


def _frozen(cls, fields: dict):
    """``cls(**fields)`` of a frozen dataclass without ``__post_init__`` (Events,
    SolverStats, Trajectory; every field given), without its generated ``__init__``,
    which sets each field through ``object.__setattr__`` (14 us for the 23 of Events)."""
    obj = object.__new__(cls)
    obj.__dict__.update(fields)
    return obj
