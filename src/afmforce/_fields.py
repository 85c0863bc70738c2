"""Field metadata: each quantity's dimension, SI unit, help and valid range, declared once.

Configuration dataclasses carry a :class:`FieldSpec` in their field metadata
(``dataclasses.field(metadata=meta(...))``, or :func:`qfield` for a quantity
of the shared vocabulary :data:`QUANTITIES`). Everything else is derived from
it: command-line flags and their help (defaults shown in the user's units,
``10 ug``, ``0.1 um/s``, ``-15 deg``), validation with one message style
(:meth:`FieldSpec.check`), the docs' table of valid ranges
(:func:`ranges_markdown`).

Ranges are physically wide -- what a surface-force experimentalist would
still call an AFM experiment -- and refuse only values outside what the model
means (a 1 m cantilever base, a 1 J Hamaker constant, a 1 m/s approach).

This module imports nothing heavy (no numpy, no pint): the command line
builds its parsers from it in a few milliseconds.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, Mapping

from .constants import DEFAULT_TEMPERATURE, PAPER_ROOM_TEMPERATURE
from .errors import ParameterError

__all__ = ["FieldSpec", "ChoiceSpec", "ANALYSIS_CHOICES", "ANALYZE_CLI_ONLY", "meta", "qfield", "spec_of", "QUANTITIES", "check", "check_beam", "show",
           "ranges_markdown", "DISPLAY_UNITS"]

#: Display unit -> its size in SI (the only conversions the help and messages need).
DISPLAY_UNITS = {
    "nm": 1e-9, "um": 1e-6, "mm": 1e-3, "m": 1.0,
    "ng": 1e-12, "ug": 1e-9, "mg": 1e-6, "kg": 1.0,
    "um/s": 1e-6, "m/s": 1.0, "deg": math.pi / 180, "rad": 1.0,
    "pN": 1e-12, "nN": 1e-9, "uN": 1e-6, "N": 1.0,
    "Hz": 1.0, "kHz": 1e3, "MHz": 1e6, "nm/V": 1e-9, "m/V": 1.0,
    "ms": 1e-3, "s": 1.0, "mV": 1e-3, "V": 1.0, "mM": 1.0,
}
#: SI prefixes, largest first.
_PREFIXES = (("G", 1e9), ("M", 1e6), ("k", 1e3), ("", 1.0), ("m", 1e-3), ("u", 1e-6), ("n", 1e-9),
             ("p", 1e-12), ("f", 1e-15))
#: SI unit -> (symbol that takes the prefix, its size in SI, largest and smallest prefix used).
_AUTO = {"m": ("m", 1.0, 1.0, 1e-9), "N": ("N", 1.0, 1.0, 1e-12), "m/s": ("m/s", 1.0, 1.0, 1e-9),
         "m/V": ("m/V", 1.0, 1.0, 1e-9), "s": ("s", 1.0, 1.0, 1e-9), "Hz": ("Hz", 1.0, 1e9, 1.0),
         "kg": ("g", 1e-3, 1.0, 1e-15)}


def _num(x: float) -> str:
    return f"{x:.4g}"


def _auto(v: float, unit: str) -> str:
    sym, size, top, bottom = _AUTO[unit]
    x = v / size
    for prefix, f in _PREFIXES:
        if f <= top and (abs(x) >= f * 0.9999 or f <= bottom):
            return f"{_num(x / f)} {prefix}{sym}"
    return f"{_num(x)} {sym}"  # pragma: no cover


def show(value: float | None, unit: str, display: str = "") -> str:
    """``value`` [SI ``unit``] as the user would write it: ``show(1e-8, 'kg', 'ug') -> '10 ug'``.

    Without a ``display`` unit, lengths, forces, speeds, masses, times and
    frequencies take the nearest SI prefix (``show(2e-7, 'm') -> '200 nm'``).
    """
    if value is None:
        return "none"
    if isinstance(value, str):
        return value
    if isinstance(value, int) and not isinstance(value, bool) and not unit:
        return str(value)
    v = float(value)
    if display and display in DISPLAY_UNITS and math.isfinite(v / DISPLAY_UNITS[display]) == math.isfinite(v):
        return f"{_num(v / DISPLAY_UNITS[display])} {display}"     # (1e308 m/s is no "inf um/s": SI below)
    if unit in _AUTO and v != 0 and math.isfinite(v):
        return _auto(v, unit)
    return f"{_num(v)} {unit}".rstrip()


@dataclass(frozen=True)
class FieldSpec:
    """What one field is: dimension, SI unit, help and valid range.

    Attributes
    ----------
    dimension : str
        Dimension for :func:`afmforce.units.parse_quantity` (``length`` ...),
        ``integer``, ``text`` or another word the owner understands.
    unit : str
        SI unit ("" for plain numbers).
    help : str
        One line: what the value is.
    lo, hi : float or None
        Valid range [SI]; ``None``: unbounded on that side.
    lo_open, hi_open : bool
        Whether the bound itself is excluded (``(0, 1 mm]``: ``lo_open``).
    display : str
        Unit in which defaults, ranges and messages are shown (e.g. ``um/s``);
        "" shows SI, lengths and forces with an automatic prefix.
    plausible : tuple of float or None
        Narrower band [SI] inside the valid range where real instruments' values lie: a value
        outside it is accepted (a valid number) but warned about as a likely slip of units.
        ``None``: no such band.
    """

    dimension: str
    unit: str
    help: str
    lo: float | None = None
    hi: float | None = None
    lo_open: bool = False
    hi_open: bool = False
    display: str = ""
    plausible: tuple[float, float] | None = None

    def show(self, value) -> str:
        """``value`` [SI] in this field's display unit."""
        return show(value, self.unit, self.display)

    @property
    def bounded(self) -> bool:
        """True when the field has a lower or an upper bound."""
        return self.lo is not None or self.hi is not None

    def _bound(self, value: float) -> str:
        if value == 0:
            return "0"
        return show(value, self.unit, "" if self.unit in _AUTO else self.display)

    def range_text(self) -> str:
        """The valid range, e.g. ``(0, 1 mm]`` or ``>= 0 kg/s``."""
        if self.lo is not None and self.hi is not None:
            return (("(" if self.lo_open else "[") + f"{self._bound(self.lo)}, {self._bound(self.hi)}"
                    + (")" if self.hi_open else "]"))
        if self.lo is not None:
            return (">" if self.lo_open else ">=") + f" {self._bound(self.lo)}"
        if self.hi is not None:
            return ("<" if self.hi_open else "<=") + f" {self._bound(self.hi)}"
        return "any finite value"

    def contains(self, value: float) -> bool:
        """Whether ``value`` [SI] lies in the valid range (and is finite)."""
        v = float(value)
        if not math.isfinite(v):
            return False
        if self.lo is not None and (v < self.lo or (self.lo_open and v == self.lo)):
            return False
        if self.hi is not None and (v > self.hi or (self.hi_open and v == self.hi)):
            return False
        return True

    def check(self, value, name: str, where: str | None = None, typed: str | None = None):
        """Return ``value`` or raise :class:`ParameterError` in the one message style.

        ``where`` is what the user typed the value as (``--radius``, ``--set radius``),
        default ``name``; ``typed`` the text they typed (default: the value in
        the display unit). The message::

            --radius -5nm is out of range: radius, the effective radius R, must lie in (0, 1 mm]
        """
        if value is None or not self.bounded:
            return value
        if isinstance(value, bool) or not _real(value):
            hint = " (a text with units: read it with afmforce.units.parse_value)" if isinstance(value, str) else ""
            raise ParameterError(f"{where or name} expects a number [{self.unit}], got {value!r}{hint}")
        if self.contains(value):
            return value
        shown = typed if typed is not None else self.show(value)
        head = f"{where} {shown}" if where else f"{name} = {shown}"
        raise ParameterError(f"{head} is out of range: {name}, the {self.help}, must lie in {self.range_text()}")


