"""Per-run setup of :func:`afmforce.dynamics.simulate`: what a run derives from its
configuration alone (packed model, start state, tolerances, drive plan, the event record's
inputs, the compiled call's records), computed once per configuration and shared by
configurations that differ in friction only (issue 16: a fit step that changes friction
costs 8 us of setup instead of 116 us)."""

from __future__ import annotations

import math

import numpy as np

from .._fields import QUANTITIES
from . import radau as R
from .config import SimulationConfig
from .drive import initial_state, segments
from .guard import _stiff_load_friction
from .load_friction import load_friction_controls
from .models import XI as _XI, ZETA as _ZETA
from .models import MODEL_BEAM, MODEL_IDS, kernel_model, state_size
from .registries import RINGING
from .static import surface_jump_in
from ._params import _beam_fmax, free_frequency_max, parameter_vector

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
#: Drive travel allowed per step: max(HMAX_FRACTION * h, HMAX_TRAVEL * z0).
HMAX_FRACTION = 0.1
HMAX_TRAVEL = 3.0


#: Damping steps only where the contact stiffness -Fs'(h) exceeds this multiple
#: of k: well inside the repulsive wall, away from the pull-off fold (h = z0).
DAMP_KAPPA_RATIO = 100.0


class _Setup:
    """What a run derives from its configuration alone (:func:`_setup`, once per
    configuration): the packed model, start state, tolerances, drive plan, the event
    record's inputs and the compiled call's records. Read-only: runs copy what they change.
    Its attributes are :data:`_FIELDS` (a plain ``__dict__``, not slots: a configuration
    that differs in friction only copies the base's in one call, issue 35.5)."""


#: The attributes of :class:`_Setup`.
_FIELDS = ("model", "kmodel", "n", "p", "y0", "atol", "rtolv", "t_total_max", "dt", "nbuf",
           "averaged", "ev0", "h_s", "z_s", "hmax_dz", "damp_cycles", "term", "f_max",
           "budget", "tolerances", "control", "beta", "k", "beam", "plan", "records",
           "seg_table", "seg_kinds", "seg_columns", "rate",
           # friction-dependent (the rest depends on probe, surface, drive, solver only)
           "vfac_scale", "stiff_load", "vfac")


#: The base _Setup by (probe, surface, drive, solver), and by their ids (-> (parts, base)):
#: a fit or sweep changes one part (e.g. friction) and keeps the others as the same objects
#: or equal ones.
_BASES: dict = {}
_BASES_MAX = 256
#: The friction-dependent fields of a setup by the identity of (base, friction) (-> those
#: and the fields): configurations built from flat names share the default friction, so a
#: short ``simulate(**flat)`` call copies them instead of computing them (~2 us, issue 35.5).
_WITH_FRICTION: dict = {}
_FRICTION_FIELDS = ("p", "vfac_scale", "ev0", "stiff_load", "vfac")


def _setup(cfg: SimulationConfig) -> _Setup:
    """The :class:`_Setup` of ``cfg``, cached on the (immutable) configuration."""
    s = cfg.__dict__.get("_setup")
    if s is not None:
        return s
    probe, surface, drive, solver = parts = (cfg.probe, cfg.surface, cfg.drive, cfg.solver)
    key = tuple(map(id, parts))
    hit = _BASES.get(key)
    if hit is not None and all(a is b for a, b in zip(hit[0], parts)):
        base = hit[1]
    else:
        # equal parts built anew: the same base; flat names (simulate(**flat)) build the
        # drive and solver anew and keep the default probe and surface objects, so those
        # two are matched by identity, without hashing their ~30 fields
        mixed = (id(probe), id(surface), drive, solver)
        hit = _BASES.get(mixed)
        if hit is not None and hit[0][0] is probe and hit[0][1] is surface:
            base = hit[1]
        else:
            base = _BASES.get(parts)
            if base is None:
                base = _base(cfg)
                if len(_BASES) >= _BASES_MAX:
                    _BASES.clear()
                _BASES[parts] = base
            _BASES[mixed] = (parts, base)
        _BASES[key] = (parts, base)
    s = _Setup()
    s.__dict__.update(base.__dict__)        # every base field (_base sets no other)
    friction = cfg.friction
    fkey = (id(base), id(friction))
    hit = _WITH_FRICTION.get(fkey)
    if hit is not None and hit[0] is base and hit[1] is friction:
        s.__dict__.update(hit[2])           # the same (read-only) arrays and values
    else:
        xi, zeta = friction.coefficients
        if s.beam:              # the same values as parameter_vector(cfg) fills in
            s.p = p = base.p.copy()
            p[_XI] = xi
            p[_ZETA] = zeta
        s.vfac_scale, ring_amp = load_friction_controls(cfg)
        s.ev0 = ev = base.ev0.copy()
        ev[R.E_RING_AMP] = ring_amp
        s.stiff_load = _stiff_load_friction(cfg)
        s.vfac = VELOCITY_TOLERANCE_FACTOR * s.vfac_scale
        if len(_WITH_FRICTION) >= _BASES_MAX:
            _WITH_FRICTION.clear()
        _WITH_FRICTION[fkey] = (base, friction, {k: s.__dict__[k] for k in _FRICTION_FIELDS})
    cfg.__dict__["_setup"] = s
    return s


