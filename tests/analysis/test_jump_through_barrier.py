"""A jump into contact through a repulsive barrier is physics, not an impossible number
(`afmforce.analysis.jumps.JumpIn.through_barrier`; the result's ``barrier_force`` and
``barrier_jump_distance``).

In liquid a double layer pushes the tip back; the tip goes over the barrier's top and jumps into the
primary minimum once the force gradient beyond the top exceeds k: the static condition dF/dh = k at h*,
where the force is still repulsive. On a hard contact it lands on the compliance line at the
deflection the position then gives, which can be repulsive too (Israelachvili, Intermolecular and
Surface Forces, 3rd ed., ch. 14; Butt, Cappella & Kappl, Surf. Sci. Rep. 59, 1 (2005)). Before, such
a curve was refused: "physically impossible: the jump into contact lands at +... nN".

The curve here is quasi-static (the statics: the tip on the stable branch of F(h) = k (h + z)),
with the law written out below (weak-overlap double layer, Derjaguin, sphere on flat, plus eq 2's van
der Waals with its soft wall) and h* found by a root find of dF/dh = k with scipy, not by afmforce.

Real case: curve 22 (map x 6, y 1) of the Bruker force volume on a gel (shared/data/real). Its approach
rises through a repulsive, curved indentation (0.07-0.2 of the position), and 0.8 nm of deflection
(+4.38 -> +3.58 nm, 0.58 -> 0.48 nN) falls within one sample before the indentation goes on: the
tip pushes through a layer that yields (a breakthrough), a jump through a repulsive barrier, not a
jump into contact from the free branch, nor a misplaced zero (the free baseline is at zero 1.7 um
out). Taken for a jump into contact it made the gel "hard" (no modulus) and the curve "physically
impossible"; now the curve is a soft contact with its modulus, as its neighbours.
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest
from scipy.optimize import brentq

from afmforce.analysis.jumps import JumpIn, PullOff, find_jump_in
from afmforce.analysis.pipeline import analyze
from afmforce.analysis.steps.jumps import _repulsive
from afmforce.io import load
from afmforce.io.curve import RawCurve
from realdata import real_file  # noqa: E402  (tests/ is on sys.path: tests/conftest.py)

EPS0 = 8.8541878128e-12
# a 20 nm tip on a flat in 6 mM 1:1 salt (Debye length 4 nm), both surfaces at -60 mV; A = 5e-20 J
A_TIP, PSI, DEBYE, HAMAKER, Z0, EPS = 20e-9, -0.06, 4e-9, 5e-20, 0.35e-9, 78.5
K, NOISE, SENS, STEP, RATE = 0.02, 0.02e-9, 50e-9, 0.05e-9, 2000.0


def force(h):
    """F(h) [N], positive repulsive: 2 pi a W(h), W = 2 eps eps0 kappa psi^2 exp(-kappa h); eq 2 (R = 2a)."""
    kap = 1.0 / DEBYE
    dl = 2 * math.pi * A_TIP * 2 * EPS * EPS0 * kap * PSI**2 * np.exp(-kap * h)
    return dl - HAMAKER * 2 * A_TIP / (12 * h**2) * (1 - Z0**6 / (4 * h**6))


def gradient(h):
    """dF/dh [N/m]."""
    kap = 1.0 / DEBYE
    dl = 2 * math.pi * A_TIP * 2 * EPS * EPS0 * kap * PSI**2 * np.exp(-kap * h)
    return -kap * dl + HAMAKER * 2 * A_TIP / 6 * (h**-3 - Z0**6 * h**-9)


def _folds():
    """(h_c, h_top, h*): the inner fold, the barrier's top and the outer fold (dF/dh = k) [m]."""
    h = np.geomspace(0.2e-9, 200e-9, 40000)
    g = gradient(h) - K
    cross = np.flatnonzero(np.sign(g[:-1]) != np.sign(g[1:]))
    h_c = brentq(lambda x: gradient(x) - K, h[cross[0]], h[cross[0] + 1], xtol=1e-18)
    h_star = brentq(lambda x: gradient(x) - K, h[cross[-1]], h[cross[-1] + 1], xtol=1e-18)
    h_top = brentq(gradient, h_star, 10e-9, xtol=1e-18)
    return h_c, h_top, h_star


