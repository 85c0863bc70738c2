"""Registry of the global parameters the dynamic fit can free (``--free``).

Each entry maps a user name to a flat name of :class:`~afmforce.dynamics.SimulationConfig`
(:data:`afmforce.dynamics.config.FLAT`), with the scale used inside the optimiser and the
finite-difference step of the Jacobian. Its unit and search bounds come from the quantity's
declaration (:data:`afmforce._fields.QUANTITIES`): the declared valid range, or a narrower
search window inside it (never wider: the fit never tries a value the records refuse). Per-curve nuisance parameters (the zero
of the piezo position ``shift``, the baseline ``offset`` and the ``drift``
slope) are always fitted and are not in this registry.
"""

from __future__ import annotations

from dataclasses import dataclass

from .._fields import QUANTITIES
from ..errors import ParameterError

__all__ = ["FitParameter", "LAW_PARAMETERS", "PARAMETERS", "SPEED_DEPENDENT", "check_free"]

#: Parameters only curves at several driving speeds can separate from A*R.
SPEED_DEPENDENT = ("xi", "zeta", "viscosity", "mass", "m_joint", "slip_length", "lever_drag")


@dataclass(frozen=True)
class FitParameter:
    """A global parameter of the dynamic model that can be fitted.

    Attributes
    ----------
    name : str
        User name (``--free`` key) and flat name of SimulationConfig; a key of
        :data:`afmforce._fields.QUANTITIES`.
    unit : str
        SI unit (default, and it must be: the declared one).
    lower, upper : float
        Search bounds [unit]; default the declared valid range. A narrower
        window must lie inside the declared range (checked on construction).
    scale : float
        Typical size [unit]; the optimiser works in units of ``scale``.
    rel_step, abs_step : float
        Forward-difference step ``max(rel_step |value|, abs_step)`` [unit].
    models : tuple of str
        Models in which the parameter has an effect.
    meaning : str
        What it is.
    physical_lower : bool
        The lower bound is a physical limit (``xi >= 0``): an interval reaching it is
        an upper bound ``[lower, hi]``. Every other bound is a search bound: an
        interval that reaches it is one-sided, reported ``None`` on that side.
    """

    name: str
    unit: str | None
    lower: float | None
    upper: float | None
    scale: float
    rel_step: float
    abs_step: float
    models: tuple[str, ...]
    meaning: str
    physical_lower: bool = False

    def __post_init__(self) -> None:
        spec = QUANTITIES[self.name]
        if self.unit is None:
            object.__setattr__(self, "unit", spec.unit)
        for side, value, declared in (("lower", self.lower, spec.lo), ("upper", self.upper, spec.hi)):
            if value is None:
                if declared is None:
                    raise ValueError(f"fit parameter {self.name}: the declared range has no {side} "
                                     "bound; give a search bound")
                object.__setattr__(self, side, float(declared))
        if self.unit != spec.unit or not (spec.contains(self.lower) or self.lower == spec.lo) \
                or not (spec.contains(self.upper) or self.upper == spec.hi) or not self.lower < self.upper:
            raise ValueError(f"fit parameter {self.name}: search bounds [{self.lower:g}, {self.upper:g}] "
                             f"{self.unit} must lie in the declared range {spec.range_text()} [{spec.unit}]")

    def step(self, value: float) -> float:
        """Forward-difference step at ``value`` [unit]."""
        return max(self.rel_step * abs(value), self.abs_step)


def _model_law(name: str) -> FitParameter:
    """The fit parameter of a parameter of the model's own surface laws (eq 2, the double layer):
    scale, steps and search window from the law's record (:mod:`afmforce.surface_laws`), bounds
    from the quantity's range."""
    from ..surface_laws import LAWS

    law, p = next((law, p) for law in LAWS.values() if not law.compiled for p in law.parameters
                  if p.name == name)
    scale, rel, step = p.fit
    lower, upper = p.fit_window if p.fit_window is not None else (None, None)
    return FitParameter(name, None, lower, upper, scale, rel, step, ("beam", "spring"),
                        f"{QUANTITIES[name].help} ({law.name} law{'; ' + p.note if p.note else ''})")


