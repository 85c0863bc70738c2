"""Finding 9 of issue 13: the README's own chain, ``afmforce simulate --instrument paper --raw run.txt``
then ``afmforce analyze run.txt``, must not give wrong numbers or wrong verdicts.

The run is the paper's Fig 5 (inclined beam, viscous friction xi = 0.1 kg/s, 0.1 um/s, A = 5e-19 J,
R = 100 nm: A R = 5e-26 J m) recorded by the ``paper`` virtual AFM (fringes, drift, 5 nm detector
steps, photodiode clipped at 150 nm). Friction hides most of the precontact attraction (the
simulation's own summary: minimum apparent deflection -1.04 nm against -1.83 nm of true
deflection), so a static fit cannot give the true A R: the honest answer is the apparent value,
flagged dynamic with its evidence. Before the fix: A R 46 % high, friction "load-proportional" and
"not dynamic". Causes fixed: the retract drift line was fitted on the overdamped relaxation after the
pull-off (1.14 V/s against a true 0.098 V/s: a -42 nm shift of the retract), the position smoothing
kept the detector's 5 nm steps in the last half window before the turn (a bent compliance line),
and the friction test ignored how little the two runs' drift lines fix the drift during contact.
"""

from __future__ import annotations

import json

import pytest

pytest.importorskip("afmforce.dynamics")
pytest.importorskip("afmforce.instrument")

from afmforce.cli.main import main  # noqa: E402

AR_TRUE = 5e-19 * 100e-9  # the Fig 5 beam's A R [J m] (constants.FIG5)
WRONG_FRICTION = ("load-proportional", "opposite", "nonlinear", "pinned")


def _chain(tmp_path, capsys, *extra):
    path = tmp_path / "run.txt"
    assert main(["simulate", "--instrument", "paper", "--seed", "1", *extra, "--raw", str(path)]) == 0
    capsys.readouterr()
    code = main(["analyze", str(path), "--json"])
    out = json.loads(capsys.readouterr().out)
    assert code == 0, out["failed"]
    return path, out["results"][path.name]


def test_readme_chain_is_flagged_dynamic_not_a_wrong_claim(tmp_path, capsys):
    from afmforce.io import load

    path, res = _chain(tmp_path, capsys)
    # the dynamic run is said to be dynamic, with the evidence in the verdict
    assert res["dynamic"] is True and res["dynamic_assessed"] is True
    assert "what the pull-off implies" in res["verdict"]
    # the apparent A R is what a static fit of this run gives: well below the static law (Figs 5-6),
    # and the fit is marked as no static force law
    assert 0 < res["hamaker_radius"] < 0.5 * AR_TRUE
    assert res["details"]["vdw"]["reliable"] is False
    # no false friction class; the reason is given
    assert res["friction"] not in WRONG_FRICTION
    assert res["friction_verdict"].startswith("not assessed") or res["friction"] in ("constant", "undetermined")
    # the retract's drift is not taken from the relaxation tail: the shift of the compliance lines
    # is the detector's backlash (0.87 nm, truth) less the friction offset, not -42 nm
    truth = load(path)[0].metadata
    backlash = 0.866e-9
    lines = res["details"]["shift"]["shift"]    # the lines' offset (the result's shift is null when undetermined)
    assert abs(lines) < backlash + 1e-9, truth.get("truth.backlash_widths")


def test_quasi_static_chain_recovers_the_force_law(tmp_path, capsys):
    """Control: the same chain with xi = 0.001 kg/s (friction negligible) gives A R within 60 % of the
    truth. The tolerance is the baseline's: a 26 nm approach baseline cannot separate the 335 nm
    fringes (amplitude 0.075 V = 1.5 nm) from drift, so the zero of deflection near contact, and with
    it the separation, is uncertain by up to 1.5 nm; over the fitted 4-30 nm that biases A R by up
    to (1 + 1.5 / 6)^2 - 1 = 56 %. (The same fringe slope biases each run's drift rate by up to
    0.1 V/s, which no self-check on a 0.3 s baseline sees: the compliance slopes then differ by 3 %,
    reported as "not parallel ... or the instrument"; a known limit, see docs/analysis.md.)"""
    _, res = _chain(tmp_path, capsys, "--xi", "0.001kg/s")
    assert res["hamaker_radius"] == pytest.approx(AR_TRUE, rel=0.6)
    assert res["dynamic"] is False
    assert res["dynamic_assessed"] is False and res["verdict"].startswith("dynamics not assessed")
