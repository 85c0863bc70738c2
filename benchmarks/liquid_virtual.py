"""Virtual liquid measurements made independently of the fitting path (issue 25).

The fit predicts curves with the compiled integrator (``simulate_many``); these curves
come from :func:`afmforce.dynamics.reference.reference_solve` -- scipy's Radau on the
equations written with the force laws of :mod:`afmforce.forces` -- at a tight tolerance,
sampled at points (fit them with ``sampling="point"``), with white noise, a random drift,
an unknown zero of the piezo position and an unknown baseline offset per curve. The
approach runs only (the fit of the slip length uses the approach).
"""

from __future__ import annotations

import numpy as np

from afmforce.dynamics import SimulationConfig
from afmforce.dynamics.reference import reference_solve
from afmforce.io.curve import RawCurve


def reference_curves(velocities, *, seed: int, sample_rates, noise: float = 0.05e-9,
                     drift_rms: float = 0.5e-9, rtol: float = 1e-8, **config) -> list[RawCurve]:
    """One approach per speed: reference solve + noise [m], drift [m/s] rms, offsets."""
    rng = np.random.default_rng(seed)
    out = []
    for v, fs in zip(velocities, sample_rates):
        cfg = SimulationConfig(velocity=float(v), sample_rate=float(fs), **config)
        t_turn = (cfg.turn - cfg.start) / v
        t = np.arange(0.0, t_turn + 0.5 / fs, 1.0 / fs)
        ref = reference_solve(cfg, rtol=rtol, atol=1e-14, t_stop=t_turn, sample_times=t)
        n = ref.time.size
        zoff, boff = rng.normal(0, 20e-9), rng.normal(0, 2e-9)
        y = ref.deflection + rng.normal(0, noise, n) + rng.normal(0, drift_rms) * ref.time + boff
        out.append(RawCurve(time=ref.time, piezo_nominal=ref.piezo_position + zoff,
                            deflection_signal=y, segment=np.zeros(n, int),
                            metadata={"velocity": float(v), "sample_rate": float(fs),
                                      "spring_constant": cfg.force_constant},
                            truth={"zero_offset": zoff, "baseline_offset": boff},
                            deflection_unit="m"))
    return out
