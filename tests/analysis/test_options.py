"""Typed step options (issue 11, item 6): the probe record, one options dataclass per step,
defaults declared once (in the registry's records), validation with units; the old dict form refused."""

from __future__ import annotations

import dataclasses
import inspect
import json
import math

import numpy as np
import pytest

from afmforce._fields import QUANTITIES, spec_of
from afmforce.analysis import options as O
from afmforce.analysis.options_text import parse_option
from afmforce.analysis.pipeline import STEPS, analyze, resolve_options
from afmforce.analysis.synthetic import static_curve
from afmforce.errors import AfmforceError, ParameterError


@pytest.fixture(scope="module")
def curve():
    return static_curve(noise=0.05e-9, drift=0.01, seed=11)


# --- the registry is the one source of defaults -----------------------------------------------
def test_every_step_has_an_options_record_and_takes_it_without_defaults():
    for name, step in STEPS.items():
        assert step.options is O.OPTIONS[name] and step.options.step == name
        params = list(inspect.signature(step.func).parameters.values())
        assert [p.name for p in params] == ["st", "o"], name
        assert all(p.default is inspect.Parameter.empty for p in params), name


def test_no_default_is_written_twice():
    """No step function's source repeats an option's default next to its name (``nsigma=5.0``)."""
    for name, step in STEPS.items():
        src = inspect.getsource(step.func)
        for f in dataclasses.fields(step.options):
            if f.default is None or isinstance(f.default, bool):
                continue
            assert f"{f.name}: " not in src.split(")")[0], (name, f.name)  # not a keyword of the signature
            assert f"{f.name}={f.default!r}" not in src.replace(" ", ""), (name, f.name)


def test_every_option_declares_dimension_unit_help_and_range():
    for cls in (O.ProbeCalibration, *O.OPTIONS.values()):
        for f in dataclasses.fields(cls):
            spec = spec_of(f)
            assert spec is not None and spec.help, (cls, f.name)
            assert f.metadata["unit"] == spec.unit
            if isinstance(f.default, float) and not isinstance(f.default, bool):
                assert spec.contains(f.default), (cls, f.name)  # the default is valid
            if spec.dimension in ("length", "frequency", "angle", "stiffness", "sensitivity", "energy"):
                assert spec.unit, (cls, f.name)


def test_probe_fields_share_the_vocabulary():
    for f in dataclasses.fields(O.ProbeCalibration):
        assert spec_of(f) == QUANTITIES[f.name]
        assert f.default is None  # None: the file's value


# --- validation: an AfmforceError naming the option and its unit ------------------------------
@pytest.mark.parametrize("make, words", [
    (lambda: O.VdwOptions(max_separation=-5e-9), ["vdw.max_separation", "nm", "out of range"]),
    (lambda: O.JumpsOptions(onset_tolerance=1.0), ["jumps.onset_tolerance", "um"]),
    (lambda: O.ZeroOptions(contact_separation=-1e-9), ["zero.contact_separation", "nm"]),
    (lambda: O.SurfaceEnergyOptions(hamaker=1.0), ["surface_energy.hamaker", "J"]),
    (lambda: O.FringesOptions(apply="sometimes"), ["fringes.apply", "auto, always, never"]),
    (lambda: O.SmoothOptions(window=4), ["smooth.window", "odd"]),
    (lambda: O.JumpsOptions(window=2.5), ["jumps.window", "whole number"]),
    (lambda: resolve_options([O.KindOptions(method="magic")]), ["kind.method", "hertz_local"]),
    (lambda: O.ProbeCalibration(radius=-5e-9), ["radius", "nm", "out of range"]),
    (lambda: O.ProbeCalibration(sensitivity=1.0), ["sensitivity", "nm/V"]),
    (lambda: O.ProbeCalibration(theta0=math.radians(95)), ["theta0", "deg"]),
])
def test_bad_values_raise_naming_the_option_and_unit(make, words):
    with pytest.raises(ParameterError) as exc:
        make()
    assert isinstance(exc.value, AfmforceError)
    for w in words:
        assert w in str(exc.value)


