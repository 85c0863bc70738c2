"""The compiled compliance-line fit against numpy's least squares on the same samples."""

from __future__ import annotations

import math

import numpy as np
import pytest

from afmforce.dynamics.events import compliance_lines
from afmforce.dynamics.radau import APPROACH, RETRACT


def _polyfit_lines(tr):
    """The fit of ``compliance_lines`` written out with ``np.polyfit`` (independent code)."""
    cfg, e = tr.config, tr.events
    z, d, h, seg = tr.piezo_position, tr.apparent_deflection, tr.separation, tr.segment
    span = e.turn_position - e.contact_position
    lo, hi = e.contact_position + 0.25 * span, e.turn_position - 0.25 * span
    fits = []
    for kind in (APPROACH, RETRACT):
        m = (seg == kind) & (h < cfg.contact_separation) & (z >= lo) & (z <= hi)
        c1, c0 = np.polyfit(d[m], z[m], 1)
        fits.append((c0, c1, d[m].min(), d[m].max(), np.count_nonzero(m)))
    (a0, a1, alo, ahi, na), (b0, b1, blo, bhi, nb) = fits
    dmid = 0.5 * (max(alo, blo) + min(ahi, bhi))
    return (a0 + a1 * dmid) - (b0 + b1 * dmid), tr.calibration_factor * 0.5 * (a1 + b1), na, nb


def test_compliance_fit_equals_numpy_least_squares_on_fig5(fig5):
    offset, slope, na, nb = _polyfit_lines(fig5)
    assert na > 1000 and nb > 1000
    e = fig5.events
    # the offset is a difference of two ~100 nm line values: agree to 1e-6 of it (~1e-16 m)
    assert e.hysteresis_offset == pytest.approx(offset, rel=1e-6, abs=1e-17)
    assert e.compliance_slope == pytest.approx(slope, rel=1e-10)


def test_compliance_fit_refuses_a_degenerate_region():
    """Fewer than five samples, or no spread of the deflection: NaN, not a made-up line."""
    n = 40
    z = np.linspace(0.0, 10e-9, n)
    h = np.zeros(n)
    seg = np.array([APPROACH] * (n // 2) + [RETRACT] * (n // 2))
    flat = np.full(n, 1e-9)
    assert all(math.isnan(v) for v in compliance_lines(z, flat, h, seg, 1e-9, 0.0, 10e-9, 1.0))
    few = compliance_lines(z[:12], z[:12], h[:12], seg[:12], 1e-9, 0.0, 10e-9, 1.0)
    assert all(math.isnan(v) for v in few)
    # a clean line on both runs, shifted by 1 nm: offset 1 nm, slope beta / c1
    d = 0.5 * z
    zz = np.where(seg == APPROACH, z, z - 1e-9)
    off, slope = compliance_lines(zz, d, h, seg, 1e-9, -1e-9, 11e-9, 3.0)
    assert off == pytest.approx(1e-9, rel=1e-9)
    assert slope == pytest.approx(3.0 * 2.0, rel=1e-12)
