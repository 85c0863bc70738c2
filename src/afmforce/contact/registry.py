"""The indentation models users choose from: one record per law (key, name, geometry, validity, reference).

>>> from afmforce.contact.registry import INDENTATION_MODELS, indentation_model
>>> indentation_model("hertz_paraboloid").geometry
('radius',)
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

from ..errors import ParameterError
from . import adhesive as _a
from . import models as _m

__all__ = ["IndentationModel", "INDENTATION_MODELS", "indentation_model"]


@dataclass(frozen=True)
class IndentationModel:
    """One indentation model.

    Attributes
    ----------
    key : str
        Name for ``--indentation-model``.
    name : str
        Human-readable name.
    geometry : tuple of str
        Geometry parameters it needs: ``radius`` [m], ``half_angle`` [rad], ``thickness`` [m].
    validity : str
        Where it holds, in words (the fit checks it: :func:`afmforce.contact.fit.validity`).
    reference : str
        Where the law comes from.
    func : callable
        The law: ``func(delta, E, *geometry, nu=...)``; adhesive laws ``func(delta, E, w, R, nu)``.
    linear : bool
        ``F = E * shape(delta)`` (fitted in closed form for each contact point); False: adhesive.
    adhesive : bool
        The law has a work of adhesion w [J/m^2].
    max_depth_over_radius : float
        Largest indentation / R the law holds for [-] (inf: no such limit).
    nanite_key : str
        nanite's model of the same law ("" if none).
    """

    key: str
    name: str
    geometry: tuple[str, ...]
    validity: str
    reference: str
    func: Callable
    linear: bool = True
    adhesive: bool = False
    max_depth_over_radius: float = math.inf
    nanite_key: str = ""


_THIN = "indentation < a tenth of the sample thickness (half space)"
_ADH = "sphere, indentation << R; w and E of one elastic half space; "

#: The registry.
INDENTATION_MODELS: dict[str, IndentationModel] = {m.key: m for m in (
    IndentationModel("hertz_paraboloid", "paraboloid (Hertz)", ("radius",),
                     "indentation < the tip radius (11.1 % stiffer than the exact sphere at delta = R); " + _THIN,
                     "Hertz 1882; Sneddon 1965 eq 6.9", _m.hertz_paraboloid, max_depth_over_radius=1.0,
                     nanite_key="hertz_para"),
    IndentationModel("sneddon_sphere", "sphere, exact (Sneddon)", ("radius",),
                     "indentation < the tip radius (a sphere only to its equator); " + _THIN,
                     "Sneddon 1965 eqs 6.13, 6.15", _m.sneddon_sphere, max_depth_over_radius=1.0,
                     nanite_key="sneddon_spher_approx"),
    IndentationModel("hertz_cone", "cone (Love, Sneddon)", ("half_angle",),
                     "sharp cone: indentation >> the apex radius; " + _THIN, "Love 1939; Sneddon 1965 eq 6.4",
                     _m.hertz_cone, nanite_key="hertz_cone"),
    IndentationModel("bilodeau_pyramid3", "three-sided pyramid (Bilodeau)", ("half_angle",),
                     "face angle alpha; indentation >> the apex radius; " + _THIN,
                     "Bilodeau 1992, J Appl Mech 59, 519", _m.bilodeau_pyramid3, nanite_key="hertz_pyr3s"),
    IndentationModel("bilodeau_pyramid4", "four-sided pyramid (Bilodeau)", ("half_angle",),
                     "face angle alpha; indentation >> the apex radius; " + _THIN,
                     "Bilodeau 1992, J Appl Mech 59, 519", _m.bilodeau_pyramid4),
    IndentationModel("hertz_thin_layer", "sphere on a layer of finite thickness (Dimitriadis)",
                     ("radius", "thickness"), "chi = sqrt(R delta)/h < 1 (the series' range); indentation < R",
                     "Dimitriadis et al. 2002, Biophys J 82, 2798, eqs 11-12", _m.hertz_thin_layer,
                     max_depth_over_radius=1.0),
    IndentationModel("jkr", "adhesive sphere, JKR", ("radius",), _ADH + "large, soft, strongly adhesive "
                     "contacts (Maugis lambda > 5)", "Johnson, Kendall & Roberts 1971; Maugis 1992",
                     _a.jkr, linear=False, adhesive=True, max_depth_over_radius=1.0),
    IndentationModel("dmt", "adhesive sphere, DMT", ("radius",), _ADH + "small, stiff, weakly adhesive contacts "
                     "(Maugis lambda < 0.1)", "Derjaguin, Muller & Toporov 1975", _a.dmt, linear=False,
                     adhesive=True, max_depth_over_radius=1.0),
    IndentationModel("maugis", "adhesive sphere, Maugis-Dugdale", ("radius",), _ADH + "any lambda (given: "
                     "`indentation.transition`)", "Maugis 1992, J Colloid Interface Sci 150, 243",
                     _a.maugis, linear=False, adhesive=True, max_depth_over_radius=1.0),
)}
assert all(k in INDENTATION_MODELS for k in _m.LINEAR_KEYS)


def indentation_model(key: str) -> IndentationModel:
    """The registered model ``key`` (ParameterError listing the choices otherwise)."""
    try:
        return INDENTATION_MODELS[key]
    except KeyError:
        raise ParameterError(f"indentation model {key!r} unknown; choose from "
                             f"{', '.join(INDENTATION_MODELS)}") from None