H_C, H_TOP, H_STAR = _folds()


def _branch(z, free):
    """The stable separation at base position z [m] on the free (h > h*) or contact (h < h_c) branch, or
    None where that branch has ended: the root of F(h) = k (h + z), the deflection being h + z."""
    g = lambda h: force(h) - K * (h + z)  # noqa: E731
    lo, hi = (H_STAR, 1e-6) if free else (0.2e-9, H_C)
    if not g(lo) > 0 > g(hi):
        return None
    return brentq(g, lo, hi, xtol=1e-18)


def dlvo_curve(seed=0):
    """Approach from 60 nm to 20 nm past contact and back: the tip on the free branch until it ends at
    h*, on the contact branch until that ends (pull-off). Returns the curve and the statics' numbers."""
    z = np.concatenate([np.arange(-60e-9, 20e-9, STEP), np.arange(20e-9, -130e-9, -STEP)])
    seg = (np.arange(z.size) >= np.arange(-60e-9, 20e-9, STEP).size).astype(np.int8)
    h = np.empty(z.size)
    on_contact, last_free = False, -1
    for i, zi in enumerate(z):
        if seg[i] == 0:
            hf = None if on_contact else _branch(zi, True)
            on_contact = hf is None
            h[i] = _branch(zi, False) if on_contact else hf
            last_free = i if not on_contact else last_free
        else:
            hc = _branch(zi, False) if on_contact else None
            on_contact = hc is not None
            h[i] = hc if on_contact else _branch(zi, True)
    d = h + z
    rng = np.random.default_rng(seed)
    volts = (d + NOISE * rng.standard_normal(z.size)) / SENS + 0.2
    meta = dict(spring_constant=K, sensitivity=SENS, sample_rate=RATE, velocity=STEP * RATE,
                source_file="quasi-static DLVO curve (test)")
    curve = RawCurve(time=np.arange(z.size) / RATE, piezo_nominal=z.copy(), piezo_measured=z.copy(),
                     deflection_signal=volts, segment=seg, metadata=meta, truth=None, deflection_unit="V")
    return curve, dict(last_free=last_free, d_before=d[last_free], d_after=d[last_free + 1], d=d, h=h)


def test_the_jump_through_a_double_layer_barrier_is_reported_not_refused():
    f_star = float(force(H_STAR))
    assert H_C < H_STAR < H_TOP and f_star > 40e-12       # the instability lies beyond the top, still repulsive
    curve, s = dlvo_curve()
    # the statics' last free sample, one position step (0.05 nm) or less before h*: a little higher on the
    # barrier's far side (F - F(h*) ~ k (h - h*) near the fold, h - h* ~ sqrt(step))
    f_last = K * s["d_before"]
    assert 0 < f_last - f_star < 5e-12
    assert s["d_after"] > 0.5e-9                          # it lands on the contact repulsive: refused before
    r = analyze(curve)
    assert "impossible" not in r.verdict, r.verdict
    assert not {"jumps", "jump_in", "vdw"} & {k for k, v in r.not_applicable.items() if "impossible" in v}
    assert r.contact_kind == "hard"
    ji = r.details["jumps"].jump_in
    assert ji.found and ji.through_barrier
    # the analysis's zero of force near the barrier (5-10 nm out): its drift line runs through the free
    # branch's own weak force (the van der Waals tail: -1.7 pN at 10 nm), 1.9 pN above the true zero here
    free = (np.arange(s["d"].size) <= s["last_free"]) & (s["h"] > 5e-9) & (s["h"] < 10e-9)
    base = float(np.median(r.force[free] - K * s["d"][free]))
    assert abs(base) < 0.1 * f_star
    # the barrier's height: F(h*) within the noise (5 k sigma) and the sampling (f_last - f_star), on that zero
    assert r.barrier_force - base == pytest.approx(f_star, abs=5 * K * NOISE + (f_last - f_star))
    assert r.barrier_force == pytest.approx(f_star, abs=5 * K * NOISE + (f_last - f_star) + abs(base))
    # the jump: the statics' fall of the deflection from the last free sample to the first on the contact
    assert r.barrier_jump_distance == pytest.approx(s["d_before"] - s["d_after"], abs=5 * math.sqrt(2) * NOISE)
    assert r.jump_in_force - base == pytest.approx(K * s["d_after"], abs=5 * K * NOISE)
    assert r.pull_off_force < 0                            # the primary minimum's adhesion stays


