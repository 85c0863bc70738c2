"""The web's simulate form and its OpenAPI schema offer the words each text field's declaration
accepts (dynamics.config.FlatName.choices): geometry and the double layer's forms too (the form
once offered only their defaults)."""

import pytest

pytest.importorskip("fastapi")


def test_simulate_form_and_openapi_offer_the_declared_choices():
    from afmforce import forces
    from afmforce.dynamics import FRICTION_LAWS, MODELS, RINGING, SAMPLING
    from afmforce.dynamics.config import FLAT
    from afmforce.web.openapi import config_schema
    from afmforce.web.schema import simulation_fields

    form = {d["name"]: d for d in simulation_fields()}
    api = config_schema()["properties"]
    want = {"model": MODELS, "friction": FRICTION_LAWS, "ringing": RINGING, "sampling": SAMPLING,
            "geometry": forces.GEOMETRIES, "double_layer": forces.DOUBLE_LAYERS}
    text = {n for n, w in FLAT.items() if w.spec is None}
    assert text == set(want)
    for name, registry in want.items():
        assert form[name]["kind"] == "choice" and form[name]["choices"] == list(registry), name
        assert api[name]["enum"] == sorted(registry) and form[name]["default"] == api[name]["default"], name
        assert form[name]["default"] in registry