#: Parameters that ``fit_dynamic(free=...)`` and ``afmforce fit --free`` accept.
PARAMETERS: dict[str, FitParameter] = {p.name: p for p in (
    # unit, lower, upper None: the declaration's (afmforce._fields.QUANTITIES); numbers: a narrower search window;
    # the parameters of the model's surface laws (eq 2, the double layer) from their records (_model_law)
    _model_law("hamaker"),
    FitParameter("radius", None, 1e-9, 1e-4, 1e-7, 0.01, 1e-11, ("beam", "spring"),
                 "effective radius R (the data fix A*R; A is given)"),
    FitParameter("xi", None, None, 10.0, 1e-2, 0.02, 2e-4, ("beam",),
                 "viscous tip friction coefficient (eq 28)", True),
    FitParameter("zeta", None, None, None, 1e14, 0.02, 1e12, ("beam",),
                 "load-proportional friction coefficient (friction='load')", True),
    _model_law("z0"),
    FitParameter("viscosity", None, None, 1.0, 1e-4, 0.02, 1e-6, ("beam", "spring"),
                 "fluid viscosity (drainage)", True),
    FitParameter("mass", None, 1e-15, None, 1e-9, 0.02, 1e-16, ("spring",),
                 "effective mass of the simple spring (inertia)"),
    FitParameter("m_joint", None, 1e-15, None, 1e-10, 0.02, 1e-16, ("beam",),
                 "point mass at the beam-base joint (inertia)"),
    # liquids (issue 25; docs/liquid.md)
    FitParameter("slip_length", None, None, None, 1e-9, 0.02, 2e-11, ("beam", "spring"),
                 "slip length b of the drainage force (Vinogradova f*)"),
    FitParameter("spring_constant", None, None, None, 0.1, 0.002, 1e-6, ("spring",),
                 "spring constant k, in situ (the drainage force fixes it: eta and R are given)"),
    FitParameter("k0", None, None, None, 0.1, 0.002, 1e-6, ("beam",),
                 "intrinsic spring constant of the beam, in situ (from the drainage force)"),
    FitParameter("lever_drag", None, None, None, 1e-5, 0.02, 1e-8, ("beam", "spring"),
                 "drag coefficient of the lever body (approach and retract together fix it)"),
    _model_law("surface_potential"),
    _model_law("debye_length"),
)}


def _law_parameters() -> dict[str, FitParameter]:
    """The fittable parameters of the surface force laws (:mod:`afmforce.surface_laws`): bounds
    from their quantities' ranges, scale and steps from the law's record."""
    from .._fields import QUANTITIES
    from ..surface_laws import LAWS

    out = {}
    for law in LAWS.values():
        for p in law.parameters:
            if p.fit is None or p.name in out or not law.compiled:
                continue
            spec = QUANTITIES[p.name]
            scale, rel, step = p.fit
            lower = spec.lo if spec.lo is not None else -1e300
            upper = spec.hi if spec.hi is not None else 1e300
            if spec.hi_open:
                upper -= max(step, 1e-9 * abs(upper))
            out[p.name] = FitParameter(p.name, spec.unit, lower, upper, scale, rel, step,
                                       ("beam", "spring"), f"{spec.help} ({law.name} law)",
                                       spec.lo == 0.0)
    return out


#: The surface force laws' fittable parameters (issue 31), from their records.
_LAWS = _law_parameters()
LAW_PARAMETERS: tuple[str, ...] = tuple(_LAWS)
PARAMETERS.update(_LAWS)


def check_free(free, model: str, friction: str | None = None) -> tuple[str, ...]:
    """Validate the free parameter names for ``model`` (and its ``friction`` law); returns them.

    Raises
    ------
    ParameterError
        Unknown name, a parameter without effect in this model or friction law
        (``xi`` with ``friction="none"``: the fit would report its start value with
        no error), or both ``hamaker`` and ``radius`` (only their product is determined).
    """
    names = tuple(dict.fromkeys(n.strip() for n in free if n.strip()))
    if not names:
        raise ParameterError(f"give at least one free parameter; known: {', '.join(PARAMETERS)}")
    for n in names:
        if n not in PARAMETERS:
            raise ParameterError(f"unknown free parameter {n!r}; known: {', '.join(PARAMETERS)}")
        if model not in PARAMETERS[n].models:
            why = " (the spring model has no lateral motion, hence no friction)" \
                if n in ("xi", "zeta") else ""
            raise ParameterError(f"{n} has no effect in the {model} model{why}; "
                                 f"use `model` {PARAMETERS[n].models[0]} or drop it from `free`")
    if friction is not None:
        from ..dynamics.registries import FRICTION_LAWS

        law = FRICTION_LAWS[friction]
        for n in names:
            if n in ("xi", "zeta") and n not in law.parameters:
                uses = [k for k, v in FRICTION_LAWS.items() if n in v.parameters]
                raise ParameterError(f"{n} has no effect with the friction law {friction!r}: the fit cannot "
                                     f"determine it; choose friction {' or '.join(map(repr, uses))}, or drop it "
                                     "from the free parameters")
    if "hamaker" in names and "radius" in names:
        raise ParameterError("hamaker and radius cannot both be free: the van der Waals force "
                             "fixes only A*R; free one and give the other")
    return names
