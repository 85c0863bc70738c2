"""SimulationConfig composed of parts (issue 11.7): validation per part, the flat names, old headers."""

from __future__ import annotations

import dataclasses
import json
import math
import pickle

import pytest

from afmforce.cantilever import InclinedCantilever
from afmforce.constants import FIG5
from afmforce.dynamics import SimulationConfig, simulate
from afmforce.dynamics import drive as drive_module
from afmforce.dynamics.config import FLAT, PARTS, flat_defaults
from afmforce.dynamics.parts import (
    DEFAULT_B,
    BeamProbe,
    Drive,
    Friction,
    SolverOptions,
    SpringProbe,
    Surface,
)
from afmforce.errors import ParameterError

PART_CLASSES = (BeamProbe, SpringProbe, Surface, Friction, Drive, SolverOptions)

#: The 35 flat names of SimulationConfig before issue 11.7: sweeps (--set, --grid), the fit, the
#: command line and stored headers use them, so every one must still be accepted.
OLD_FLAT_NAMES = (
    "model", "L0", "L1", "L2", "theta0", "k0", "B", "m_joint", "m_base", "spring_constant", "mass",
    "radius", "hamaker", "z0", "viscosity", "friction", "xi", "zeta", "velocity", "retract_velocity",
    "start", "turn", "turn_force", "turn_deflection", "dwell", "end", "sample_rate", "rtol", "atol",
    "contact_separation", "jump_factor", "spike_window", "ringing", "sampling", "max_steps")
#: Flat names added since (issue 23: the lever's quality factors, probe fields).
NEW_FLAT_NAMES = ("quality_factor", "quality_factor_2")
#: Surface fields added by issue 25 (liquids).
LIQUID_FLAT_NAMES = (
    "geometry", "double_layer", "surface_potential", "surface_potential_2", "debye_length",
    "salt_concentration", "valence", "permittivity", "slip_length", "lever_drag", "lever_height",
    # issue 31: the surface force laws' parameters, from their records (a new law adds its own)
    *__import__("afmforce.surface_laws", fromlist=["PARAMETERS"]).PARAMETERS)

#: Trajectory headers written by the version before issue 11.7 (every field of both probes).
OLD_HEADERS = [
    ('{"model": "spring", "L0": 0.0002, "L1": 2e-06, "L2": 4e-06, "theta0": -0.2617993877991494, '
     '"k0": null, "B": null, "m_joint": 1e-10, "m_base": 1e-10, "spring_constant": 0.21, "mass": 1e-08, '
     '"radius": 1e-07, "hamaker": 5e-19, "z0": 3.5e-10, "viscosity": 1.8e-05, "friction": "viscous", '
     '"xi": 0.1, "zeta": 0.0, "velocity": 1e-06, "retract_velocity": null, "start": -4e-08, '
     '"turn": 5e-09, "turn_force": null, "turn_deflection": null, "dwell": 0.0, "end": -1.5e-07, '
     '"sample_rate": 10000.0, "rtol": 0.0001, "atol": 1e-12, "contact_separation": 1e-09, '
     '"jump_factor": 2.0, "spike_window": 0.002, "ringing": "damp", "sampling": "point", "max_steps": null}',
     dict(model="spring", velocity=1e-6, end=-150e-9, turn=5e-9)),
    ('{"model": "beam", "L0": 0.0002, "L1": 2e-06, "L2": 4e-06, "theta0": -0.2617993877991494, '
     '"k0": 0.2, "B": null, "m_joint": 1e-10, "m_base": 1e-10, "spring_constant": 0.21, "mass": 1e-08, '
     '"radius": 1e-07, "hamaker": 5e-19, "z0": 3.5e-10, "viscosity": 1.8e-05, "friction": "load", '
     '"xi": 0.1, "zeta": 10000000000000.0, "velocity": 1e-06, "retract_velocity": null, "start": -4e-08, '
     '"turn": 2e-08, "turn_force": null, "turn_deflection": null, "dwell": 0.0, "end": -2.3e-07, '
     '"sample_rate": 20000.0, "rtol": 0.0001, "atol": 1e-12, "contact_separation": 1e-09, '
     '"jump_factor": 2.0, "spike_window": 0.002, "ringing": "damp", "sampling": "point", "max_steps": null}',
     dict(k0=0.2, friction="load", zeta=1e13, sample_rate=2e4, velocity=1e-6)),
]

#: A value outside each domain (the domain is declared in the field metadata).
BAD = {"positive": (0.0, -1.0, math.nan), "non_negative": (-1e-3, math.inf), "finite": (math.nan,),
       "optional_positive": (0.0, -1.0), "count": (0, 2.5, math.inf), "range": (10.0, -1.0),
       "optional_finite": (math.nan, math.inf)}


