"""Colloid-probe cycles in a viscous liquid from the independent scipy solver (issue 34).

Curves made by :func:`afmforce.dynamics.reference.reference_solve` (scipy's Radau on the
equations written with the force laws of :mod:`afmforce.forces`), not by the compiled
integrator the fit uses: approach and retract without a pause, sampled at points, white
noise, a random drift, an unknown zero of the piezo position and baseline offset per
curve, written as raw text files whose header holds ``spring_constant`` (the files'
calibration, 0.25 N/m; the spring model's default is 0.21 N/m).

Two sets, each with a small (tests) and a full (benchmark) size:

* ``slip``: sphere R = 10 um on a flat, slip b = 5 nm, constant lever drag 5e-5 kg/s,
  viscosity 0.05 Pa s, the spring model's defaults otherwise; 2-20 um/s at 20 kHz.
* ``water``: the DLVO set: psi -40 mV (constant potential), Debye length 10 nm, A 1e-20 J,
  no slip, no lever drag, water (0.89 mPa s).
"""

from __future__ import annotations

import numpy as np

from afmforce.dynamics import SimulationConfig
from afmforce.dynamics.reference import reference_solve
from afmforce.io.curve import RawCurve

K_FILE = 0.25
SPEEDS = (2e-6, 5e-6, 10e-6, 20e-6)
#: The model's other parts at the defaults of ``afmforce simulate --model spring`` (A 5e-19 J,
#: z0 0.35 nm, mass 10 ng), as the issue's command fits them.
SLIP = dict(model="spring", spring_constant=K_FILE, radius=10e-6, geometry="sphere-flat",
            viscosity=0.05, slip_length=5e-9, lever_drag=5e-5)
WATER = dict(model="spring", spring_constant=K_FILE, radius=10e-6, geometry="sphere-flat",
             viscosity=0.89e-3, permittivity=78.4, hamaker=1e-20,
             double_layer="constant_potential", surface_potential=-0.04, debye_length=10e-9)
#: Drive of each set and size: approach from ``start`` to ``turn``, retract to ``end`` [m], and
#: the sample rate [Hz]. ``full`` is the issue's set (4 cycles, 107,100 samples at 20 kHz);
#: ``small`` a shorter approach for the tests (1 um: 39,100 samples); the water set's double
#: layer reaches ~100 nm, so its drive is shorter (``water``, 23,800 samples at 20 kHz).
SIZES = {"small": (dict(start=-1000e-9, turn=150e-9, end=-1000e-9), 20e3),
         "full": (dict(start=-3000e-9, turn=150e-9, end=-3000e-9), 20e3),
         "water": (dict(start=-600e-9, turn=100e-9, end=-600e-9), 20e3)}


def cycles(config: dict, size: str = "small", *, seed: int = 1, speeds=SPEEDS,
           drive: dict | None = None, noise: float = 0.05e-9, drift_rms: float = 0.2e-9,
           rtol: float = 1e-8, oversample: int = 1) -> list[RawCurve]:
    """One approach-retract cycle per speed from the reference solver (``size`` of
    :data:`SIZES`, or ``drive`` = start, turn, end [m]), with white noise [m], a drift [m/s]
    rms, a random zero of position (20 nm) and baseline offset (2 nm) per curve.

    The first sample is the drive's start (the lever at rest there, as the fit's model starts).
    ``oversample=1``: point samples; more: each sample is the mean of the solution at
    ``oversample`` points spread over the sample interval centred on its time (midpoint rule),
    as an averaging detector records it, the first interval starting at the drive's start."""
    rng = np.random.default_rng(seed)
    out = []
    sdrive, sample_rate = SIZES[size]
    for v in speeds:
        cfg = SimulationConfig(velocity=float(v), sample_rate=float(sample_rate),
                               **{**config, **sdrive, **(drive or {})})
        t_end = ((cfg.turn - cfg.start) + (cfg.turn - cfg.end)) / v
        dt = 1.0 / sample_rate
        t = (np.arange(0.0, t_end - 0.5 * dt, dt) if oversample == 1
             else np.arange(0.5 * dt, t_end - 0.5 * dt, dt))   # every interval inside the run
        sub = (np.arange(oversample) - 0.5 * (oversample - 1)) * dt / oversample
        ref = reference_solve(cfg, rtol=rtol, atol=1e-14,
                              sample_times=(t[:, None] + sub[None, :]).ravel())
        m = ref.time.size // oversample
        time, defl, piezo = (a[:m * oversample].reshape(m, oversample).mean(axis=1)
                             for a in (ref.time, ref.deflection, ref.piezo_position))
        n = time.size
        zoff, boff = rng.normal(0, 20e-9), rng.normal(0, 2e-9)
        y = defl + rng.normal(0, noise, n) + rng.normal(0, drift_rms) * time + boff
        seg = (time > (cfg.turn - cfg.start) / v).astype(int)
        out.append(RawCurve(time=time, piezo_nominal=piezo + zoff,
                            deflection_signal=y, segment=seg,
                            metadata={"velocity": float(v), "sample_rate": float(sample_rate),
                                      "spring_constant": K_FILE},
                            truth={"zero_offset": zoff, "baseline_offset": boff},
                            deflection_unit="m"))
    return out


def write_cycles(curves, directory, stem: str = "c") -> list:
    """Write ``curves`` as raw text files ``c1.txt``, ... in ``directory``; returns the paths."""
    from afmforce.io.native.rawfile import write_raw

    paths = []
    for i, c in enumerate(curves):
        p = directory / f"{stem}{i + 1}.txt"
        write_raw(c, p)
        paths.append(p)
    return paths
