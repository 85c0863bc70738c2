"""The figure of a soft curve shows force against indentation with the modulus fit (issue 26, item 5)."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

from afmforce.analysis.options import IndentationOptions
from afmforce.analysis.pipeline import analyze
from afmforce.io import load
from afmforce.plotting import plot_indentation, plot_summary

GEL = Path(__file__).resolve().parents[1] / "data" / "bruker-nanoscope_PyFMlab_Egel4_00025.spm"


def test_summary_figure_of_a_soft_curve_has_the_indentation_fit():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        curve = load(GEL)[0]
    res = analyze(curve, steps=["indentation"], options=[IndentationOptions(tip_radius=5e-6)])
    fig = plot_summary(res, curve)
    ax = next(a for a in fig.axes if a.get_xlabel() == "indentation [µm]")
    data, fit = ax.lines[0], ax.lines[1]
    fit_info = res.details["indentation"]
    # the fitted line is the model through the data: E with its interval in the legend
    assert "E = 0.4388 kPa" in fit.get_label() and "hertz_paraboloid" in fit.get_label()
    x, y = fit.get_data()
    expected = 4 / 3 * res.youngs_modulus / 0.75 * np.sqrt(5e-6) * np.clip(x * 1e-6, 0, None) ** 1.5 * 1e9
    assert np.allclose(y, expected, rtol=1e-9, atol=1e-9)
    assert np.asarray(data.get_xdata()).size == fit_info.n_points
    assert abs(np.asarray(data.get_ydata()).max() - 3.3) < 0.3  # nN: the gel pushes back ~3 nN


def test_figure_says_why_without_a_fit():
    curve = load(Path(__file__).resolve().parents[1] / "data" / "asylum-mfp3d_SiN-tip_air.ibw")[0]
    res = analyze(curve, steps=["indentation"], options=[IndentationOptions(tip_radius=20e-9)])
    ax = plot_indentation(res)
    assert "hard contact" in ax.texts[0].get_text()
