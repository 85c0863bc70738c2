"""Static analysis of the inclined cantilever with friction (paper section 2.2).

Each friction model of the paper gives the force-measuring spring constant,
the calibration factor of the optical lever and the hysteresis between the
inward and outward constant-compliance lines. Models live in the explicit
registry :data:`FRICTION_MODELS`; :func:`static_analysis` dispatches on it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Callable

from ._fields import check
from ._validate import non_negative, positive
from .cantilever import InclinedCantilever
from .errors import ParameterError
from .friction import steady_sliding_friction

__all__ = [
    "FrictionModel",
    "FRICTION_MODELS",
    "StaticResult",
    "static_analysis",
    "constant_friction_force_difference",
    "constant_friction_offset",
    "constant_friction_for_offset",
    "load_friction_constants",
    "load_friction_slope_ratio",
    "load_friction_for_slope_ratio",
    "load_friction_gap",
    "pinned_calibration_factor",
    "pinned_spring_constant",
    "viscous_friction_force",
]


@dataclass(frozen=True)
class StaticResult:
    """Static constants of a cantilever under one friction model.

    Attributes
    ----------
    friction : str
        Registry identifier of the friction model.
    spring_constant : float
        Force-measuring spring constant dFz/dz2 [N/m] (eq 13; inward run when
        the model distinguishes runs).
    calibration_factor : float
        beta = dz2/dtheta [m/rad] (eq 15, 19 or 21).
    intrinsic_spring_constant : float
        k0 [N/m].
    spring_constant_tilt_only : float
        k0 / cos^2 theta0 (eq 14) [N/m].
    extra : dict
        Model-specific values in SI (see each model), e.g. ``hysteresis_offset`` [m],
        ``inward``/``outward`` sub-results.
    units : dict
        Unit of every numeric entry, for printing.
    """

    friction: str
    spring_constant: float
    calibration_factor: float
    intrinsic_spring_constant: float
    spring_constant_tilt_only: float
    extra: dict[str, Any] = field(default_factory=dict)
    units: dict[str, str] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        """Flat JSON-ready dict with SI values."""
        d = {
            "friction": self.friction,
            "spring_constant": self.spring_constant,
            "calibration_factor": self.calibration_factor,
            "intrinsic_spring_constant": self.intrinsic_spring_constant,
            "spring_constant_tilt_only": self.spring_constant_tilt_only,
        }
        d.update(self.extra)
        d["units"] = dict(self.units)
        return d


_BASE_UNITS = {
    "spring_constant": "N/m",
    "calibration_factor": "m/rad",
    "intrinsic_spring_constant": "N/m",
    "spring_constant_tilt_only": "N/m",
}


# --- constant friction (eqs 16, 17) -------------------------------------------------
def constant_friction_force_difference(c: InclinedCantilever, mu: float) -> float:
    """``Fz+ - Fz-`` at fixed theta for ``Fy = +-mu`` (eq 17) [N]."""
    L0, s, co = c.L0, math.sin(c.theta0), math.cos(c.theta0)
    return -2.0 * mu * (L0**2 * s + 2.0 * c.b * L0) / (L0**2 * co + 2.0 * c.a * L0)


def constant_friction_offset(c: InclinedCantilever, mu: float) -> float:
    """``z+(theta) - z-(theta)``: inward minus outward position at fixed theta (eq 16) [m].

    For the paper's sign convention (Fy = +mu inward) and theta0 < 0 this is
    positive: the outward constant-compliance line lies above the inward one.
    """
    L0, B, s, co = c.L0, c.B, math.sin(c.theta0), math.cos(c.theta0)
    dF = constant_friction_force_difference(c, mu)
    return (co / (2.0 * B)) * ((2.0 / 3.0 * L0**3 * co + c.a * L0**2) * dF
                               + 2.0 * mu * (2.0 / 3.0 * L0**3 * s + c.b * L0**2))


def constant_friction_for_offset(c: InclinedCantilever, offset: float) -> float:
    """The constant friction ``mu`` whose eq-16 offset ``z+(theta) - z-(theta)`` is ``offset`` [N].

    Eq 16 with eq 17 is linear in mu: ``offset = mu * D`` with ``D`` =
    :func:`constant_friction_offset` ``(c, 1)`` [m/N], so ``mu = offset / D``. D vanishes for a
    tip on the beam's axis (L1 = L2 = 0: a = b = 0, the friction only bends the beam along its
    own compliance line) and grows about as ``L2 / (L0 k)``: without the lever's geometry an
    offset fixes no friction force. NaN when ``D`` is not positive.
    """
    d = constant_friction_offset(c, 1.0)
    return float(offset / d) if d > 0 else math.nan


# --- friction proportional to load (eqs 18, 19) -------------------------------------
def load_friction_constants(c: InclinedCantilever, lam: float, direction: int) -> tuple[float, float]:
    """Spring constant and calibration factor for ``Fy = +-lambda Fz`` (eqs 18, 19).

    Parameters
    ----------
    direction : int
        +1 inward (loading), -1 outward.

    Returns
    -------
    (k [N/m], beta [m/rad])
    """
    C = c.compliance_matrix
    g = c.angle_compliance
    sl = direction * lam
    compliance = C[0, 0] + sl * C[0, 1]
    dtheta = g[0] + sl * g[1]
    if compliance <= 0:
        raise ParameterError(
            f"friction coefficient lambda = {lam:g} makes the {'inward' if direction > 0 else 'outward'} "
            "compliance non-positive: the tip would be mechanically unstable; use a smaller lambda")
    return 1.0 / compliance, compliance / dtheta


def load_friction_gap(c: InclinedCantilever, lam: float, deflection: float) -> float:
    """Gap along z2 between the inward and outward lines at the inward line's theta [m].

    Evaluated where the inward line has deflection ``deflection`` (Fig 4: 10 nm);
    positive when the inward line lies above the outward one at that angle.
    """
    k_in, b_in = load_friction_constants(c, lam, +1)
    k_out, b_out = load_friction_constants(c, lam, -1)
    theta = deflection / b_in
    return deflection - b_out * theta


def load_friction_slope_ratio(c: InclinedCantilever, lam: float) -> float:
    """Approach / retract constant-compliance slope for ``Fy = +-lambda Fz`` (eqs 18, 19) [-].

    In hard contact the tip follows the substrate (``dz2 = dz``) and the photodiode reads
    ``theta = z2 / beta``, so a run's compliance slope is proportional to ``1 / beta`` and
    the ratio is ``beta_out / beta_in`` (Fig 4, lambda = 2: 1.2772e5 / 1.3654e5 = 0.9354).
    """
    return load_friction_constants(c, lam, -1)[1] / load_friction_constants(c, lam, +1)[1]


def load_friction_for_slope_ratio(c: InclinedCantilever, ratio: float) -> float:
    """Smallest ``lambda >= 0`` at which :func:`load_friction_slope_ratio` equals ``ratio`` [-].

    With ``C`` the compliance matrix and ``g`` the angle compliance (eqs 7-12),
    ``beta(+-lambda) = (Czz +- lambda Czy) / (gz +- lambda gy)`` (eqs 18, 19: the bracket of
    eq 18 is ``2B (Czz +- lambda Czy)``, that of eq 19 ``2B (gz +- lambda gy) / k``), so
    ``ratio = (Czz - l Czy)(gz + l gy) / ((gz - l gy)(Czz + l Czy))``; clearing denominators,

        ``-(1 - ratio) Czy gy l^2 + (1 + ratio)(Czz gy - Czy gz) l + (1 - ratio) Czz gz = 0``,

    a quadratic in ``l``. Its smallest root in ``(0, lambda_max)`` is returned, ``lambda_max``
    the first lambda where a run's compliance or ``beta`` changes sign (the tip turns
    mechanically unstable or the optical lever's reading reverses); ``inf`` when none: the
    ratio does not bound lambda below that limit. ``0`` for ``ratio == 1``.
    """
    C, g = c.compliance_matrix, c.angle_compliance
    czz, czy, gz, gy = float(C[0, 0]), float(C[0, 1]), float(g[0]), float(g[1])
    if ratio == 1.0:
        return 0.0
    poles = [abs(a / b) for a, b in ((czz, czy), (gz, gy)) if b != 0.0]
    lam_max = min(poles) if poles else math.inf
    qa, qb, qc = -(1.0 - ratio) * czy * gy, (1.0 + ratio) * (czz * gy - czy * gz), (1.0 - ratio) * czz * gz
    if qa == 0.0:
        roots = [-qc / qb] if qb != 0.0 else []
    else:
        disc = qb * qb - 4.0 * qa * qc
        if disc < 0.0:
            return math.inf
        sq = math.sqrt(disc)
        q = -0.5 * (qb + math.copysign(sq, qb))   # the stable form of the two roots
        roots = [q / qa] + ([qc / q] if q != 0.0 else [])
    ok = [r for r in roots if 0.0 < r < lam_max]
    return float(min(ok)) if ok else math.inf


# --- pinned tip (eqs 20, 21) --------------------------------------------------------
def pinned_calibration_factor(c: InclinedCantilever) -> float:
    """``beta = a - b cot(theta0)`` for a pinned tip, y2 = 0 (eq 21) [m/rad]."""
    if c.theta0 == 0.0:
        raise ParameterError("a pinned tip needs theta0 != 0 (eq 21 divides by sin theta0)")
    return c.a - c.b / math.tan(c.theta0)


def pinned_spring_constant(c: InclinedCantilever) -> float:
    """``dFz/dz2`` at y2 = 0: ``1 / (Czz - Czy^2 / Cyy)`` [N/m]."""
    C = c.compliance_matrix
    return 1.0 / (C[0, 0] - C[0, 1] ** 2 / C[1, 1])


# --- viscous friction in steady sliding ---------------------------------------------
def viscous_friction_force(c: InclinedCantilever, xi: float, velocity: float) -> float:
    """Steady friction ``|Fy| = xi |dy2/dz2| |dz/dt|`` in constant compliance [N]."""
    return float(steady_sliding_friction(xi, c.slide_ratio, velocity))


# --- registry -------------------------------------------------------------------------
@dataclass(frozen=True)
class FrictionModel:
    """One entry of the friction registry.

    Attributes
    ----------
    identifier : str
        Name used by the library and the CLI (``--friction``).
    name : str
        Human description with the paper's equation numbers.
    parameters : tuple of (name, unit) pairs
        Required parameters.
    compute : callable
        ``compute(cantilever, **parameters) -> (extra dict, units dict, k, beta)``.
    """

    identifier: str
    name: str
    parameters: tuple[tuple[str, str], ...]
    compute: Callable[..., tuple[dict, dict, float | None, float | None]]


def _none(c):
    return {}, {}, None, None


def _constant(c, mu):
    mu = non_negative("mu", check("mu", mu), "N")
    return ({"friction_force": mu,
             "force_difference": constant_friction_force_difference(c, mu),
             "hysteresis_offset": constant_friction_offset(c, mu)},
            {"friction_force": "N", "force_difference": "N", "hysteresis_offset": "m"}, None, None)


def _load(c, lam, deflection=10e-9):
    lam = non_negative("lambda", check("lam", lam))
    deflection = check("gap_deflection", deflection)
    k_in, b_in = load_friction_constants(c, lam, +1)
    k_out, b_out = load_friction_constants(c, lam, -1)
    extra = {
        "inward": {"spring_constant": k_in, "calibration_factor": b_in},
        "outward": {"spring_constant": k_out, "calibration_factor": b_out},
        "gap_deflection": deflection,
        "inward_force_at_gap": k_in * deflection,
        "hysteresis_offset": load_friction_gap(c, lam, deflection),
    }
    units = {"inward": "", "outward": "", "gap_deflection": "m", "inward_force_at_gap": "N",
             "hysteresis_offset": "m"}
    return extra, units, k_in, b_in


def _pinned(c):
    return {}, {}, pinned_spring_constant(c), pinned_calibration_factor(c)


def _viscous(c, xi, velocity):
    xi = non_negative("xi", check("xi", xi), "kg/s")
    velocity = positive("velocity", check("velocity", abs(velocity)), "m/s")
    fy = viscous_friction_force(c, xi, velocity)
    return ({"friction_force": fy, "hysteresis_offset": constant_friction_offset(c, fy),
             "slide_ratio": c.slide_ratio},
            {"friction_force": "N", "hysteresis_offset": "m", "slide_ratio": ""}, None, None)


#: Friction models of section 2.2, by identifier.
FRICTION_MODELS: dict[str, FrictionModel] = {
    m.identifier: m
    for m in (
        FrictionModel("none", "no friction (eqs 13-15)", (), _none),
        FrictionModel("constant", "constant friction Fy = +-mu (eqs 16-17)", (("mu", "N"),), _constant),
        FrictionModel("load", "friction proportional to load Fy = +-lambda Fz (eqs 18-19)",
                      (("lam", ""),), _load),
        FrictionModel("pinned", "pinned tip y2 = 0 (eqs 20-21)", (), _pinned),
        FrictionModel("viscous", "viscous friction in steady sliding Fy = xi |dy2/dz2| dz/dt (eq 28)",
                      (("xi", "kg/s"), ("velocity", "m/s")), _viscous),
    )
}


def static_analysis(cantilever: InclinedCantilever, friction: str = "none", **parameters) -> StaticResult:
    """Spring constant, calibration factor and hysteresis under a friction model.

    Parameters
    ----------
    cantilever : InclinedCantilever
        Geometry and stiffness.
    friction : str
        One of :data:`FRICTION_MODELS`: ``none``, ``constant`` (needs ``mu`` [N]),
        ``load`` (needs ``lam`` [-]; optional ``deflection`` [m] where the gap is
        evaluated, default 10 nm), ``pinned``, ``viscous`` (needs ``xi`` [kg/s] and
        ``velocity`` [m/s]).

    Returns
    -------
    StaticResult
    """
    if friction not in FRICTION_MODELS:
        raise ParameterError(f"unknown friction model {friction!r}; choose one of {', '.join(FRICTION_MODELS)}")
    model = FRICTION_MODELS[friction]
    missing = [p for p, _ in model.parameters if parameters.get(p) is None]
    if missing:
        raise ParameterError(f"friction model {friction!r} needs {', '.join(missing)}")
    known = {p for p, _ in model.parameters} | ({"deflection"} if friction == "load" else set())
    unknown = set(k for k, v in parameters.items() if v is not None) - known
    if unknown:
        raise ParameterError(f"friction model {friction!r} does not take {', '.join(sorted(unknown))}")
    extra, units, k, beta = model.compute(cantilever, **{k: v for k, v in parameters.items() if v is not None})
    return StaticResult(
        friction=friction,
        spring_constant=cantilever.spring_constant if k is None else k,
        calibration_factor=cantilever.calibration_factor if beta is None else beta,
        intrinsic_spring_constant=cantilever.k0,
        spring_constant_tilt_only=cantilever.spring_constant_tilt_only,
        extra=extra,
        units={**_BASE_UNITS, **units},
    )
