"""The parts a :class:`~afmforce.dynamics.SimulationConfig` is composed of.

One simulated cycle is a probe (:class:`BeamProbe`, the inclined cantilever
of Fig 2, or :class:`SpringProbe`, the simple spring of eq 1), the surfaces
(:class:`Surface`, eq 2 and drainage), the tip friction (:class:`Friction`,
eq 28), the drive protocol (:class:`Drive`) and the numerics
(:class:`SolverOptions`: sampling, tolerances, event definitions). Each part is
a frozen dataclass that validates its own fields on construction and computes
nothing else: no static solve, no matrix.

Every numeric field carries the metadata of its quantity in
:data:`afmforce._fields.QUANTITIES` (dimension, SI unit, help, valid range;
read with :func:`afmforce._fields.spec_of`) plus the ``domain`` the model
itself needs (checked on construction, :mod:`._part`): ``positive``, ``non_negative``, ``finite``,
``range`` (the spec's range), ``optional_positive`` (None or > 0) or
``count`` (None or a whole number >= 1). The valid *ranges* of the vocabulary
(what an AFM experiment means) are enforced on construction too, with the
message the command line and the web give, and so are the cross-field rules
(:func:`afmforce._fields.check_beam`: L1, L2 < L0).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, make_dataclass
from functools import lru_cache
from typing import ClassVar

from .._fields import check_beam, show
from ..cantilever import InclinedCantilever
from ..constants import FIG1, FIG5
from ..errors import ParameterError
from ..forces import GEOMETRIES
from ..surface_laws import LAWS as _LAWS
from ..surface_laws import MODEL_PARAMETERS
from ..surface_laws import PARAMETERS as LAW_PARAMETERS
from ..surface_laws.double_layer import screening_length
from ..surface_laws import active_laws
from ..surface_laws import reach as law_reach
from ._part import DOMAINS, Part, choice, quantity, validate
from .registries import FRICTION_LAWS, RINGING

__all__ = [
    "DEFAULT_B",
    "DOMAINS",
    "MODELS",
    "PROBES",
    "SAMPLING",
    "BeamProbe",
    "Drive",
    "Friction",
    "SolverOptions",
    "SpringProbe",
    "Surface",
]

#: Flexural rigidity used when neither k0 nor B is given [N m^2] (spec section 5 decision).
DEFAULT_B = FIG5["B"]
#: Dynamical models selectable with ``model=`` / ``--model``.
MODELS = {
    "beam": "inclined cantilever with base, probe and tip friction (eqs 22-28)",
    "spring": "mass on a spring moving vertically (eq 1)",
}
#: What one trajectory sample is: the state at the sample time, or its mean over the sample interval.
SAMPLING = {
    "point": "the state at the sample time",
    "average": "the state averaged over the sample interval centred on the sample time "
               "(a detector averaged over each interval; removes aliased MHz ringing)",
}


# --- probes -------------------------------------------------------------------
@lru_cache(maxsize=256)
def _cantilever(L0, L1, L2, theta0, k0, B) -> InclinedCantilever:
    """The (immutable) cantilever of these values, built and validated once per geometry."""
    return InclinedCantilever(L0, L1, L2, theta0, k0=k0, B=B)


@lru_cache(maxsize=256)
def _k_beta(cant: InclinedCantilever) -> tuple[float, float]:
    """(k of eq 13 [N/m], beta of eq 15 [m/rad]) of a cantilever, computed once."""
    return float(cant.spring_constant), float(cant.calibration_factor)


@dataclass(frozen=True)
class BeamProbe(Part):
    """The inclined cantilever of Fig 2 with its masses (the ``beam`` model, eqs 22-28).

    Attributes
    ----------
    L0, L1, L2 : float
        Beam, base and probe lengths [m].
    theta0 : float
        Inclination [rad] (negative: -15 deg in the paper).
    k0, B : float or None
        The beam's stiffness, given as the intrinsic spring constant k0 [N/m]
        *or* the flexural rigidity B [N m^2] (``B = k0 L0^3 / 3``), not both;
        neither: B = :data:`DEFAULT_B` (3.5e-13; spec section 5 decision: the
        paper prints 3.5e-12). After construction exactly one is set; read
        both from :attr:`cantilever`.
    m_joint, m_base : float
        Point mass at the beam-base joint and mass spread along the base [kg]
        (``m_alpha = m_joint + m_base/4``, ``m_beta = m_base/3``).
    quality_factor, quality_factor_2 : float or None
        Quality factor Q [-] of the lever's first and second free mode in its
        medium (issue 23): Rayleigh damping ``C = alpha M + beta K`` of the
        beam's mass and stiffness matrices, chosen so that the free modes have
        exactly these Q (``quality_factor_2`` None: both get ``quality_factor``;
        ``quality_factor`` None with ``quality_factor_2`` given: the first mode
        stays undamped; :func:`afmforce.dynamics.damping.beam_damping`). Both
        None (default): no lever damping, the paper's model.
    """

    model: ClassVar[str] = "beam"

    L0: float = quantity("L0", FIG5["L0"], "positive")
    L1: float = quantity("L1", FIG5["L1"], "positive")
    L2: float = quantity("L2", FIG5["L2"], "finite")
    theta0: float = quantity("theta0", FIG5["theta0"], "finite")
    k0: float | None = quantity("k0", None, "optional_positive")
    B: float | None = quantity("B", None, "optional_positive")
    m_joint: float = quantity("m_joint", FIG5["m_joint"], "positive")
    m_base: float = quantity("m_base", FIG5["m_base"], "positive")
    quality_factor: float | None = quantity("quality_factor", None, "optional_positive")
    quality_factor_2: float | None = quantity("quality_factor_2", None, "optional_positive")

    def __post_init__(self) -> None:
        if self.k0 is not None and self.B is not None:
            raise ParameterError("give at most one of k0 [N/m] or B [N m^2]")
        if self.k0 is None and self.B is None:
            object.__setattr__(self, "B", DEFAULT_B)
        validate(self, skip=("L0", "L1", "L2", "theta0"))   # the cantilever checks its geometry
        check_beam(self.L0, self.L1, self.L2, k0=self.k0, B=self.B)   # L1, L2 < L0; k0 of B in range
        cant = _cantilever(self.L0, self.L1, self.L2, self.theta0, self.k0, self.B)
        for name in ("L0", "L1", "L2", "theta0"):
            object.__setattr__(self, name, getattr(cant, name))
        object.__setattr__(self, "_cant", cant)

    def replace(self, **changes) -> BeamProbe:
        """A copy with some fields changed; giving k0 (or B) alone replaces the other."""
        if "k0" in changes and "B" not in changes:
            changes["B"] = None
        elif "B" in changes and "k0" not in changes:
            changes["k0"] = None
        return super().replace(**changes)

    @property
    def cantilever(self) -> InclinedCantilever:
        """The :class:`~afmforce.cantilever.InclinedCantilever` (k0 and B both resolved)."""
        return self._cant

    @property
    def force_constant(self) -> float:
        """Force-measuring spring constant k of eq 13 [N/m]."""
        return _k_beta(self._cant)[0]

    @property
    def calibration_factor(self) -> float:
        """beta = dz2/dtheta of eq 15 [m/rad]."""
        return _k_beta(self._cant)[1]


@dataclass(frozen=True)
class SpringProbe(Part):
    """A mass on a spring moving vertically (the ``spring`` model, eq 1; no tilt, no friction).

    Attributes
    ----------
    spring_constant : float
        k [N/m] (default: Fig 1, 0.21).
    mass : float
        m [kg] (default: Fig 1, 10 ug).
    quality_factor : float or None
        Quality factor Q [-] of the spring in its medium (issue 23): viscous
        damping ``m omega0 / Q`` (omega0 = sqrt(k/m)). None (default): undamped,
        the paper's eq 1.
    """

    model: ClassVar[str] = "spring"

    spring_constant: float = quantity("spring_constant", FIG1["spring_constant"], "positive")
    mass: float = quantity("mass", FIG1["mass"], "positive")
    quality_factor: float | None = quantity("quality_factor", None, "optional_positive")

    def __post_init__(self) -> None:
        validate(self)

    @property
    def force_constant(self) -> float:
        """k [N/m]."""
        return self.spring_constant

    @property
    def calibration_factor(self) -> float:
        """NaN: the spring does not tilt (no eq 15)."""
        return math.nan


#: Model name -> its probe class.
PROBES: dict[str, type] = {"beam": BeamProbe, "spring": SpringProbe}


# --- surfaces, friction, drive, numerics ---------------------------------------
def _law_quantity(name: str):
    """A field of a parameter of the model's own surface laws (eq 2, the double layer): default and
    domain from its law's record (:data:`afmforce.surface_laws.MODEL_PARAMETERS`)."""
    p = MODEL_PARAMETERS[name]
    return quantity(name, p.default, p.domain)


