"""Verdicts only with evidence: oscillations need a significant peak in both runs, away from Nyquist."""

from __future__ import annotations

import math

import numpy as np
import pytest

from afmforce.analysis.oscillation import both_runs, false_alarm_probability, find_peak


def test_false_alarm_probability_closed_form():
    # P(max of m exponentials > z) = 1 - (1 - e^-z)^m
    assert false_alarm_probability(10.0, 100) == pytest.approx(1 - (1 - math.exp(-10)) ** 100, rel=1e-12)
    rng = np.random.default_rng(0)
    z = -np.log(1e-3 / 200)  # threshold for 1e-3 over 200 frequencies
    hits = np.mean(rng.exponential(size=(20000, 200)).max(axis=1) > z)
    assert hits == pytest.approx(1e-3, abs=6e-4)


def _run(freq: float, amp: float, rate: float = 2000.0, n: int = 2000, seed: int = 0):
    t = np.arange(n) / rate
    r = np.random.default_rng(seed).normal(0, 1e-10, n) + amp * np.sin(2 * np.pi * freq * t)
    return t, r


def test_peak_found_in_both_runs_gives_one_oscillation():
    a = find_peak(*_run(300.0, 1e-10), 1e-6, "approach")
    r = find_peak(*_run(300.0, 1e-10, seed=1), 1e-6, "retract")
    assert a.found and r.found and a.false_alarm < 1e-3
    origin, verdict, f = both_runs(a, r)
    assert f == pytest.approx(300.0, rel=0.01) and "false alarm" in verdict


def test_noise_only_or_one_run_only_is_no_oscillation():
    a = find_peak(*_run(300.0, 1e-10), 1e-6, "approach")
    noise = find_peak(*_run(300.0, 0.0, seed=2), 1e-6, "retract")
    assert not noise.found and noise.false_alarm > 1e-3
    origin, verdict, f = both_runs(a, noise)
    assert origin == "none" and math.isnan(f) and "both runs" in verdict


def test_unrelated_peaks_are_not_averaged():
    a = find_peak(*_run(300.0, 1e-10), 1e-6, "approach")
    r = find_peak(*_run(600.0, 1e-10, seed=1), 1e-6, "retract")
    origin, verdict, f = both_runs(a, r)
    assert origin == "none" and math.isnan(f) and "unrelated" in verdict


def test_a_line_near_nyquist_is_not_reported():
    p = find_peak(*_run(950.0, 3e-10), 1e-6, "approach")  # Nyquist 1000 Hz
    assert not (p.found and p.frequency > 800.0)
