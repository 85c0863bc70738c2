"""`afmforce simulate` refuses a bad virtual-instrument input before it simulates anything.

The instrument's TOML file used to be read after the simulation (a post-hook): a binary file was refused
only after the run, and on a cold numba cache after the integrator's compile notice, a second stderr
line (tests/cli/test_contract.py failed once so under load). Now the file is read and the instrument
built first: the simulation is never called.
"""

from __future__ import annotations

import pytest

import afmforce.dynamics as dynamics
from afmforce.cli.main import main


def _no_simulation(*args, **kwargs):
    raise AssertionError("the simulation ran before the instrument's inputs were checked")


@pytest.mark.parametrize("content, words", [(bytes(range(256)) * 4, "not a UTF-8 text file"),
                                            (b"[instrument]\nno_such_parameter = 3\n", "no_such_parameter")])
def test_bad_instrument_config_is_refused_before_simulating(tmp_path, capsys, monkeypatch, content, words):
    cfg = tmp_path / "instrument.toml"
    cfg.write_bytes(content)
    monkeypatch.setattr(dynamics, "simulate", _no_simulation)
    code = main(["simulate", "--instrument-config", str(cfg), "--raw", str(tmp_path / "r.txt")])
    err = capsys.readouterr().err
    assert code != 0 and err.count("\n") == 1 and err.startswith("error: "), err
    assert words in err and "the simulation ran" not in err
    assert not (tmp_path / "r.txt").exists()
