"""Issue 23: a friction verdict that hangs on the lever's missing damping is withheld;
interference fringes shared by the curves of one spot (``fringes="periodic"``).

The null set of the issue: an undamped beam (xi = 0) whose in-contact ringing is recorded
by point samples. The undamped model can explain what is left of the ringing with a small
friction (xi ~ 2e-5 kg/s); with the lever damped at Q = 30 the friction-free model fits as
well, so such a verdict is withheld ("undetermined") and names the quality factor.
"""

from __future__ import annotations

import dataclasses
import json
import math
import warnings

import numpy as np
import pytest

from afmforce.fit import fit_dynamic, virtual_curves
from afmforce.fit.core import base_config
from afmforce.fit.damping_check import CHECK_QUALITY_FACTOR
from afmforce.fit.model import Evaluator
from afmforce.fit.problem import Problem

SPEEDS = (0.5e-6, 1e-6, 2e-6, 5e-6)


def _fit(curves, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return fit_dynamic(curves, "beam", free=("hamaker", "xi"), profile=(), starts=1, **kw)


@pytest.fixture(scope="module")
def undamped_null():
    return _fit(virtual_curves(SPEEDS, seed=1, xi=0.0, sampling="point"), fringes="off")


def test_damping_check_on_the_undamped_null_set(undamped_null):
    """The friction-free model with the lever damped at Q = 30 fits the undamped, point-sampled
    null set as well as the friction model: the check detects no friction (the verdict of the
    fit itself depends on which samples around the jump are left out: with the fit's own masks
    the undamped model "detected" friction at p = 1e-5, with the analysis's masks it does not)."""
    from afmforce.fit.damping_check import damping_check
    from afmforce.fit.uncertainty import fit_nested

    r = undamped_null
    prob, x = r._problem, r._x
    nested = fit_nested(prob, x, prob.ev.curves, prob.ev.base, True, 40)
    chk = damping_check(prob, x, nested, 0.95, max(r.redchi, 1.0))
    assert chk["quality_factor"] == CHECK_QUALITY_FACTOR
    assert chk["p_value"] > 0.05 and not chk["detected"]
    assert chk["chi2_friction"] <= chk["chi2_no_friction"]
    assert chk["friction"]["xi"] < 1e-4                     # truth 0 (real friction: 0.005)
    assert r.friction_detected is not True


def test_friction_standing_in_for_damping_gives_no_verdict(monkeypatch):
    """The wiring: when the damped check finds no friction, the fit withholds its verdict."""
    import afmforce.fit.damping_check as dc

    def no_friction_when_damped(prob, x, nested, level, s2, max_nfev=40):
        return {"quality_factor": 30.0, "chi2_friction": 1.0, "chi2_no_friction": 1.0, "lr": 0.0,
                "p_value": 1.0, "detected": False, "friction": {"xi": 0.0}}

    monkeypatch.setattr(dc, "damping_check", no_friction_when_damped)
    r = _fit(virtual_curves(SPEEDS, seed=1, xi=0.005), fringes="off")
    c = r.comparison
    assert c.p_value < 1e-10 and r.friction_detected is None
    assert c.verdict.startswith("undetermined: friction is detected only in the undamped model")
    assert "(`quality_factor`" in c.verdict and c.verdict in r.warnings    # the key; the CLI renders --quality-factor
    d = json.loads(json.dumps(r.to_dict()))
    assert d["friction_detected"] is None and d["comparison"]["damping_check"]["detected"] is False


def test_real_friction_survives_the_damping_check():
    r = _fit(virtual_curves(SPEEDS, seed=1, xi=0.005), fringes="off")
    chk = r.comparison.damping_check
    assert r.friction_detected is True and chk["detected"] and chk["p_value"] < 1e-10
    assert chk["friction"]["xi"] == pytest.approx(0.005, rel=0.5)


def test_a_given_quality_factor_needs_no_check():
    # with the lever's damping in the model the verdict stands as tested (Q = 30: no friction)
    r = _fit(virtual_curves(SPEEDS, seed=1, xi=0.0, sampling="point"), fringes="off",
             fixed={"quality_factor": 30.0})
    assert r.comparison.damping_check is None and r.friction_detected is False


# --- fringes shared by the curves of one spot ------------------------------------------------
def _curves_with_fringe(amplitude, period=335e-9, phase=1.0):
    cs = virtual_curves((1e-6, 5e-6), seed=3, xi=0.005, noise=0.02e-9, drift_rms=0.0,
                        start=-60e-9, turn=10e-9, end=-230e-9)
    out = []
    for c in cs:   # the fringe runs with the true separation h = z2 - z and stops in contact
        h = np.asarray(c.truth["separation"])
        out.append(dataclasses.replace(c, deflection_signal=np.asarray(c.deflection_signal)
                                       + amplitude * np.cos(2 * math.pi * h / period + phase)))
    return out


def _chi2_at_truth(curves, fringes):
    from afmforce.fit import prepare_curves

    fc = prepare_curves(curves)
    base = base_config("beam", xi=0.005)
    ev = Evaluator(fc, base, "dynamic", True, fringes)
    prob = Problem(ev, ("hamaker",))
    shifts = [c.truth["zero_offset"] for c in curves]
    r = prob.curve_residuals(prob.pack({"hamaker": 5e-19}, shifts))
    return sum(float(x @ x) for x in r) / sum(x.size for x in r), prob


def test_periodic_fringes_absorb_a_shared_fringe():
    # the same curves without the fringe set the bar (reduced chi-square at the truth)
    clean, _ = _chi2_at_truth(_curves_with_fringe(0.0), "off")
    curves = _curves_with_fringe(1e-9)
    off, _ = _chi2_at_truth(curves, "off")
    per, prob = _chi2_at_truth(curves, "periodic")
    par, _ = _chi2_at_truth(curves, "parabola")
    assert off > 2 * clean
    assert per == pytest.approx(clean, rel=0.02)       # two shared nuisances take it all
    assert par == pytest.approx(clean, rel=0.10)       # eight per-curve ones nearly
    assert prob.ev.n_linear() == sum(prob.ev.n_linear(i) for i in range(2)) + 2


def test_periodic_fringes_couple_the_curves_in_the_jacobian():
    # a shared nuisance: moving curve 0's zero changes curve 1's residual (and not without it);
    # the forward-difference column equals a central difference of the residual
    curves = _curves_with_fringe(0.4e-9)
    for fringes, coupled in (("periodic", True), ("off", False)):
        _, prob = _chi2_at_truth(curves, fringes)
        x = prob.pack({"hamaker": 5e-19}, [c.truth["zero_offset"] for c in curves])
        J = prob.jacobian(x)
        n0 = prob.curve_residuals(x)[0].size
        col = J[:, 1]                                  # shift of curve 0
        assert bool(np.abs(col[n0:]).max() > 1e-3) is coupled
        e = np.zeros_like(x)
        e[1] = 0.05
        central = (prob.residual(x + e) - prob.residual(x - e)) / 0.1
        assert np.linalg.norm(col - central) < 0.05 * np.linalg.norm(central)


def test_cli_fringe_options(tmp_path, capsys):
    import sys

    sys.path.insert(0, str(__import__("pathlib").Path(__file__).parent))
    from afmforce.cli.main import main
    from fit_virtual import make_curves, write_curves

    paths = write_curves(make_curves(0.005, seed=3, speeds=(1e-6, 4e-6), spacing=0.5e-9), tmp_path)
    rc = main(["fit", *map(str, paths), "--fringe-period", "400nm", "--no-profile", "--no-compare",
               "--starts", "1", "--json"])
    d = json.loads(capsys.readouterr().out)
    assert rc == 0 and d["fringes"]["mode"] == "periodic"
    assert d["fringes"]["period"] == pytest.approx(4e-7)
    assert 0 <= d["fringes"]["amplitude"] < 3e-9 and d["fringes"]["amplitude_stderr"] > 0
    rc = main(["fit", *map(str, paths), "--fringes", "off", "--no-profile", "--no-compare",
               "--starts", "1", "--json"])
    d = json.loads(capsys.readouterr().out)
    assert rc == 0 and d["fringes"] == {"mode": "off", "period": pytest.approx(3.35e-7),
                                        "amplitude": 0.0, "amplitude_stderr": 0.0}
    with pytest.raises(SystemExit) as e:
        main(["fit", *map(str, paths), "--fringe-period", "-5nm", "--json"])
    out, err = capsys.readouterr()
    assert e.value.code == 2 and "--fringe-period" in json.loads(out)["error"]["message"]
    assert err.count("\n") == 1
