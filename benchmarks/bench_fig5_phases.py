"""Where the Fig-5 cycle's steps go, phase by phase (issue 35.5): ``python benchmarks/bench_fig5_phases.py``.

Runs the default Fig-5 cycle with the integrator as Python (``NUMBA_DISABLE_JIT``; the Python
integrator takes the compiled one's steps bitwise, docs/dynamics.md "The first call") and
records every accepted step (``radau.sample_step`` is called once per accepted step), then
counts them per phase of the cycle and prints, for the steps after the pull-off, the
separation, the step sizes and the free modes of the beam linearised there (eigenvalues of the
Jacobian): what the error control is resolving. Takes ~5-10 s (no compilation). Options:
``--config KEY=VALUE`` (repeatable, flat names, numbers in SI).
"""

from __future__ import annotations

import argparse
import os
import sys

os.environ["NUMBA_DISABLE_JIT"] = "1"      # before numba is imported

import numpy as np  # noqa: E402


def _parse(items):
    out = {}
    for item in items:
        k, v = item.split("=", 1)
        try:
            out[k] = float(v)
        except ValueError:
            out[k] = v
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--config", action="append", default=[], metavar="KEY=VALUE")
    args = ap.parse_args(argv)

    from afmforce.dynamics import SimulationConfig, radau, simulate
    from afmforce.dynamics.models import HQA, HQB, jac

    steps = []                                  # (t_old, t_new, y_old)
    inner = radau.sample_step

    def record(t_old, t_new, h, y_old, *rest):
        steps.append((t_old, t_new, y_old.copy()))
        return inner(t_old, t_new, h, y_old, *rest)

    radau.sample_step = record
    cfg = SimulationConfig(**_parse(args.config))
    tr = simulate(cfg)
    radau.sample_step = inner
    e = tr.events
    t0 = np.array([s[0] for s in steps])
    h = np.array([s[1] - s[0] for s in steps])
    win = cfg.spike_window
    t_turn = e.turn_time
    edges = [("approach, before jump-in", -np.inf, e.jump_in_time),
             ("jump-in to contact", e.jump_in_time, e.contact_time),
             ("contact to end of spike window", e.contact_time, e.contact_time + win),
             ("rest of the approach (in contact)", e.contact_time + win, t_turn),
             ("retract in contact", t_turn, e.pull_off_time),
             ("first 2 ms after pull-off", e.pull_off_time, e.pull_off_time + 2e-3),
             ("rest of the retract", e.pull_off_time + 2e-3, np.inf)]
    print(f"{cfg.model}: {tr.solver.steps} steps ({tr.solver.accepted} accepted, "
          f"{tr.solver.rejected} rejected), {len(tr.time)} samples")
    for name, a, b in edges:
        if not (np.isfinite(a) or np.isfinite(b)) or np.isnan(a) or np.isnan(b):
            continue
        sel = (t0 >= a) & (t0 < b)
        print(f"  {name:36s} {sel.sum():5d} accepted steps"
              + (f", step {h[sel].min():.3g}-{h[sel].max():.3g} s" if sel.any() else ""))
    # after the pull-off: separation, and the free modes of the linearised model there
    from afmforce.dynamics._setup import _setup
    st = _setup(cfg)
    sel = np.flatnonzero((t0 >= e.pull_off_time) & (t0 < e.pull_off_time + 2e-3))
    if sel.size:
        J = np.zeros((st.n, st.n))
        print("  after pull-off: t - t_pull [ms], h [nm], |dh/dt| / omega of the oscillatory mode "
              "[pm] (its amplitude, roughly), eigenvalues of the Jacobian [1/s]")
        for i in sel[:: max(1, sel.size // 6)]:
            t, _, y = steps[i]
            seg = [g for g in st.plan if g.t_start <= t <= g.t_end][-1]
            z = seg.position(t)
            jac(st.kmodel, st.p, z, seg.velocity, y, J)
            hq = (st.p[HQA], st.p[HQB]) if st.beam else (1.0, 0.0)
            sep = hq[0] * y[0] + hq[1] * y[1] - z
            n2 = st.n // 2
            hd = hq[0] * y[n2] + (hq[1] * y[n2 + 1] if st.beam else 0.0) - seg.velocity
            lam = np.linalg.eigvals(J)
            w = max(abs(x.imag) for x in lam)
            amp = abs(hd) / w if w > 0 else float("nan")
            osc = [f"{x.real:.4g}{x.imag:+.4g}j" for x in lam if x.imag >= 0]
            print(f"    {1e3 * (t - e.pull_off_time):7.3f} {1e9 * sep:7.3f} {1e12 * amp:8.2f}  "
                  + "  ".join(osc))
    return 0


if __name__ == "__main__":
    sys.exit(main())
