"""The composed instrument: ideal reproduces the trajectory exactly, metadata, truth, bad input."""

import types

import numpy as np
import pytest

from afmforce.errors import ParameterError
from afmforce.instrument import PRESETS, Instrument, get_preset

from afm_trajectories import ramp_trajectory


def test_ideal_reproduces_the_trajectory_exactly():
    tr = ramp_trajectory([-0.3e-6, 0.05e-6, -0.4e-6], 1e-6, 1e4, contact=0.0)
    raw = get_preset("ideal").record(tr, seed=0)
    assert raw.deflection_unit == "m"
    assert raw.time.tobytes() == tr.time.tobytes()
    assert raw.piezo_nominal.tobytes() == tr.piezo_position.tobytes()
    assert raw.piezo_measured.tobytes() == tr.piezo_position.tobytes()
    assert raw.deflection_signal.tobytes() == tr.apparent_deflection.tobytes()
    assert raw.segment.tobytes() == tr.segment.tobytes()
    for name in ("piezo_position", "deflection", "separation", "angle", "normal_force"):
        assert raw.truth[name].tobytes() == getattr(tr, name).tobytes()


@pytest.mark.parametrize("name", list(PRESETS))
def test_every_preset_records_a_valid_curve(name):
    tr = ramp_trajectory([-0.3e-6, 0.05e-6, -0.4e-6], 2e-6, 5e3, contact=0.0)
    raw = get_preset(name).record(tr, seed=1)
    assert len(raw) == len(tr.time)
    assert raw.metadata["instrument"] == name
    assert raw.metadata["velocity"] == 2e-6
    assert raw.metadata["spring_constant"] == 0.21
    assert raw.truth["calibration_factor"] == 1.3e-4
    assert raw.truth["instrument"] == get_preset(name).to_dict()
    assert np.all(np.isfinite(raw.deflection_signal))


def test_to_dict_from_dict_round_trip():
    for name in PRESETS:
        inst = get_preset(name)
        assert Instrument.from_dict(inst.to_dict()) == inst


def test_minimal_duck_typed_trajectory():
    t = np.linspace(0, 1, 101)
    z = np.linspace(-1e-7, 1e-8, 101)
    obj = types.SimpleNamespace(time=t, piezo_position=z, segment=np.zeros(101, np.int8),
                                deflection=np.maximum(z, 0))
    raw = get_preset("ideal").record(obj)
    assert np.array_equal(raw.deflection_signal, np.maximum(z, 0))
    assert np.array_equal(raw.truth["separation"], np.maximum(z, 0) - z)
    assert raw.metadata["velocity"] == pytest.approx(1.1e-7)


def test_angle_and_calibration_factor_give_the_apparent_deflection():
    t = np.linspace(0, 1, 11)
    obj = types.SimpleNamespace(time=t, piezo_position=t * 1e-8, segment=np.zeros(11, np.int8),
                                angle=t * 1e-5, calibration_factor=1.3e-4)
    raw = get_preset("ideal").record(obj)
    assert np.allclose(raw.deflection_signal, 1.3e-4 * t * 1e-5, rtol=1e-15)


@pytest.mark.parametrize("change, match", [
    (dict(time=None), "lacks time"),
    (dict(time=np.array([0.0, 2.0, 1.0])), "strictly increasing"),
    (dict(piezo_position=np.zeros(4)), "shape"),
    (dict(piezo_position=np.array([0.0, np.nan, 0.0])), "NaN"),
    (dict(deflection=None), "apparent_deflection"),
])
def test_bad_trajectories(change, match):
    base = dict(time=np.array([0.0, 1.0, 2.0]), piezo_position=np.zeros(3), segment=np.zeros(3, np.int8),
                deflection=np.zeros(3))
    base.update(change)
    with pytest.raises(ParameterError, match=match):
        get_preset("ideal").record(types.SimpleNamespace(**base))


def test_bad_seed_and_components():
    tr = ramp_trajectory([0.0, 1e-7], 1e-6, 1e3)
    with pytest.raises(ParameterError):
        get_preset("typical").record(tr, seed=-1)
    with pytest.raises(ParameterError):
        Instrument(piezo="strong")
    with pytest.raises(ParameterError, match="unknown instrument preset"):
        get_preset("park")
    with pytest.raises(ParameterError, match="unknown piezo parameter"):
        Instrument.from_dict({"piezo": {"hysterisis": 0.1}})