def _real(value) -> bool:
    """Whether ``value`` is one real number (``float()`` takes it): not a list, a complex, a text."""
    try:
        float(value)
    except (TypeError, ValueError):
        return False
    return True


def meta(dimension: str, unit: str, help: str, *, lo: float | None = None, hi: float | None = None,
         lo_open: bool = False, hi_open: bool = False, display: str = "") -> dict[str, Any]:
    """Field metadata: ``{"dimension", "unit", "help", "spec"}`` (``spec``: a :class:`FieldSpec`)."""
    spec = FieldSpec(dimension, unit, help, lo, hi, lo_open, hi_open, display)
    return _meta_of(spec)


def _meta_of(spec: FieldSpec) -> dict[str, Any]:
    return {"dimension": spec.dimension, "unit": spec.unit, "help": spec.help, "spec": spec}


def spec_of(f: dataclasses.Field) -> FieldSpec | None:
    """The :class:`FieldSpec` a dataclass field declares, or ``None``."""
    return f.metadata.get("spec")


def _q(dimension, unit, help, lo=None, hi=None, *, lo_open=False, hi_open=False, display="",
       plausible=None):
    return FieldSpec(dimension, unit, help, lo, hi, lo_open, hi_open, display, plausible)


_POS = {"lo": 0.0, "lo_open": True}