#: The double layer's choice of boundary condition, declared by its law's record.
_DL = _LAWS["double_layer"].switch


@dataclass(frozen=True)
class _SurfaceBase(Part):
    """The surfaces: van der Waals force with a soft wall (eq 2) and drainage; in a liquid also
    the double layer, slip and the drag on the lever (issue 25; docs/liquid.md).

    Attributes
    ----------
    radius : float
        Radius R [m]: of each of two spheres (``geometry="sphere-sphere"``, the paper's
        effective radius) or of the probe on a flat (``"sphere-flat"``).
    hamaker : float
        Hamaker constant A [J].
    z0 : float
        Soft-wall length [m].
    viscosity : float
        Fluid viscosity for drainage [Pa s] (0 switches drainage off).
    geometry : {"sphere-sphere", "sphere-flat"}
        :data:`afmforce.forces.GEOMETRIES`: R_eff = R/2 (the paper) or R (a colloid probe).
    double_layer : {"none", "weak_overlap", "constant_potential", "constant_charge"}
        :data:`afmforce.forces.DOUBLE_LAYERS`.
    surface_potential, surface_potential_2 : float
        psi1 and psi2 [V] (psi2 None: equal to psi1).
    debye_length : float or None
        1/kappa [m]; or give ``salt_concentration`` [mol/m^3] (and ``valence``) instead.
        Neither: 10 nm. After construction ``debye_length`` is always set.
    permittivity : float
        Relative permittivity of the medium (water 78.5).
    slip_length : float
        Slip length b [m] on both surfaces (Vinogradova's f*; 0: no slip).
    lever_drag : float
        Drag coefficient of the lever body [N s/m] on the relative velocity of lever and substrate.
    lever_height : float
        Lever height above the substrate at contact [m]: drag ``c H/(h + H)``; 0: constant.

    The parameters of the surface force laws of :mod:`afmforce.surface_laws` follow (issue 31:
    hydration, steric brushes, capillary meniscus ...), one field each, made from the laws'
    records; every law is off at its defaults.
    """

    radius: float = quantity("radius", FIG5["radius"], "positive")
    hamaker: float = _law_quantity("hamaker")
    z0: float = _law_quantity("z0")
    viscosity: float = quantity("viscosity", FIG5["viscosity"], "non_negative")
    geometry: str = choice("sphere-sphere", GEOMETRIES, "geometry of the surfaces")
    double_layer: str = choice(_DL.default, _DL.choices, _DL.help)
    surface_potential: float = _law_quantity("surface_potential")
    surface_potential_2: float | None = _law_quantity("surface_potential_2")
    debye_length: float | None = _law_quantity("debye_length")
    salt_concentration: float | None = _law_quantity("salt_concentration")
    valence: float = _law_quantity("valence")
    permittivity: float = _law_quantity("permittivity")
    slip_length: float = quantity("slip_length", 0.0, "non_negative")
    lever_drag: float = quantity("lever_drag", 0.0, "non_negative")
    lever_height: float = quantity("lever_height", 0.0, "non_negative")

    def __post_init__(self) -> None:
        validate(self)
        lam = screening_length(self.debye_length, self.salt_concentration, self.valence, self.permittivity)
        if self.salt_concentration is not None and self.debye_length is not None \
                and not math.isclose(self.debye_length, lam, rel_tol=1e-9):
            raise ParameterError("give at most one of debye_length [m] or salt_concentration "
                                 "[mol/m^3]")
        object.__setattr__(self, "debye_length", lam)

    def replace(self, **changes) -> Surface:
        """A copy with some fields changed; a new salt concentration replaces the Debye length
        (and a new Debye length drops the concentration)."""
        if "salt_concentration" in changes and "debye_length" not in changes:
            changes["debye_length"] = None
        elif "debye_length" in changes and "salt_concentration" not in changes:
            changes["salt_concentration"] = None
        if ("permittivity" in changes or "valence" in changes) and self.salt_concentration is not None \
                and "debye_length" not in changes:
            changes["debye_length"] = None
        return super().replace(**changes)

    @property
    def liquid(self) -> bool:
        """True when any force beyond the paper's air model is on (double layer, slip, lever drag)."""
        return self.double_layer != "none" or self.slip_length > 0 or self.lever_drag > 0

    @property
    def paper_radius(self) -> float:
        """The radius the paper's sphere-sphere formulas take (R, or 2R on a flat) [m]."""
        return self.radius if self.geometry == "sphere-sphere" else 2.0 * self.radius

    @property
    def eq2_only(self) -> bool:
        """True when the static force is the paper's eq 2 alone (no double layer, no law of
        :mod:`afmforce.surface_laws`): the closed-form static solutions apply."""
        return self.double_layer == "none" and not self.laws

    @property
    def law_values(self) -> dict[str, float]:
        """The surface force laws' parameters (:data:`afmforce.surface_laws.PARAMETERS`) [SI]."""
        return {n: getattr(self, n) for n in LAW_PARAMETERS}

    @property
    def laws(self) -> tuple[str, ...]:
        """Names of the surface force laws that act (:mod:`afmforce.surface_laws`; () in the paper)."""
        return active_laws(self.law_values)

    @property
    def law_reach(self) -> float:
        """Separation beyond which the active surface force laws are negligible [m] (0: none)."""
        return law_reach(self.law_values)

    @property
    def radius_eff(self) -> float:
        """The Derjaguin radius R_eff [m] (R/2 for two spheres, R on a flat)."""
        return 0.5 * self.paper_radius


