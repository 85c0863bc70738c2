"""The six findings of issue 12, as runnable cases (used by tests/dynamics/make_references.py).

``CASES``: name -> simulate() overrides. Run this file to print what the
current code gives at default settings next to a tighter solve.
"""
from __future__ import annotations

import math
import time
import warnings

CASES = {
    # finding 1: bouncing probes (spring model, air)
    "bounce_heavy": dict(model="spring", mass=5e-8, spring_constant=0.5, radius=500e-9,
                         velocity=10e-6, start=-60e-9, turn=20e-9, end=-320e-9),
    "bounce_light": dict(model="spring", mass=1e-12, spring_constant=0.1, radius=50e-9,
                         velocity=50e-6, start=-30e-9, turn=10e-9, end=-200e-9),
    "bounce_random": dict(model="spring", mass=6.47e-9, spring_constant=0.366, radius=312e-9,
                          hamaker=6.06e-19, velocity=31.7e-6, start=-60e-9, turn=20e-9,
                          end=-320e-9),
    # finding 2: load-dependent friction
    "load_friction": dict(friction="load", xi=0.01, zeta=2e15, velocity=0.5e-6,
                          start=-40e-9, turn=20e-9, end=-250e-9),
    # finding 3: jump-in position of the Fig 9 spring, slow
    "fig9_slow_jump": dict(model="spring", mass=1e-9, spring_constant=0.21, radius=220e-9,
                           velocity=0.1e-6, start=-20e-9, turn=5e-9, end=-60e-9),
    # finding 4: slow Fig 9 run
    "fig9_1nms": dict(model="spring", mass=1e-9, spring_constant=0.21, radius=220e-9,
                      velocity=1e-9, start=-20e-9, turn=5e-9, end=-400e-9),
    # finding 5/6: Fig 1 style spring case and Fig 5
    "fig5": dict(),
}


def summarize(tr):
    e = tr.events
    return dict(jump=e.jump_in_position * 1e9, contact=e.contact_position * 1e9,
                pull=e.pull_off_position * 1e9, pull_force=e.pull_off_force * 1e9,
                hyst=e.hysteresis_offset * 1e9, slope=e.compliance_slope * 1e9,
                spike=e.spike_height * 1e9, steps=tr.solver.steps,
                wall=tr.solver.wall_time)


def scipy_window():
    """The load-friction case from -8 nm, scipy Radau (rtol 1e-8, atol 1e-15) up to 1 ms after
    contact: separation range over the last 0.1 ms (tests/dynamics/test_issue12.py)."""
    import numpy as np
    from afmforce.dynamics import SimulationConfig
    from afmforce.dynamics.reference import reference_solve
    cfg = SimulationConfig(**dict(CASES["load_friction"], start=-8e-9, turn=-2.6e-9, end=-30e-9))
    pre = reference_solve(cfg, rtol=1e-8, atol=1e-15, t_stop=0.0093)
    tc = pre.contact_time
    tw = np.linspace(tc + 0.9e-3, tc + 1.0e-3, 4001)
    ref = reference_solve(cfg, rtol=1e-8, atol=1e-15, t_stop=tc + 1.0e-3, sample_times=tw)
    print(f"contact t = {tc:.9g} s; h over [tc+0.9, tc+1.0] ms: "
          f"{ref.separation.min() * 1e9:.5f} .. {ref.separation.max() * 1e9:.5f} nm")


def main():
    import sys
    from afmforce.dynamics import simulate
    if sys.argv[1:] == ["--scipy-window"]:
        return scipy_window()
    names = sys.argv[1:] or list(CASES)
    for name in names:
        for extra in (dict(), dict(rtol=1e-6, atol=1e-14), dict(rtol=1e-8, atol=1e-15)):
            t0 = time.perf_counter()
            try:
                with warnings.catch_warnings(record=True) as w:
                    warnings.simplefilter("always")
                    tr = simulate(**CASES[name], **extra)
                s = summarize(tr)
                msg = " ".join(f"{k}={v:.5g}" for k, v in s.items())
                if w:
                    msg += f" WARN[{w[0].message}]"
            except Exception as exc:  # noqa: BLE001
                msg = f"{type(exc).__name__}: {exc}"
            print(f"{name:16s} {extra!s:32s} {time.perf_counter() - t0:7.2f}s {msg}", flush=True)


if __name__ == "__main__":
    main()
