"""Electrical double layer between charged surfaces in an electrolyte (issue 25), a law of the model.

Derjaguin force ``F = 2 pi R_eff W(h)`` on the planar energy per area W of one of
:data:`afmforce.forces.DOUBLE_LAYERS` (weak overlap; Hogg, Healy & Fuerstenau at constant
potential or charge): :func:`afmforce.forces.double_layer_force`. The compiled model computes it
in its own slots (:mod:`afmforce.dynamics.models`); this record declares its parameters once
(defaults, the fit's scales, the choice of the boundary condition) for every face that reads the
registry, and :func:`screening_length` is the one rule giving the Debye length.
"""

from __future__ import annotations

from ..forces import DOUBLE_LAYERS, debye_length, double_layer_force, double_layer_force_gradient
from ._record import LawParameter, LawSwitch, SurfaceLaw

#: The Debye length when neither it nor a salt concentration is given [m].
DEFAULT_DEBYE_LENGTH = 10e-9


def screening_length(debye: float | None, salt_concentration: float | None, valence: float,
                     permittivity: float) -> float:
    """The Debye length [m]: ``debye`` [m] when given, else that of a z:z salt of
    ``salt_concentration`` [mol/m^3] (:func:`afmforce.forces.debye_length` at 25 C), else
    :data:`DEFAULT_DEBYE_LENGTH`."""
    if salt_concentration is not None:
        return float(debye_length(valence**2 * salt_concentration * 1e-3, permittivity))
    return DEFAULT_DEBYE_LENGTH if debye is None else float(debye)


def _args(v):
    lam = screening_length(v.get("debye_length"), v.get("salt_concentration"), v.get("valence", 1.0),
                           v.get("permittivity", 78.5))
    law = v.get("double_layer", "constant_potential")
    return (v["surface_potential"], lam, v.get("surface_potential_2"), v.get("permittivity", 78.5), law,
            "sphere-flat")


def _force(h, r_eff, v):
    a = _args(v)
    return double_layer_force(h, r_eff, *a), double_layer_force_gradient(h, r_eff, *a)


LAW = SurfaceLaw(
    name="double_layer",
    title="electrical double layer (Derjaguin, weak overlap or Hogg-Healy-Fuerstenau)",
    parameters=(LawParameter("surface_potential", 0.0, "finite", fit=(0.01, 0.01, 1e-5)),
                LawParameter("surface_potential_2", None, "optional_finite"),
                LawParameter("debye_length", None, "optional_positive", fit=(1e-8, 0.01, 1e-12)),
                LawParameter("salt_concentration", None, "optional_positive"),
                LawParameter("valence", 1.0, "positive"),
                LawParameter("permittivity", 78.5, "positive")),
    force=_force,
    active=lambda v: v.get("double_layer", "none") != "none",
    pack=None,
    kernel=None,
    n_slots=0,
    reach=lambda v: 60.0 * screening_length(v.get("debye_length"), v.get("salt_concentration"),
                                            v.get("valence", 1.0), v.get("permittivity", 78.5)),
    reference="Hogg, Healy & Fuerstenau, Trans. Faraday Soc. 62, 1638 (1966); Derjaguin approximation",
    validity="linearised Poisson-Boltzmann (|psi| < ~50 mV; weak overlap also h > 1/kappa); "
             "Derjaguin: R_eff >> 1/kappa",
    example={"double_layer": "constant_potential", "surface_potential": -0.03, "debye_length": 10e-9},
    switch=LawSwitch("double_layer", DOUBLE_LAYERS, "none", "none", "double-layer law"),
)
