"""``afmforce simulate`` (issue 3: flags, outputs, JSON summary, errors)."""

from __future__ import annotations

import json

import pytest

from afmforce.cli.main import main


def test_simulate_json_defaults_are_fig5(capsys, fig5):
    """`afmforce simulate --json` alone runs Fig 5 and prints the issue's summary keys."""
    assert main(["simulate", "--json"]) == 0
    s = json.loads(capsys.readouterr().out)
    assert set(s) == {"jump_in", "pull_off", "min_deflection", "min_apparent_deflection",
                      "hysteresis_offset", "spike_height", "solver"}
    assert s["pull_off"]["piezo_position"] == pytest.approx(fig5.events.pull_off_position)
    assert s["min_apparent_deflection"] == pytest.approx(fig5.events.min_apparent_deflection)
    assert s["solver"]["status"] == "success"


def test_simulate_flags_with_units(capsys, sim):
    argv = ["simulate", "--json", "--xi", "0.01kg/s", "--velocity", "1um/s", "--start=-30nm",
            "--theta0", "-15deg", "--sample-rate", "20kHz"]
    assert main(argv) == 0
    s = json.loads(capsys.readouterr().out)
    ref = sim(xi=0.01, velocity=1e-6, start=-30e-9, sample_rate=20e3).events
    assert s["jump_in"]["piezo_position"] == pytest.approx(ref.jump_in_position, rel=1e-9)


def test_simulate_spring_table_output(capsys):
    argv = ["simulate", "--model", "spring", "--mass", "1ug", "--spring-constant", "0.21N/m",
            "--radius", "220nm", "--velocity", "2um/s", "--start=-100nm", "--end=-300nm"]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "jump-in" in out and "nm" in out and "pull-off position" in out


def test_simulate_writes_outputs_and_refuses_overwrite(tmp_path, capsys):
    out, png = tmp_path / "t.csv", tmp_path / "t.png"
    argv = ["simulate", "--xi", "0.01", "--velocity", "1um/s", "--out", str(out), "--plot",
            str(png)]
    assert main(argv) == 0
    assert out.read_text().startswith("# afmforce trajectory")
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    capsys.readouterr()
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error:") and "--force" in err and len(err.splitlines()) == 1
    assert main(argv + ["--force"]) == 0
    h5 = tmp_path / "t.h5"
    assert main(["simulate", "--xi", "0.01", "--velocity", "1um/s", "--out", str(h5)]) == 0
    assert h5.exists()


@pytest.mark.parametrize("argv,match", [
    (["--velocity", "0um/s"], "velocity"),
    (["--velocity", "5nN"], "--velocity expects a speed"),
    (["--xi", "-0.1kg/s"], "xi"),
    (["--start=-2nm"], "already in contact"),
    (["--m-joint", "0kg"], "m_joint"),
    (["--sample-rate", "1Hz"], "sample_rate"),
    (["--out", "x.txt"], ".csv or .h5"),
    (["--sampling", "boxcar"], "sampling"),
])
def test_simulate_bad_input_is_one_line_exit_2(capsys, tmp_path, monkeypatch, argv, match):
    monkeypatch.chdir(tmp_path)
    try:
        code = main(["simulate", *argv])
    except SystemExit as exc:          # argparse rejects unparsable values itself
        code = exc.code
    assert code == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and err.startswith("error:") and match in err


def test_simulate_warns_on_stderr_when_no_contact(capsys):
    assert main(["simulate", "--turn=-10nm", "--end=-60nm", "--json"]) == 0
    cap = capsys.readouterr()
    assert "warning:" in cap.err and "never reached contact" in cap.err
    assert json.loads(cap.out)["jump_in"]["time"] is None


def test_simulate_sampling_flag(tmp_path, capsys):
    """``--sampling average`` reaches the trajectory: the file's samples are interval means."""
    import numpy as np

    from afmforce.dynamics import simulate

    out = tmp_path / "avg.csv"
    argv = ["simulate", "--sampling", "average", "--start=-30nm", "--turn", "10nm", "--end=-250nm",
            "--check", "off", "--out", str(out)]
    assert main(argv) == 0
    text = out.read_text()
    assert "np.float64" not in text                  # plain numbers in the header
    cfg = json.loads(next(ln for ln in text.splitlines() if ln.startswith("# config: "))[10:])
    assert cfg["sampling"] == "average"
    # the CLI's "30nm" is 3.0000000000000004e-08 m: the same drive to the last bit
    ref = simulate(sampling="average", start=cfg["start"], turn=cfg["turn"], end=cfg["end"])
    lines = [ln for ln in text.splitlines() if not ln.startswith("#")]
    names = [h.split(" [")[0] for h in lines[0].split(",")]
    data = np.loadtxt(lines[1:], delimiter=",")
    col = data[:, names.index("apparent_deflection")]
    np.testing.assert_allclose(col, ref.apparent_deflection, rtol=1e-8, atol=1e-18)