def _outside(spec):
    """Values outside a ``range`` field's valid range (issue 31: laws' parameters use it)."""
    return tuple(v for v in (None if spec.hi is None else spec.hi + abs(spec.hi) + 1.0,
                             None if spec.lo is None else spec.lo - abs(spec.lo) - 1.0) if v is not None)


def _bad_cases():
    for cls in PART_CLASSES:
        for f in dataclasses.fields(cls):
            domain = f.metadata.get("domain")
            values = ("bogus",) if "choices" in f.metadata else (
                _outside(f.metadata["spec"]) if domain == "range" else BAD[domain])
            for v in values:
                yield pytest.param(cls, f.name, v, id=f"{cls.__name__}.{f.name}={v}")


@pytest.mark.parametrize("cls, name, value", list(_bad_cases()))
def test_every_part_field_refuses_a_value_outside_its_domain(cls, name, value):
    flat = "friction" if name == "law" else name
    with pytest.raises(ParameterError, match=flat):
        cls(**{name: value})
    with pytest.raises(ParameterError, match=flat):   # the same check through the flat name
        SimulationConfig(**{flat: value, "model": "spring" if cls is SpringProbe else "beam"})


@pytest.mark.parametrize("cls, kw, match", [
    (BeamProbe, dict(k0=0.13, B=3.5e-13), "at most one of k0"),
    (BeamProbe, dict(theta0=-2.0), "theta0"),            # the cantilever's own geometry check
    (BeamProbe, dict(L2=-1e-6), "L2"),
    (Drive, dict(turn=-50e-9), "turn"),
    (Drive, dict(end=30e-9), "end"),
    (Drive, dict(turn_force=1e-9, turn_deflection=1e-9), "turn_force"),
])
def test_cross_field_checks_of_a_part(cls, kw, match):
    with pytest.raises(ParameterError, match=match):
        cls(**kw)


def test_parts_are_frozen_and_the_model_is_the_probe():
    cfg = SimulationConfig()
    for part in PARTS:
        with pytest.raises(dataclasses.FrozenInstanceError):
            getattr(cfg, part).x = 1.0
    with pytest.raises(dataclasses.FrozenInstanceError):
        cfg.drive = Drive()
    assert isinstance(cfg.probe, BeamProbe) and cfg.model == "beam"
    assert SimulationConfig(probe=SpringProbe()).model == "spring"
    with pytest.raises(ParameterError, match="contradicts"):
        SimulationConfig(probe=SpringProbe(), model="beam")
    with pytest.raises(ParameterError, match="surface must be a Surface"):
        SimulationConfig(surface=Drive())


def test_the_flat_names_are_the_old_ones():
    """Sweeps' --set/--grid names, fit parameters and header keys keep working."""
    extra = NEW_FLAT_NAMES + LIQUID_FLAT_NAMES
    assert tuple(n for n in FLAT if n not in extra) == OLD_FLAT_NAMES
    assert set(FLAT) == set(OLD_FLAT_NAMES) | set(extra)
    from afmforce.sweep.simulation import simulation_dimensions

    dims = simulation_dimensions()
    assert set(dims) == set(OLD_FLAT_NAMES) | set(extra)
    assert dims["velocity"] == "velocity" and dims["friction"] is None and dims["max_steps"] == "dimensionless"


def _other_value(name):
    where = FLAT[name]
    if where.field is None:
        return "spring"
    choices = where.field.metadata.get("choices")
    if choices is not None:
        return next(k for k in choices if k != where.default)
    special = {"k0": 0.2, "B": 2e-13, "retract_velocity": 2e-7, "turn_force": 1e-9,
               "turn_deflection": 1e-9, "max_steps": 1000}
    if name in special:
        return special[name]
    if where.default:
        return where.default * 1.1
    spec = where.spec
    if spec is None or spec.contains(1e-3):
        return 1e-3
    if spec.hi is not None and spec.hi < 1e-3:
        return spec.hi / 2                      # inside the declared range
    return 2 * spec.lo


@pytest.mark.parametrize("name", [n for n in FLAT if n != "model"])
def test_a_flat_name_sets_its_part_and_round_trips(name):
    value = _other_value(name)
    model = FLAT[name].models[0]
    cfg = SimulationConfig(model=model, **{name: value})
    where = FLAT[name]
    assert getattr(getattr(cfg, where.part), where.attr) == value
    assert cfg.to_dict()[name] == value
    if name != "friction":
        assert getattr(cfg, name) == value          # read-only flat attribute
    assert SimulationConfig.from_dict(cfg.to_dict()) == cfg
    assert SimulationConfig(**cfg.to_dict()) == cfg
    assert SimulationConfig().replace(model=model, **{name: value}) == cfg
    assert json.loads(json.dumps(cfg.to_dict())) == cfg.to_dict()    # the header is plain JSON


