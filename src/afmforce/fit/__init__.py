"""Fit the dynamic model to force curves measured at several driving speeds.

>>> from afmforce.fit import fit_dynamic, virtual_curves
>>> curves = virtual_curves([0.5e-6, 1e-6, 2e-6, 5e-6], xi=0.005, seed=1)   # doctest: +SKIP
>>> res = fit_dynamic(curves, "beam", free=("hamaker", "xi"))               # doctest: +SKIP
>>> res.parameters["xi"].interval, res.friction_detected, res.p_value       # doctest: +SKIP

Modules: :mod:`.data` (curves prepared from raw files, static guesses),
:mod:`.model` (dynamic and static predictions, variable projection),
:mod:`.problem` (parameter vector, block Jacobian), :mod:`.core`
(:func:`fit_dynamic`), :mod:`.uncertainty` (profile likelihood, model
comparison), :mod:`.result`, :mod:`.figures`, :mod:`.plan` (experiment
design), :mod:`.virtual` (virtual multi-speed measurements). See docs/fit.md.
"""

from .core import IdentifiabilityError, fit_dynamic
from .data import FitCurve, prepare_curves
from .params import PARAMETERS, FitParameter
from .result import CurveFit, Estimate, FitResult, ModelComparison
from .virtual import virtual_curves

__all__ = ["fit_dynamic", "IdentifiabilityError", "FitCurve", "prepare_curves", "PARAMETERS",
           "FitParameter", "FitResult", "Estimate", "CurveFit", "ModelComparison",
           "virtual_curves"]
