"""Virtual multi-speed measurements for the dynamic fit (tests, docs, benchmarks).

Each curve is simulated with :func:`afmforce.dynamics.simulate`, recorded by
the virtual AFM (:mod:`afmforce.instrument`, ``ideal`` preset with white noise
and a random linear drift per run, which act on volts) and calibrated back to
metres with the known sensitivity: ``deflection_signal [m]`` in a raw text
file, the apparent deflection an instrument reports after calibration; and then given
what an experimenter does not know: an unknown zero of the piezo position and a
baseline offset of the deflection, different for every curve.
"""

from __future__ import annotations

import dataclasses
import warnings
from typing import Sequence

import numpy as np

from ..raw import RawCurve

__all__ = ["virtual_curves"]


def virtual_curves(velocities: Sequence[float], *, seed: int = 0,
                   sample_rates: Sequence[float] | None = None, noise: float = 0.05e-9,
                   drift_rms: float = 1e-9, zero_offsets: Sequence[float] | None = None,
                   baseline_offsets: Sequence[float] | None = None,
                   **config) -> list[RawCurve]:
    """Simulate and record one approach-retract curve per driving speed.

    Parameters
    ----------
    velocities : sequence of float
        Driving speeds [m/s].
    seed : int
        Seed of noise, drift and (when not given) the offsets.
    sample_rates : sequence of float, optional
        Sample rate of each curve [Hz]; default ``v / 0.5 nm`` (one sample per
        0.5 nm of drive travel).
    noise : float
        White noise rms of the deflection [m].
    drift_rms : float
        rms of the random drift slope per run [m/s].
    zero_offsets, baseline_offsets : sequence of float, optional
        Added to the recorded piezo position and to the deflection [m];
        default: random, ~N(0, 20 nm) and ~N(0, 2 nm).
    **config
        :class:`~afmforce.dynamics.SimulationConfig` fields shared by all
        curves (model, xi, hamaker, start, turn, end, ...); ``sampling``
        defaults to ``"average"`` (a detector averaged over each sample
        interval, like the instruments the fit assumes).

    Returns
    -------
    list of RawCurve
        ``deflection_unit == "m"``; metadata ``velocity`` and ``sample_rate``;
        ``truth`` holds the trajectory columns and ``zero_offset`` and
        ``baseline_offset`` [m].
    """
    from ..dynamics import DynamicsWarning, simulate
    from ..instrument import build_instrument

    rng = np.random.default_rng(seed)
    n = len(velocities)
    fs = list(sample_rates) if sample_rates is not None else [v / 0.5e-9 for v in velocities]
    zoff = list(zero_offsets) if zero_offsets is not None else list(rng.normal(0, 20e-9, n))
    boff = list(baseline_offsets) if baseline_offsets is not None else list(rng.normal(0, 2e-9, n))
    config.setdefault("sampling", "average")    # the detector averages over each sample interval
    config.setdefault("start", -40e-9)
    config.setdefault("turn", 20e-9)
    config.setdefault("end", -260e-9 if config.get("model", "beam") == "beam" else -500e-9)
    sens = 50e-9   # [m/V]: the instrument adds noise and drift in volts; we calibrate back to metres
    inst = build_instrument("ideal", overrides={"photodiode.sensitivity": sens,
                                                "noise.white": noise / sens,
                                                "drift.rate_rms": drift_rms / sens})
    curves = []
    for i, (v, f) in enumerate(zip(velocities, fs)):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", DynamicsWarning)
            tr = simulate(velocity=float(v), sample_rate=float(f), **config)
        raw = inst.record(tr, seed=int(rng.integers(2**31)))
        truth = dict(raw.truth or {})
        truth.update(zero_offset=float(zoff[i]), baseline_offset=float(boff[i]))
        curves.append(dataclasses.replace(
            raw, piezo_nominal=raw.piezo_nominal + zoff[i],
            piezo_measured=None if raw.piezo_measured is None else raw.piezo_measured + zoff[i],
            deflection_signal=np.asarray(raw.deflection_signal) * sens + boff[i],
            deflection_unit="m", truth=truth))
    return curves
