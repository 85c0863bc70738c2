"""Issue 32 vs liquids: a repulsive rise before the two-line split is a contact only when its shape is
one (analysis/regions.py, _repulsive_onset): a Hertz onset (a power of the indentation) is contact,
an exponential in the position (a double layer) or a rise ended by a jump into contact is not."""

import warnings

import numpy as np

from afmforce.analysis import regions
from afmforce.analysis.regions import _surface_force_like, find_run_regions, run_indices, saturated_mask


def _split(z, s, idx, shape_test=True, monkeypatch=None):
    if not shape_test:       # the rule of issue 32 alone: every repulsive rise taken for contact
        monkeypatch.setattr(regions, "_surface_force_like", lambda *a: False)
        monkeypatch.setattr(regions, "ONSET_JUMP_NSIGMA", np.inf)
    run = find_run_regions(z, s, idx, "approach", saturated=saturated_mask(s))
    if not shape_test:
        monkeypatch.undo()
    return run.split


def _approach(rise, z):
    """An approach run: baseline with noise, the given rise, then a steep compliance line."""
    rng = np.random.default_rng(0)
    sigma = 0.05e-9
    zc = np.linspace(z[-1] + 0.2e-9, z[-1] + 15e-9, 80)
    s = np.concatenate([rise, rise[-1] + (zc - z[-1])]) + rng.normal(0, sigma, z.size + zc.size)
    return np.concatenate([z, zc]), s


def test_hertz_onset_of_a_stiff_lever_is_contact():
    # k d = (4/3) E* sqrt(R) delta^1.5 with delta = z - z0 - d (90 N/m lever, 10 nm tip, E* = 10 GPa)
    k, R, E, z0 = 90.0, 10e-9, 10e9, 0.0
    z = np.linspace(-150e-9, 20e-9, 600)
    d = np.zeros_like(z)
    for i, zi in enumerate(z):
        if zi > z0:
            lo, hi = 0.0, zi - z0
            for _ in range(60):   # bisection: force balance on the lever
                m = 0.5 * (lo + hi)
                lo, hi = (m, hi) if k * m < 4 / 3 * E * np.sqrt(R) * (zi - z0 - m) ** 1.5 else (lo, m)
            d[i] = lo
    zz, s = _approach(d, z)
    run = find_run_regions(zz, s, np.arange(zz.size), "approach", saturated=saturated_mask(s))
    assert abs(zz[run.split] - z0) < 3e-9     # the contact begins at the Hertz onset
    x = zz[:z.size]
    up = x > 2e-9
    assert not _surface_force_like(x[up], d[up], 20e-9, 0.05e-9)


def test_double_layer_rise_is_not_contact(monkeypatch):
    lam = 8e-9
    z = np.linspace(-150e-9, 0.0, 600)
    rise = 3e-9 * np.exp(z / lam)
    zz, s = _approach(rise, z)
    idx = np.arange(zz.size)
    # the contact starts within the last decay length (the two lines' split), not where the rise begins
    assert zz[_split(zz, s, idx)] > -lam
    assert zz[_split(zz, s, idx, False, monkeypatch)] < -3 * lam     # what issue 32's rule alone did
    assert _surface_force_like(z, rise, 0.0, 0.05e-9)


def test_virtual_liquid_double_layer_stays_out_of_contact(monkeypatch):
    from afmforce.fit import virtual_curves
    liq = dict(model="spring", spring_constant=0.1, mass=1e-11, radius=5e-6, geometry="sphere-flat",
               hamaker=1e-22, viscosity=0.89e-3, lever_drag=1e-5, start=-100e-9, turn=40e-9, end=-100e-9)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        c = virtual_curves([10e-6], seed=3, sample_rates=[1e4], surface_potential=-0.05,
                           debye_length=8e-9, **liq)[0]
    z, s = np.asarray(c.piezo_nominal), np.asarray(c.deflection_signal)
    idx = run_indices(c.segment, 0)
    zr, sep = z[idx], np.asarray(c.truth["separation"])[idx]
    touch = zr[int(np.argmax(sep <= 0.5e-9))]        # the sphere reaches the surface
    # the contact starts within two Debye lengths of the true contact, not where the double layer rises
    assert zr[_split(z, s, idx)] > touch - 16e-9
    assert zr[_split(z, s, idx, False, monkeypatch)] < touch - 30e-9   # issue 32's rule alone
