"""The one-pass orientation scan (``orientation.plain_scan``, issue 35 item 2) decides as ``orient``'s own steps.

Where the scan says a curve needs no change, ``orient``'s numpy steps (the scan switched off) must return the
curve itself without a note, and ``prepare`` given the scan must give the state it gives without it (the
position's direction and span checks, the sign check). Checked on every curve of ``tests/data`` (and the
shared real set when present), on crafted curves that break each convention, and on random curves whose
run ends step near the end-jump threshold (the scan shows "no jump" without the median: a screen).
"""

from __future__ import annotations

import dataclasses
import warnings
from pathlib import Path

import numpy as np
import pytest

from afmforce.analysis import orientation
from afmforce.analysis.orientation import END_JUMP_STEPS, orient, plain_scan
from afmforce.analysis.state import prepare
from afmforce.errors import AfmforceError
from afmforce.io import load
from afmforce.io.curve import RawCurve

from realdata import DATA, SHARED

pytestmark = pytest.mark.skipif(not orientation.COMPILED, reason="the scan runs compiled only")


def _orient_steps(curve, channel="auto"):
    """``orient`` by its own numpy steps (the scan off)."""
    keep = orientation.plain_scan
    orientation.plain_scan = lambda *a, **k: None
    try:
        return orient(curve, channel)
    finally:
        orientation.plain_scan = keep


def _same_state(a, b):
    assert a.channel == b.channel and a.warnings == b.warnings
    for name in ("z", "signal", "time"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    assert a.curve is b.curve or a.curve.deflection_signal is b.curve.deflection_signal or np.array_equal(
        a.curve.deflection_signal, b.curve.deflection_signal)


def _check(curve, channel="auto"):
    """The scan's verdict against the steps'; returns whether the scan decided."""
    scan = plain_scan(curve, channel)
    out, notes = _orient_steps(curve, channel)
    if scan is None:
        return False
    assert out is curve and notes == (), (notes, curve.metadata.get("source_file"))
    try:
        plain = prepare(curve, channel)
    except AfmforceError as exc:
        with pytest.raises(type(exc), match="."):
            prepare(curve, channel, scan=scan)
        return True
    _same_state(prepare(curve, channel, scan=scan), plain)
    return True


def _curves(folder: Path, per_file: int = 3):
    for path in sorted(folder.iterdir()):
        if not path.is_file() or path.suffix in (".md", ".py", ".json", ".gz", ".zip"):
            continue
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                curves = load(path)
        except Exception:
            continue
        yield from ((path.name, c) for c in list(curves)[:per_file])


def test_scan_decides_as_orient_on_the_repository_files():
    decided = [name for name, c in _curves(DATA) if _check(c)]
    assert len(decided) >= 20, decided   # the readers' curves: the scan decides most


@pytest.mark.skipif(not SHARED.is_dir(), reason="no shared real set")
def test_scan_decides_as_orient_on_the_shared_real_set():
    decided = [name for name, c in _curves(SHARED, 2) if _check(c)]
    assert decided


N = 400


def _curve(*, reverse_app=False, backwards_time=False, cycles=1, tail_step=None, falling=False, negate=False,
           rng=None):
    """A ramp (the position rising on the approach), a linear contact past 70 % of it, some noise."""
    rng = np.random.default_rng(1) if rng is None else rng
    z_app = np.linspace(0.0, 1e-6, N)
    z = np.tile(np.r_[z_app, z_app[::-1]], cycles)
    s = np.clip(z - 0.7e-6, 0, None) * 1e-2 / 0.3e-6 + 1e-5 * rng.standard_normal(z.size)
    seg = np.tile(np.r_[np.zeros(N, np.int8), np.ones(N, np.int8)], cycles)
    t = np.arange(z.size) / 1000.0
    if tail_step is not None:
        z[2 * N - 1] = z[2 * N - 2] - tail_step
    if reverse_app:
        z[:N], s[:N] = z[:N][::-1].copy(), s[:N][::-1].copy()
    if backwards_time:
        t[:N] = t[:N][::-1].copy()
    if falling:
        z = -z
    if negate:
        s = -s
    meta = dict(spring_constant=0.1, sensitivity=50e-9, source_file="crafted (test)")
    return RawCurve(time=t, piezo_nominal=z.copy(), piezo_measured=None, deflection_signal=s, segment=seg,
                    metadata=meta, truth=None, deflection_unit="V")


@pytest.mark.parametrize("change", [dict(reverse_app=True), dict(backwards_time=True), dict(cycles=2),
                                    dict(tail_step=5e-7), dict(falling=True)])
def test_a_curve_orient_changes_is_left_to_orient(change):
    curve = _curve(**change)
    assert plain_scan(curve) is None
    assert not _check(curve)


def test_the_plain_curve_is_decided_and_an_inverted_sign_is_still_found():
    assert _check(_curve())
    flipped = _curve(negate=True)
    scan = plain_scan(flipped)
    assert scan is not None and not scan[7]   # the screen does not clear an inverted signal
    st = prepare(flipped, scan=scan)
    assert any("sign is inverted" in w for w in st.warnings)
    _same_state(st, prepare(flipped))


def test_end_steps_near_the_jump_threshold():
    """Random ramps whose last retract step is 40-60 median steps: the scan never clears a jump."""
    rng = np.random.default_rng(7)
    step = 1e-6 / (N - 1)
    decided = 0
    for _ in range(60):
        curve = _curve(tail_step=step * rng.uniform(0.8, 1.2) * END_JUMP_STEPS, rng=rng)
        z = curve.piezo_nominal.copy()
        z[N:] += step * 0.3 * rng.standard_normal(N)   # the retract's steps scatter about their median
        curve = dataclasses.replace(curve, piezo_nominal=z)
        decided += _check(curve)
    assert 0 < decided < 60
