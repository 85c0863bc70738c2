"""Configuration validation, drive protocols, warnings and trajectory output."""

from __future__ import annotations

import dataclasses
import json
import math
import warnings

import numpy as np
import pytest

from afmforce.constants import FIG5
from afmforce.dynamics import DynamicsWarning, SimulationConfig, simulate
from afmforce.errors import AfmforceError, FileFormatError, OutputExistsError, ParameterError


@pytest.mark.parametrize("bad,match", [
    (dict(velocity=0.0), "velocity"),
    (dict(velocity=-1e-6), "velocity"),
    (dict(m_joint=0.0), "m_joint"),
    (dict(m_base=-1e-10), "m_base"),
    (dict(model="spring", mass=0.0), "mass"),
    (dict(xi=-0.1), "xi"),
    (dict(sample_rate=10.0), "sample_rate"),
    (dict(turn=-50e-9), "turn"),
    (dict(end=30e-9), "end"),
    (dict(model="cantilever"), "model"),
    (dict(friction="coulomb"), "friction"),
    (dict(ringing="ignore"), "ringing"),
    (dict(k0=0.13, B=3.5e-13), "k0"),
    (dict(turn_force=1e-9, turn_deflection=1e-9), "turn_force"),
    (dict(turn_force=-1e-9), "turn_force"),
    (dict(dwell=-1.0), "dwell"),
    (dict(rtol=0.5), "rtol"),
    (dict(theta0=-2.0), "theta0"),
    (dict(radius=float("nan")), "radius"),
])
def test_bad_input_raises_parameter_error(bad, match):
    with pytest.raises(ParameterError, match=match):
        SimulationConfig(**bad)


@pytest.mark.parametrize("bad", [dict(start=-5e-9),          # beam: static jump-in at -5.87 nm
                                 dict(start=1e-9, turn=30e-9)])
def test_start_in_contact_is_refused_before_any_work(bad):
    """The static start solve left construction (issue 11.7): validate(), simulate() and
    simulate_many() refuse the start before integrating anything."""
    from afmforce.dynamics import simulate_many

    cfg = SimulationConfig(**bad)                      # cheap: no static solve yet
    with pytest.raises(ParameterError, match="already in contact"):
        cfg.validate()
    with pytest.raises(ParameterError, match="already in contact"):
        simulate(cfg)
    with pytest.raises(ParameterError, match="already in contact"):
        simulate_many([dict(velocity=1e-6), cfg], threads=1)
    out = simulate_many([cfg], on_error="return", threads=1)
    assert isinstance(out[0], ParameterError)


def test_unknown_override_is_an_afmforce_error():
    with pytest.raises(AfmforceError, match="unknown simulation parameter"):
        simulate(velocty=1e-6)


def test_defaults_are_fig5():
    """Every default is the paper's Figs 5-6 value (spec 5; B decision 3.5e-13)."""
    cfg = SimulationConfig()
    for key in ("L0", "L1", "L2", "theta0", "m_joint", "m_base", "radius", "hamaker", "z0",
                "viscosity", "xi", "velocity", "start", "turn", "end"):
        assert getattr(cfg, key) == FIG5[key], key
    assert cfg.model == "beam" and cfg.friction.law == "viscous" and cfg.to_dict()["friction"] == "viscous"
    assert cfg.cantilever.B == FIG5["B"]


def test_turn_before_contact_warns_and_returns(sim):
    with pytest.warns(DynamicsWarning, match="never reached contact"):
        tr = simulate(turn=-10e-9, end=-60e-9)
    e = tr.events
    assert e.jumped is None and math.isnan(e.contact_time) and math.isnan(e.pull_off_position)
    assert "no contact" in e.jump_in_note
    assert tr.piezo_position.max() == pytest.approx(-10e-9, abs=1e-15)


def test_retract_ending_in_contact_warns():
    with pytest.warns(DynamicsWarning, match="ended in contact"):
        simulate(end=-100e-9)


def test_turn_at_a_load(sim):
    """Turn where the load k z2 reaches turn_force (the instrument's trigger)."""
    f = 2e-9
    tr = sim(turn_force=f, turn=100e-9)
    k = tr.spring_constant
    app = tr.segment == 0
    assert tr.events.turn_position < 100e-9
    # the last approach sample is within one sample's travel of the trigger deflection
    dz = tr.config.velocity / tr.config.sample_rate
    assert tr.deflection[app][-1] == pytest.approx(f / k, abs=2 * dz)
    assert tr.piezo_position[app].max() <= tr.events.turn_position + 1e-15
    with pytest.warns(DynamicsWarning, match="not reached"):
        simulate(turn_force=1e-6, turn=30e-9)


