"""The ``surface_energy`` step: surface energy and radius from the pull-off (JKR/DMT; hard contacts).

Declared once by its record :data:`SURFACE_ENERGY` (:mod:`afmforce.analysis.registry`).
"""

from __future__ import annotations

import dataclasses
import math

from ...errors import AnalysisError
from .._step_helpers import _kind, _skip
from ..jumps import adhesion
from ..options import SurfaceEnergyOptions
from ..plausibility import unphysical_surface_energy
from ..registry import AnalysisStep, ResultField
from ..state import State

__all__ = ["surface_energy", "SURFACE_ENERGY"]


def surface_energy(st: State, o: SurfaceEnergyOptions) -> State:
    """Surface energy from the pull-off and the probe's R, and R from the jump-out distance (hard contacts)."""
    j = st.details.get("jumps")
    if j is None:
        raise AnalysisError("step 'surface_energy' needs the jumps")
    if _kind(st) == "soft":
        return _skip(st, "surface_energy", "soft contact: JKR/DMT from a pull-off jump need a rigid contact")
    if "jumps" in st.skipped or "pull_off" in st.skipped:
        return _skip(st, "surface_energy", f"no pull-off: {st.skipped.get('jumps') or st.skipped['pull_off']}")
    if not j.pull_off.found:
        return _skip(st, "surface_energy", "no pull-off found")
    radius = st.probe.value("radius", st.metadata)
    res = adhesion(j.pull_off, st.spring_constant, radius=radius, model=o.model, hamaker=o.hamaker, z0=o.z0)
    why = unphysical_surface_energy(res.surface_energy, res.radius_given)
    if why:  # no solid has it: not a result (the radius estimate from the jump-out stays)
        return _skip(st, "surface_energy", why, dataclasses.replace(res, surface_energy=math.nan))
    return st.update("surface_energy", res)


SURFACE_ENERGY = AnalysisStep(
    "surface_energy", "Surface energy and radius from the pull-off (JKR/DMT; hard contacts)", surface_energy,
    SurfaceEnergyOptions, requires=("jumps",), reference="section 2.1",
    fields=(ResultField("surface_energy", "J/m^2", "surface energy", summary=True, column=True),
            ResultField("radius", "m", "radius", summary=True, column=True)),
    collect=lambda st: {"surface_energy": st.details["surface_energy"].surface_energy,
                        "radius": st.details["surface_energy"].radius})