def test_records_are_frozen():
    with pytest.raises(dataclasses.FrozenInstanceError):
        O.VdwOptions().max_separation = 1e-9  # type: ignore[misc]


def test_parse_option_takes_units_words_and_flags():
    assert parse_option("vdw.max_separation=20nm") == ("vdw", "max_separation", pytest.approx(20e-9))
    assert parse_option("fringes.apply=never") == ("fringes", "apply", "never")
    assert parse_option("vdw.fit_separation_offset=true") == ("vdw", "fit_separation_offset", True)
    assert parse_option("fringes.period=none") == ("fringes", "period", None)
    assert parse_option("jumps.window=5") == ("jumps", "window", 5)
    for bad, word in (("vdw.max_separation=20nN", "length"), ("vdw.nope=1", "unknown option"),
                      ("vwd.z0=1nm", "unknown step"), ("vdw", "STEP.NAME=VALUE"),
                      ("vdw.max_separation=-2nm", "out of range"), ("shift.apply=maybe", "true or false")):
        with pytest.raises(AfmforceError, match=word):
            parse_option(bad)


# --- the pipeline takes records (the old dict form is removed) -----------------------------------
def test_defaults_come_from_the_records():
    opts, probe = resolve_options()
    assert set(opts) == set(STEPS) and probe == O.ProbeCalibration()
    for name, rec in opts.items():
        assert rec == STEPS[name].options()


def test_records_change_the_results(curve):
    new = analyze(curve, options=[O.VdwOptions(max_separation=20e-9), O.ZeroOptions(contact_separation=0.0)],
                  probe=O.ProbeCalibration(radius=20e-9, spring_constant=0.2))
    default = analyze(curve)
    assert new.hamaker_radius != default.hamaker_radius  # the options did something
    assert new.spring_constant == 0.2 and new.contact_separation == 0.0
    assert new.hamaker == pytest.approx(new.hamaker_radius / 20e-9)


def test_the_old_dict_form_is_an_afmforce_error_naming_the_records(curve):
    with pytest.raises(AfmforceError, match="VdwOptions.*ProbeCalibration.*no longer accepted"):
        analyze(curve, options={"vdw": {"radius": 20e-9}, "surface_energy": {"radius": 30e-9}})
    with pytest.raises(AfmforceError, match="no longer accepted"):
        resolve_options({"force": {"spring_constant": 0.2}})


def test_options_given_twice_or_of_the_wrong_type_are_refused(curve):
    with pytest.raises(ParameterError, match="twice"):
        analyze(curve, options=[O.VdwOptions(), O.VdwOptions(z0=0.2e-9)])
    with pytest.raises(ParameterError, match="records"):
        analyze(curve, options=[{"vdw": {}}])
    with pytest.raises(ParameterError, match="step names"):
        analyze(curve, [O.VdwOptions()])


def test_probe_overrides_the_file(curve):
    """The probe's spring constant replaces the file's: forces scale with it, deflections do not."""
    k_file = curve.metadata["spring_constant"]
    a = analyze(curve, steps=["force"])
    b = analyze(curve, steps=["force"], probe=O.ProbeCalibration(spring_constant=2 * k_file))
    np.testing.assert_allclose(b.deflection, a.deflection)
    np.testing.assert_allclose(b.force, 2 * a.force)


# --- details entries are dataclasses ------------------------------------------------------------
def test_details_entries_are_dataclasses(curve):
    res = analyze(curve)
    assert res.details and "skipped" not in res.details
    for name, detail in res.details.items():
        assert dataclasses.is_dataclass(detail), name
    assert json.loads(res.to_json())["details"]["jumps"]["jump_in"]["index"] == res.details["jumps"].jump_in.index


def _numeric_fields_without_unit(obj, path):
    missing = []
    for f in dataclasses.fields(obj):
        v = getattr(obj, f.name)
        if dataclasses.is_dataclass(v):
            missing += _numeric_fields_without_unit(v, f"{path}.{f.name}")
        elif isinstance(v, tuple) and v and dataclasses.is_dataclass(v[0]):
            missing += _numeric_fields_without_unit(v[0], f"{path}.{f.name}[0]")
        elif isinstance(v, (int, float, np.number)) and not isinstance(v, (bool, np.bool_)) \
                and "unit" not in f.metadata:
            missing.append(f"{path}.{f.name}")
    return missing


