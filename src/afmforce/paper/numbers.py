"""Every number the paper states that afmforce can recompute.

Each :class:`PaperCheck` names its source (equation or figure), the value the
paper prints, the value our closed forms give (``reference``, from the spec,
computed independently of this package), the tolerance against the paper's
rounding, and a function that computes our value with the library. Nothing
here is a literal copy of a result: ``compute`` always calls the library.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

from .. import constants as C
from .. import forces
from ..cantilever import InclinedCantilever
from ..diagnostics import inertia_parameter, inertial_lag, resonance_frequency
from ..statics import (
    constant_friction_force_difference,
    constant_friction_offset,
    load_friction_constants,
    load_friction_gap,
    pinned_calibration_factor,
    viscous_friction_force,
)

__all__ = ["PaperCheck", "CheckResult", "CHECKS", "all_checks", "evaluate_checks"]


@dataclass(frozen=True)
class PaperCheck:
    """One recomputable number of the paper.

    Attributes
    ----------
    key : str
        Identifier.
    quantity : str
        What it is, in words.
    source : str
        Equation / figure / section of the paper.
    unit : str
        Display unit of ``paper``, ``reference`` and the computed value.
    paper : float or None
        Value printed in the paper (None where the paper gives none).
    reference : float
        Our closed-form value from the spec (independent computation).
    tolerance : float
        Relative tolerance of the paper's value (its rounding or "about").
    compute : callable
        ``compute() -> float`` in the display unit, through the library.
    note : str
        Decision or remark (spec section 4.2 / 5).
    group : str
        "statics", "forces", "inertia" or "dynamics".
    """

    key: str
    quantity: str
    source: str
    unit: str
    paper: float | None
    reference: float
    tolerance: float
    compute: Callable[[], float]
    note: str = ""
    group: str = "statics"
    reference_tolerance: float = 1e-3


@dataclass(frozen=True)
class CheckResult:
    """A :class:`PaperCheck` evaluated: ours beside the paper's."""

    key: str
    quantity: str
    source: str
    unit: str
    paper: float | None
    reference: float
    ours: float
    relative_difference: float | None
    tolerance: float
    passed: bool
    note: str
    group: str

    def to_dict(self) -> dict:
        return dict(self.__dict__)


def _fig3() -> InclinedCantilever:
    return InclinedCantilever(**C.FIG3)


def _fig5() -> InclinedCantilever:
    g = C.FIG5
    return InclinedCantilever(L0=g["L0"], L1=g["L1"], L2=g["L2"], theta0=g["theta0"], B=g["B"])


def _fig1_f() -> float:
    return float(resonance_frequency(C.FIG1["spring_constant"], C.FIG1["mass"]))


def _fig1_grad() -> float:
    return abs(float(forces.vdw_force_gradient(5e-9, C.FIG1["radius"])))


def _R(v: float) -> float:
    return float(inertia_parameter(v, _fig1_grad(), _fig1_f(), C.FIG1["spring_constant"], 0.5e-9))


