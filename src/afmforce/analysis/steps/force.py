"""The ``force`` step: deflection to force (tilt-corrected spring constant).

Declared once by its record :data:`FORCE` (:mod:`afmforce.analysis.registry`).
"""

from __future__ import annotations

import math

from ...calibration.record import INVOLS_METHODS
from ...io.given import file_sensitivity
from ..options import ForceOptions, origin_words
from ..registry import AnalysisStep, ResultField
from ..separation import effective_spring_constant
from ..state import State

__all__ = ["force", "FORCE"]


def force(st: State, o: ForceOptions) -> State:
    """Force = k x deflection, tilt-corrected (eq 13/14) when theta0 is given.

    k, theta0 and the lengths are the probe's (:class:`~afmforce.analysis.options.ProbeCalibration`),
    k and theta0 from the file when the user gives none. A thermal spring constant (the
    instruments' usual one, ``thermal_k``) is ``kB T / <d^2>`` with the deflection ``d`` in the
    file's sensitivity: when the sensitivity is refitted from the compliance slope the file's k
    scales by (file's / fitted sensitivity)^2 (the file's own, also where the user gave a
    ``sensitivity``: :func:`_file_invols`) (the deflections by fitted / file's, so forces by
    file's / fitted), never by one factor alone. A probe calibration file's k (``--probe-calibration``)
    follows its ``method``: a thermal one scales by (the file's InvOLS / fitted)^2, Sader's does not
    (:func:`_calibration_file_k`).
    """
    md, p = st.metadata, st.probe
    k = p.value("spring_constant", md)
    theta0 = p.value("theta0", md)
    cal = st.details.get("calibration")
    slope_k = cal.spring_constant_from_slope if cal is not None else math.nan
    warn = []
    fitted = (cal is not None and cal.source == "fit" and math.isfinite(cal.sensitivity_fit) and cal.sensitivity_fit > 0)
    inv = _file_invols(md, cal)
    if (o.thermal_k and p.spring_constant is None and k is not None and fitted and math.isfinite(inv)):
        k_new = float(k) * (inv / cal.sensitivity_fit) ** 2
        whose = origin_words(p, "spring_constant")[0]
        warn.append(f"spring constant rescaled with the refitted sensitivity: {float(k):.4g} -> {k_new:.4g} N/m "
                    f"(a thermal k goes as 1/InvOLS^2: {inv * 1e9:.4g} -> {cal.sensitivity_fit * 1e9:.4g} "
                    f"nm/V; the k: {whose}); give `spring_constant` if it did not come from a thermal tune "
                    "(or set `force.thermal_k` to false)")
        k = k_new
    elif p.origin("spring_constant") == "calibration" and fitted:
        k = _calibration_file_k(float(k), p, cal, warn)
    conv = effective_spring_constant(k, theta0=theta0, L0=p.L0, L1=p.L1, L2=p.L2, from_slope=slope_k)
    if conv.method == "none":
        warn.append("no spring constant (give `spring_constant`): forces not computed")
    elif conv.method == "compliance slope":
        warn.append("spring constant taken from the compliance slope of the force signal (rigid contact assumed)")
    return st.update("force", conv, warn=warn, spring_constant=conv.spring_constant,
                     force=st.deflection * conv.spring_constant)


def _file_invols(md, cal) -> float:
    """The InvOLS [m/V] the file's thermal spring constant rests on: the file's own sensitivity (its metadata,
    kept under :data:`~afmforce.io.given.FILE_SENSITIVITY` where the user's was put over the curve: a user's
    ``sensitivity`` is the probe's, never the one the file's k was converted with), else the one the
    calibration used; NaN without either."""
    inv = file_sensitivity(md)
    if math.isfinite(inv):
        return inv
    return float(cal.sensitivity) if cal is not None else math.nan


def _calibration_file_k(k: float, p, cal, warn: list) -> float:
    """A probe calibration file's spring constant ``k`` [N/m] under a refitted sensitivity: a thermal k (its
    ``method``, :data:`~afmforce.calibration.record.INVOLS_METHODS`) rests on the InvOLS its spectrum was
    converted with, so it scales by (that InvOLS / fitted)^2 and is said with the numbers; one that records no
    InvOLS is kept and said; Sader's (geometry, f0, Q) rests on none and is kept silently."""
    if p.calibration_method not in INVOLS_METHODS:
        return k
    inv = p.calibration_invols
    if inv is None or not (math.isfinite(inv) and inv > 0):
        warn.append(f"the probe calibration file's {p.calibration_method} spring constant {k:.4g} N/m is not "
                    f"rescaled with the refitted sensitivity ({cal.sensitivity_fit * 1e9:.4g} nm/V): the file records "
                    "no InvOLS it rests on (a spectrum in m^2/Hz); a thermal k goes as 1/InvOLS^2, so give "
                    "`spring_constant` rescaled by (its InvOLS / the refitted)^2")
        return k
    k_new = k * (inv / cal.sensitivity_fit) ** 2
    warn.append(f"the probe calibration file's {p.calibration_method} spring constant rescaled with the refitted "
                f"sensitivity: {k:.4g} -> {k_new:.4g} N/m (a thermal k goes as 1/InvOLS^2: its "
                f"{inv * 1e9:.4g} -> {cal.sensitivity_fit * 1e9:.4g} nm/V)")
    return k_new


FORCE = AnalysisStep("force", "Deflection to force (tilt-corrected spring constant)", force, ForceOptions,
                     requires=("calibration",), channels=("deflection",), reference="eqs 13, 14", runs=(),
                     fields=(ResultField("spring_constant", "N/m", "spring constant", summary=True, column=True),),
                     collect=lambda st: {"spring_constant": st.details["force"].spring_constant})
