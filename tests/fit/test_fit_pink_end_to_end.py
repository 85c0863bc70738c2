"""The 1/f misfit refusal end to end: ``fit_dynamic`` on virtual-AFM curves (the unit that decides,
:func:`afmforce.fit.noise.pink_refusal`, is tested alone in ``test_fit_pink_refusal.py``).

Two speeds of the beam model (``fit_virtual.make_curves``: 0.05 nm white noise), the Hamaker constant
free and xi fixed at the truth, three cases:

* the typical detector's 1/f noise added (0.05 nm rms, :func:`afmforce.instrument.noise.pink_noise`,
  as the ``typical`` preset): real 1/f noise, measured and modelled (the refit), no refusal;
* white noise only: no significant excess, no 1/f model, no refusal;
* the same 1/f curves fitted with a wrong lever (``k0`` 200 N/m, the colleague's slip for 0.2):
  the excess the white fit leaves is tens of nm, read as 1/f noise it would be > 10x the white
  noise, so the fit refuses it with the message, keeps the white noise model (pink 0) and its
  adequacy test judges the misfit (not adequate) instead of whitening it away.

Pure 1/f noise, however strong, is not refused: the white rms is taken from second differences,
which see ~sqrt(0.2) of the 1/f rms, so the ratio the refusal tests stays near 2 (measured: 0.5 nm
of 1/f on 0.01 nm white gave 1.8 nm against 0.2 nm, ratio 9); the refusal is for misfits.
"""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pytest

from afmforce.fit import fit_dynamic
from afmforce.fit.noise import PINK_MAX_RATIO
from afmforce.instrument.noise import pink_noise

from fit_virtual import make_curves

XI = 0.005
WHITE = PINK = 0.05e-9      # [m] the typical preset's white and 1/f rms


@pytest.fixture(scope="module")
def curves():
    white = make_curves(XI, seed=3, speeds=(1e-6, 5e-6), noise=WHITE)
    rng = np.random.default_rng(5)
    pink = [dataclasses.replace(c, deflection_signal=np.asarray(c.deflection_signal)
                                + pink_noise(len(c.time), PINK, rng)) for c in white]
    return {"white": white, "pink": pink}


def _fit(curves, **fixed):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return fit_dynamic(curves, "beam", free=("hamaker",), fixed={"xi": XI, **fixed}, compare=False,
                           profile=())


def _refusals(result):
    return [w for w in result.warnings if "read as 1/f noise" in w]


def test_real_1f_noise_is_modelled_not_refused(curves):
    r = _fit(curves["pink"])
    assert _refusals(r) == []
    assert all(0.5 * PINK < c.pink < 2.0 * PINK for c in r.curves), [c.pink for c in r.curves]
    assert r.adequacy["adequate"] and r.redchi < 1.5


def test_white_noise_gets_no_1f_model_and_no_refusal(curves):
    r = _fit(curves["white"])
    assert _refusals(r) == [] and all(c.pink == 0.0 for c in r.curves)
    assert r.adequacy["adequate"]


def test_a_misfit_read_as_1f_noise_is_refused_with_the_message(curves):
    r = _fit(curves["pink"], k0=200.0)
    (refusal,) = _refusals(r)
    level, white = (float(refusal.split(part)[1].split(" nm")[0]) for part in ("would be ", "against "))
    assert level > PINK_MAX_RATIO * white and white == pytest.approx(WHITE * 1e9, rel=0.3)
    assert "misfit" in refusal and "keeps the white noise model" in refusal
    assert all(c.pink == 0.0 for c in r.curves)           # not whitened away
    assert not r.adequacy["adequate"]                      # the adequacy test judges the misfit