@pytest.mark.parametrize("kind", ["hard", "soft"])
def test_every_number_in_details_declares_its_unit(kind):
    """Each numeric field of each step's result dataclass (nested ones too) carries its unit as
    metadata; the JSON states them under ``details_units`` with the signal's unit filled in."""
    from pathlib import Path

    from afmforce.io import load

    soft = Path(__file__).resolve().parents[1] / "data" / "jpk_cellhesion_spot3.jpk-force"
    c = static_curve(noise=0.05e-9, drift=0.01, seed=11) if kind == "hard" else load(soft)[0]
    res = analyze(c)
    assert res.contact_kind == kind
    missing = [m for step, d in res.details.items() for m in _numeric_fields_without_unit(d, step)]
    assert not missing
    units = json.loads(res.to_json())["details_units"]
    assert units["vdw" if kind == "hard" else "contact_point"]
    if kind == "hard":
        assert units["jumps"]["pull_off"]["force"] == "N" and units["vdw"]["hamaker_radius"] == "J m"
        assert units["compliance"]["approach"]["slope"] == f"{res.deflection_unit}/m"
        assert units["calibration"]["factor"] == f"m/{res.deflection_unit}"
    else:
        assert units["contact_point"]["indentation"] == "m"


ALGORITHMS = [  # (module, function, record, options whose default the function shares)
    ("vdw", "fit_vdw", O.VdwOptions, ["z0", "max_separation", "baseline", "fit_separation_offset"]),
    ("jumps", "find_jump_in", O.JumpsOptions, ["nsigma", "window"]),
    ("jumps", "find_pull_off", O.JumpsOptions, ["nsigma", "window"]),
    ("jumps", "adhesion", O.SurfaceEnergyOptions, ["model", "hamaker", "z0"]),
    ("compliance", "calibrate", O.CalibrationOptions, ["source", "run"]),
    ("compliance", "friction_signature", O.FrictionOptions, ["nsigma", "slope_tolerance", "offset_tolerance"]),
    ("unbinding", "retract_adhesion", O.AdhesionOptions, ["nsigma"]),
    ("oscillation", "find_peak", O.OscillationOptions, ["min_cycles", "false_alarm"]),
    ("separation", "zero_of_separation", O.ZeroOptions, ["contact_separation"]),
    ("fringes", "fit_fringes", O.FringesOptions, ["period", "order"]),
    ("contact_point", "classify_contact", O.KindOptions, ["nsigma", "min_stiffness", "max_curvature"]),
    ("drift", "remove_drift", O.DriftOptions, ["order"]),
]


@pytest.mark.parametrize("module, func, record, names", ALGORITHMS, ids=lambda x: x if isinstance(x, str) else "")
def test_algorithms_take_their_defaults_from_the_records(module, func, record, names):
    """The functions behind the steps name the record's default (``nsigma: float = _J.nsigma``),
    never a second literal: one place to change a default."""
    import ast
    import importlib

    mod = importlib.import_module(f"afmforce.analysis.{module}")
    tree = ast.parse(inspect.getsource(mod))
    fn = next(n for n in ast.walk(tree) if isinstance(n, ast.FunctionDef) and n.name == func)
    args = fn.args.args + fn.args.kwonlyargs
    defaults = dict(zip([a.arg for a in fn.args.args][len(fn.args.args) - len(fn.args.defaults):], fn.args.defaults))
    defaults.update({a.arg: d for a, d in zip(fn.args.kwonlyargs, fn.args.kw_defaults) if d is not None})
    sig = inspect.signature(getattr(mod, func))
    for name in names:
        assert name in [a.arg for a in args] and name in defaults, (func, name)
        assert not isinstance(defaults[name], ast.Constant), f"{func}({name}=literal): use the record's default"
        assert sig.parameters[name].default == getattr(record(), name)
