"""Lever damping and load-dependent friction (issue 23), in one command.

``python benchmarks/bench_damping.py [--q 30,100,300] [--reference]``

1. Issue 12's load-friction case (beam, ``friction=load``, xi 0.01 kg/s, zeta 2e15 kg/(s N^2),
   0.5 um/s, -40 -> +20 -> -250 nm) undamped and at each quality factor: hysteresis offset,
   compliance slope, steps and wall time (docs/dynamics.md, "Cantilever damping").
2. ``--reference``: the shortened cycle (-10 -> +20 -> -2 nm) at Q = 30 with the scipy reference
   of the full damped equations (``afmforce.dynamics.reference``, Radau, rtol 1e-8, atol 1e-15;
   ~4 CPU minutes) against afmforce at default and tight tolerances: the hysteresis offset of
   the same compliance-line fit.
3. The undamped Fig-5 cycle's time per run next to the damped one (Q = 300), best of 20: the
   damping costs four multiply-adds per right-hand side.
4. First, the contact mode's frequency and Q at three loads (eigen-analysis of the linearised
   contact): Rayleigh damping with Q for both free modes reaches it weakly.
"""

from __future__ import annotations

import argparse
import time
import warnings

import numpy as np

LOAD = dict(friction="load", xi=0.01, zeta=2e15, velocity=0.5e-6, start=-40e-9, turn=20e-9,
            end=-250e-9)
DEFAULT_Q = "none,30,50,100,150,200,300,1e3,1e4,1e5,300/30,300/100"


def _q(text: str):
    q1, _, q2 = text.partition("/")
    return (None if q1 == "none" else float(q1)), (float(q2) if q2 else None)


def table(qs) -> None:
    from afmforce.dynamics import simulate

    print("load-friction case: Q (Q2)        hysteresis [nm]   slope [nm/rad]   steps      wall [s]")
    for q1, q2 in qs:
        t0 = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            tr = simulate(**LOAD, quality_factor=q1, quality_factor_2=q2)
        e = tr.events
        name = "none" if q1 is None else f"{q1:g}" + (f" ({q2:g})" if q2 else "")
        print(f"  {name:28s} {e.hysteresis_offset * 1e9:12.4f} {e.compliance_slope * 1e9:16.6g} "
              f"{tr.solver.steps:10d} {time.perf_counter() - t0:10.2f}", flush=True)


def reference(q: float = 30.0) -> None:
    from afmforce.dynamics import SimulationConfig, simulate
    from afmforce.dynamics.reference import reference_solve

    cfg = SimulationConfig(**dict(LOAD, start=-10e-9, end=-2e-9), quality_factor=q)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        tr = simulate(cfg)
        tight = simulate(cfg, rtol=1e-7, atol=1e-15)
    t0 = time.perf_counter()
    ref = reference_solve(cfg, rtol=1e-8, atol=1e-15, sample_times=tr.time)
    wall = time.perf_counter() - t0
    e = tr.events
    z, d, h = ref.piezo_position, cfg.calibration_factor * ref.angle, ref.separation
    t_turn = (cfg.turn - cfg.start) / cfg.velocity
    span = e.turn_position - e.contact_position
    lo, hi = e.contact_position + 0.25 * span, e.turn_position - 0.25 * span
    fits = []
    for approach in (True, False):
        m = ((ref.time <= t_turn) == approach) & (h < cfg.contact_separation) & (z >= lo) & (z <= hi)
        c1, c0 = np.polyfit(d[m], z[m], 1)
        fits.append((c0, c1, d[m].min(), d[m].max()))
    (a0, a1, alo, ahi), (b0, b1, blo, bhi) = fits
    dmid = 0.5 * (max(alo, blo) + min(ahi, bhi))
    print(f"shortened cycle at Q = {q:g}: hysteresis offset [nm]")
    print(f"  scipy Radau rtol 1e-8 ({ref.steps} steps, {wall:.0f} s): "
          f"{((a0 + a1 * dmid) - (b0 + b1 * dmid)) * 1e9:.6f}")
    print(f"  afmforce default ({tr.solver.steps} steps): {e.hysteresis_offset * 1e9:.6f}")
    print(f"  afmforce rtol 1e-7, atol 1e-15 ({tight.solver.steps} steps): "
          f"{tight.events.hysteresis_offset * 1e9:.6f}")


def contact_modes(qs=((300.0, None), (30.0, None), (300.0, 30.0))) -> None:
    """Frequency and Q of the beam's contact mode (linearised at three loads; eigenvalues of
    M q'' + C q' + (K + kappa dh dh^T) q = 0): how far the Rayleigh damping reaches it."""
    from afmforce.dynamics import SimulationConfig
    from afmforce.dynamics.damping import beam_damping, free_modes
    from afmforce.dynamics.models import beam_couplings, beam_matrices
    from afmforce.forces import vdw_force, vdw_force_gradient

    cfg = SimulationConfig(**LOAD)
    A, masses = beam_matrices(cfg.cantilever, cfg.m_joint, cfg.m_base)
    hq = beam_couplings(cfg.cantilever)[0]
    Mi = np.diag(1.0 / np.array(masses))
    w = free_modes(A, masses) / (2 * np.pi * 1e3)
    print(f"free modes {w[0]:.4g} kHz, {w[1]:.4g} kHz; contact mode (load, frequency, Q):")
    for q1, q2 in qs:
        C = beam_damping(A, masses, q1, q2)
        row = []
        for h in (0.9 * cfg.z0, 0.8 * cfg.z0, 0.7 * cfg.z0):
            K = -A - float(vdw_force_gradient(h, cfg.radius, cfg.hamaker, cfg.z0)) * np.outer(hq, hq)
            lam = np.linalg.eigvals(np.block([[np.zeros((2, 2)), np.eye(2)], [-Mi @ K, -Mi @ C]]))
            lam = min(lam[lam.imag > 0], key=abs)
            fz = float(vdw_force(h, cfg.radius, cfg.hamaker, cfg.z0))
            row.append(f"{fz * 1e9:+.3g} nN {abs(lam) / 2e3 / np.pi:.0f} kHz Q {abs(lam) / (2 * abs(lam.real)):.3g}")
        print(f"  Q {q1:g}" + (f" (Q2 {q2:g})" if q2 else "") + ": " + "; ".join(row))


def speed(repeat: int = 20) -> None:
    from afmforce.dynamics import simulate

    best = {}
    for _ in range(repeat):
        for q in (None, 300.0):
            t0 = time.perf_counter()
            simulate(quality_factor=q)
            best[q] = min(best.get(q, np.inf), time.perf_counter() - t0)
    print(f"Fig-5 cycle, best of {repeat} (interleaved): undamped {best[None] * 1e3:.2f} ms, "
          f"Q = 300 {best[300.0] * 1e3:.2f} ms")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--q", default=DEFAULT_Q, help=f"quality factors, Q or Q/Q2 (default {DEFAULT_Q})")
    ap.add_argument("--reference", action="store_true", help="also the scipy reference (minutes)")
    args = ap.parse_args(argv)
    contact_modes()
    speed()
    table([_q(t) for t in args.q.split(",")])
    if args.reference:
        reference()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
