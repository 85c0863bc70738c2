"""Samples at a run's end taken while the scanner jumped on (not on the ramp) are dropped, with a warning.

Found on a real JPK file (matfiz/afm-curve-procesing ``dane_JPK/inne/force-save-2014.02.20-15.54.10``,
no licence stated: ``AFMFORCE_REAL_DATA``): the retract's last 2 of 3865 samples jumped 0.17 and 6.5 um in
0.5 ms (the ramp's steps ~1 nm) with the deflection at -8.5 nN; afmforce reported an adhesion of
-7.1 nN off a curve whose retract dips -0.405 nN below its far baseline (numpy on afmformats' read).
"""

from __future__ import annotations

import numpy as np
import pytest

from afmforce.analysis.orientation import END_JUMP_STEPS, orient
from afmforce.analysis.pipeline import analyze
from afmforce.io.curve import RawCurve

from realdata import real_file

K = 0.05          # [N/m]
STEP = 1e-9       # the ramp's step [m]
N = 600           # samples per run


def _soft_curve(tail_jump: float | None = None, head_jump: float | None = None) -> RawCurve:
    """A soft contact (Hertz-like F ~ d^1.5 past z = 450 nm), no adhesion, force in newtons; ``tail_jump``
    [m]: the retract's last 2 samples 0.2 um and then ``tail_jump`` away, at -8.5 nN (the real file's);
    ``head_jump``: the approach's first sample that far before the ramp's start."""
    z_app = np.arange(N) * STEP
    z = np.r_[z_app, z_app[::-1]]
    rng = np.random.default_rng(3)
    f = 50.0 * np.clip(z - 450e-9, 0, None) ** 1.5 + 5e-12 * rng.standard_normal(z.size)  # 2.9 nN at 150 nm
    seg = np.r_[np.zeros(N, np.int8), np.ones(N, np.int8)]
    if tail_jump is not None:
        z = np.r_[z, z[-1] - 0.2e-6, z[-1] - 0.2e-6 - tail_jump]
        f = np.r_[f, -1.7e-9, -8.5e-9]
        seg = np.r_[seg, 1, 1].astype(np.int8)
    if head_jump is not None:
        z = np.r_[z[0] - head_jump, z]
        f = np.r_[-3e-9, f]
        seg = np.r_[0, seg].astype(np.int8)
    meta = dict(spring_constant=K, sensitivity=50e-9, sample_rate=2000.0, velocity=STEP * 2000.0,
                source_file="soft curve (test)")
    return RawCurve(time=np.arange(z.size) / 2000.0, piezo_nominal=z.copy(), piezo_measured=z.copy(),
                    deflection_signal=f, segment=seg, metadata=meta, truth=None, deflection_unit="N")


def _absent(x) -> bool:
    """No value reported (None, or NaN in the Python result)."""
    return x is None or not np.isfinite(x)


def test_the_scanners_jump_after_the_retract_is_dropped_not_taken_for_adhesion():
    clean, jumped = analyze(_soft_curve()), analyze(_soft_curve(tail_jump=6.5e-6))
    assert _absent(clean.adhesion_force)                      # the curve has no adhesion
    assert _absent(jumped.adhesion_force), jumped.adhesion_force   # was -7.1 nN on the real file
    assert any("retract's last 2 samples lie past a position jump of 6500 nm" in w for w in jumped.warnings)
    assert jumped.indentation == pytest.approx(clean.indentation, rel=1e-6)


def test_a_jump_before_the_approach_is_dropped_and_a_ramp_is_left_alone():
    out, notes = orient(_soft_curve(head_jump=3e-6))
    assert len(out) == 2 * N and "approach's first 1 sample lies past a position jump" in notes[0]
    plain = _soft_curve()
    out, notes = orient(plain)
    assert out is plain and notes == ()
    # a step just under the threshold at the end is a ramp's (uneven sampling): kept
    c = _soft_curve(tail_jump=(END_JUMP_STEPS - 5) * STEP - 0.2e-6)
    c.piezo_nominal[-2] = c.piezo_measured[-2] = c.piezo_measured[-3] - (END_JUMP_STEPS - 5) * STEP / 2
    out, notes = orient(c)
    assert len(out) == len(c) and notes == ()


def test_real_jpk_2014_retract_ends_in_a_jump():
    """The real file: adhesion -0.395 nN (numpy on afmformats' read of the retract less its last 2 samples,
    against the median of its far 500: -0.405 nN), not -7.1 nN."""
    from afmforce.io import load

    r = analyze(load(real_file("jpk-force_matfiz_2014.02.20-15.54.10_retract-end-jump.jpk-force"))[0])
    assert r.adhesion_force == pytest.approx(-0.405e-9, rel=0.05)
    assert any("retract's last 2 samples lie past a position jump" in w for w in r.warnings)
