"""The configuration of one simulated approach-retract cycle.

Every default is a value of the paper's Figs 5-6 (``afmforce.constants.FIG5``;
spec section 5), so ``simulate()`` with no argument runs Fig 5. The simple
spring model defaults to the Fig 1 spring (``FIG1``).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, fields
from functools import lru_cache

from .._fields import qfield
from .._validate import finite, non_negative, positive
from ..cantilever import InclinedCantilever, SimpleSpring
from ..constants import FIG1, FIG5
from ..errors import ParameterError
from .models import FRICTION_LAWS, RINGING

__all__ = ["SimulationConfig", "DEFAULT_B", "MODELS", "SAMPLING"]

#: What one trajectory sample is: the state at the sample time, or its mean over the sample interval.
SAMPLING = {
    "point": "the state at the sample time",
    "average": "the state averaged over the sample interval centred on the sample time "
               "(a detector averaged over each interval; removes aliased MHz ringing)",
}

#: Flexural rigidity used when neither k0 nor B is given [N m^2] (spec section 5 decision).
DEFAULT_B = FIG5["B"]
#: Dynamical models selectable with ``model=`` / ``--model``.
MODELS = {
    "beam": "inclined cantilever with base, probe and tip friction (eqs 22-28)",
    "spring": "mass on a spring moving vertically (eq 1)",
}


@lru_cache(maxsize=256)
def _cantilever(L0, L1, L2, theta0, k0, B) -> InclinedCantilever:
    """The (immutable) cantilever of these fields, built and validated once per geometry."""
    if k0 is not None and B is not None:
        raise ParameterError("give at most one of k0 [N/m] or B [N m^2]")
    if k0 is not None:
        return InclinedCantilever(L0, L1, L2, theta0, k0=k0)
    return InclinedCantilever(L0, L1, L2, theta0, B=DEFAULT_B if B is None else B)


@lru_cache(maxsize=256)
def _spring(k, m) -> SimpleSpring:
    return SimpleSpring(k, m)


@dataclass(frozen=True)
class SimulationConfig:
    """Parameters of one simulated force measurement (SI units).

    Model
    -----
    model : {"beam", "spring"}
        ``beam``: the inclined cantilever of Fig 2 (eqs 22-28);
        ``spring``: the simple spring of eq 1 (no lateral motion, no friction).

    Inclined cantilever (beam model)
    --------------------------------
    L0, L1, L2 : float
        Beam, base and probe lengths [m].
    theta0 : float
        Inclination [rad] (negative: -15 deg in the paper).
    k0 : float or None
        Intrinsic spring constant [N/m]; or give ``B``.
    B : float or None
        Flexural rigidity [N m^2]; when neither k0 nor B is given, 3.5e-13
        (spec section 5 decision: the paper prints 3.5e-12).
    m_joint, m_base : float
        Point mass at the beam-base joint and mass spread along the base [kg]
        (``m_alpha = m_joint + m_base/4``, ``m_beta = m_base/3``).

    Simple spring (spring model)
    ----------------------------
    spring_constant : float
        k [N/m] (default: Fig 1, 0.21).
    mass : float
        m [kg] (default: Fig 1, 10 ug).

    Surfaces
    --------
    radius : float
        Effective radius R [m].
    hamaker : float
        Hamaker constant A [J].
    z0 : float
        Soft-wall length [m].
    viscosity : float
        Fluid viscosity for drainage [Pa s] (0 switches drainage off).

    Friction (beam model)
    ---------------------
    friction : {"viscous", "load", "none"}
        Law from :data:`afmforce.dynamics.FRICTION_LAWS`.
    xi : float
        Viscous friction coefficient [kg/s].
    zeta : float
        Load-dependent coefficient [kg/(s N^2)] (``friction="load"``).

    Drive
    -----
    velocity : float
        Approach speed [m/s], > 0.
    retract_velocity : float or None
        Retract speed [m/s]; default: ``velocity``.
    start : float
        Drive position at t = 0 [m]; the cantilever starts at static
        equilibrium there (no friction at rest). Must be out of contact.
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

    Output and solver
    -----------------
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
        jump-in (or contact) to this long after contact, and the in-contact
        ringing is resolved at least this long [s]. 0: the spike is not asked
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

    model: str = "beam"
    L0: float = qfield("L0", FIG5["L0"])
    L1: float = qfield("L1", FIG5["L1"])
    L2: float = qfield("L2", FIG5["L2"])
    theta0: float = qfield("theta0", FIG5["theta0"])
    k0: float | None = qfield("k0", None)
    B: float | None = qfield("B", None)
    m_joint: float = qfield("m_joint", FIG5["m_joint"])
    m_base: float = qfield("m_base", FIG5["m_base"])
    spring_constant: float = qfield("spring_constant", FIG1["spring_constant"])
    mass: float = qfield("mass", FIG1["mass"])
    radius: float = qfield("radius", FIG5["radius"])
    hamaker: float = qfield("hamaker", FIG5["hamaker"])
    z0: float = qfield("z0", FIG5["z0"])
    viscosity: float = qfield("viscosity", FIG5["viscosity"])
    friction: str = "viscous"
    xi: float = qfield("xi", FIG5["xi"])
    zeta: float = qfield("zeta", 0.0)
    velocity: float = qfield("velocity", FIG5["velocity"])
    retract_velocity: float | None = qfield("retract_velocity", None)
    start: float = qfield("start", FIG5["start"])
    turn: float = qfield("turn", FIG5["turn"])
    turn_force: float | None = qfield("turn_force", None)
    turn_deflection: float | None = qfield("turn_deflection", None)
    dwell: float = qfield("dwell", 0.0)
    end: float = qfield("end", FIG5["end"])
    sample_rate: float = qfield("sample_rate", 10e3)
    rtol: float = qfield("rtol", 1e-4)
    atol: float = qfield("atol", 1e-12)
    contact_separation: float = qfield("contact_separation", 1e-9)
    jump_factor: float = qfield("jump_factor", 2.0)
    spike_window: float = qfield("spike_window", 2e-3)
    ringing: str = "damp"
    sampling: str = "point"
    max_steps: int | None = qfield("max_steps", None)

    def __post_init__(self) -> None:
        set_ = lambda n, v: object.__setattr__(self, n, v)  # noqa: E731
        if self.model not in MODELS:
            raise ParameterError(f"model must be one of {sorted(MODELS)}, got {self.model!r}")
        if self.ringing not in RINGING:
            raise ParameterError(
                f"ringing must be one of {sorted(RINGING)}, got {self.ringing!r}")
        if self.sampling not in SAMPLING:
            raise ParameterError(
                f"sampling must be one of {sorted(SAMPLING)}, got {self.sampling!r}")
        if self.friction not in FRICTION_LAWS:
            raise ParameterError(
                f"friction must be one of {sorted(FRICTION_LAWS)}, got {self.friction!r}")
        for name, unit in (("m_joint", "kg"), ("m_base", "kg"), ("spring_constant", "N/m"),
                           ("mass", "kg"), ("radius", "m"), ("hamaker", "J"), ("z0", "m"),
                           ("velocity", "m/s"), ("sample_rate", "Hz"), ("atol", "m"),
                           ("contact_separation", "m"), ("jump_factor", "")):
            set_(name, positive(name, getattr(self, name), unit))
        for name, unit in (("viscosity", "Pa s"), ("xi", "kg/s"), ("zeta", "kg/(s N^2)"),
                           ("dwell", "s"), ("spike_window", "s")):
            set_(name, non_negative(name, getattr(self, name), unit))
        for name in ("start", "turn", "end"):
            set_(name, finite(name, getattr(self, name), "m"))
        if self.retract_velocity is not None:
            set_("retract_velocity", positive("retract_velocity", self.retract_velocity, "m/s"))
        if self.turn_force is not None and self.turn_deflection is not None:
            raise ParameterError("give at most one of turn_force [N] or turn_deflection [m]")
        if self.turn_force is not None:   # a repulsive load: the turn is in contact
            set_("turn_force", positive("turn_force", self.turn_force, "N"))
        if self.turn_deflection is not None:
            set_("turn_deflection", positive("turn_deflection", self.turn_deflection, "m"))
        rtol = finite("rtol", self.rtol)
        if not 1e-12 <= rtol <= 0.1:
            raise ParameterError(f"rtol must lie between 1e-12 and 0.1, got {self.rtol!r}")
        set_("rtol", rtol)
        if self.max_steps is not None:
            if int(self.max_steps) < 1:
                raise ParameterError(
                    f"max_steps must be a positive integer, got {self.max_steps!r}")
            set_("max_steps", int(self.max_steps))
        if self.turn <= self.start:
            raise ParameterError(
                f"turn ({self.turn:.4g} m) must lie above start ({self.start:.4g} m): "
                "the approach moves the substrate up (z increasing)")
        if self.end >= self.turn:
            raise ParameterError(
                f"end ({self.end:.4g} m) must lie below turn ({self.turn:.4g} m): "
                "the retract moves the substrate down")
        n_app = (self.turn - self.start) / self.velocity * self.sample_rate
        if n_app < 10:
            raise ParameterError(
                f"sample_rate {self.sample_rate:.4g} Hz gives only {n_app:.1f} samples on the "
                "approach; raise it (at least 10 samples per run)")
        if self.model == "beam":
            # validates the geometry; kept (with k and beta) so that a run builds it once
            cant = _cantilever(self.L0, self.L1, self.L2, self.theta0, self.k0, self.B)
            set_("_cant", cant)
            set_("_k", cant.spring_constant)
            set_("_beta", cant.calibration_factor)
        else:
            _spring(self.spring_constant, self.mass)
            set_("_cant", None)
            set_("_k", self.spring_constant)
            set_("_beta", math.nan)
        from .drive import start_deflection

        # raises if the start is already in contact; kept for initial_state()
        set_("_start_deflection", start_deflection(self))

    # --- derived -----------------------------------------------------------
    @property
    def cantilever(self) -> InclinedCantilever:
        """The :class:`~afmforce.cantilever.InclinedCantilever` of the beam model."""
        cant = self.__dict__.get("_cant")
        if cant is None:
            cant = _cantilever(self.L0, self.L1, self.L2, self.theta0, self.k0, self.B)
        return cant

    @property
    def force_constant(self) -> float:
        """Force-measuring spring constant k [N/m] (eq 13 for the beam, k for the spring)."""
        return self._k

    @property
    def calibration_factor(self) -> float:
        """beta = dz2/dtheta of eq 15 [m/rad] (NaN for the spring model: it does not tilt)."""
        return self._beta

    @property
    def retract_speed(self) -> float:
        """Retract speed [m/s]."""
        return self.velocity if self.retract_velocity is None else self.retract_velocity

    def replace(self, **changes) -> "SimulationConfig":
        """A copy with some fields changed (validated again)."""
        unknown = set(changes) - {f.name for f in fields(self)}
        if unknown:
            raise ParameterError(
                f"unknown simulation parameter(s) {sorted(unknown)}; "
                f"known: {', '.join(f.name for f in fields(self))}")
        return SimulationConfig(**{**asdict(self), **changes})

    def to_dict(self) -> dict:
        """The fields as a plain dict (SI values)."""
        return asdict(self)
