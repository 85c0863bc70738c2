"""The ``adhesion`` step: the deepest retract dip below its own baseline, last rupture, unbinding steps.

Declared once by its record :data:`ADHESION` (:mod:`afmforce.analysis.registry`).
"""

from __future__ import annotations

import math

from .._step_helpers import _kind
from ..options import AdhesionOptions
from ..registry import AnalysisStep, ResultField
from ..state import State
from ..unbinding import retract_adhesion

__all__ = ["adhesion_step", "ADHESION"]


def adhesion_step(st: State, o: AdhesionOptions) -> State:
    """Adhesion for every contact kind: the retract's deepest dip below its own baseline (<= 0).

    See :mod:`~afmforce.analysis.unbinding`; the dip counts above ``o.nsigma``
    baseline noise, with its position, the last rupture and the unbinding steps.
    """
    po = st.details["jumps"].pull_off if "jumps" in st.details else None
    hard = po is not None and po.found and _kind(st) == "hard"  # the paper's pull-off jump ends the dip
    res = retract_adhesion(st.deflection, st.position, st.retract, st.spring_constant, nsigma=o.nsigma,
                           pull_off=po.index if hard else -1)
    warn = None
    if (po is not None and po.found and math.isfinite(po.force) and po.force < 0 and math.isfinite(res.force)
            and abs(res.force) < 0.5 * abs(po.force)):
        # both are below zero force; they differ only by the baseline each is measured from
        warn = (f"adhesion {res.force * 1e9:.3g} nN (from the retract's own baseline) is under half the pull-off "
                f"force {po.force * 1e9:.3g} nN (from the drift-corrected zero): the retract's free part does not "
                "return to the approach's baseline (still relaxing, drift, or an offset at the turn); "
                "trust the pull-off only with a settled baseline")
    return st.update("adhesion", res, warn=warn)


def _adhesion_fields(st: State) -> dict:
    a = st.details["adhesion"]
    return dict(adhesion_force=a.force, adhesion_deflection=a.deflection, adhesion_distance=a.distance,
                adhesion_noise=a.noise, rupture_distance=a.rupture_distance, unbinding_steps=len(a.steps),
                adhesion_verdict=a.verdict)


ADHESION = AnalysisStep(
    "adhesion", "Adhesion: deepest retract dip below its own baseline, last rupture, unbinding steps",
    adhesion_step, AdhesionOptions, requires=("zero", "force"), channels=("position",),
    reference="afmforce (every contact kind)", runs=("retract",),
    fields=(ResultField("adhesion_force", "N", "adhesion (deepest retract dip)", summary=True, column=True),
            ResultField("adhesion_deflection", "m", "adhesion as a deflection"),
            ResultField("adhesion_distance", "m", "adhesion position from contact", summary=True, column=True),
            ResultField("adhesion_noise", "N", "baseline noise of the retract", column=True),
            ResultField("rupture_distance", "m", "last rupture from contact", summary=True, column=True),
            ResultField("unbinding_steps", "", "unbinding steps", default=0, column=True),
            ResultField("adhesion_verdict", None, default="")),
    collect=_adhesion_fields)
