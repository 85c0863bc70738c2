"""The convergence guard (``afmforce.dynamics.guard``): which run a flagged result should
trust, with the numbers behind it."""

from __future__ import annotations

import math
import warnings
from types import SimpleNamespace

import pytest

from afmforce.dynamics import ConvergenceWarning, SimulationConfig, simulate
from afmforce.dynamics.guard import EVENT_TOLERANCES, run_check
from afmforce.errors import SolverError

nm = 1e-9
#: an undamped spring probe (1 ug, R 220 nm, 7.2 um/s): it bounces in contact
BOUNCING = dict(model="spring", mass=1e-9, radius=220e-9, velocity=7.2e-6)


def _events(**kw):
    ev = {name: math.nan for name in EVENT_TOLERANCES}
    ev.update(kw)
    return SimpleNamespace(**ev)


def _check(default, tight, tighter, check="always"):
    cfg = SimulationConfig(**BOUNCING)
    runs = iter([tight, tighter])
    asked = []

    def resolve(c):
        asked.append((c.rtol, c.atol))
        return next(runs)

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        errors, note = run_check(check, cfg, default, resolve)
    msgs = [str(w.message) for w in caught if issubclass(w.category, ConvergenceWarning)]
    return errors, note, msgs, asked, cfg


def test_converged_run_is_solved_once_more_only():
    e = _events(pull_off_position=20 * nm, pull_off_force=-10 * nm)
    errors, note, msgs, asked, cfg = _check(e, _events(pull_off_position=20.1 * nm,
                                                       pull_off_force=-10.05 * nm), None)
    assert msgs == [] and "NOT" not in note
    assert asked == [(cfg.rtol / 10, cfg.atol / 10)]
    assert errors["pull_off_position"] == pytest.approx(0.1 * nm)


def test_flagged_run_says_to_use_the_tighter_run_when_that_one_is_converged():
    default = _events(pull_off_force=-56 * nm)
    tight, tighter = _events(pull_off_force=-10 * nm), _events(pull_off_force=-10.02 * nm)
    errors, note, msgs, asked, cfg = _check(default, tight, tighter)
    assert asked == [(cfg.rtol / 10, cfg.atol / 10), (cfg.rtol / 100, cfg.atol / 100)]
    (msg,) = msgs
    assert "pull_off_force -56 vs -10 vs -10.02 nN" in msg
    assert "agrees with the 100x tighter one: use it" in msg
    assert "NOT converged: pull_off_force; the 10x tighter run is" in note
    assert errors["pull_off_force"] == pytest.approx(46 * nm)


def test_flagged_run_says_when_the_tighter_run_is_not_converged_either():
    default = _events(pull_off_force=-56 * nm, hysteresis_offset=-0.46 * nm)
    tight = _events(pull_off_force=-10 * nm, hysteresis_offset=-0.46 * nm)
    tighter = _events(pull_off_force=-18 * nm, hysteresis_offset=-0.46 * nm)
    _, note, msgs, _, _ = _check(default, tight, tighter)
    (msg,) = msgs
    assert "not converged either (pull_off_force moved again" in msg
    assert "free-mode damping ratio 0" in msg          # the regime, as risky() found it
    assert "nor at 10x tighter: pull_off_force" in note
    with pytest.raises(SolverError, match="not converged either"):
        _check(default, tight, tighter, check="raise")


def test_bouncing_spring_is_not_converged_at_any_of_the_three_tolerances():
    """The real run: check='auto' flags it and says the 10x tighter run moved again; the
    three solves, run here on their own, differ as the message says."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        tr = simulate(**BOUNCING, check="auto")
    msgs = [str(w.message) for w in caught if issubclass(w.category, ConvergenceWarning)]
    assert len(msgs) == 1 and "not converged either" in msgs[0]
    cfg = tr.config
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        runs = [simulate(cfg.replace(rtol=cfg.rtol / f, atol=cfg.atol / f)).events
                for f in (10, 100)]
    moved = abs(runs[0].pull_off_force - runs[1].pull_off_force)
    assert moved > EVENT_TOLERANCES["pull_off_force"][0]
    assert moved > EVENT_TOLERANCES["pull_off_force"][1] * abs(runs[1].pull_off_force)
    assert "pull_off_force" in tr.solver.check.split("nor at 10x tighter:")[1]


def test_no_pull_off_warning_of_an_unchecked_bouncing_run_points_to_the_check():
    """The default solve of the bouncing spring settles it in contact (no pull-off, while
    tighter solves pull off at the turn): unchecked, the warning names that possibility."""
    with pytest.warns(Warning) as caught:
        tr = simulate(**BOUNCING)
    assert math.isnan(tr.events.pull_off_position)
    (msg,) = [str(w.message) for w in caught if "ended in contact" in str(w.message)]
    assert "check='auto'" in msg and "free-mode damping ratio 0" in msg
    tight = simulate(**BOUNCING, rtol=1e-7, atol=1e-15).events
    assert tight.pull_off_position == pytest.approx(20e-9, abs=0.5e-9)   # off at the turn


def test_an_unchecked_run_says_whether_its_regime_is_risky():
    """check='off' (the library default): the solver's note and the summary say "not
    checked", with the reason a check would matter where the regime is risky (the spring:
    free-mode damping ratio 0), and nothing more where it is not (Fig 5's beam); the free
    mode (an eigenproblem) is cached per probe."""
    from afmforce.dynamics import DynamicsWarning, SimulationConfig, simulate
    from afmforce.dynamics.guard import _free_mode, damping_ratio, risky

    with pytest.warns(DynamicsWarning, match="never reached contact"):     # a short run
        spring = simulate(model="spring", start=-40e-9, turn=-35e-9, end=-40e-9, velocity=1e-6)
    assert spring.solver.check.startswith("not checked (risky regime: free-mode damping ratio 0")
    assert spring.summary()["solver"]["check"] == spring.solver.check
    fig5 = SimulationConfig()
    assert risky(fig5) == "" and simulate(fig5).solver.check == "not checked"
    first = damping_ratio(fig5)
    hits = _free_mode.cache_info().hits
    assert all(damping_ratio(fig5) == first for _ in range(5))   # the eigenproblem once
    assert _free_mode.cache_info().hits == hits + 5
