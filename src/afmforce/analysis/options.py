"""Typed inputs of the analysis pipeline: the probe record and one options record per step.

:class:`ProbeCalibration` holds what the user knows about the probe and its
calibration (radius, spring constant, inclination, sensitivity, ...); a field
left ``None`` takes the file's value. Each built-in step of
:data:`afmforce.analysis.pipeline.STEPS` has an options dataclass here
(:class:`VdwOptions`, :class:`ZeroOptions`, ...) whose field defaults are the
step's defaults -- declared once, here, and nowhere else (the step functions
take the record, not keyword defaults); a :class:`StepOptions` subclass registers
itself in :data:`OPTIONS` when defined (a step added in its own module defines
its record there). Every field carries a
:class:`~afmforce._fields.FieldSpec` in its metadata (dimension, SI unit, help,
valid range), from which the records validate themselves
(:class:`~afmforce.errors.ParameterError` naming the option and its range), and
:mod:`.options_text` parses ``--option STEP.NAME=VALUE`` (values with units)
and writes the docs table with the defaults in the user's units.

>>> from afmforce.analysis.options import ProbeCalibration, VdwOptions
>>> probe = ProbeCalibration(radius=20e-9, spring_constant=0.21)
>>> VdwOptions(max_separation=20e-9)                                   # doctest: +ELLIPSIS
VdwOptions(z0=3.5e-10, max_separation=2e-08, ...)

This module imports nothing heavy: the command line builds its parser from it.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, ClassVar, Mapping

from .._fields import QUANTITIES, check_beam, meta, qfield, spec_of
from ..constants import HAMAKER, MEDIA, Z0
from ..errors import ParameterError
from ..forces import DOUBLE_LAYER_LAWS, GEOMETRIES

__all__ = ["ProbeCalibration", "StepOptions", "SmoothOptions", "ContactOptions", "DriftOptions",
           "FringesOptions", "ComplianceOptions", "CalibrationOptions", "KindOptions", "ShiftOptions",
           "ZeroOptions", "ForceOptions", "JumpsOptions", "AdhesionOptions", "SurfaceEnergyOptions",
           "VdwOptions", "OscillationOptions", "FrictionOptions", "DiagnosisOptions", "IndentationOptions",
           "LiquidOptions", "OPTIONS", "option_field", "CALIBRATION_SOURCES"]


def _opt(default: Any, dimension: str, unit: str, help: str, *, lo: float | None = None, hi: float | None = None,
         lo_open: bool = False, hi_open: bool = False, display: str = "", choices: tuple = ()) -> Any:
    """An option field: its default, and its :class:`FieldSpec` (plus the words it accepts) as metadata.

    ``choices`` are the words (or values) accepted besides a number in the range;
    a field of dimension ``"choice"`` accepts only those, ``"flag"`` only True/False.
    """
    md = dict(meta(dimension, unit, help, lo=lo, hi=hi, lo_open=lo_open, hi_open=hi_open, display=display))
    md["choices"] = tuple(choices)
    return dataclasses.field(default=default, metadata=md)


#: The public name of :func:`_opt`: an option field of a step's options record (a step added in its
#: own module declares its options with it).
option_field = _opt


def _q(name: str, default: Any, help: str | None = None) -> Any:
    """A field of the shared vocabulary :data:`~afmforce._fields.QUANTITIES` (its range and unit)."""
    if help is None:
        return qfield(name, default)
    s = QUANTITIES[name]
    return _opt(default, s.dimension, s.unit, help, lo=s.lo, hi=s.hi, lo_open=s.lo_open, hi_open=s.hi_open,
                display=s.display)


def _frac(default: float, help: str) -> Any:
    return _opt(default, "dimensionless", "", help, lo=0.0, hi=1.0, lo_open=True)


def _nsigma(default: float, help: str = "significance threshold in multiples of the noise") -> Any:
    return _opt(default, "dimensionless", "", help, lo=0.0, hi=1e3, lo_open=True)


def _check_field(obj: Any, f: dataclasses.Field, where: str) -> None:
    """Validate one field of a record against its metadata (ParameterError in the one message style)."""
    value = getattr(obj, f.name)
    spec = spec_of(f)
    if spec is None or value is None:
        return
    choices = f.metadata.get("choices", ())
    name = f"{where}.{f.name}" if where else f.name
    if spec.dimension == "text":  # a registry key: the record checks it (see KindOptions)
        if not isinstance(value, str):
            raise ParameterError(f"{name} expects a name, got {value!r}")
        return
    if spec.dimension == "flag":
        if not isinstance(value, (bool, int)) or value not in (0, 1):
            raise ParameterError(f"{name} must be true or false, got {value!r}")
        return
    if isinstance(value, str) or spec.dimension == "choice":
        if value in choices:
            return
        words = ", ".join(str(c) for c in choices)
        what = f"a number ({spec.range_text()}) or {words}" if spec.dimension != "choice" else words
        raise ParameterError(f"{name} = {value!r} is not valid: {f.name}, the {spec.help}, must be {what}")
    if spec.dimension == "integer" and not (isinstance(value, int) or float(value).is_integer()):
        raise ParameterError(f"{name} expects a whole number, got {value!r}")
    try:
        float(value)
    except (TypeError, ValueError):
        raise ParameterError(f"{name} expects a number [{spec.unit or '-'}], got {value!r}") from None
    spec.check(value, f.name, name, typed=spec.show(value) if spec.unit else None)


class _Validated:
    """Mix-in: validate every field against its metadata on construction."""

    step: ClassVar[str] = ""

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):  # type: ignore[arg-type]
            _check_field(self, f, self.step or "probe")

    def to_dict(self) -> dict[str, Any]:
        """Field name -> value (SI)."""
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}  # type: ignore[arg-type]

    @classmethod
    def units(cls) -> dict[str, str]:
        """Field name -> SI unit ("" for plain numbers and words)."""
        return {f.name: f.metadata["unit"] for f in dataclasses.fields(cls)}  # type: ignore[arg-type]


@dataclass(frozen=True)
class ProbeCalibration(_Validated):
    """The probe and its calibration, as the user gives them (SI; ``None``: the file's value).

    Attributes
    ----------
    radius : float or None
        Effective tip radius R [m] (surface energy from the pull-off, A from A R).
    spring_constant : float or None
        Spring constant k [N/m]; with ``theta0`` the intrinsic k0, tilt-corrected (eqs 13, 14).
    theta0 : float or None
        Cantilever inclination [rad] for the tilt correction.
    sensitivity : float or None
        Deflection sensitivity (InvOLS) [m/V].
    resonance_frequency : float or None
        Resonance frequency [Hz] (inertia diagnosis, eq 3).
    L0, L1, L2 : float or None
        Beam, rigid base and rigid probe lengths [m] (eq 13 instead of eq 14).
    """

    radius: float | None = qfield("radius", None)
    spring_constant: float | None = qfield("spring_constant", None)
    theta0: float | None = qfield("theta0", None)
    sensitivity: float | None = qfield("sensitivity", None)
    resonance_frequency: float | None = qfield("resonance_frequency", None)
    L0: float | None = qfield("L0", None)
    L1: float | None = qfield("L1", None)
    L2: float | None = qfield("L2", None)

    def __post_init__(self) -> None:
        super().__post_init__()
        check_beam(self.L0, self.L1, self.L2)      # the base and the probe are shorter than the beam

    def value(self, name: str, metadata: Mapping[str, Any]) -> Any:
        """The user's ``name`` if given, else the file's (``metadata[name]``, ``None`` if absent)."""
        v = getattr(self, name)
        return v if v is not None else metadata.get(name)

    def given(self) -> dict[str, float]:
        """The fields the user gave (name -> SI value)."""
        return {k: v for k, v in self.to_dict().items() if v is not None}

    def origin(self, name: str) -> str:
        """Where the value of ``name`` the analysis uses comes from: ``file`` (not given here: the file's own),
        ``user`` (given: ``--sensitivity``, ``probe=ProbeCalibration(...)``), ``meta`` (typed as the file's
        metadata: ``--meta sensitivity=...``, the web's ``meta``; :meth:`given_as_metadata`) or
        ``calibration`` (a probe calibration file's: ``--probe-calibration``, the web's calibration upload;
        :meth:`from_calibration_file`); the warnings' words are :data:`ORIGIN_WORDS`."""
        marks = self.__dict__.get("_origins", {})
        if getattr(self, name) is None:
            return "meta" if marks.get(name) == "meta" else "file"
        return "calibration" if marks.get(name) == "calibration" else "user"

    def _marked(self, marks: Mapping[str, str], **extra: Any) -> "ProbeCalibration":
        out = dataclasses.replace(self)
        for key in ("_origins", "_calibration_method", "_calibration_invols"):
            if key in self.__dict__:
                object.__setattr__(out, key, self.__dict__[key])
        object.__setattr__(out, "_origins", {**self.__dict__.get("_origins", {}), **marks})
        for key, value in extra.items():
            object.__setattr__(out, key, value)
        return out

    def without(self, *names: str) -> "ProbeCalibration":
        """This record with ``names`` not given (the file's then; the other values and their origins kept): a
        given sensitivity that could not rescale the stored force of a curve recording none is not reported
        as the one used (:func:`afmforce.analysis.state.prepare`; tests/io/test_given_calibration.py)."""
        out = self._marked({})
        for name in names:
            object.__setattr__(out, name, None)
        return out

    def from_calibration_file(self, names, method: str | None = None,
                              invols: float | None = None) -> "ProbeCalibration":
        """This record with ``names`` marked as taken from a probe calibration file (:meth:`origin`) made by
        ``method`` (its ``"method"``: ``thermal``, ``sader``, ...) with the InvOLS ``invols`` [m/V] its
        spring constant rests on (a thermal one's: :attr:`calibration_invols`). The CLI's
        ``--probe-calibration`` and the web's calibration upload both mark it here."""
        return self._marked({n: "calibration" for n in names}, _calibration_method=method,
                            _calibration_invols=invols)

    def given_as_metadata(self, names) -> "ProbeCalibration":
        """This record with ``names`` marked as typed by the user as the file's metadata (``--meta
        sensitivity=...``, the web's ``meta``): still the file's in the analysis (a thermal k is rescaled
        as the file's), but named as the user's in the warnings (:meth:`origin`)."""
        return self._marked({n: "meta" for n in names if n in self.__dataclass_fields__})

    @property
    def calibration_method(self) -> str | None:
        """The probe calibration file's method (``thermal``, ``sader``, ...; ``None``: no file)."""
        return self.__dict__.get("_calibration_method")

    @property
    def calibration_invols(self) -> float | None:
        """The InvOLS [m/V] the probe calibration file's spring constant rests on (a thermal k goes as
        1/InvOLS^2, :data:`afmforce.calibration.record.INVOLS_METHODS`); ``None``: none recorded or none
        it rests on (Sader's k)."""
        return self.__dict__.get("_calibration_invols")

    def origins(self) -> dict[str, Any]:
        """The marks of :meth:`origin` other than the plain ``file``/``user`` ones, and the calibration
        file's method and InvOLS: what, beside :meth:`given`, changes an analysis's words or its k
        (part of the analysis's key)."""
        out: dict[str, Any] = dict(sorted(self.__dict__.get("_origins", {}).items()))
        if self.calibration_method is not None or self.calibration_invols is not None:
            out["calibration_method"], out["calibration_invols"] = self.calibration_method, self.calibration_invols
        return out


#: How a warning names a calibration value by its origin (:meth:`ProbeCalibration.origin`): origin -> (the value,
#: as in "2 x the file's", its owner, as in "the file's is used"); ``{name}`` is the value's option name.
ORIGIN_WORDS: dict[str, tuple[str, str]] = {
    "file": ("the file's", "the file's"),
    "user": ("the one you gave (`{name}`)", "yours"),
    "meta": ("the one you gave as metadata (meta {name})", "yours"),
    "calibration": ("the probe calibration file's", "the calibration file's"),
}


def origin_words(probe: "ProbeCalibration", name: str) -> tuple[str, str]:
    """:data:`ORIGIN_WORDS` of ``name``'s origin on ``probe``, the option named."""
    value, owner = ORIGIN_WORDS[probe.origin(name)]
    return value.format(name=name), owner.format(name=name)


#: Step identifier -> its options class: every subclass of :class:`StepOptions` that names its
#: ``step`` registers itself here when it is defined (the step's record points to it).
OPTIONS: dict[str, type["StepOptions"]] = {}


@dataclass(frozen=True)
class StepOptions(_Validated):
    """Base of the per-step options records: a subclass sets ``step`` (its step's identifier) and
    is registered in :data:`OPTIONS` when defined."""

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        step = cls.__dict__.get("step")
        if not step:
            return
        old = OPTIONS.get(step)
        if old is not None and (old.__module__, old.__qualname__) != (cls.__module__, cls.__qualname__):
            raise TypeError(f"options of step {step!r} are declared twice: {old.__qualname__} and {cls.__qualname__}")
        OPTIONS[step] = cls


@dataclass(frozen=True)
class SmoothOptions(StepOptions):
    """Running average of the position (Fig 7C)."""

    step: ClassVar[str] = "smooth"
    window: int | str = _opt("auto", "integer", "", "running-average window in samples (odd; 'auto': 11, or two "
                             "digitization steps of a stepped channel)", lo=1, hi=1e6, choices=("auto",))

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.window != "auto" and int(self.window) % 2 == 0:
            raise ParameterError(f"smooth.window must be an odd number of samples, got {self.window}")


@dataclass(frozen=True)
class ContactOptions(StepOptions):
    """Contact, constant-compliance and zero-force regions."""

    step: ClassVar[str] = "contact"
    min_points: int = _opt(5, "integer", "", "fewest samples of a region", lo=1, hi=1e6)
    baseline_fraction: float = _frac(0.7, "fraction of the free part taken as zero-force baseline")
    compliance_fraction: float = _frac(0.5, "fraction of the contact part taken as compliance line")
    flat_ratio: float = _opt(0.05, "dimensionless", "", "free/contact slope ratio below which a contact "
                             "region is a constant-compliance line", lo=0.0, hi=1.0, lo_open=True)
    max_slope_ratio: float | str = _opt("auto", "dimensionless", "", "largest slope ratio of the two runs' "
                                        "contact lines ('auto': 2 on the measured channel, none on the "
                                        "nominal one)", lo=1.0, lo_open=True, choices=("auto",))


@dataclass(frozen=True)
class DriftOptions(StepOptions):
    """Thermal drift: a line in time through each run's zero-force region."""

    step: ClassVar[str] = "drift"
    order: int = _opt(1, "integer", "", "drift polynomial order in time (0: offset, 1: line)", lo=0, hi=1)
    tail: bool = _opt(True, "flag", "", "detect a retract tail still relaxing after the pull-off")


@dataclass(frozen=True)
class FringesOptions(StepOptions):
    """Interferometric calibration from baseline fringes."""

    step: ClassVar[str] = "fringes"
    apply: str = _opt("auto", "choice", "", "when to subtract the fringes and remap positions",
                      choices=("auto", "always", "never"))
    period: float | None = _opt(None, "length", "m", "fringe period (None: searched)", lo=0.0, hi=1e-4,
                                lo_open=True)
    order: int | str = _opt("auto", "integer", "", "polynomial order of the position map", lo=1, hi=3,
                            choices=("auto",))
    in_contact: str = _opt("hold", "choice", "", "fringe term in contact: held at the contact value or "
                           "following the position", choices=("hold", "follow"))
    margin: float = _opt(0.1, "dimensionless", "", "fraction of the baseline next to contact left out of the "
                         "fit", lo=0.0, hi=1.0, hi_open=True)


@dataclass(frozen=True)
class ComplianceOptions(StepOptions):
    """Constant-compliance lines (robust fit): no options."""

    step: ClassVar[str] = "compliance"


#: The words of ``calibration.source`` (the CLI's ``--calibration`` of analyze and fit repeat them without
#: importing this module, which loads numba: tests/cli/test_faces_agree.py holds them equal).
CALIBRATION_SOURCES = ("auto", "fit", "metadata")


@dataclass(frozen=True)
class CalibrationOptions(StepOptions):
    """Deflection sensitivity: the file's or user's, or from the compliance slope.

    ``source`` (declared here once; ``afmforce analyze --calibration``, the web's option and the fit's
    preprocessing, ``afmforce fit --calibration``, take these words): ``auto`` uses the file's or user's
    sensitivity wherever there is one, the compliance slope only without one or where the file's is
    impossible on a hard contact (:func:`afmforce.analysis.steps.kind.kind`); ``fit`` always uses the
    slope (and rescales a file's thermal spring constant, step ``force``); ``metadata`` always the
    file's or user's (an error without one). See docs/analysis.md, "Which calibration".
    """

    step: ClassVar[str] = "calibration"
    source: str = _opt("auto", "choice", "", "calibration source (auto: the file's or user's if any, the "
                       "compliance slope without; fit: the slope)", choices=CALIBRATION_SOURCES)
    run: str = _opt("approach", "choice", "", "compliance line giving the slope",
                    choices=("approach", "retract", "both"))


@dataclass(frozen=True)
class KindOptions(StepOptions):
    """Contact kind (hard or soft) and a soft contact's contact point."""

    step: ClassVar[str] = "kind"
    nsigma: float = _nsigma(5.0, "jump-in significance in multiples of the step noise")
    min_stiffness: float = _opt(0.7, "dimensionless", "", "least deflection per position of a hard contact",
                                lo=0.0, hi=10.0, lo_open=True)
    max_curvature: float = _opt(1.6, "dimensionless", "", "largest late/early slope ratio of a straight "
                                "contact line", lo=1.0, hi=100.0)
    method: str = _opt("power_local", "text", "", "soft contact point method (a key of "
                       "analysis.contact_point.CONTACT_POINT_METHODS)")
    force_fraction: float = _frac(0.65, "fraction of the largest (block-averaged) deflection fitted for the contact point")
    window: float = _frac(0.15, "window of the local fit, as a fraction of the approach")

    def check_method(self, methods) -> None:
        """Raise ParameterError unless :attr:`method` is a key of ``methods`` (the contact point registry)."""
        if self.method not in methods:
            raise ParameterError(f"kind.method = {self.method!r} is not valid: method, the soft contact point "
                                 f"method, must be one of {', '.join(methods)}")


@dataclass(frozen=True)
class ShiftOptions(StepOptions):
    """Inward/outward shift overlaying the compliance lines."""

    step: ClassVar[str] = "shift"
    apply: bool = _opt(True, "flag", "", "shift the inward run onto the outward line")


@dataclass(frozen=True)
class ZeroOptions(StepOptions):
    """Zero of separation at the compliance line."""

    step: ClassVar[str] = "zero"
    contact_separation: float = _q("compliance_separation", Z0)
    run: str = _opt("auto", "choice", "", "compliance line that defines the zero",
                    choices=("auto", "approach", "retract"))
    parallel_tolerance: float = _opt(0.25, "dimensionless", "", "largest relative slope difference of the two "
                                     "lines before the inward one is used", lo=0.0, hi=10.0, lo_open=True)


@dataclass(frozen=True)
class ForceOptions(StepOptions):
    """Deflection to force (k, theta0 and the lengths are the probe's)."""

    step: ClassVar[str] = "force"
    thermal_k: bool = _opt(True, "flag", "", "the file's spring constant is a thermal one: with a refitted "
                           "sensitivity it scales by (file's / fitted sensitivity)^2")


@dataclass(frozen=True)
class JumpsOptions(StepOptions):
    """Jump into contact and pull-off."""

    step: ClassVar[str] = "jumps"
    nsigma: float = _nsigma(5.0, "jump significance in multiples of the step noise")
    window: int = _opt(3, "integer", "", "samples around the contact split searched for the jump", lo=1, hi=1e4)
    onset_tolerance: float = _opt(3e-9, "length", "m", "distance of the first contact sample from the "
                                  "compliance line before a warning", lo=0.0, hi=1e-6)


@dataclass(frozen=True)
class AdhesionOptions(StepOptions):
    """Adhesion: the retract's deepest dip below its own baseline."""

    step: ClassVar[str] = "adhesion"
    nsigma: float = _nsigma(5.0, "dip significance in multiples of the baseline noise")
    wlc_model: str = _opt("marko-siggia", "choice", "", "worm-like chain fitted to each tether's rise: "
                          "Marko-Siggia's interpolation, or with Bouchiat's 7-term correction",
                          choices=("marko-siggia", "bouchiat"))


@dataclass(frozen=True)
class SurfaceEnergyOptions(StepOptions):
    """Surface energy and radius from the pull-off (JKR/DMT)."""

    step: ClassVar[str] = "surface_energy"
    model: str = _opt("jkr", "choice", "", "contact mechanics model", choices=("jkr", "dmt"))
    hamaker: float = _q("hamaker", HAMAKER)
    z0: float = _q("z0", Z0)


@dataclass(frozen=True)
class VdwOptions(StepOptions):
    """van der Waals fit before the jump (eq 2)."""

    step: ClassVar[str] = "vdw"
    z0: float = _q("z0", Z0)
    max_separation: float = _opt(30e-9, "length", "m", "largest separation fitted", lo=0.0, hi=1e-6,
                                 lo_open=True)
    baseline: str = _opt("line", "choice", "", "baseline fitted with the force law",
                         choices=("none", "offset", "line"))
    fit_separation_offset: bool = _opt(False, "flag", "", "fit a shift of the zero of separation too")


@dataclass(frozen=True)
class OscillationOptions(StepOptions):
    """Post-contact oscillation."""

    step: ClassVar[str] = "oscillation"
    false_alarm: float = _opt(1e-3, "dimensionless", "", "false-alarm probability of a periodogram peak",
                              lo=0.0, hi=1.0, lo_open=True, hi_open=True)
    min_cycles: float = _opt(3.0, "dimensionless", "", "fewest oscillation cycles in the compliance region",
                             lo=0.0, hi=1e6, lo_open=True)


@dataclass(frozen=True)
class FrictionOptions(StepOptions):
    """Friction signature of the compliance lines."""

    step: ClassVar[str] = "friction"
    nsigma: float = _nsigma(3.0, "significance of a slope or offset difference in standard errors")
    slope_tolerance: float = _opt(0.02, "dimensionless", "", "relative slope difference below which the lines "
                                  "are parallel", lo=0.0, hi=1.0, lo_open=True)
    offset_tolerance: float = _opt(0.2e-9, "length", "m", "offset below which the lines coincide", lo=0.0,
                                   hi=1e-6)
    max_curvature: float = _opt(1.25, "dimensionless", "", "largest late/early slope ratio of a straight line",
                                lo=1.0, hi=100.0)


@dataclass(frozen=True)
class DiagnosisOptions(StepOptions):
    """Dynamic diagnosis (eqs 3, 4)."""

    step: ClassVar[str] = "diagnosis"
    resolution: float | None = _q("resolution", None, "deflection resolution (None: the measured noise, at "
                                  "least min_resolution)")
    min_resolution: float = _opt(0.01e-9, "length", "m", "smallest deflection resolution", lo=0.0, hi=1e-6,
                                 lo_open=True)
    attraction_ratio: float = _frac(0.75, "share of the jump-in a static attraction must explain")


#: The sample's Poisson ratio where neither the user nor the file gives one (incompressible).
DEFAULT_POISSON = 0.5


@dataclass(frozen=True)
class IndentationOptions(StepOptions):
    """Young's modulus (and work of adhesion) from the indentation of a soft contact (docs/contact.md)."""

    step: ClassVar[str] = "indentation"
    model: str = _opt("hertz_paraboloid", "text", "", "indentation model (a key of "
                      "afmforce.contact.INDENTATION_MODELS)")
    tip_radius: float | None = _q("tip_radius", None)
    half_angle: float | None = _q("half_angle", None)
    # None: the file's own (metadata `poisson`, e.g. NanoScope's Sample Poisson's Ratio), else 0.5
    # (:meth:`sample_poisson`); the field keeps the shared quantity's declaration (range, help, messages)
    poisson: float | None = _q("poisson", None)
    thickness: float | None = _opt(None, "length", "m", "sample (layer) thickness: the thin-layer model's h, "
                                   "the validity check of the others (None: a half space)", lo=0.0, hi=1e-2,
                                   lo_open=True)
    bonded: bool = _opt(True, "flag", "", "thin-layer model: the layer is bonded to the substrate")
    max_indentation: float | None = _opt(None, "length", "m", "fit only the samples up to this indentation "
                                         "past the whole run's contact point (None: the whole run)", lo=0.0, hi=1e-3, lo_open=True)
    contact_point: float | None = _opt(None, "length", "m", "the contact point, fixed, as the tip depth u = z "
                                       "- deflection (None: fitted with E; laws without adhesion)",
                                       lo=-1e-3, hi=1e-3)
    weight_width: float = _opt(0.0, "length", "m", "residuals within this distance of the contact point "
                               "weighted down linearly (nanite's weight_cp; 0: none)", lo=0.0, hi=1e-3)
    run: str = _opt("approach", "choice", "", "run fitted", choices=("approach", "retract"))
    transition: float = _opt(1.0, "dimensionless", "", "Maugis-Dugdale transition parameter lambda",
                             lo=0.0, hi=1e3, lo_open=True)

    def __post_init__(self) -> None:
        super().__post_init__()
        from ..contact.registry import INDENTATION_MODELS

        if self.model not in INDENTATION_MODELS:
            raise ParameterError(f"indentation.model = {self.model!r} is not valid: choose one of "
                                 f"{', '.join(INDENTATION_MODELS)}")

    def sample_poisson(self, metadata: Mapping[str, Any]) -> tuple[float, str]:
        """The Poisson ratio to use and where it comes from: the user's (``"user"``), else the file's
        (metadata ``poisson``: ``"file"``), else :data:`DEFAULT_POISSON` (``"default"``)."""
        if self.poisson is not None:
            return float(self.poisson), "user"
        nu = metadata.get("poisson")
        if nu is not None:
            return float(nu), "file"
        return DEFAULT_POISSON, "default"


@dataclass(frozen=True)
class LiquidOptions(StepOptions):
    """Colloid-probe curves in a liquid (docs/liquid.md): quadratic compliance, drag, drainage, DLVO fit."""

    step: ClassVar[str] = "liquid"
    medium: str = _opt("none", "choice", "", "medium the curve was measured in (none or air: the step is "
                       "skipped); sets the viscosity and permittivity",
                       choices=("none", *MEDIA))
    permittivity: float | None = _q("permittivity", None, "relative permittivity (None: the medium's)")
    viscosity: float | None = _q("viscosity", None, "viscosity (None: the medium's)")
    geometry: str = _opt("sphere-flat", "choice", "", "probe geometry (a colloid probe on a flat)",
                         choices=tuple(sorted(GEOMETRIES)))
    double_layer: str = _opt("constant_potential", "choice", "", "double-layer law fitted",
                             choices=DOUBLE_LAYER_LAWS)
    potential_sign: str = _opt("negative", "choice", "", "sign of the (symmetric) surface potential: the "
                               "force gives only its magnitude", choices=("negative", "positive"))
    far_fraction: float = _frac(0.3, "part of the approach travel (farthest out) taken as the far baseline")
    contact_separation: float = _opt(0.0, "length", "m", "separation given to the compliance line", lo=0.0,
                                     hi=1e-8)
    min_separation: float = _opt(2e-9, "length", "m", "smallest separation of the DLVO fit", lo=0.0, hi=1e-6)
    max_separation: float | None = _opt(None, "length", "m", "largest separation of the DLVO fit (None: ten "
                                        "Debye lengths of the first estimate, within the far region)", lo=0.0,
                                        hi=1e-5, lo_open=True)
    z0: float = _q("z0", Z0, "van der Waals cut-off z0 of the DLVO fit")
    nsigma: float = _nsigma(3.0, "double-layer repulsion threshold in multiples of the static force noise")