def test_defaults_and_flat_defaults():
    d = flat_defaults()
    assert set(d) == set(FLAT)
    assert d["B"] == DEFAULT_B == FIG5["B"] and d["k0"] is None and d["model"] == "beam"
    assert d["spring_constant"] == 0.21 and d["friction"] == "viscous"
    assert SimulationConfig().probe.B == DEFAULT_B and SimulationConfig().probe.k0 is None


def test_old_trajectory_headers_still_read():
    for text, kw in OLD_HEADERS:
        old = json.loads(text)
        cfg = SimulationConfig.from_dict(old)
        assert cfg == SimulationConfig(**kw)
        # every value the old header states for this model is the config's
        assert all(cfg.to_dict()[k] == v or (k, v) == ("B", None)
                   for k, v in old.items() if k in cfg.to_dict())


def test_a_written_header_reads_back(tmp_path):
    tr = simulate(velocity=2e-6, end=-150e-9, turn=5e-9, model="spring")
    path = tr.write(tmp_path / "run.csv")
    line = next(ln for ln in path.read_text().splitlines() if ln.startswith("# config:"))
    assert SimulationConfig.from_dict(json.loads(line[len("# config:"):])) == tr.config


def test_other_model_fields_are_refused_not_ignored():
    with pytest.raises(ParameterError, match="k0 is a field of the beam model's probe"):
        SimulationConfig(model="spring", k0=0.2)
    with pytest.raises(ParameterError, match="mass is a field of the spring model's probe"):
        SimulationConfig(mass=1e-9)
    with pytest.raises(AttributeError, match="L0 is a field of the beam"):
        _ = SimulationConfig(model="spring").L0
    with pytest.raises(AttributeError, match="no cantilever"):
        _ = SimulationConfig(model="spring").cantilever
    with pytest.raises(ParameterError, match="unknown simulation parameter"):
        SimulationConfig(velocty=1e-6)


def test_replace_switches_model_and_stiffness():
    beam = SimulationConfig(k0=0.2, xi=0.01)
    spring = beam.replace(model="spring", mass=1e-9)
    assert spring.probe == SpringProbe(mass=1e-9) and spring.friction == beam.friction
    assert spring.replace(model="beam").probe == BeamProbe()
    assert beam.probe.k0 == 0.2 and beam.probe.B is None
    b = beam.replace(B=2e-13)
    assert b.probe.B == 2e-13 and b.probe.k0 is None
    assert b.replace(k0=0.3).probe.B is None
    with pytest.raises(ParameterError, match="at most one"):
        beam.replace(k0=0.1, B=1e-13)
    mixed = SimulationConfig(drive=Drive(velocity=1e-6), xi=0.01, friction="load")
    assert mixed.drive.velocity == 1e-6 and mixed.friction == Friction("load", xi=0.01)
    assert mixed.replace(drive=Drive()).drive == Drive() and mixed.replace(friction="none").friction.law == "none"


def test_construction_does_no_static_solve(monkeypatch):
    """The start deflection left construction: solved when first needed, then cached."""
    calls = []
    real = drive_module.start_deflection
    monkeypatch.setattr(drive_module, "start_deflection", lambda cfg: calls.append(cfg) or real(cfg))
    cfg = SimulationConfig(hamaker=1.234e-19, velocity=1e-6)
    cfg.replace(xi=0.02)
    assert calls == []
    d = cfg.validate().start_deflection
    assert calls == [cfg] and cfg.start_deflection == d
    from afmforce.dynamics.static import static_deflection

    assert d == pytest.approx(static_deflection(cfg.drive.start, cfg.force_constant, 100e-9, 1.234e-19,
                                                FIG5["z0"]), rel=1e-12)
    simulate(cfg)
    assert len(calls) == 1                           # the run used the cached solution


def test_cantilever_built_once_per_geometry_and_independent_k():
    a, b = SimulationConfig(xi=0.01), SimulationConfig(velocity=1e-6)
    assert a.cantilever is b.cantilever
    ref = InclinedCantilever(FIG5["L0"], FIG5["L1"], FIG5["L2"], FIG5["theta0"], B=FIG5["B"])
    assert a.force_constant == ref.spring_constant and a.calibration_factor == ref.calibration_factor


def test_pickles():
    cfg = SimulationConfig(model="spring", mass=1e-9, velocity=1e-6)
    assert pickle.loads(pickle.dumps(cfg)) == cfg
    assert hash(pickle.loads(pickle.dumps(cfg))) == hash(cfg)
