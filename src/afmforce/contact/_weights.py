"""Shared by the modulus fit (:mod:`.fit`) and the adhesive fit (:mod:`.adhesive_fit`): the
weights of the fitted samples and the 95 % Student t quantile of the intervals."""

from __future__ import annotations

import functools
import math

import numpy as np

__all__ = ["t95", "weights"]


@functools.lru_cache(maxsize=256)
def t95(dof: int) -> float:
    """Two-sided 95 % Student t quantile for ``dof`` degrees of freedom (NaN for none)."""
    if dof <= 0:
        return math.nan
    from scipy.special import stdtrit

    return float(stdtrit(dof, 0.975))


def weights(d: np.ndarray, width: float) -> np.ndarray:
    """Weight of each sample at indentation ``d`` [m]: ramped up over ``width`` [m] from the
    contact point (none: all 1). Every sample given is weighted: the fits' range is a fixed set of
    samples chosen before (:func:`afmforce.contact.fit.fit_indentation`), never a window that moves
    with the contact point tried."""
    return np.ones_like(d) if width <= 0 else np.minimum(np.abs(d) / width, 1.0)
