"""The web fit takes a lever mass typed in its form, as ``afmforce fit --mass`` does (fitwalk found
``web/tasks.py`` passing ``lever=`` but not ``mass=``: a form's mass was replaced by the files' resonance).
One declaration (:func:`afmforce.fit.core.lever_sources`) serves both faces."""
from __future__ import annotations

import afmforce.fit as fit_pkg
from afmforce.fit.core import LEVER_FIELDS, MASS_FIELDS, lever_sources
from afmforce.web import tasks


def test_lever_sources_model_only_where_given():
    assert lever_sources(()) == {"lever": "file", "mass": "file"}
    assert lever_sources(["hamaker", "xi"]) == {"lever": "file", "mass": "file"}
    for n in LEVER_FIELDS:
        assert lever_sources([n]) == {"lever": "model", "mass": "file"}
    for n in MASS_FIELDS:
        assert lever_sources([n]) == {"lever": "file", "mass": "model"}


def test_the_web_fit_passes_a_given_mass_on(monkeypatch):
    seen = {}

    class Stop(Exception):
        pass

    def fake_fit(curves, model, **kw):
        seen.update(kw)
        raise Stop

    monkeypatch.setattr(fit_pkg, "fit_dynamic", fake_fit)
    monkeypatch.setattr(fit_pkg, "virtual_curves", lambda velocities, **kw: [object()] * len(velocities))
    for truth, want in (({"mass": 2e-11}, ("file", "model")), ({"B": 5e-13}, ("model", "file")),
                        ({}, ("file", "file"))):
        seen.clear()
        try:
            tasks.fit_task({"truth": dict(truth, model="spring") if "mass" in truth else truth,
                            "velocities": [1e-6, 1e-5]}, lambda *a, **k: None)
        except Stop:
            pass
        assert (seen["lever"], seen["mass"]) == want, truth
