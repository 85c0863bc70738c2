"""A spring constant fitted in situ far from the files' is no result (review of 2026-11-29).

``spring_constant`` / ``k0`` free (the drainage force fixes k, docs/liquid.md) could end anywhere in
the declared range (1e-4 .. 1e3 N/m) and be printed with a tight interval; a lever is not 5x off
its calibration. Reference: the ratio to the files' k (the analysis's, median over the curves),
and for the beam its eq-13 spring constant, linear in k0 (``force_constant * k0_fit / k0``).
"""

from __future__ import annotations

from types import SimpleNamespace as NS

import pytest

from afmforce.fit.core import K_FILE_FACTOR, lever_off_files


def _curves(*ks):
    return [NS(metadata={"calibration": {"spring_constant": k}}) for k in ks]


SPRING = NS(model="spring", force_constant=0.1, cantilever=None)
BEAM = NS(model="beam", force_constant=0.14, cantilever=NS(k0=0.12))


@pytest.mark.parametrize("k_fit, off", [(0.1, False), (0.45, False), (0.55, True), (0.025, False),
                                        (0.015, True), (1.0, True)])
def test_the_spring_against_the_files(k_fit, off):
    why = lever_off_files({"spring_constant": NS(value=k_fit)}, SPRING, _curves(0.1, 0.1, 0.11))
    assert bool(why) is off
    if off:
        assert "not a result" in why and f"{k_fit / 0.1:.3g} x" in why


def test_the_beam_through_its_eq13_constant():
    # k0 fitted 10x the model's: the beam's spring constant 1.4 N/m against the files' 0.14
    why = lever_off_files({"k0": NS(value=1.2)}, BEAM, _curves(0.14))
    assert why and "1.4 N/m" in why and "10 x" in why
    assert lever_off_files({"k0": NS(value=0.13)}, BEAM, _curves(0.14)) is None


def test_nothing_to_compare():
    assert lever_off_files({"hamaker": NS(value=1e-19)}, SPRING, _curves(0.1)) is None
    assert lever_off_files({"spring_constant": NS(value=50.0)}, SPRING, [NS(metadata={})]) is None
    assert K_FILE_FACTOR == 5.0