def test_only_a_rise_makes_a_barrier():
    """A downward step from a repulsive deflection is a barrier only when the approach rose to it from zero
    force; on a free branch that never comes down to zero the zero is misplaced: the landing is judged."""
    run = SimpleNamespace(index=np.arange(40), split=30, has_compliance=True, saturated=np.zeros(40, bool))
    z = np.arange(40) * 1e-9
    rise = np.concatenate([np.zeros(25), np.linspace(0.5e-9, 3e-9, 5), np.linspace(1e-9, 10e-9, 10)])
    ji = find_jump_in(rise, z, z, run, 0.02e-9, K, attractive_below=0.1e-9)
    assert ji.found and ji.through_barrier and ji.jump_distance == pytest.approx(2e-9)
    assert ji.force_before == pytest.approx(K * 3e-9)
    assert _repulsive(ji, None, 0.1e-9) is None
    offset = rise + 5e-9                                   # the same curve with its zero 5 nm off
    ji = find_jump_in(offset, z, z, run, 0.02e-9, K, attractive_below=0.1e-9)
    assert ji.found and not ji.through_barrier
    assert "physically impossible: the jump into contact lands at" in _repulsive(ji, None, 0.1e-9)
    # a rise that starts in an attraction (the tip jumped in before it, 6 samples before the split) and a fall
    # into attraction: a slip in contact (a stiff lever's in air; the Nanosurf map's curve 52: +3.7 -> -0.6 nN
    # after a jump to -2.8 nN), not a barrier
    slip = rise.copy()
    slip[22:25], slip[30] = -2e-9, -0.5e-9
    ji = find_jump_in(slip, z, z, run, 0.02e-9, K, attractive_below=0.1e-9)
    assert ji.found and ji.index == 29 and not ji.through_barrier
    # a jump-in that rises (a step away from the surface on the approach) stays impossible
    nan = math.nan
    away = JumpIn(True, 10, nan, 1e-9, 0.0, 1.5e-9, 0.0, 3e-11, 30.0)
    assert _repulsive(away, PullOff(False, -1, nan, nan, nan, nan, 0.0, False), 1e-10) is not None


VOLUME = "bruker-nanoscope_force-volume_v9.2_Egel.spm"


def test_egel_curve_22_breakthrough_is_not_refused():
    curves = load(real_file(VOLUME))
    c = curves[22]
    assert (c.metadata["map_x"], c.metadata["map_y"]) == (6, 1)
    # the raw approach, read without afmforce's analysis: the header's DeflSens (27.39 nm/V) and k (0.1332 N/m)
    v = np.asarray(c.deflection_signal, float)[np.asarray(c.segment) == 0]
    d = (v - np.median(v[:200])) * 27.39e-9                 # from the free baseline, 1.7 um out
    turn = int(np.argmax(d))
    s = int(np.argmin(np.diff(d[:turn])))                  # the largest fall of the deflection on the approach
    assert 0.6e-9 < d[s] - d[s + 1] < 1.0e-9               # 0.8 nm in one sample
    assert 0.1332 * d[s + 1] > 0.3e-9                      # from a repulsive load, and landing on one
    assert np.all(np.diff(d[s - 25: s + 1]) > -0.1e-9)      # the load rose to it, no attraction before
    r = analyze(c)
    assert "impossible" not in r.verdict, r.verdict
    assert r.contact_kind == "soft" and np.isfinite(r.adhesion_force) and r.adhesion_force < 0
    # its modulus, as its neighbours' (x 5 and x 7 of the same row, with no step)
    neighbours = [analyze(curves[n]).youngs_modulus for n in (21, 23)]
    assert min(neighbours) / 1.5 < r.youngs_modulus < 1.5 * max(neighbours), (r.youngs_modulus, neighbours)
