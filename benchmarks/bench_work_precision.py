"""Work-precision of the Fig-5 cycle: afmforce vs scipy Radau / BDF / LSODA (issue 12).

``python benchmarks/bench_work_precision.py [--full] [--cap SECONDS] [--json FILE]``

The default grid (rtol 1e-3..1e-5 for scipy, a 45 s cap per scipy solve) finishes in
about 5-10 minutes on a 2-core machine; ``--full`` adds rtol 1e-6 and raises the cap
to 600 s. A solve that hits the cap is reported as such ("> cap"), and tighter
tolerances of that method are skipped (they only cost more).

Every solver integrates the same equations (beam, xi 0.1 kg/s, 0.1 um/s,
-40 -> +20 -> -230 nm). scipy gets a lean scalar right-hand side and the analytic
Jacobian, one solve_ivp call per drive segment, pull-off by its event location.
Errors against a tight afmforce run (rtol 1e-8, atol 1e-15 m): approach deflection
(max over the 10 kHz samples before contact), pull-off position, hysteresis offset
(compliance lines fitted to the 10 kHz samples, as afmforce does). Wall times are
the best of several repeats (afmforce 7 before and 7 after the scipy solves, scipy 3
where one solve takes under 10 s), all measured in this run; the load average is
printed with the table. The headline ratio: afmforce at
default against the fastest scipy configuration whose three errors are all at most
afmforce's (or within approach 0.01 nm, pull-off 0.5 nm, hysteresis 0.005 nm).
Also: per-call overhead of simulate() on a short run.
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import sys
import time
import warnings

import numpy as np

TARGET = dict(approach=0.01e-9, pull_off=0.5e-9, hysteresis=0.005e-9)


def lean_problem(cfg):
    """Scalar f(t, y) and J(t, y) of the beam (eqs 22-28) for one drive segment."""
    from afmforce.dynamics.models import beam_couplings, beam_matrices

    A, (ma, mb) = beam_matrices(cfg.cantilever, cfg.m_joint, cfg.m_base)
    (hqa, hqb), (yqa, yqb), _ = beam_couplings(cfg.cantilever)
    a00, a01, a10, a11 = A[0, 0], A[0, 1], A[1, 0], A[1, 1]
    ima, imb = 1 / ma, 1 / mb
    ar, z0, xi = cfg.hamaker * cfg.radius, cfg.z0, cfg.xi
    cd = 6 * math.pi * cfg.viscosity * cfg.radius**2 / 4

    def make(z_a, t_a, v):
        def f(t, y):
            qa, qb, va, vb = y
            h = hqa * qa + hqb * qb - (z_a + v * (t - t_a))
            hd = hqa * va + hqb * vb - v
            ih2 = 1 / (h * h)
            r6 = (z0 * z0 * ih2) ** 3
            fz = -(ar / 12) * ih2 * (1 - 0.25 * r6) - cd * hd / h
            fy = -xi * (yqa * va + yqb * vb)
            return [va, vb, ima * (a00 * qa + a01 * qb + fz * hqa + fy * yqa),
                    imb * (a10 * qa + a11 * qb + fz * hqb + fy * yqb)]

        def jac(t, y):
            qa, qb, va, vb = y
            h = hqa * qa + hqb * qb - (z_a + v * (t - t_a))
            hd = hqa * va + hqb * vb - v
            ih2 = 1 / (h * h)
            r6 = (z0 * z0 * ih2) ** 3
            dfh = (ar / 6) * ih2 / h * (1 - r6) + cd * hd * ih2
            dfv = -cd / h
            return [[0, 0, 1, 0], [0, 0, 0, 1],
                    [ima * (a00 + hqa * dfh * hqa), ima * (a01 + hqa * dfh * hqb),
                     ima * (hqa * dfv * hqa - xi * yqa * yqa), ima * (hqa * dfv * hqb - xi * yqa * yqb)],
                    [imb * (a10 + hqb * dfh * hqa), imb * (a11 + hqb * dfh * hqb),
                     imb * (hqb * dfv * hqa - xi * yqb * yqa), imb * (hqb * dfv * hqb - xi * yqb * yqb)]]

        def hsep(t, y):
            return hqa * y[0] + hqb * y[1] - (z_a + v * (t - t_a))

        return f, jac, hsep

    return make, (hqa, hqb), (cfg.cantilever.theta0,)


class SolveTimeout(RuntimeError):
    """A scipy solve ran past the per-solve cap."""


def scipy_cycle(cfg, method, rtol, atol, cap=math.inf):
    """(samples dict, pull-off z) of a scipy solve of the cycle (SolveTimeout past ``cap`` s)."""
    from scipy.integrate import solve_ivp

    from afmforce.dynamics.drive import initial_state, segments
    from afmforce.dynamics.models import beam_couplings

    make, (hqa, hqb), _ = lean_problem(cfg)
    _, _, (tqa, tqb) = beam_couplings(cfg.cantilever)
    y = initial_state(cfg)
    atol_v = np.array([atol, atol, atol * 2 * math.pi * 1e7, atol * 2 * math.pi * 1e7])
    dt = 1 / cfg.sample_rate
    out = dict(t=[], z=[], d=[], th=[], h=[], seg=[])
    pull = math.nan
    t_start = time.perf_counter()
    for seg in segments(cfg):
        f0, jac, hsep = make(seg.z_start, seg.t_start, seg.velocity)
        calls = [0]

        def f(t, y, f0=f0, calls=calls):
            calls[0] += 1
            if calls[0] % 2000 == 0 and time.perf_counter() - t_start > cap:
                raise SolveTimeout(f"> {cap:g} s")
            return f0(t, y)

        ev = (lambda t, y: hsep(t, y) - cfg.contact_separation)
        ev.direction = 1
        kw = dict(jac=jac) if method != "LSODA" else dict(jac=jac)
        sol = solve_ivp(f, (seg.t_start, seg.t_end), y, method=method, rtol=rtol, atol=atol_v,
                        dense_output=True, events=ev if seg.kind == 1 else None,
                        first_step=1e-9, **kw)
        if sol.status < 0:
            raise RuntimeError(sol.message)
        k0 = math.ceil(seg.t_start / dt - 1e-9)
        if out["t"] and k0 * dt <= out["t"][-1][-1] + 1e-15:
            k0 += 1
        tt = np.arange(k0, math.floor(seg.t_end / dt + 1e-9) + 1) * dt
        Y = sol.sol(tt)
        zz = seg.position(tt)
        d = hqa * Y[0] + hqb * Y[1]
        out["t"].append(tt); out["z"].append(zz); out["d"].append(d)
        out["th"].append(tqa * Y[0] + tqb * Y[1]); out["h"].append(d - zz)
        out["seg"].append(np.full(tt.size, seg.kind))
        if seg.kind == 1 and sol.t_events[0].size and math.isnan(pull):
            pull = float(seg.position(sol.t_events[0][0]))
        y = sol.y[:, -1]
    return {k: np.concatenate(v) for k, v in out.items()}, pull


def measures(cfg, t, z, d, th, h, seg, pull, contact_z, contact_t):
    from afmforce.dynamics.events import compliance_lines

    beta = cfg.calibration_factor
    off, _ = compliance_lines(z, beta * th, h, seg, cfg.contact_separation, contact_z,
                              cfg.turn, beta)
    return dict(approach_d=d[(seg == 0) & (t < contact_t)], pull=pull, hyst=off)


def errors(m, ref):
    n = min(m["approach_d"].size, ref["approach_d"].size)
    return dict(approach=float(np.max(np.abs(m["approach_d"][:n] - ref["approach_d"][:n]))),
                pull_off=abs(m["pull"] - ref["pull"]), hysteresis=abs(m["hyst"] - ref["hyst"]))


def best_time(fn, n, long=math.inf):
    """Best wall time of up to ``n`` calls (stop repeating once one call takes ``long`` s).

    ``best_time.cpu`` is then the best CPU time of this thread over the same calls: on a
    shared machine the wall time of a long (scipy) solve grows with the load more than
    that of a short one, so the wall-time ratio drifts with the load; the CPU-time ratio
    much less.
    """
    ts, cs, res = [], [], None
    for _ in range(n):
        t0, c0 = time.perf_counter(), time.thread_time()
        res = fn()
        ts.append(time.perf_counter() - t0)
        cs.append(time.thread_time() - c0)
        if ts[-1] > long:
            break
    best_time.cpu = min(cs)
    return min(ts), res


def main(argv=None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--full", action="store_true", help="rtol down to 1e-6, 600 s cap per solve")
    ap.add_argument("--cap", type=float, default=None, help="seconds per scipy solve (default 45)")
    ap.add_argument("--json")
    args = ap.parse_args(argv)
    from afmforce.dynamics import SimulationConfig, simulate

    cfg = SimulationConfig()
    warnings.simplefilter("ignore")
    simulate()

    def ours(**kw):
        tr = simulate(**kw)
        e = tr.events
        return tr, measures(cfg, tr.time, tr.piezo_position, tr.deflection, tr.angle,
                            tr.separation, tr.segment, e.pull_off_position, e.contact_position,
                            e.contact_time)

    def timed_ours(kw):
        # only simulate() is timed (scipy's timing also excludes the error measures)
        t, tr = best_time(lambda: simulate(**kw), reps)
        cpu = best_time.cpu
        return t, ours(**kw), cpu

    tref, ref = ours(rtol=1e-8, atol=1e-15)
    rows = []
    reps = 7
    cap = args.cap if args.cap is not None else (600.0 if args.full else 45.0)
    n_ours = 0
    for kw in ([dict()] + [dict(rtol=r, atol=a) for r, a in ((1e-5, 1e-13), (1e-6, 1e-14))]):
        t, (tr, m), cpu = timed_ours(kw)
        rows.append(("afmforce", kw.get("rtol", 1e-4), kw.get("atol", 1e-12), t,
                     dict(errors(m, ref), cpu=cpu)))
        n_ours += 1
    tols = [(1e-3, 1e-11), (1e-4, 1e-12), (1e-5, 1e-13)] + ([(1e-6, 1e-14)] if args.full else [])
    wall0 = time.perf_counter()
    for method in ("Radau", "BDF", "LSODA"):
        capped = False
        for rtol, atol in tols:
            if capped:
                rows.append((f"scipy {method}", rtol, atol, math.nan,
                             dict(approach=math.nan, pull_off=math.nan, hysteresis=math.nan,
                                  failed="skipped (a looser rtol hit the cap)")))
                continue
            try:
                t, (s, pull) = best_time(lambda: scipy_cycle(cfg, method, rtol, atol, cap), 3, 10.0)
                # contact from samples (first h < hc on the approach)
                app = (s["seg"] == 0) & (s["h"] < cfg.contact_separation)
                tc = s["t"][app][0] if app.any() else math.inf
                zc = s["z"][app][0] if app.any() else math.nan
                m = measures(cfg, s["t"], s["z"], s["d"], s["th"], s["h"], s["seg"], pull,
                             zc, tc)
                rows.append((f"scipy {method}", rtol, atol, t,
                             dict(errors(m, ref), cpu=best_time.cpu)))
            except SolveTimeout as exc:
                capped = True
                rows.append((f"scipy {method}", rtol, atol, math.inf,
                             dict(approach=math.nan, pull_off=math.nan, hysteresis=math.nan,
                                  failed=f"did not finish: {exc}")))
            except Exception as exc:  # noqa: BLE001
                rows.append((f"scipy {method}", rtol, atol, math.nan,
                             dict(approach=math.nan, pull_off=math.nan, hysteresis=math.nan,
                                  failed=str(exc)[:60])))
            print(f"  ... {method} rtol {rtol:.0e} done ({time.perf_counter() - wall0:.0f} s so far)",
                  file=sys.stderr, flush=True)
    # the machine's load drifts: time afmforce's rows again after the scipy solves, keep the best
    for i in range(n_ours):
        name, r, a, t, e = rows[i]
        kw = {} if i == 0 else dict(rtol=r, atol=a)
        t2, _ = best_time(lambda kw=kw: simulate(**kw), reps)
        e = dict(e, cpu=min(e["cpu"], best_time.cpu))
        rows[i] = (name, r, a, min(t, t2), e)
    import os

    print("Fig-5 cycle work-precision (errors vs afmforce rtol 1e-8 / atol 1e-15); "
          f"{os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.1f}")
    print(f"{'solver':14s} {'rtol':>7s} {'atol':>7s} {'time':>9s} {'CPU':>9s} {'approach':>10s} "
          f"{'pull-off':>9s} {'hyster.':>9s}")
    for name, r, a, t, e in rows:
        print(f"{name:14s} {r:7.0e} {a:7.0e} {t * 1e3:7.1f}ms {e.get('cpu', math.nan) * 1e3:7.1f}ms "
              f"{e['approach'] * 1e9:8.4f}nm "
              f"{e['pull_off'] * 1e9:7.3f}nm {e['hysteresis'] * 1e9:7.4f}nm"
              + (f"  FAILED {e['failed']}" if "failed" in e else ""))
    ours_default = rows[0]
    ed = ours_default[4]
    need = {k: max(ed[k], TARGET[k]) for k in TARGET}
    print(f"\nequal accuracy: approach <= {need['approach'] * 1e9:.4f} nm, pull-off <= "
          f"{need['pull_off'] * 1e9:.3f} nm, hysteresis <= {need['hysteresis'] * 1e9:.4f} nm "
          "(afmforce default's errors, or the targets if larger)")
    ok = [r for r in rows[n_ours:] if math.isfinite(r[3]) and all(r[4][k] <= need[k] for k in TARGET)]
    best = min(ok, key=lambda r: r[3]) if ok else None
    if best:
        print(f"fastest competitor at equal accuracy: {best[0]} rtol {best[1]:.0e}: "
              f"{best[3] * 1e3:.0f} ms -> afmforce default ({ours_default[3] * 1e3:.1f} ms) "
              f"{best[3] / ours_default[3]:.0f}x faster (wall); CPU {best[4]['cpu'] * 1e3:.0f} ms vs "
              f"{ours_default[4]['cpu'] * 1e3:.1f} ms: {best[4]['cpu'] / ours_default[4]['cpu']:.0f}x")
    else:
        print("no scipy configuration reached afmforce's default accuracy")
    radau = [r for r in ok if r[0] == "scipy Radau"]
    if radau:
        rb = min(radau, key=lambda r: r[3])
        print(f"scipy Radau at equal accuracy: rtol {rb[1]:.0e}, {rb[3] * 1e3:.0f} ms -> "
              f"{rb[3] / ours_default[3]:.0f}x")
    # per-call overhead on a short run
    short = dict(start=-8e-9, turn=-6.5e-9, end=-9e-9, velocity=1e-6, sample_rate=1e5)
    t_short, trs = best_time(lambda: simulate(**short), 50)
    t_med = statistics.median(best_time(lambda: simulate(**short), 1)[0] for _ in range(50))
    print(f"per-call simulate() on a short run ({trs.solver.steps} steps): best {t_short * 1e3:.3f} ms, "
          f"median {t_med * 1e3:.3f} ms")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(dict(rows=[(n, r, a, t, e) for n, r, a, t, e in rows],
                           ratio=(best[3] / ours_default[3]) if best else None,
                           ratio_cpu=(best[4]["cpu"] / ours_default[4]["cpu"]) if best else None,
                           per_call_s=t_short), fh, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