CHECKS: tuple[PaperCheck, ...] = (
    # --- forces (section 2.1) ---
    PaperCheck("surface_energy", "surface energy gamma = A/(16 pi z0^2)", "section 2.1", "J/m^2",
               0.08, 0.0812, 0.07, lambda: float(forces.surface_energy()), group="forces"),
    PaperCheck("radius_from_jump_out", "R from a 200 nm jump-out, k = 0.21 N/m (JKR)", "section 3, Fig 9", "nm",
               220, 219.5, 0.01,
               lambda: 1e9 * float(forces.radius_from_jump_out(0.21, 200e-9, forces.surface_energy())),
               group="forces"),
    PaperCheck("static_jump_in", "static jump-in separation, R = 220 nm, k = 0.21 N/m", "section 3, Fig 9",
               "nm", 4.4, 4.436, 0.02,
               lambda: 1e9 * float(forces.static_jump_in_separation(0.21, 220e-9)), group="forces"),
    PaperCheck("max_attraction", "Fs(z0) / (-A R / 16 z0^2), R = 100 nm", "eq 2", "",
               1.0, 1.0, 1e-12,
               lambda: float(forces.vdw_force(C.Z0, 100e-9) / forces.max_attraction_force(100e-9)),
               group="forces", reference_tolerance=1e-12),
    # --- inertia (section 2.1, Fig 1) ---
    PaperCheck("fig1_resonance", "resonance frequency, k = 0.21 N/m, m = 10 ug", "section 2.1", "kHz",
               0.73, 0.7293, 0.01, lambda: _fig1_f() / 1e3, group="inertia"),
    PaperCheck("fig1_gradient", "|Fs'(5 nm)|, R = 100 nm", "section 2.1", "N/m",
               0.067, 0.06667, 0.01, _fig1_grad, group="inertia"),
    PaperCheck("fig1_R_10", "inertia parameter at 10 um/s, dx = 0.5 nm", "eq 3", "",
               2.2, 2.176, 0.025, lambda: _R(10e-6), group="inertia"),
    PaperCheck("fig1_R_1", "inertia parameter at 1 um/s, dx = 0.5 nm", "eq 3", "",
               0.2, 0.2176, 0.25, lambda: _R(1e-6), group="inertia",
               note="paper rounds 0.218 to one digit"),
    PaperCheck("fig1_lag_10", "inertial lag at 10 um/s", "eq 4", "nm",
               3.4, 3.428, 0.02, lambda: 1e9 * float(inertial_lag(10e-6, _fig1_f())), group="inertia"),
    PaperCheck("fig1_lag_1", "inertial lag at 1 um/s", "eq 4", "nm",
               0.3, 0.3428, 0.17, lambda: 1e9 * float(inertial_lag(1e-6, _fig1_f())), group="inertia",
               note="paper rounds 0.343 to one digit"),
    # --- statics (section 2.2, Figs 3-4) ---
    PaperCheck("k_over_k0", "k/k0 = 1/cos^2(theta0) at -15 deg", "eq 14", "",
               1.07, 1.0718, 0.005, lambda: _fig3().spring_constant_tilt_only / _fig3().k0),
    PaperCheck("k_fig3", "force-measuring spring constant, Fig 3 geometry", "eq 13", "N/m",
               None, 0.13741, 0.0, lambda: _fig3().spring_constant),
    PaperCheck("beta_fig3", "calibration factor beta, Fig 3 geometry", "eq 15", "nm/rad",
               1.3e5, 1.29391e5, 0.01, lambda: 1e9 * _fig3().calibration_factor),
    PaperCheck("constant_offset", "inward-outward offset, constant friction mu = 5 nN", "eq 16, Fig 3", "nm",
               0.76, 0.7622, 0.01, lambda: 1e9 * constant_friction_offset(_fig3(), C.FIG3_MU)),
    PaperCheck("constant_force_difference", "Fz+ - Fz- at fixed theta, mu = 5 nN", "eq 17, Fig 3", "nN",
               None, 3.104, 0.0, lambda: 1e9 * constant_friction_force_difference(_fig3(), C.FIG3_MU)),
    PaperCheck("load_k_in", "inward spring constant, lambda = 2", "eq 18, Fig 4", "N/m",
               None, 0.3434, 0.0, lambda: load_friction_constants(_fig3(), C.FIG4_LAMBDA, +1)[0]),
    PaperCheck("load_beta_in", "inward calibration factor, lambda = 2", "eq 19, Fig 4", "nm/rad",
               None, 1.3654e5, 0.0, lambda: 1e9 * load_friction_constants(_fig3(), C.FIG4_LAMBDA, +1)[1]),
    PaperCheck("load_k_out", "outward spring constant, lambda = 2", "eq 18, Fig 4", "N/m",
               None, 0.0859, 0.0, lambda: load_friction_constants(_fig3(), C.FIG4_LAMBDA, -1)[0]),
    PaperCheck("load_beta_out", "outward calibration factor, lambda = 2", "eq 19, Fig 4", "nm/rad",
               None, 1.2772e5, 0.0, lambda: 1e9 * load_friction_constants(_fig3(), C.FIG4_LAMBDA, -1)[1]),
    PaperCheck("load_force_in", "inward force at z2 = 10 nm, lambda = 2", "Fig 4", "nN",
               3.4, 3.434, 0.015, lambda: 1e9 * load_friction_constants(_fig3(), C.FIG4_LAMBDA, +1)[0] * 10e-9,
               note="the paper's outward forces at z2 = 10 nm (5 and 0.3 nN) follow from no reading "
                    "of eqs 7-19; not compared (spec 4.2)"),
    PaperCheck("load_gap", "gap between the lines at the inward theta where z2 = 10 nm", "Fig 4", "nm",
               0.65, 0.646, 0.01, lambda: 1e9 * load_friction_gap(_fig3(), C.FIG4_LAMBDA, 10e-9)),
    PaperCheck("pinned_beta", "calibration factor, pinned tip (negative)", "eq 21", "nm/rad",
               None, -1.5455e4, 0.0, lambda: 1e9 * pinned_calibration_factor(_fig3()),
               note="the paper states only that it is negative"),
    PaperCheck("viscous_force", "steady friction xi |dy2/dz2| v, xi = 0.1 kg/s, 0.1 um/s", "eq 28, section 2.3",
               "nN", 3.0, 3.00, 0.01, lambda: 1e9 * viscous_friction_force(_fig5(), 0.1, 0.1e-6)),
    PaperCheck("viscous_offset", "outward line above inward, xi = 0.1 kg/s, 0.1 um/s", "eq 16 + Fig 5",
               "nm", 0.5, 0.453, 0.12,
               lambda: 1e9 * constant_friction_offset(_fig5(), viscous_friction_force(_fig5(), 0.1, 0.1e-6)),
               note="B = 3.5e-13 N m^2 (spec 5 decision); the paper says 'about 0.5 nm'"),
)


def all_checks() -> tuple[PaperCheck, ...]:
    """Static and dynamic checks together (the dynamic ones run simulations)."""
    from .numbers_dynamic import DYNAMIC_CHECKS

    return CHECKS + DYNAMIC_CHECKS


def evaluate_checks(checks=None, groups: set[str] | None = None) -> list[CheckResult]:
    """Compute every check and compare with the paper (and our reference).

    ``checks`` defaults to :func:`all_checks`; ``groups`` selects among
    "forces", "inertia", "statics", "dynamics".
    """
    if checks is None:
        checks = all_checks()
    out = []
    for c in checks:
        if groups is not None and c.group not in groups:
            continue
        ours = float(c.compute())
        ref_ok = math.isclose(ours, c.reference, rel_tol=c.reference_tolerance) if c.reference else True
        ref_ok = ref_ok and math.isfinite(ours)
        if c.paper is not None:
            rel = (ours - c.paper) / abs(c.paper)
            passed = abs(rel) <= c.tolerance and ref_ok
        else:
            rel = None
            passed = ref_ok
        out.append(CheckResult(c.key, c.quantity, c.source, c.unit, c.paper, c.reference, ours, rel,
                               c.tolerance, passed, c.note, c.group))
    return out
