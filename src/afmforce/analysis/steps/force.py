"""The ``force`` step: deflection to force (tilt-corrected spring constant).

Declared once by its record :data:`FORCE` (:mod:`afmforce.analysis.registry`).
"""

from __future__ import annotations

import math

from ..options import ForceOptions
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
    scales by (file's / fitted sensitivity)^2 (the deflections by fitted / file's, so forces by
    file's / fitted), never by one factor alone.
    """
    md, p = st.metadata, st.probe
    k = p.value("spring_constant", md)
    theta0 = p.value("theta0", md)
    cal = st.details.get("calibration")
    slope_k = cal.spring_constant_from_slope if cal is not None else math.nan
    warn = []
    if (o.thermal_k and p.spring_constant is None and k is not None and cal is not None and cal.source == "fit"
            and math.isfinite(cal.sensitivity) and math.isfinite(cal.sensitivity_fit) and cal.sensitivity_fit > 0):
        k_new = float(k) * (cal.sensitivity / cal.sensitivity_fit) ** 2
        warn.append(f"spring constant rescaled with the refitted sensitivity: {float(k):.4g} -> {k_new:.4g} N/m "
                    f"(a thermal k goes as 1/InvOLS^2: {cal.sensitivity * 1e9:.4g} -> {cal.sensitivity_fit * 1e9:.4g} "
                    "nm/V); give `spring_constant` if the file's k did not come from a thermal tune "
                    "(or set `force.thermal_k` to false)")
        k = k_new
    conv = effective_spring_constant(k, theta0=theta0, L0=p.L0, L1=p.L1, L2=p.L2, from_slope=slope_k)
    if conv.method == "none":
        warn.append("no spring constant (give `spring_constant`): forces not computed")
    elif conv.method == "compliance slope":
        warn.append("spring constant taken from the compliance slope of the force signal (rigid contact assumed)")
    return st.update("force", conv, warn=warn, spring_constant=conv.spring_constant,
                     force=st.deflection * conv.spring_constant)


FORCE = AnalysisStep("force", "Deflection to force (tilt-corrected spring constant)", force, ForceOptions,
                     requires=("calibration",), channels=("deflection",), reference="eqs 13, 14", runs=(),
                     fields=(ResultField("spring_constant", "N/m", "spring constant", summary=True, column=True),),
                     collect=lambda st: {"spring_constant": st.details["force"].spring_constant})
