"""Every number a command prints is a physically possible one with its unit, or the row says why
there is none (faces audit, 2026-11-29). Before: ``simulate --model spring`` printed
``calibration factor (eq 15)  nan nm/rad``, ``apparent-deflection spike  nan``; ``diagnose`` with a
stiff lever ``static jump-in separation  nan``; ``calibrate thermal --correction 1e-30`` a spring
constant of 5e-29 mN/m."""

from __future__ import annotations

import math
import re

import pytest

from afmforce.cli.main import main
from afmforce.forces import vdw_force_gradient

NOT_A_NUMBER = re.compile(r"(?<![A-Za-z])(nan|inf)(?![A-Za-z])", re.IGNORECASE)


def _run(capsys, argv) -> str:
    assert main(argv) == 0
    return capsys.readouterr().out


def test_simulate_spring_prints_no_nan(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    out = _run(capsys, ["simulate", "--model", "spring", "--velocity", "10um/s"])
    assert not NOT_A_NUMBER.search(out), out
    row = next(line for line in out.splitlines() if "calibration factor (eq 15)" in line)
    assert "spring model has no lever angle" in row
    beam = _run(capsys, ["simulate", "--velocity", "10um/s"])       # the beam's factor is a number in nm/rad
    row = next(line for line in beam.splitlines() if "calibration factor (eq 15)" in line)
    assert re.search(r"\d nm/rad$", row), row


def test_diagnose_says_why_there_is_no_static_jump_in(capsys):
    from afmforce.constants import FIG1, HAMAKER, Z0

    z0, radius = Z0, FIG1["radius"]
    steepest = float(vdw_force_gradient(3 ** (1 / 6) * z0, radius, HAMAKER, z0))
    assert steepest < 100.0                                         # no instability: the premise of the row
    out = _run(capsys, ["diagnose", "--spring-constant", "100N/m"])
    assert not NOT_A_NUMBER.search(out), out
    row = next(line for line in out.splitlines() if "static jump-in separation" in line)
    assert "does not jump into contact" in row


@pytest.mark.parametrize("chi", ["1e-30", "0.3", "2"])
def test_an_equipartition_factor_no_lever_has_is_refused(capsys, chi):
    try:
        code = main(["calibrate", "thermal", "--example", "jpk-water", "--correction", chi])
    except SystemExit as exc:       # argparse refuses while parsing
        code = exc.code
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1 and "must lie in [0.5, 1.5]" in err, err


def test_the_literature_s_factors_are_taken(capsys):
    out = _run(capsys, ["calibrate", "thermal", "--example", "jpk-water", "--correction", "0.817"])
    k = float(re.search(r"spring constant k\s+([0-9.]+) \+-", out).group(1))
    ref = float(re.search(r"the file's k\s+([0-9.]+) mN/m", out).group(1))
    assert 0.5 < k / ref < 1.5 and math.isfinite(k)


def test_plan_prints_no_infinite_sigma(capsys):
    """``plan`` printed ``inf kg/s`` as the slowest speed's sigma "with the slowest speed" (itself)."""
    out = _run(capsys, ["plan", "--xi", "5e-3kg/s", "--noise", "0.01nm", "--speeds", "0.5um/s,2um/s",
                        "--curves", "2"])
    assert not NOT_A_NUMBER.search(out), out
    rows = [line for line in out.splitlines() if line.startswith("| 5e-07 m/s | 1000 Hz")]
    assert rows and "(the slowest itself)" in rows[0]