def test_dwell_segment(sim):
    tr = sim(turn_deflection=5e-9, turn=100e-9, dwell=0.05)
    dw = tr.segment == 2
    assert np.ptp(tr.piezo_position[dw]) == 0.0
    assert np.ptp(tr.time[dw]) == pytest.approx(0.05, abs=2 / tr.config.sample_rate)
    assert list(dict.fromkeys(tr.segment.tolist())) == [0, 2, 1]


def test_trajectory_columns_and_summary(fig5):
    tr = fig5
    n = len(tr)
    assert n == int(round(tr.time[-1] * tr.config.sample_rate)) + 1
    np.testing.assert_allclose(np.diff(tr.time), 1 / tr.config.sample_rate)
    np.testing.assert_allclose(tr.separation, tr.deflection - tr.piezo_position, atol=1e-20)
    np.testing.assert_allclose(tr.apparent_deflection, tr.calibration_factor * tr.angle)
    np.testing.assert_allclose(tr.apparent_separation, tr.apparent_deflection - tr.piezo_position)
    assert tr.calibration_factor / 1e-9 == pytest.approx(1.2939e5, rel=1e-4)     # eq 15
    assert set(np.unique(tr.segment)) == {0, 1}
    assert np.all(np.diff(tr.piezo_position[tr.segment == 0]) > 0)
    assert np.all(np.diff(tr.piezo_position[tr.segment == 1]) < 0)
    s = tr.summary()
    assert list(s) == ["jump_in", "pull_off", "min_deflection", "min_apparent_deflection",
                       "hysteresis_offset", "spike_height", "solver"]
    assert list(s["jump_in"]) == ["time", "piezo_position", "separation"]
    assert list(s["pull_off"]) == ["piezo_position", "force"]
    assert list(s["solver"]) == ["status", "steps", "rhs_evaluations", "wall_time", "check"]
    with pytest.raises(dataclasses.FrozenInstanceError):
        tr.time = None


def test_spring_model_has_no_angle(sim):
    tr = sim(model="spring", velocity=1e-6, end=-150e-9)
    assert np.all(np.isnan(tr.angle)) and math.isnan(tr.calibration_factor)
    np.testing.assert_array_equal(tr.apparent_deflection, tr.deflection)
    assert np.all(tr.friction_force == 0) and tr.spring_constant == 0.21


def test_write_csv_and_h5(tmp_path, fig5):
    h5py = pytest.importorskip("h5py")
    csv = tmp_path / "run.csv"
    fig5.write(csv)
    lines = csv.read_text().splitlines()
    header = [ln for ln in lines if ln.startswith("#")]
    assert any(ln.startswith("# calibration_factor:") and ln.endswith("m/rad") for ln in header)
    events = json.loads(next(ln for ln in header if ln.startswith("# events:"))[len("# events:"):])
    assert events["pull_off_position"] == pytest.approx(fig5.events.pull_off_position)
    cols = lines[len(header)].split(",")
    assert cols[0] == "time [s]" and "normal_force [N]" in cols and cols[-1] == "segment [1]"
    data = np.loadtxt(csv, delimiter=",", comments="#", skiprows=len(header) + 1)
    assert data.shape == (len(fig5), len(cols))
    np.testing.assert_allclose(data[:, 2], fig5.deflection, rtol=1e-9, atol=1e-21)

    h5 = tmp_path / "run.h5"
    fig5.write(h5)
    with h5py.File(h5, "r") as f:
        np.testing.assert_array_equal(f["apparent_deflection"][:], fig5.apparent_deflection)
        assert f["normal_force"].attrs["unit"] == "N"
        assert json.loads(f.attrs["config"])["xi"] == 0.1

    with pytest.raises(OutputExistsError):
        fig5.write(csv, force=False)
    with pytest.raises(FileFormatError):
        fig5.write(tmp_path / "run.xlsx")
    assert not list(tmp_path.glob(".*"))          # no temporary files left behind


def test_library_does_not_print(capsys, sim):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        simulate(xi=0.01, velocity=1e-6, progress=lambda f: None)
    out = capsys.readouterr()
    assert out.out == "" and out.err == ""
