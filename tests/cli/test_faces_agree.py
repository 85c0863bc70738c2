"""Choices and defaults the command line shows are the records' (style: declare once, derive every
face): the surfaces' geometry and double-layer forms of ``simulate`` (the configuration's fields,
the double layer's law record) and the liquid step's short flags of ``analyze`` (its options record)."""

import dataclasses

import pytest

from afmforce import forces
from afmforce.cli.main import build_parser


def _actions(command):
    return {a.dest: a for a in build_parser(command)._subparsers._group_actions[0].choices[command]._actions}


def _help(action):
    return action.help + (action.lazy_help() if hasattr(action, "lazy_help") else "")


def test_simulate_surface_choices_are_the_configurations():
    from afmforce.dynamics.parts import Surface
    from afmforce.surface_laws import law

    fields = {f.name: f for f in dataclasses.fields(Surface)}
    flags = _actions("simulate")
    switch = law("double_layer").switch
    for name, registry in (("geometry", forces.GEOMETRIES), ("double_layer", forces.DOUBLE_LAYERS)):
        assert tuple(flags[name].choices) == tuple(registry) == tuple(fields[name].metadata["choices"]), name
        assert f"(default {fields[name].default})" in _help(flags[name]), name
    assert fields["double_layer"].default == switch.default and tuple(switch.choices) == tuple(forces.DOUBLE_LAYERS)


@pytest.mark.parametrize("name", ["medium", "geometry", "double_layer"])
def test_analyze_liquid_flags_are_the_steps_options(name):
    from afmforce.analysis.options import LiquidOptions

    field = {f.name: f for f in dataclasses.fields(LiquidOptions)}[name]
    flag = _actions("analyze")[name]
    assert tuple(flag.choices) == tuple(field.metadata["choices"])
    assert f"default {field.default})" in _help(flag)
    if name == "double_layer":        # the fit chooses among the laws that exert a force
        assert set(flag.choices) == set(forces.DOUBLE_LAYERS) - {"none"}
    if name == "geometry":
        assert set(flag.choices) == set(forces.GEOMETRIES)


def test_analyze_channel_is_the_curves():
    from afmforce.io.curve import POSITION_CHANNELS

    flag = _actions("analyze")["channel"]
    assert tuple(flag.choices) == POSITION_CHANNELS and flag.default == "auto"


def test_simulate_text_flags_offer_the_configurations_words():
    """``--model``, ``--sampling``, ``--friction``, ``--ringing``: the parser is built without importing
    the dynamics (cold start), so their words are written in cli/simulate.py or checked after parsing;
    here they are held to the configuration's declaration (FlatName.choices) and its defaults."""
    from afmforce.dynamics.config import FLAT

    flags = _actions("simulate")
    for name in ("model", "sampling"):
        assert tuple(flags[name].choices) == FLAT[name].choices, name
        assert f"default {FLAT[name].default}" in _help(flags[name]), name
    for name in ("friction", "ringing"):            # listed in the help from the registries themselves
        assert all(f"{c}:" in _help(flags[name]) for c in FLAT[name].choices), name
        assert f"(default {FLAT[name].default})" in _help(flags[name]), name


def test_analyze_calibration_flag_is_the_steps_option():
    """``--calibration`` is the short form of ``--option calibration.source``: the same words (the parser
    is built without the options' module, which loads numba), the record's default in its help."""
    from afmforce.analysis.options import CalibrationOptions

    field = {f.name: f for f in dataclasses.fields(CalibrationOptions)}["source"]
    flag = _actions("analyze")["calibration"]
    assert tuple(flag.choices) == tuple(field.metadata["choices"])
    assert f"default {field.default})" in _help(flag)


def test_fit_calibration_flag_takes_the_analysis_words():
    """`afmforce fit --calibration` is the analysis's calibration.source (one rule for analyze, fit and the
    web): the same words and default; `file`, its former word, still reads as `metadata`."""
    from afmforce.analysis.options import CALIBRATION_SOURCES, CalibrationOptions

    field = {f.name: f for f in dataclasses.fields(CalibrationOptions)}["source"]
    flag = _actions("fit")["calibration"]
    assert tuple(flag.choices) == tuple(field.metadata["choices"]) == CALIBRATION_SOURCES
    assert flag.default == field.default
    assert flag.type("file") == "metadata" and flag.type("fit") == "fit"