#: The shared vocabulary: one meaning, unit and valid range per name, used by
#: the configuration dataclasses (:func:`qfield`), the command line and sweeps.
QUANTITIES: dict[str, FieldSpec] = {
    # probe: cantilever (Fig 2) and simple spring (eq 1)
    "k0": _q("stiffness", "N/m", "intrinsic spring constant k0", 1e-4, 1e3),
    "B": _q("rigidity", "N m^2", "flexural rigidity B = k0 L0^3/3", 1e-24, 1e-5),
    "L0": _q("length", "m", "length of the flexible beam", 1e-6, 2e-3),
    # the base carries the joint's rotation: the library needs it positive (cantilever.py), and one
    # much shorter than a nanometre gives a rotational mode no step budget resolves (1e-30 m: an
    # integer overflow in the integrator's budget; the web answered 500)
    "L1": _q("length", "m", "length of the rigid base", 1e-9, 1e-3),
    "L2": _q("length", "m", "length of the rigid probe", 0.0, 1e-3),
    "theta0": _q("angle", "rad", "inclination of the beam", -math.radians(89), math.radians(89),
                 display="deg"),
    "m_joint": _q("mass", "kg", "point mass at the beam-base joint", hi=1e-5, display="ng", **_POS),
    "m_base": _q("mass", "kg", "mass spread along the base", hi=1e-5, display="ng", **_POS),
    # valid: any lever a model may hold; plausible: the cantilevers made (1 mN/m .. 100 N/m), outside
    # which a file's or a user's k is warned about (a unit slip: 200 for 0.2 N/m) by the analysis and the fit
    "spring_constant": _q("stiffness", "N/m", "spring constant k", 1e-4, 1e3, plausible=(1e-3, 100.0)),
    "mass": _q("mass", "kg", "effective mass m", hi=1e-5, display="ug", **_POS),
    "resonance_frequency": _q("frequency", "Hz", "resonance frequency", 1.0, 1e8, display="kHz"),
    "quality_factor": _q("dimensionless", "", "quality factor Q of the lever in its medium (none: undamped)",
                         0.1, 1e6),
    "quality_factor_2": _q("dimensionless", "", "quality factor of the beam's second free mode "
                           "(none: quality_factor)", 0.1, 1e6),
    "sensitivity": _q("sensitivity", "m/V", "deflection sensitivity (InvOLS)", 1e-10, 1e-5,
                      display="nm/V"),
    # surfaces (eq 2, drainage)
    "radius": _q("length", "m", "effective radius R", hi=1e-3, **_POS),
    # contact mechanics (docs/contact.md)
    "tip_radius": _q("length", "m", "tip radius of the indentation model (none: the probe's radius)", hi=1e-3,
                     **_POS),
    "half_angle": _q("angle", "rad", "half-angle of a cone, face angle of a pyramid", hi=math.radians(89),
                     display="deg", **_POS),
    "poisson": _q("dimensionless", "", "Poisson ratio of the sample", -1.0, 0.5, lo_open=True),
    "hamaker": _q("energy", "J", "Hamaker constant A", 1e-22, 1e-17),
    # a soft wall much thinner than an atom is no wall: from 1 pm (z0 = 1e-30 m overflowed the jump-in cubic)
    "z0": _q("length", "m", "soft-wall length z0", 1e-12, 1e-8),
    "viscosity": _q("viscosity", "Pa s", "fluid viscosity (0: no drainage)", 0.0, 100.0),
    # liquids (issue 25; docs/liquid.md)
    "slip_length": _q("length", "m", "slip length b (Vinogradova drainage)", 0.0, 1e-6),
    "lever_drag": _q("damping", "kg/s", "viscous drag coefficient of the lever body (N s/m)", 0.0, 1.0),
    "lever_height": _q("length", "m", "lever height above the substrate at contact (0: constant drag)",
                       0.0, 1e-3),
    "surface_potential": _q("voltage", "V", "surface potential psi1", -1.0, 1.0, display="mV"),
    "surface_potential_2": _q("voltage", "V", "surface potential psi2 of the substrate (default psi1)",
                              -1.0, 1.0, display="mV"),
    "debye_length": _q("length", "m", "Debye length 1/kappa", 1e-10, 1e-5),
    "salt_concentration": _q("concentration", "mol/m^3",
                             "concentration of a symmetric z:z salt (sets the Debye length)",
                             hi=1e4, display="mM", **_POS),
    "valence": _q("dimensionless", "", "valence z of the symmetric salt", 1.0, 4.0),
    "permittivity": _q("dimensionless", "", "relative permittivity of the medium", 1.0, 200.0),
    # surface force laws (issue 31; afmforce.surface_laws, docs/dynamics.md "Surface force laws")
    "hydration_pressure": _q("pressure", "Pa", "hydration pressure P0 between planes in contact "
                             "(0: no hydration force)", 0.0, 1e10),
    "hydration_length": _q("length", "m", "decay length lambda of the hydration force", 1e-11, 1e-8),
    "brush_length": _q("length", "m", "polymer brush thickness L0 (0: no brush)", 0.0, 1e-6),
    "brush_spacing": _q("length", "m", "mean distance s between the brush's grafting points",
                        1e-10, 1e-6),
    # temperature: declared once below (probe calibration), shared by the laws that need kT
    "relative_humidity": _q("dimensionless", "", "relative humidity RH of the air (0: no meniscus)",
                            0.0, 1.0, hi_open=True),
    "surface_tension": _q("surface_energy", "J/m^2", "surface tension gamma of the meniscus liquid "
                          "(J/m^2 = N/m)", 1e-3, 1.0),
    "contact_angle": _q("angle", "rad", "contact angle theta1 of the liquid on the probe", 0.0,
                        math.pi, display="deg"),
    "contact_angle_2": _q("angle", "rad", "contact angle theta2 of the liquid on the substrate", 0.0,
                          math.pi, display="deg"),
    # friction (section 2.2, eq 28)
    "xi": _q("damping", "kg/s", "viscous friction coefficient xi", 0.0, 100.0),
    "zeta": _q("friction_per_force2", "kg/(s N^2)", "load-dependent friction coefficient zeta", 0.0, 1e20),
    "mu": _q("force", "N", "constant friction force mu", hi=1e-5, **_POS),
    "lam": _q("dimensionless", "", "friction/load ratio lambda", hi=10.0, **_POS),
    # drive
    "velocity": _q("velocity", "m/s", "driving speed", 1e-10, 1e-2, display="um/s"),
    "retract_velocity": _q("velocity", "m/s", "retract speed", 1e-10, 1e-2, display="um/s"),
    "start": _q("length", "m", "drive start position", -1e-4, 1e-4),
    "turn": _q("length", "m", "drive turn position", -1e-4, 1e-4),
    "end": _q("length", "m", "drive end position", -1e-4, 1e-4),
    "turn_force": _q("force", "N", "load at which the approach turns", hi=1e-5, **_POS),
    "turn_deflection": _q("length", "m", "deflection at which the approach turns", hi=1e-5, **_POS),
    "dwell": _q("time", "s", "pause at the turn", 0.0, 1e4),
    # sampling and solver
    "sample_rate": _q("frequency", "Hz", "sample rate", 1.0, 1e8, display="kHz"),
    "rtol": _q("dimensionless", "", "relative tolerance", 1e-12, 0.1),
    "atol": _q("length", "m", "absolute tolerance on positions", 1e-15, 1e-9),
    "contact_separation": _q("length", "m", "separation counted as contact", hi=1e-8, **_POS),
    "jump_factor": _q("dimensionless", "", "jump-in criterion dh/dt < -factor dz/dt", hi=1e3, **_POS),
    "spike_window": _q("time", "s", "jump-in transient window (0: no spike)", 0.0, 10.0),
    "jump_window": _q("time", "s", "time after the jump-in left out of the dynamic fit", 0.0, 1.0, display="ms"),
    "fringe_period": _q("length", "m", "period of the interference fringes in the separation (half the laser "
                        "wavelength)", 100e-9, 10e-6, display="nm"),
    # measurement design (afmforce plan)
    "deflection_noise": _q("length", "m", "deflection noise rms of a curve", hi=100e-9, display="nm", **_POS),
    "force_error": _q("force", "N", "allowed error of the static pull-in force", hi=1e-6, **_POS),
    "slip_target": _q("length", "m", "95 % half-width wanted of the slip length", hi=1e-6, display="nm", **_POS),
    "max_steps": _q("integer", "", "solver step budget", 1, 1e9),
    # probe calibration (issue 34; docs/calibration.md): thermal noise, Sader, InvOLS
    # one default room temperature for every kT (afmforce.constants.DEFAULT_TEMPERATURE: why 295 K)
    "temperature": _q("temperature", "K", "temperature of the lever and its medium", 1.0, 1000.0),
    # the factors of the literature lie in 0.76-1.1 (Butt & Jaschke 1995: 0.817, 0.971; Hutter 2005:
    # 0.764-1.09); (0, 2] let chi = 1e-30 print k = 5e-29 mN/m as a calibration
    "equipartition_correction": _q("dimensionless", "", "chi of k = chi kB T / <z^2> (0.817: optical "
                                   "lever, static InvOLS; 1: true displacement, one mode)", 0.5, 1.5),
    "lever_tilt": _q("angle", "rad", "tilt of the lever to the sample (k normal = k / cos^2)",
                     -math.radians(45), math.radians(45), display="deg"),
    "frequency_min": _q("frequency", "Hz", "lowest frequency fitted", 0.0, 1e8, display="kHz"),
    "frequency_max": _q("frequency", "Hz", "highest frequency fitted", 0.0, 1e8, lo_open=True,
                        display="kHz"),
    "lever_length": _q("length", "m", "length L of the rectangular lever", hi=1e-3, **_POS),
    "lever_width": _q("length", "m", "width b of the rectangular lever", hi=1e-3, **_POS),
    "density": _q("density", "kg/m^3", "density of the medium", hi=2e4, **_POS),
    "reference_spring_constant": _q("stiffness", "N/m", "spring constant of the reference lever (general "
                                    "Sader method)", 1e-4, 1e3),
    "reference_frequency": _q("frequency", "Hz", "resonance frequency of the reference lever", 1.0, 1e8,
                              display="kHz"),
    "reference_quality_factor": _q("dimensionless", "", "quality factor of the reference lever", 0.1, 1e6),
    "sader_exponent": _q("dimensionless", "", "exponent a of Gamma_i ~ Re^-a (general Sader method)",
                         0.0, 1.0, lo_open=True),
    # analysis and diagnosis
    "resolution": _q("length", "m", "deflection resolution", hi=1e-6, **_POS),
    "separation": _q("length", "m", "separation where the force gradient is taken", hi=1e-6, **_POS),
    "gap_deflection": _q("length", "m", "deflection where the load-friction gap is taken", hi=1e-6, **_POS),
    "compliance_separation": _q("length", "m", "separation given to the compliance line (paper: z0; 0 also "
                                "common)", 0.0, 1e-8),
}


