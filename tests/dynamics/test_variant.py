"""The terms beyond the paper's are compiled only where a run uses them (issue 35.5).

The compiled calls get the model id as ``models.PLAIN`` (np.int8) when the packed vector turns
no term beyond the paper's on (double layer, slip, lever drag, lever damping, surface force
laws), and ``models.extras`` is then a compile-time False. These tests check the choice slot by
slot, that ``extras`` is a constant of the argument's type in compiled code, and that the
paper's cycle integrated by the code with every term compiled in (all of them zero) is bitwise
the cycle of the plain code: dropping the zero terms changed no number.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from numba import njit

from afmforce.dynamics import SimulationConfig, simulate
from afmforce.dynamics import models as M
from afmforce.dynamics._params import parameter_vector
from afmforce.dynamics._setup import _setup


@njit(cache=False)
def _extras_of(model):
    return M.extras(model)


def test_extras_is_a_constant_of_the_model_ids_type():
    assert _extras_of(M.PLAIN(1)) is False
    assert _extras_of(1) is True
    assert M.extras(M.PLAIN(0)) is False and M.extras(0) is True     # the Python twin agrees


@pytest.mark.parametrize("changes", [dict(), dict(model="spring"), dict(xi=0.01),
                                     dict(friction="load", zeta=1e13), dict(hamaker=1e-19)])
def test_the_paper_s_terms_only_give_the_plain_id(changes):
    cfg = SimulationConfig(**changes)
    km = _setup(cfg).kmodel
    assert isinstance(km, M.PLAIN) and int(km) == M.MODEL_IDS[cfg.model]


@pytest.mark.parametrize("changes", [
    dict(quality_factor=300.0), dict(quality_factor_2=1e3),
    dict(model="spring", quality_factor=30.0),
    dict(double_layer="weak_overlap", surface_potential=-0.03, debye_length=5e-9),
    dict(slip_length=5e-9), dict(lever_drag=5e-5),
    dict(hydration_pressure=3e7, hydration_length=0.5e-9),
])
def test_any_term_beyond_the_paper_s_gives_the_full_id(changes):
    cfg = SimulationConfig(**changes)
    assert M.uses_extras(parameter_vector(cfg))
    km = _setup(cfg).kmodel
    assert type(km) is int and km == M.MODEL_IDS[cfg.model]


def test_every_slot_beyond_the_paper_s_is_seen():
    p0 = parameter_vector(SimulationConfig())
    assert not M.uses_extras(p0)
    for slot in (M.C00, M.C01, M.C10, M.C11, M.DL_KAPPA, M.SLIP6B, M.LEVER, M.P_LAWS):
        p = p0.copy()
        p[slot] = 1e-3
        assert M.uses_extras(p), slot


@pytest.mark.parametrize("changes", [dict(), dict(model="spring", velocity=10e-6, start=-2e-6,
                                                  turn=100e-9, end=-2e-6)])
def test_plain_and_full_code_give_the_same_paper_cycle_bitwise(changes):
    cfg = SimulationConfig(**changes)
    plain = simulate(cfg)
    assert isinstance(_setup(cfg).kmodel, M.PLAIN)
    full_cfg = SimulationConfig(**changes)
    s = _setup(full_cfg)
    s.kmodel = int(s.kmodel)             # every term compiled in, all of them zero
    full = simulate(full_cfg)
    for f in dataclasses.fields(plain):
        a, b = getattr(plain, f.name), getattr(full, f.name)
        if isinstance(a, np.ndarray):
            assert a.dtype == b.dtype and np.array_equal(a, b, equal_nan=True), f.name
    assert dataclasses.astuple(plain.events) == dataclasses.astuple(full.events)
    assert plain.solver.steps == full.solver.steps
    assert plain.solver.rhs_evaluations == full.solver.rhs_evaluations