#: The surfaces (:class:`_SurfaceBase`) with one field per parameter of the surface force laws
#: (:data:`afmforce.surface_laws.PARAMETERS`), made from the laws' records.
Surface = make_dataclass(
    "Surface", [(n, float, quantity(n, p.default, p.domain)) for n, p in LAW_PARAMETERS.items()],
    bases=(_SurfaceBase,), frozen=True,
    namespace={"__doc__": _SurfaceBase.__doc__, "__module__": __name__})


@dataclass(frozen=True)
class Friction(Part):
    """Lateral friction on the probe tip (beam model; the spring has no lateral motion).

    Attributes
    ----------
    law : {"viscous", "load", "none"}
        Law from :data:`afmforce.dynamics.FRICTION_LAWS` (the flat name is ``friction``).
    xi : float
        Viscous friction coefficient [kg/s].
    zeta : float
        Load-dependent coefficient [kg/(s N^2)] (``law="load"``).
    """

    law: str = choice("viscous", FRICTION_LAWS, "friction law", name="friction")
    xi: float = quantity("xi", FIG5["xi"], "non_negative")
    zeta: float = quantity("zeta", 0.0, "non_negative")

    def __post_init__(self) -> None:
        validate(self)

    @property
    def coefficients(self) -> tuple[float, float]:
        """(xi, zeta) as the compiled force law ``Fy = -(xi + zeta Fz^2) y2'`` uses them."""
        return FRICTION_LAWS[self.law].coefficients(self.xi, self.zeta)