@dataclass(frozen=True)
class ChoiceSpec:
    """A setting that is a word of a fixed list, not a quantity: its choices, default and help.

    One declaration gives the command line's flag (``--channel {auto,measured,nominal}``), the web's
    form field and schema entry, and the docs.

    Attributes
    ----------
    help : str
        One line: what the setting chooses.
    choices : tuple of str
        The words it takes.
    default : str
        The word used when none is given (one of ``choices``).
    """

    help: str
    choices: tuple[str, ...]
    default: str

    def check(self, value, where: str) -> str:
        """Return ``value`` or raise :class:`ParameterError` naming ``where`` and the choices."""
        if not isinstance(value, str) or value not in self.choices:
            raise ParameterError(f"{where} {str(value)[:60]!r}: unknown; choose one of {', '.join(self.choices)}")
        return value


#: Settings of ``analyze`` that are words, not quantities: name -> :class:`ChoiceSpec`. The command line
#: (``afmforce analyze --channel``), the web (``POST /api/analyze`` field ``channel``, the analyse view's
#: control, ``GET /api/schema`` ``analysis_settings``) and :data:`afmforce.io.curve.POSITION_CHANNELS` read them here.
ANALYSIS_CHOICES: dict[str, ChoiceSpec] = {
    "channel": ChoiceSpec("position channel: auto (the measured position when recorded, else the nominal), "
                          "measured (the scanner's position detector) or nominal (the piezo's commanded "
                          "position)", ("auto", "measured", "nominal"), "auto"),
}


