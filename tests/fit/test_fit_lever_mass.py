"""The fit's model lever takes its mass from the files' resonance (a thermal tune's), as it takes
its spring constant from them: found by the audit. Before, the Asylum SiN curve in air (wave note
ThermalFrequency 23251 Hz) was fitted with the model's default lever: 10 ug on the spring (f = 809
Hz), two 0.1 ug masses on the beam (5.5 kHz), an inertia off by 800x and 17x.

The expected mass is computed here from the file's bytes (the wave note's ``ThermalFrequency``)
and the spring constant the fit reports: ``m = k / (2 pi f)^2``; the beam's first mode from the
spec's matrices (numpy, as tests/instrument/test_instrument_resonance.py)."""

from __future__ import annotations

import json
import math
import re

import numpy as np
import pytest

from afmforce.cli.main import main
from afmforce.dynamics import SimulationConfig
from realdata import real_file

SIN = "asylum-mfp3d_SiN-tip_air.ibw"


def _note_frequency(path) -> float:
    return float(re.search(rb"ThermalFrequency:\s*([0-9.eE+-]+)", path.read_bytes()).group(1))


def _beam_first_mode(p) -> float:
    L0, L1 = p.L0, p.L1
    B = p.B if p.B is not None else p.k0 * L0 ** 3 / 3.0
    k_xt = B * np.array([[12 / L0 ** 3, -6 / L0 ** 2], [-6 / L0 ** 2, 4 / L0]])
    T = np.array([[1.0, 0.0], [-1.5 / L1, 1.0 / L1]])
    M = np.diag([p.m_joint + p.m_base / 4.0, p.m_base / 3.0])
    w2 = np.sort(np.linalg.eigvals(np.linalg.solve(M, T.T @ k_xt @ T)).real)
    return math.sqrt(w2[0]) / (2.0 * math.pi)


def _fit(capsys, *extra):
    path = real_file(SIN)
    assert main(["fit", str(path), "--calibration", "fit", "--free", "hamaker", "--no-profile",
                 "--no-compare", "--json", *extra]) == 0
    d = json.loads(capsys.readouterr().out)
    return _note_frequency(path), d, SimulationConfig(**d["config"])


def test_the_spring_models_mass_gives_the_files_resonance(capsys):
    f, d, cfg = _fit(capsys, "--model", "spring")
    k = d["calibration"][SIN]["spring_constant"]
    assert f == 23251.0 and cfg.probe.spring_constant == pytest.approx(k, rel=1e-12)
    assert cfg.probe.mass == pytest.approx(k / (2 * math.pi * f) ** 2, rel=1e-9)      # 1.21e-11 kg, not 1e-8


def test_the_beams_masses_give_the_files_resonance_and_a_given_mass_is_kept(capsys):
    f, d, cfg = _fit(capsys, "--xi", "0")
    assert _beam_first_mode(cfg.probe) == pytest.approx(f, rel=1e-6)
    assert cfg.probe.m_joint == pytest.approx(cfg.probe.m_base, rel=1e-12)             # scaled together
    _, _, given = _fit(capsys, "--model", "spring", "--mass", "1ng")
    assert given.probe.mass == pytest.approx(1e-12, rel=1e-12)
