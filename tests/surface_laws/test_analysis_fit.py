"""The analysis' fit of a surface force law to a static force curve
(afmforce.analysis.surface_law_fit), for every law of the registry with its record's example."""

import math

import numpy as np
import pytest

from afmforce import surface_laws as L
from afmforce.analysis.surface_law_fit import fit_surface_law
from afmforce.errors import ParameterError

R = 1e-6


def _window(name, v):
    """Separations where the law acts: from 1/80 to 1/8 of its reach (and, for brushes, the
    exponential form's validity)."""
    if name == "steric":
        return np.linspace(0.2, 0.9, 200) * v["brush_length"]
    if name == "van_der_waals":          # eq 2: the soft wall acts within a few z0
        return np.linspace(0.7, 6.0, 200) * v["z0"]
    return np.linspace(1 / 80, 1 / 8, 200) * L.law(name).reach(v)


#: The meniscus force is linear in h: an offset would trade against its value at contact.
OFFSET = {"capillary": 0.0}


@pytest.mark.parametrize("name", list(L.LAWS))
def test_fit_recovers_the_example_parameters(name):
    rec = L.law(name)
    true = {**{p.name: p.default for p in rec.parameters}, **rec.example}
    h = _window(name, true)
    f_true = np.asarray(rec.force(h, R, true)[0])
    sigma = 1e-3 * float(np.max(np.abs(f_true)))
    rng = np.random.default_rng(7)
    c0 = OFFSET.get(name, 3e-12)
    f = f_true + rng.normal(0.0, sigma, h.size) + c0          # and an offset
    free = [p.name for p in rec.parameters if p.fit is not None]
    start = {n: true[n] * 0.8 for n in free}
    fit = fit_surface_law(h, f, name, radius=R, geometry="sphere-flat", free=free,
                          fixed={**true, **start}, sigma=sigma, offset=name not in OFFSET)
    assert fit.note == "" and fit.redchi == pytest.approx(1.0, abs=0.3)
    for n in free:
        assert abs(fit.values[n] - true[n]) < 4 * fit.stderr[n], n
        assert fit.stderr[n] < 0.05 * abs(true[n]), n
    assert fit.offset == pytest.approx(c0, abs=5 * sigma / math.sqrt(h.size))


def test_a_parameter_the_data_do_not_see_is_undetermined():
    # a brush's force far beyond its reach says nothing about the brush
    rec = L.law("steric")
    v = {**{p.name: p.default for p in rec.parameters}, **rec.example}
    h = np.linspace(20, 30, 50) * v["brush_length"]
    f = np.random.default_rng(1).normal(0, 1e-12, h.size)
    fit = fit_surface_law(h, f, "steric", radius=R, free=["brush_spacing"], fixed=v)
    assert math.isnan(fit.values["brush_spacing"]) and "brush_spacing" in fit.note
    with pytest.raises(ParameterError, match="steric"):
        fit_surface_law(h, f, "steric", radius=R, free=["hydration_length"])
