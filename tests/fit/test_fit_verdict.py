"""Issue 23: no friction verdict on curves no model describes; nested chi-squares ordered;
the measured piezo channel of the virtual AFM's ``typical`` instrument.

The curves no model describes: virtual beam curves whose contact is made soft after the
fact (the deflection follows the position with slope 0.8 in contact; the model's
surfaces are rigid, eq 2), fitted with friction free.
"""

from __future__ import annotations

import dataclasses
import json
import warnings

import numpy as np
import pytest

from afmforce.dynamics import simulate
from afmforce.fit import fit_dynamic, prepare_curves
from afmforce.instrument import build_instrument

from fit_virtual import make_curves


def _soften(c, slope=0.8):
    """The curve with its approach contact line tilted to ``slope`` (a deformable sample)."""
    y = np.asarray(c.deflection_signal, float).copy()
    z = np.asarray(c.truth["piezo_position"])
    inc = (np.asarray(c.truth["separation"]) < 0.3e-9) & (np.asarray(c.segment) == 0)
    y[inc] -= (1.0 - slope) * (z[inc] - z[inc][0])
    return dataclasses.replace(c, deflection_signal=y)


@pytest.fixture(scope="module")
def soft_fit():
    curves = [_soften(c) for c in make_curves(0.005, seed=4, speeds=(1e-6, 5e-6),
                                               spacing=0.5e-9)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return fit_dynamic(curves, "beam", free=("hamaker", "xi"), profile=(), noise="white",
                           starts=1)


def test_no_verdict_when_no_model_describes_the_curves(soft_fit):
    r = soft_fit
    assert r.redchi > 20 * r.adequacy["threshold"] and not r.adequacy["adequate"]
    assert r.friction_detected is None
    d = json.loads(json.dumps(r.to_dict()))
    assert d["friction_detected"] is None and d["comparison"]["friction_detected"] is None
    v = r.comparison.verdict
    assert v.startswith(f"undetermined: the model does not describe the data (reduced chi-square "
                        f"{r.redchi:.3g}")
    assert d["verdict"] == v
    # the worst curve is the slow one (more contact samples), its misfit in contact, at z > 0
    worst = r.adequacy["worst"][0]
    assert worst.startswith("curve 1:") and "in contact" in worst
    hi = float(worst.split(" to ")[1].split(" nm")[0])
    assert hi > 3.0
    assert "does not describe the data" in r.markdown()
    # what to check: the misfit sits in contact (the tilted contact line)
    from afmforce.fit.adequacy import ADVICE

    assert r.adequacy["advice"] == ADVICE["contact"] and v.endswith(ADVICE["contact"])
    # the shared fringe terms could take up the tilted contact line with each curve's drift
    # (a 10 nm "fringe"): refused as fringes, the fit went on without them
    assert r.fringes["mode"] == "off"
    assert any(w.startswith("the fitted interference fringes") for w in r.warnings)


def test_nested_chi_squares_are_ordered(soft_fit):
    c = soft_fit.comparison.chi2
    assert c["dynamic, friction"] <= c["dynamic, no friction"]
    assert c["dynamic, friction"] == pytest.approx(soft_fit.chi2, rel=1e-12)


def test_fit_takes_the_measured_piezo_channel():
    # typical instrument: 10 % piezo hysteresis and creep; the sensor has 0.1 nm steps, 0.05 nm noise
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        tr = simulate(velocity=2e-6, xi=0.005, sampling="average", start=-30e-9, turn=10e-9,
                      end=-60e-9)
    raw = build_instrument("typical").record(tr, seed=3)
    fc = prepare_curves([raw])[0]
    app = np.asarray(raw.segment) == 0
    z_true = np.asarray(raw.truth["piezo_position"])[app]
    assert fc.metadata["position_channel"] == "measured"
    assert fc.velocity == pytest.approx(2e-6, rel=2e-3)
    assert np.max(np.abs(fc.position - z_true)) < 0.1e-9      # the drive line, sensor noise removed
    nominal = np.asarray(raw.piezo_nominal)[app]
    assert np.max(np.abs(nominal - z_true)) > 2e-9            # what the nominal channel would give
    # the static guess of the zero of position: from the measured channel, within 0.3 nm
    assert abs(fc.guess["shift"]) < 0.3e-9


def test_residual_figure_per_curve(soft_fit, tmp_path):
    from afmforce.fit.figures import plot_residuals

    p = plot_residuals(soft_fit, soft_fit._problem.ev.curves, tmp_path / "res.png")
    assert p.exists() and p.stat().st_size > 10_000
