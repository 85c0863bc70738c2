"""Experiment design for the slip length (issue 25; ``afmforce plan --slip-target``).

Which driving speeds and sample rate give the slip length b to +-x nm (95 %)? The same
Fisher information as :mod:`afmforce.fit.plan` (noiseless model curves, the zero, offset and
drift of every curve profiled out), on (slip_length, spring constant): the spring constant is
fitted in situ with b, so its uncertainty is part of b's. With white noise the information
grows in proportion to the samples per nm of travel, so one set of curves gives every
sample rate: the smallest that reaches the target is reported for the best design.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import asdict, dataclass
from typing import Sequence

import numpy as np

from ..errors import ParameterError
from .core import base_config
from .plan import check_plan_size, curve_information

__all__ = ["SlipPlan", "plan_slip"]

#: Two-sided 95 % normal quantile.
Z95 = 1.959963984540054


@dataclass
class SlipPlan:
    """Result of :func:`plan_slip` (SI)."""

    slip_length: float
    target: float
    noise: float
    speeds: list
    points_per_nm: float
    best_speeds: list
    half_width: float          # 95 % half-width of b at points_per_nm [m]
    points_per_nm_needed: float   # samples per nm of travel reaching the target (best design)
    sample_rates_needed: list
    notes: list

    def to_dict(self) -> dict:
        return asdict(self)

    def markdown(self) -> str:
        from ..units import format_quantity as fq

        need = ("not reachable" if not math.isfinite(self.points_per_nm_needed) else
                f"{self.points_per_nm_needed:.3g} samples per nm of travel: sample rates "
                + ", ".join(fq(f, "Hz") for f in self.sample_rates_needed))
        return "\n".join([
            f"# Slip-length plan (b = {fq(self.slip_length, 'm')}, target +-{fq(self.target, 'm')} "
            f"at 95 %, noise {fq(self.noise, 'm')})", "",
            "Best speeds: " + ", ".join(fq(v, "m/s") for v in self.best_speeds)
            + f"; at {self.points_per_nm:g} samples/nm: b +- {fq(self.half_width, 'm')} (95 %).", "",
            f"Target reached with {need}.", ""] + [f"- {n}" for n in self.notes]) + "\n"


def plan_slip(model="spring", *, target: float, noise: float = 0.05e-9,
              speeds: Sequence[float] = (2e-6, 5e-6, 10e-6, 20e-6, 40e-6, 80e-6),
              points_per_nm: float = 1.0, n_curves: int = 4, **fields) -> SlipPlan:
    """Speeds and sample rate that give the slip length to +-``target`` [m] (95 %).

    ``model``: a configuration (or model name and ``fields``) with the slip length, radius,
    viscosity, lever drag ... assumed; its drive range (start, turn) is each approach's.
    """
    from .._fields import check

    check("slip_target", target)                 # the declared ranges, before any work
    check("deflection_noise", noise)
    base = base_config(model, **fields)
    if not base.surface.slip_length > 0 or not base.viscosity > 0:
        raise ParameterError("planning the slip length (`slip_target`) needs the slip length to expect (> 0) and a "
                             "viscosity (`slip_length`, and `viscosity` or `medium`)")
    if target <= 0 or noise <= 0 or n_curves < 2 or len(set(speeds)) < 2:
        raise ParameterError("plan needs target > 0 [m], noise > 0 [m], n_curves >= 2 and >= 2 different speeds")
    speeds = sorted(float(v) for v in speeds)
    check_plan_size(base, speeds, [points_per_nm * v * 1e9 for v in speeds], n_curves)
    k_name = "spring_constant" if base.model == "spring" else "k0"
    infos = curve_information(base, speeds, [points_per_nm * v * 1e9 for v in speeds], noise,
                              free=("slip_length", k_name))
    best = None
    for combo in itertools.combinations_with_replacement(range(len(speeds)), n_curves):
        try:
            var = float(np.linalg.inv(sum(infos[i] for i in combo))[0, 0])
        except np.linalg.LinAlgError:
            continue
        if var > 0 and (best is None or var < best[0]):
            best = (var, combo)
    if best is None:
        raise ParameterError("no design determines the slip length: add faster speeds")
    var, combo = best
    hw = Z95 * math.sqrt(var)
    need = points_per_nm * (hw / target) ** 2     # information proportional to samples per nm
    floor = 100.0 / ((base.turn - base.start) * 1e9)  # >= 100 samples per approach (the fit's prep)
    need = max(need, floor)
    notes = [f"at least 100 samples per approach ({floor:.3g} per nm over the drive range)",
             "Cramer-Rao bound from noiseless model curves; white noise assumed (the information "
             "scales with the samples per nm); the spring constant is fitted with b",
             "above ~10 samples per nm the detector's bandwidth, not the sample rate, limits: "
             "prefer more curves or faster speeds"]
    return SlipPlan(base.surface.slip_length, target, noise, speeds, points_per_nm,
                    [speeds[i] for i in combo], hw, need,
                    [need * speeds[i] * 1e9 for i in combo], notes)