@dataclass(frozen=True)
class Drive(Part):
    """The drive protocol: approach, optional dwell, retract (substrate position z, up > 0).

    Attributes
    ----------
    velocity : float
        Approach speed [m/s], > 0.
    retract_velocity : float or None
        Retract speed [m/s]; default: ``velocity``.
    start : float
        Drive position at t = 0 [m]; the cantilever starts at static
        equilibrium there (no friction at rest). Must be out of contact
        (checked by :meth:`SimulationConfig.validate`, which needs a static solve).
    turn : float
        Drive position where the approach turns [m]. With ``turn_force`` or
        ``turn_deflection`` it is the farthest the approach may go.
    turn_force : float or None
        Turn when the load ``k z2`` first reaches this value [N] (k of eq 13
        for the beam): the trigger of an instrument, which sees the deflection;
        the contact force Fz itself rings at jump-in.
    turn_deflection : float or None
        Turn when the deflection z2 first reaches this value [m].
    dwell : float
        Pause at the turn point [s].
    end : float
        Drive position where the retract ends [m].
    """

    velocity: float = quantity("velocity", FIG5["velocity"], "positive")
    retract_velocity: float | None = quantity("retract_velocity", None, "optional_positive")
    start: float = quantity("start", FIG5["start"], "finite")
    turn: float = quantity("turn", FIG5["turn"], "finite")
    turn_force: float | None = quantity("turn_force", None, "optional_positive")
    turn_deflection: float | None = quantity("turn_deflection", None, "optional_positive")
    dwell: float = quantity("dwell", 0.0, "non_negative")
    end: float = quantity("end", FIG5["end"], "finite")

    def __post_init__(self) -> None:
        validate(self)
        if self.turn_force is not None and self.turn_deflection is not None:
            raise ParameterError("give at most one of turn_force [N] or turn_deflection [m]")
        if self.turn <= self.start:
            raise ParameterError(
                f"`turn` ({show(self.turn, 'm')}) must lie above `start` ({show(self.start, 'm')}): "
                "the approach moves the substrate up (z increasing)")
        if self.end >= self.turn:
            raise ParameterError(
                f"`end` ({show(self.end, 'm')}) must lie below `turn` ({show(self.turn, 'm')}): "
                "the retract moves the substrate down")

    @property
    def retract_speed(self) -> float:
        """Retract speed [m/s]."""
        return self.velocity if self.retract_velocity is None else self.retract_velocity