#: Quantity options of ``afmforce analyze``, by their destination (``file_timeout``), that have no control in
#: the web's analyse view, each with the reason. Every other quantity option of ``analyze`` is a web control
#: of the same name and range (a probe field, a step's option): tests/cli/test_faces_walk_declarations.py
#: walks the parser against this set.
ANALYZE_CLI_ONLY: dict[str, str] = {
    "file_timeout": "a budget of the command's own batch run (reading one file); the web bounds its requests "
                    "by its own limits (afmforce.web.limits: upload size, curves, analysis time)",
}


def qfield(name: str, default: Any = dataclasses.MISSING) -> Any:
    """A dataclass field carrying the metadata of :data:`QUANTITIES` ``[name]``."""
    return dataclasses.field(default=default, metadata=_meta_of(QUANTITIES[name]))


def check(name: str, value, where: str | None = None):
    """Check ``value`` of the vocabulary quantity ``name`` (unknown names pass unchanged)."""
    spec = QUANTITIES.get(name)
    return value if spec is None else spec.check(value, name, where)


def check_all(values: Mapping[str, Any], where: str = "") -> None:
    """Check every ``name -> value`` of the vocabulary; ``where`` prefixes the name (``--set``)."""
    for name, value in values.items():
        check(name, value, f"{where} {name}".strip() if where else None)


