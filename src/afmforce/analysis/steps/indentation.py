"""The ``indentation`` step: Young's modulus (and work of adhesion) of a soft contact, an indentation
model fitted with the contact point (the fit itself: :mod:`afmforce.analysis.indentation`).

Declared once by its record :data:`INDENTATION` (:mod:`afmforce.analysis.registry`).
"""

from __future__ import annotations

from ..indentation import indentation
from ..options import IndentationOptions
from ..registry import AnalysisStep, ResultField
from ..state import State

__all__ = ["INDENTATION"]


def _indentation_fields(st: State) -> dict:
    i = st.details["indentation"]
    return dict(indentation_model=i.model, youngs_modulus=i.youngs_modulus, youngs_modulus_se=i.youngs_modulus_se,
                youngs_modulus_low=i.youngs_modulus_low, youngs_modulus_high=i.youngs_modulus_high,
                contact_point=i.contact_point, work_of_adhesion=i.work_of_adhesion,
                work_of_adhesion_se=i.work_of_adhesion_se)


INDENTATION = AnalysisStep(
    "indentation", "Young's modulus (and work of adhesion) of a soft contact: indentation model fitted with the "
    "contact point", indentation, IndentationOptions, requires=("kind", "force"), runs=("approach",),
    reference="Hertz, Sneddon, Bilodeau, Dimitriadis, JKR, DMT, Maugis (docs/contact.md); checked against nanite",
    fields=(ResultField("indentation_model", None, default=""),
            ResultField("youngs_modulus", "Pa", "Young's modulus (indentation fit)", summary=True, column=True),
            ResultField("youngs_modulus_se", "Pa", "its standard error", summary=True, column=True),
            ResultField("youngs_modulus_low", "Pa", "Young's modulus, 95 % interval low", column=True),
            ResultField("youngs_modulus_high", "Pa", "Young's modulus, 95 % interval high", column=True),
            ResultField("contact_point", "m", "contact point (indentation fit; piezo position)", summary=True,
                        column=True),
            ResultField("work_of_adhesion", "J/m^2",
                        "work of adhesion (JKR, DMT or Maugis fit; a fast map: DMT from the adhesion)",
                        summary=True, column=True),
            ResultField("work_of_adhesion_se", "J/m^2", "standard error of the work of adhesion", column=True)),
    collect=_indentation_fields)
