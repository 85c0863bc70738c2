"""The configuration of one simulated approach-retract cycle, composed of parts.

A :class:`SimulationConfig` is five frozen parts (:mod:`afmforce.dynamics.parts`):
``probe`` (:class:`~.parts.BeamProbe` or :class:`~.parts.SpringProbe`; it
decides the model), ``surface``, ``friction``, ``drive`` and ``solver``. Every
default is a value of the paper's Figs 5-6 (``afmforce.constants.FIG5``; spec
section 5), so ``simulate()`` with no argument runs Fig 5; the spring model
defaults to the Fig 1 spring (``FIG1``).

Flat names. Every field also has one flat name -- the field's own name, and
``friction`` for ``friction.law``, ``model`` for the probe kind -- the
vocabulary of the command line (``--xi``), sweeps (``--set xi=0.01``), fits
(``free=("xi",)``) and stored trajectory headers. :data:`FLAT` maps each flat
name to its part. They are accepted wherever a configuration is built or
changed, and readable as attributes::

    SimulationConfig(xi=0.01, velocity=1e-6)            # flat names (as before issue 11.7)
    SimulationConfig(friction=Friction(xi=0.01), drive=Drive(velocity=1e-6))   # parts
    cfg.replace(model="spring", mass=1e-9)              # flat names or parts
    cfg.xi == cfg.friction.xi; cfg.to_dict()["friction"] == cfg.friction.law

Construction only validates the fields: the cantilever's matrices, k and beta
are computed once per geometry and cached; the static solve of the start
deflection runs when a run (or :meth:`SimulationConfig.validate`) first needs it.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from ..cantilever import InclinedCantilever
from ..errors import ParameterError
from ..limits import check_samples, simulation_samples
from .parts import (
    DEFAULT_B,
    MODELS,
    PROBES,
    SAMPLING,
    BeamProbe,
    Drive,
    Friction,
    SolverOptions,
    SpringProbe,
    Surface,
)

__all__ = [
    "DEFAULT_B",
    "FLAT",
    "MODELS",
    "SAMPLING",
    "BeamProbe",
    "Drive",
    "FlatName",
    "Friction",
    "SimulationConfig",
    "SolverOptions",
    "SpringProbe",
    "Surface",
    "flat_defaults",
]

#: The parts of a configuration, in order, and the class of each (probe: by model).
PARTS: dict[str, Any] = {"probe": (BeamProbe, SpringProbe), "surface": Surface, "friction": Friction,
                         "drive": Drive, "solver": SolverOptions}
_DEFAULT = {"beam": BeamProbe(), "spring": SpringProbe(), "surface": Surface(),
            "friction": Friction(), "drive": Drive(), "solver": SolverOptions()}


@dataclass(frozen=True)
class FlatName:
    """Where one flat parameter name lives in a :class:`SimulationConfig`.

    Attributes
    ----------
    name : str
        The flat name (``xi``, ``friction``, ``model`` ...).
    part : str
        The part holding it (``probe``, ``surface``, ``friction``, ``drive``, ``solver``).
    attr : str
        Its field in the part (``law`` for ``friction``; ``model`` is the probe's kind).
    models : tuple of str
        Models whose configuration has it (probe fields belong to one model).
    field : dataclasses.Field or None
        The part's field (metadata: unit, dimension, range); None for ``model``.
    """

    name: str
    part: str
    attr: str
    models: tuple[str, ...]
    field: dataclasses.Field | None

    @property
    def spec(self):
        """The field's :class:`~afmforce._fields.FieldSpec` (None for text fields)."""
        return None if self.field is None else self.field.metadata.get("spec")

    @property
    def choices(self) -> tuple[str, ...]:
        """The words a text field accepts, as its part declares them (``model``: the probes'
        kinds); () for a number. Every face (the web's form, the OpenAPI schema) reads this."""
        if self.field is None:
            return tuple(MODELS)
        return tuple(self.field.metadata.get("choices", ()))

    @property
    def default(self) -> Any:
        """The default value [SI] (B: the rigidity used when neither k0 nor B is given)."""
        if self.field is None:
            return "beam"
        return getattr(_DEFAULT[self.models[0] if self.part == "probe" else self.part], self.attr)


def _flat_table() -> dict[str, FlatName]:
    out = {"model": FlatName("model", "probe", "model", tuple(MODELS), None)}
    for model, cls in PROBES.items():
        for f in dataclasses.fields(cls):
            known = out.get(f.name)        # a field of both probes (quality_factor): both models
            models = (known.models if known is not None else ()) + (model,)
            out[f.name] = FlatName(f.name, "probe", f.name, models, f)
    for part, cls in PARTS.items():
        if part == "probe":
            continue
        for f in dataclasses.fields(cls):
            name = "friction" if (part, f.name) == ("friction", "law") else f.name
            out[name] = FlatName(name, part, f.name, tuple(MODELS), f)
    return out


#: Flat name -> :class:`FlatName`, in the order of the stored headers (model, probe,
#: surface, friction, drive, solver).
FLAT: dict[str, FlatName] = _flat_table()


def flat_defaults() -> dict[str, Any]:
    """Default value [SI] of every flat name (both models' probes)."""
    return {n: f.default for n, f in FLAT.items()}


def _unknown(names) -> ParameterError:
    return ParameterError(f"unknown simulation parameter(s) {sorted(names)}; known: {', '.join(FLAT)}")


#: Flat name -> (part, attr, models) of :data:`FLAT`, read per given name by :func:`_resolve`.
_WHERE: dict[str, tuple[str, str, tuple[str, ...]]] = {n: (w.part, w.attr, w.models)
                                                      for n, w in FLAT.items()}


def _resolve(parts: dict[str, Any], flat: dict[str, Any]) -> dict:
    """The five parts from given parts (None: default) and flat-name changes."""
    for name in flat:              # not a set difference with FLAT's ~100 names per call
        if name not in _WHERE:
            raise _unknown([n for n in flat if n not in _WHERE])
    probe = parts["probe"]
    model = flat.pop("model", None)
    if model is not None and model not in MODELS:
        raise ParameterError(f"model must be one of {sorted(MODELS)}, got {model!r}")
    if probe is not None and model is not None and probe.model != model:
        raise ParameterError(f"model={model!r} contradicts the {type(probe).__name__} given as probe")
    model = model or (probe.model if probe is not None else "beam")
    changes: dict[str, dict] = {}
    for name, value in flat.items():
        part, attr, models = _WHERE[name]
        if model not in models:
            raise ParameterError(
                f"{name} is a field of the {models[0]} model's probe; model {model!r} has no "
                f"{name} (give model={models[0]!r} or drop it)")
        c = changes.get(part)
        if c is None:
            changes[part] = c = {}
        c[attr] = value
    out = {}
    for part in PARTS:
        value = probe if part == "probe" else parts[part]
        if value is None:
            value = _DEFAULT[model if part == "probe" else part]
        c = changes.get(part)
        if c is not None:
            value = value.replace(**c)
        out[part] = value
    return out


@dataclass(frozen=True, init=False)
class SimulationConfig:
    """Parameters of one simulated force measurement (SI units), composed of parts.

    Parameters
    ----------
    probe : BeamProbe or SpringProbe, optional
        The probe; its kind is the model (``beam``: the inclined cantilever of
        Fig 2, eqs 22-28; ``spring``: the simple spring of eq 1, no lateral
        motion, no friction). Default: ``BeamProbe()`` (Figs 5-6).
    surface : Surface, optional
        Surface forces (eq 2) and drainage.
    friction : Friction or str, optional
        Tip friction (beam model); a string is the law's name (flat ``friction``).
    drive : Drive, optional
        Approach, dwell and retract.
    solver : SolverOptions, optional
        Sampling, tolerances and event definitions.
    **flat
        Fields by flat name (:data:`FLAT`), applied on top of the parts:
        ``SimulationConfig(model="spring", mass=1e-9, velocity=7.2e-6)``.

    Raises
    ------
    ParameterError
        A bad value, an unknown name, or a name the chosen model has no
        place for (``k0`` with ``model="spring"``).
    """

    probe: BeamProbe | SpringProbe
    surface: Surface
    friction: Friction
    drive: Drive
    solver: SolverOptions

    def __init__(self, probe: BeamProbe | SpringProbe | None = None, surface: Surface | None = None,
                 friction: Friction | str | None = None, drive: Drive | None = None,
                 solver: SolverOptions | None = None, **flat: Any) -> None:
        if isinstance(friction, str):
            flat["friction"], friction = friction, None
        parts = {"probe": probe, "surface": surface, "friction": friction, "drive": drive,
                 "solver": solver}
        self._set(_resolve(parts, flat) if flat else
                  {k: v if v is not None else _DEFAULT["beam" if k == "probe" else k]
                   for k, v in parts.items()})

    def _set(self, parts: dict[str, Any]) -> None:
        for name, kind in PARTS.items():
            value = parts[name]
            if not isinstance(value, kind):
                want = " or ".join(c.__name__ for c in kind) if isinstance(kind, tuple) else kind.__name__
                raise ParameterError(f"{name} must be a {want}, got {type(value).__name__}")
            object.__setattr__(self, name, value)
        drive = parts["drive"]
        n_app = (drive.turn - drive.start) / drive.velocity * parts["solver"].sample_rate
        if n_app < 10:
            raise ParameterError(
                f"sample_rate {parts['solver'].sample_rate:.4g} Hz gives only {n_app:.1f} samples on "
                "the approach; raise it (at least 10 samples per run)")
        check_samples(simulation_samples(drive.start, drive.turn, drive.end, drive.velocity,
                                         drive.retract_velocity, drive.dwell, parts["solver"].sample_rate))

    def __getstate__(self) -> dict[str, Any]:
        # pickled (sweep workers, caches): the parts and the solved start deflection, not
        # the arrays simulate() caches here (rebuilt on first use)
        state = dict(self.__dict__)
        state.pop("_setup", None)
        return state

    # --- flat names -----------------------------------------------------------
    @classmethod
    def from_flat(cls, values: Mapping[str, Any] | None = None, /, **flat: Any) -> SimulationConfig:
        """A configuration from flat names (:data:`FLAT`), as sweeps, fits and scripts give them."""
        return cls(**{**dict(values or {}), **flat})

    @classmethod
    def from_dict(cls, values: Mapping[str, Any]) -> SimulationConfig:
        """Read a stored :meth:`to_dict` (e.g. a trajectory file's ``config`` header).

        Also reads the headers written before issue 11.7, which list every
        field of both probes: the other model's probe fields are dropped (they
        had no effect on the run).
        """
        values = dict(values)
        model = values.get("model", "beam")
        return cls(**{k: v for k, v in values.items()
                      if k not in FLAT or model not in MODELS or model in FLAT[k].models})

    def to_dict(self) -> dict[str, Any]:
        """The flat names of this configuration and their values (SI); :meth:`from_dict` reads it."""
        out = {}
        for name, where in FLAT.items():
            if self.model in where.models:
                out[name] = self.model if where.field is None else getattr(getattr(self, where.part),
                                                                              where.attr)
        return out

    to_flat = to_dict

    def replace(self, **changes: Any) -> SimulationConfig:
        """A copy with some parts (``drive=Drive(...)``) or flat names (``xi=0.01``) changed.

        ``model=`` with another model starts from that model's default probe;
        ``k0=`` (or ``B=``) alone replaces the other stiffness of the beam.
        """
        probe_given = "probe" in changes
        parts = {k: changes.pop(k, getattr(self, k)) for k in PARTS}
        if isinstance(parts["friction"], str):
            changes["friction"], parts["friction"] = parts["friction"], self.friction
        if "model" in changes and changes["model"] == parts["probe"].model:
            del changes["model"]
        elif "model" in changes and not probe_given:
            parts["probe"] = None              # another model: start from its default probe
        new = object.__new__(SimulationConfig)
        new._set(_resolve(parts, changes) if changes else parts)
        return new

    # --- derived --------------------------------------------------------------
    @property
    def model(self) -> str:
        """``beam`` or ``spring``: the kind of :attr:`probe`."""
        return self.probe.model

    @property
    def cantilever(self) -> InclinedCantilever:
        """The :class:`~afmforce.cantilever.InclinedCantilever` of the beam model."""
        if self.model != "beam":
            raise AttributeError("the spring model has no cantilever (probe is a SpringProbe)")
        return self.probe.cantilever

    @property
    def force_constant(self) -> float:
        """Force-measuring spring constant k [N/m] (eq 13 for the beam, k for the spring)."""
        return self.probe.force_constant

    @property
    def calibration_factor(self) -> float:
        """beta = dz2/dtheta of eq 15 [m/rad] (NaN for the spring model: it does not tilt)."""
        return self.probe.calibration_factor

    @property
    def retract_speed(self) -> float:
        """Retract speed [m/s]."""
        return self.drive.retract_speed

    @property
    def start_deflection(self) -> float:
        """Static (friction-free) deflection z2 at the start [m], solved once per configuration.

        Raises
        ------
        ParameterError
            The start is at or past the static jump-in (already in contact).
        """
        d = self.__dict__.get("_start_deflection")
        if d is None:
            from .drive import start_deflection

            d = start_deflection(self)
            self.__dict__["_start_deflection"] = d
        return d

    def validate(self) -> SimulationConfig:
        """Run the checks that need a static solve (the start is out of contact); returns self.

        :func:`~afmforce.dynamics.simulate` and ``simulate_many`` run them before any work.
        """
        _ = self.start_deflection
        return self


def _flat_property(where: FlatName) -> property:
    part, attr = where.part, where.attr

    def get(self):
        try:
            return getattr(getattr(self, part), attr)
        except AttributeError:
            raise AttributeError(f"{where.name} is a field of the {where.models[0]} model's probe; "
                                 f"this configuration's model is {self.model!r}") from None

    return property(get, doc=f"``{part}.{attr}`` (flat name, read-only).")


for _name, _where in FLAT.items():
    if _name not in ("model", "friction"):     # model: a property; friction: the part itself
        setattr(SimulationConfig, _name, _flat_property(_where))
del _name, _where