def check_beam(L0: float | None, L1: float | None, L2: float | None, *, k0: float | None = None,
               B: float | None = None, prefix: str = "") -> None:
    """The cross-field rules of the inclined cantilever (Fig 2), for every face.

    The base ``L1`` and the probe ``L2`` are short rigid parts of the beam
    (``L1 < L0``, ``L2 < L0``), and a rigidity ``B`` must give an intrinsic spring
    constant ``k0 = 3 B / L0^3`` inside k0's range. ``prefix`` is written before
    each name (the command line gives ``"--"``).

    Raises
    ------
    ParameterError
    """
    for name, value in (("L1", L1), ("L2", L2)):
        if value is not None and L0 is not None and value >= L0:
            raise ParameterError(
                f"{prefix}{name} {QUANTITIES[name].show(value)} is not shorter than the flexible beam "
                f"{prefix}L0 {QUANTITIES['L0'].show(L0)}; the base and the probe are short rigid parts "
                "of the cantilever (Fig 2)")
    if B is not None and L0 is not None and k0 is None:
        k = 3.0 * B / L0**3
        spec = QUANTITIES["k0"]
        if not spec.contains(k):
            raise ParameterError(
                f"{prefix}B {QUANTITIES['B'].show(B)} with {prefix}L0 {QUANTITIES['L0'].show(L0)} gives "
                f"k0 = 3B/L0^3 = {spec.show(k)}, out of range: k0 must lie in {spec.range_text()}")


def ranges_markdown() -> str:
    """The docs table of :data:`QUANTITIES`: name, meaning, SI unit, valid range."""
    lines = ["| name | meaning | SI unit | valid range |", "|---|---|---|---|"]
    for name, s in QUANTITIES.items():
        lines.append(f"| `{name}` | {s.help} | {s.unit or '-'} | {s.range_text()} |")
    lines += ["", f"The room temperature, the default of every `temperature` not given or stored in a file (the "
              f"thermal calibration, the tethers' chain fits, the capillary and steric laws): "
              f"{QUANTITIES['temperature'].show(DEFAULT_TEMPERATURE)} (`afmforce.constants.DEFAULT_TEMPERATURE`; "
              f"the paper's measurements: {PAPER_ROOM_TEMPERATURE - 273.15:.1f} C)."]
    return "\n".join(lines)