def _base(cfg: SimulationConfig) -> _Setup:
    """The friction-independent part of :func:`_setup` (``p``: friction coefficients 0)."""
    s = _Setup()
    s.model = model = MODEL_IDS[cfg.model]
    s.n = n = state_size(model)
    s.p = p = parameter_vector(cfg.replace(friction="none") if model == MODEL_BEAM else cfg)
    s.kmodel = kernel_model(model, p)       # its type: the paper's terms only, or all
    s.y0 = initial_state(cfg)
    atol = np.full(n, cfg.atol)
    atol[n // 2:] = cfg.atol * 2.0 * math.pi * VELOCITY_ATOL_FREQUENCY
    rtolv = np.full(n, cfg.rtol)
    rtolv[: n // 2] = cfg.rtol * POSITION_RTOL_FACTOR
    s.atol, s.rtolv = atol, rtolv
    s.t_total_max = t_total_max = segments(cfg)[-1].t_end
    s.dt = 1.0 / cfg.sample_rate
    s.nbuf = int(math.floor(t_total_max * cfg.sample_rate * (1.0 + 1e-12))) + 1
    s.averaged = cfg.sampling == "average"
    s.ev0 = ev = np.full(R.E_SIZE, np.nan)
    ev[R.E_IN_CONTACT] = 0.0
    ev[R.E_H_CONTACT] = cfg.contact_separation
    ev[R.E_SPIKE_WINDOW] = cfg.spike_window
    ev[R.E_JUMP_FACTOR] = cfg.jump_factor
    s.h_s, s.z_s, _ = surface_jump_in(cfg.force_constant, cfg.surface)
    ev[R.E_H_STATIC] = s.h_s if math.isfinite(s.h_s) else -math.inf
    s.hmax_dz = HMAX_TRAVEL * cfg.z0
    s.damp_cycles = RINGING[cfg.ringing].damp_cycles
    if cfg.turn_force is not None:
        # the load an instrument triggers on: k z2, not the ringing contact force Fz
        s.term = (R.TERM_DEFLECTION, cfg.turn_force / cfg.force_constant)
    elif cfg.turn_deflection is not None:
        s.term = (R.TERM_DEFLECTION, cfg.turn_deflection)
    else:
        s.term = (R.TERM_NONE, 0.0)
    s.f_max = f_max = (_beam_fmax(cfg.cantilever, cfg.m_joint, cfg.m_base)
                       if model == MODEL_BEAM else free_frequency_max(p, model))
    s.budget = cfg.max_steps if cfg.max_steps is not None else max(   # within max_steps' declared range
        2_000_000, int(min(QUANTITIES["max_steps"].hi, 60.0 * f_max * t_total_max)))
    s.beam = model == MODEL_BEAM
    s.beta = float(cfg.calibration_factor)
    s.k = cfg.force_constant
    s.tolerances = R.tolerance_record(cfg.rtol, rtolv, atol)
    s.control = _control(s, 2**62)
    s.rate = float(cfg.sample_rate)
    s.plan = plan = segments(cfg)          # the plan unless the approach turns at a load
    s.records = [_record(seg) for seg in plan]
    s.records[0] = _record(plan[0], *s.term)
    s.seg_table = _seg_table(plan)
    s.seg_kinds = _seg_kinds(plan)
    s.seg_columns = _seg_columns(s.seg_table)
    return s


def _record(seg, term_kind=R.TERM_NONE, term_level=0.0) -> tuple:
    return R.drive_record(seg.kind, seg.t_start, seg.z_start, seg.velocity, seg.t_end, term_kind,
                          term_level)


def _seg_table(plan) -> np.ndarray:
    """(t_start, z_start, velocity, t_end) of every segment (for the sampled columns)."""
    return np.array([(g.t_start, g.z_start, g.velocity, g.t_end) for g in plan], dtype=float)


def _seg_kinds(plan) -> np.ndarray:
    """The kind of every segment (int8, for the sampled columns)."""
    return np.array([g.kind for g in plan], dtype=np.int8)


def _seg_columns(seg_table) -> tuple:
    """(t_start, z_start, velocity) columns of :func:`_seg_table` (for the sampled columns)."""
    return seg_table[:, 0], seg_table[:, 1], seg_table[:, 2]


def _control(s: _Setup, chunk: int) -> tuple:
    return R.control_record(HMAX_FRACTION, s.hmax_dz, s.damp_cycles, DAMP_KAPPA_RATIO, s.budget,
                            chunk)
