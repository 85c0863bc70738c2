"""The virtual AFM on real dynamics-engine output (short runs), and the Fig 7 protocol."""

import numpy as np
import pytest

from afmforce.errors import ParameterError
from afmforce.instrument import get_preset
from afmforce.instrument.protocols import out_then_in
from afmforce.io.native.rawfile import read_raw, write_raw

from afm_trajectories import ramp_trajectory


@pytest.fixture(scope="module")
def trajectory():
    dynamics = pytest.importorskip("afmforce.dynamics")
    # Fig 5 geometry, xi = 0.01 kg/s at 1 um/s (spec section 7, row 3), ending where it started.
    return dynamics.simulate(xi=0.01, velocity=1e-6, start=-230e-9, turn=20e-9, end=-230e-9, sample_rate=5e3)


def test_ideal_instrument_reproduces_a_simulation(trajectory):
    raw = get_preset("ideal").record(trajectory)
    assert raw.piezo_nominal.tobytes() == np.asarray(trajectory.piezo_position, float).tobytes()
    assert raw.deflection_signal.tobytes() == np.asarray(trajectory.apparent_deflection, float).tobytes()
    assert raw.metadata["spring_constant"] == trajectory.spring_constant
    assert raw.metadata["velocity"] == 1e-6
    assert raw.truth["calibration_factor"] == trajectory.calibration_factor


def test_paper_instrument_on_the_fig7_protocol(tmp_path, trajectory):
    fig7 = out_then_in(trajectory)
    assert fig7.segment[0] == 1 and fig7.segment[-1] == 0
    assert np.all(np.diff(fig7.time) > 0)
    raw = get_preset("paper").record(fig7, seed=2)
    path = tmp_path / "fig7.h5"
    write_raw(raw, path)
    back = read_raw(path)
    assert back.deflection_signal.tobytes() == raw.deflection_signal.tobytes()
    # constant compliance at both ends: the signal is saturated or steep there, flat in between
    d = raw.truth["deflection"]
    assert d[0] > 0 and d[-1] > 0
    # the inward run of the detector reads low by b(v)/2 (paper, Fig 7B)
    b = raw.truth["backlash_widths"]
    assert b[0] == pytest.approx(get_preset("paper").detector.backlash_width(1e-6), rel=1e-2)


def test_out_then_in_ordering_and_errors():
    tr = ramp_trajectory([-1e-7, 2e-8, -1e-7], 1e-6, 1e4, contact=0.0)
    ro = out_then_in(tr)
    n_ret = int(np.sum(tr.segment == 1))
    assert np.array_equal(ro.piezo_position[:n_ret], tr.piezo_position[tr.segment == 1])
    assert np.array_equal(ro.deflection[n_ret:], tr.deflection[tr.segment == 0])
    assert np.allclose(np.diff(ro.time), 1e-4)
    with pytest.raises(ParameterError, match="end == start"):
        out_then_in(ramp_trajectory([-1e-7, 2e-8, -3e-7], 1e-6, 1e4))
    with pytest.raises(ParameterError, match="approach and a retract"):
        out_then_in(ramp_trajectory([-1e-7, 2e-8], 1e-6, 1e4))


def test_afmforce_simulate_writes_a_raw_file(tmp_path, capsys):
    from afmforce.cli.main import main

    out = tmp_path / "run.txt"
    argv = ["simulate", "--velocity", "1um/s", "--xi", "0.01", "--instrument", "paper", "--seed", "1",
            "--raw", str(out), "--json"]
    code = main(argv)
    capsys.readouterr()
    assert code == 0 and out.exists()
    raw = read_raw(out)
    assert raw.metadata["instrument"] == "paper" and raw.metadata["seed"] == 1
    assert raw.metadata["sample_rate"] == 10e3
    assert main(argv) == 2  # exists: refused without --force
    assert "exists" in capsys.readouterr().err
    assert main(argv + ["--force"]) == 0