@dataclass(frozen=True)
class SolverOptions(Part):
    """Sampling of the returned trajectory, integrator tolerances and event definitions.

    Attributes
    ----------
    sample_rate : float
        Instrument sampling rate of the returned trajectory [Hz].
    rtol : float
        Relative tolerance of the integrator on velocities; also sets the
        Newton tolerance.
    atol : float
        Absolute tolerance on positions [m] (positions have no relative
        tolerance: the forces depend on h, a small difference of two large
        positions in contact); velocities use ``atol * 10 * w`` with w the
        model's own free or contact frequency at the current state
        (:func:`afmforce.dynamics.models.error_frequency`; docs/dynamics.md).
    contact_separation : float
        Separation below which the surfaces count as in contact [m]
        (contact and pull-off events; spec section 7 uses 1 nm).
    jump_factor : float
        Jump-in criterion: the first time ``dh/dt < -jump_factor * dz/dt``
        on the approach before contact.
    spike_window : float
        The jump-in transient: the apparent-deflection spike is searched from
        jump-in (or contact) to this long after contact [s]; the in-contact
        ringing is resolved until the spike has not grown for 30 contact-mode
        cycles (``simulate.SPIKE_QUIET_CYCLES``), at most this long. 0: the spike is not asked
        for (``spike_height`` etc. NaN); the ringing is then damped as soon as
        its amplitude allows, which takes 2-4x fewer steps (Fig 5/6 runs) and
        leaves every other event within its tolerance (docs/dynamics.md).
    ringing : {"damp", "resolve"}
        Treatment of the nearly undamped in-contact mode
        (:data:`afmforce.dynamics.RINGING`; docs/dynamics.md): ``damp`` lets
        the L-stable integrator damp it after ``spike_window``; ``resolve``
        follows it under normal error control.
    sampling : {"point", "average"}
        What one sample of the trajectory is (:data:`SAMPLING`): ``point``
        (default) the state at the sample time; ``average`` the state averaged
        over the sample interval centred on it (exact integral of the
        solver's dense output), as an instrument whose detector signal is
        averaged (oversampled) over each sample interval records it. Linear
        observables (deflection, angle, apparent deflection, separation) are
        then exact interval means; force columns are evaluated at the mean
        state. Events are located on the dense output in both modes.
    max_steps : int or None
        Step budget; exceeding it raises :class:`~afmforce.errors.SolverError`.
        None (default): sized from the run, ``max(2e6, 60 f_max T)`` with
        ``f_max`` the highest free mode and ``T`` the simulated time, so a
        slow run that must follow a free oscillation for minutes finishes.
    """

    sample_rate: float = quantity("sample_rate", 10e3, "positive")
    rtol: float = quantity("rtol", 1e-4, "range")
    atol: float = quantity("atol", 1e-12, "positive")
    contact_separation: float = quantity("contact_separation", 1e-9, "positive")
    jump_factor: float = quantity("jump_factor", 2.0, "positive")
    spike_window: float = quantity("spike_window", 2e-3, "non_negative")
    ringing: str = choice("damp", RINGING, "treatment of the in-contact ringing")
    sampling: str = choice("point", SAMPLING, "what one trajectory sample is")
    max_steps: int | None = quantity("max_steps", None, "count")

    def __post_init__(self) -> None:
        validate(self)
