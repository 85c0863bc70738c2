"""Thermal spectra on disk: afmforce's own format and the instruments' thermal files.

* **afmforce spectrum** (``.txt``/``.csv``): ``#`` header lines ``key: value [unit]`` (first
  line ``# afmforce thermal spectrum 1``), then a header row ``frequency [Hz],psd [m^2/Hz]``
  (or ``[V^2/Hz]``) and comma-separated rows; ``# rows: N`` (written by :func:`write_spectrum`; optional on
  reading) lets a truncated copy be refused. Written atomically (:func:`write_spectrum`).
* **Plain text**: two numeric columns, frequency (in Hz) and the spectrum, with the unit stated in
  a header line (``m^2/Hz``, ``V^2/Hz``, or an amplitude ``m/sqrt(Hz)``, ``V/sqrt(Hz)``, squared
  here) or given by the caller.
* **Nanosurf thermal tune** (``.nid``, :mod:`afmforce.calibration.nid`): the ``Spectrum FFT``
  frame (an amplitude spectral density in m/sqrt(Hz), squared) and the tune's own results.
* **JPK thermal noise data** (``.tnd``, JPK/Bruker NanoWizard "Calibration manager" export):
  ``#`` header with the vendor's calibration (``sensitivity``, ``spring constant``,
  ``parameter.f``, ``parameter.Q``, ``settings.temperature``, ``settings.environment``,
  ``cantilever.angle``, ``cantilever.correction factor``) and four columns ``Frequency``,
  ``Vertical Deflection`` (the last spectrum), ``average`` (the averaged one, fitted here),
  ``fit-data`` [V^2/Hz].

The reader never modifies its input; :class:`ThermalSpectrum` keeps the spectrum in the file's
unit and converts to m^2/Hz with the sensitivity on request.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .._files import atomic_write_text
from ..errors import FileFormatError, MissingMetadataError, ParameterError

__all__ = ["ThermalSpectrum", "read_spectrum", "read_nid_spectrum", "write_spectrum", "SPECTRUM_SUFFIXES", "TEXT_UNITS"]

_MAGIC = "# afmforce thermal spectrum 1"
#: suffixes the thermal readers accept
SPECTRUM_SUFFIXES = (".tnd", ".psd", ".txt", ".csv", ".nid")


@dataclass(frozen=True, eq=False)
class ThermalSpectrum:
    """A one-sided deflection power spectrum and what the file says about it.

    Attributes
    ----------
    frequency : ndarray  [Hz]
    psd : ndarray  [unit]
    unit : str  ``"m^2/Hz"`` or ``"V^2/Hz"``
    temperature : float or None  [K]
    medium : str or None  ``"air"``, ``"water"``, ...
    sensitivity : float or None  InvOLS [m/V]
    correction : float or None  chi of equipartition stored by the file [-]
    tilt : float or None  lever tilt [rad]
    averages : int or None  periodograms averaged [-]
    vendor : dict  the file's own calibration, SI (``spring_constant`` [N/m],
        ``resonance_frequency`` [Hz], ``quality_factor`` [-], ...)
    source : str  where it came from
    window : (float, float) or None  the frequency window the instrument fitted [Hz] (the default
        window of :func:`~afmforce.calibration.fit_thermal` for this file)
    """

    frequency: np.ndarray
    psd: np.ndarray
    unit: str = "m^2/Hz"
    temperature: float | None = None
    medium: str | None = None
    sensitivity: float | None = None
    correction: float | None = None
    tilt: float | None = None
    averages: int | None = None
    vendor: dict[str, Any] = field(default_factory=dict)
    source: str = ""
    window: tuple[float, float] | None = None

    def __post_init__(self) -> None:
        if self.unit not in ("m^2/Hz", "V^2/Hz"):
            raise ParameterError(f"spectrum unit {self.unit!r}: expected m^2/Hz or V^2/Hz")
        f, p = np.asarray(self.frequency, float), np.asarray(self.psd, float)
        if f.ndim != 1 or f.shape != p.shape or f.size < 8:
            raise ParameterError("a thermal spectrum needs 1-D frequency and psd of one length (>= 8 bins)")
        object.__setattr__(self, "frequency", f)
        object.__setattr__(self, "psd", p)

    def displacement_psd(self, sensitivity: float | None = None) -> np.ndarray:
        """The PSD in m^2/Hz: as stored, or V^2/Hz times ``sensitivity^2`` (given, else the file's)."""
        if self.unit == "m^2/Hz":
            return self.psd
        s = sensitivity if sensitivity is not None else self.sensitivity
        if s is None:
            raise MissingMetadataError("the spectrum is in V^2/Hz and carries no sensitivity (InvOLS); "
                                       "give the sensitivity", keys=("sensitivity",))
        return self.psd * s * s


# -- afmforce's own format ----------------------------------------------------------------

_HEADER_UNITS = {"temperature": "K", "sensitivity": "m/V", "tilt": "rad"}


def write_spectrum(path, spectrum: ThermalSpectrum, force: bool = True) -> Path:
    """Write ``spectrum`` in afmforce's own format, atomically; returns the path."""
    lines = [_MAGIC, f"# unit: {spectrum.unit}"]
    for key in ("temperature", "medium", "sensitivity", "correction", "tilt", "averages"):
        value = getattr(spectrum, key)
        if value is not None:
            unit = _HEADER_UNITS.get(key, "")
            lines.append(f"# {key}: {value!r}{' ' + unit if unit else ''}".replace("'", ""))
    for key, value in spectrum.vendor.items():
        lines.append(f"# vendor.{key}: {value!r}".replace("'", ""))
    if spectrum.source:
        lines.append(f"# source: {spectrum.source}")
    lines.append(f"# rows: {len(spectrum.frequency)}")     # a truncated copy is refused on reading
    lines.append(f"frequency [Hz],psd [{spectrum.unit}]")
    body = "\n".join(f"{f!r},{p!r}" for f, p in zip(spectrum.frequency.tolist(), spectrum.psd.tolist()))
    return atomic_write_text(path, "\n".join(lines) + "\n" + body + "\n", force=force)


def _lines(text: str, head: dict[str, str]):
    """The data lines of a ``# key: value`` headed text, numbered from 1; the header lines fill ``head``."""
    for n, line in enumerate(text.splitlines(), 1):
        s = line.strip()
        if not s:
            continue
        if s.startswith("#"):
            key, sep, value = s[1:].partition(":")
            if sep:
                head[key.strip()] = value.strip()
            continue
        yield n, s


def _read_own(path: Path, text: str) -> ThermalSpectrum:
    head: dict[str, str] = {}
    rows = []
    for n, s in _lines(text, head):
        if s.lower().startswith("frequency"):
            if "[" in s:
                unit = s.rsplit("[", 1)[1].rstrip("]").strip()
                head.setdefault("unit", unit)
            continue
        try:
            f, p = (float(x) for x in s.split(","))
        except ValueError:
            raise FileFormatError(f"{path}, line {n}: expected 'frequency,psd', got {s[:60]!r}") from None
        rows.append((f, p))
    if not rows:
        raise FileFormatError(f"{path}: no spectrum rows")
    declared = head.get("rows")
    if declared is not None and declared.strip() != str(len(rows)):
        raise FileFormatError(f"{path}: the header declares {declared.strip()[:20]} rows, the file holds "
                              f"{len(rows)}: it is truncated or damaged; write or copy it again")
    data = np.array(rows)

    def num(key):
        v = head.get(key)
        if v is None:
            return None
        try:
            x = float(v.split()[0])
        except (ValueError, IndexError):
            x = math.nan
        if not math.isfinite(x):
            raise FileFormatError(f"{path}: header '{key}' must be a finite number, got {v[:40]!r}: the file is "
                                  "damaged; correct or remove that line")
        return x

    vendor = {k[len("vendor."):]: _maybe_float(v) for k, v in head.items() if k.startswith("vendor.")}
    averages = num("averages")
    if averages is not None and not (averages >= 1 and averages == int(averages)):
        raise FileFormatError(f"{path}: header 'averages' must be a whole number >= 1, got {head['averages'][:40]!r}: "
                              "the file is damaged; correct or remove that line")
    return ThermalSpectrum(data[:, 0], data[:, 1], unit=head.get("unit", "m^2/Hz"),
                           temperature=num("temperature"), medium=head.get("medium"),
                           sensitivity=num("sensitivity"), correction=num("correction"),
                           tilt=num("tilt"), averages=None if averages is None else int(averages),
                           vendor=vendor, source=head.get("source", str(path)))


def _maybe_float(v: str):
    try:
        return float(v)
    except ValueError:
        return v


# -- JPK thermal noise data (.tnd) ---------------------------------------------------------

_SUPERSCRIPT = str.maketrans("⁻⁰¹²³⁴⁵⁶⁷⁸⁹", "-0123456789")
_PREFIX = {"": 1.0, "k": 1e3, "M": 1e6, "m": 1e-3, "µ": 1e-6, "μ": 1e-6, "u": 1e-6, "n": 1e-9, "p": 1e-12,
           "f": 1e-15}


def _jpk_number(text: str) -> tuple[float, str]:
    """``'4.501×10⁻¹⁰ V²/Hz'`` -> (4.501e-10, 'V²/Hz'); ``'11.0399 nm/V'`` -> (11.0399, 'nm/V')."""
    s = text.strip().translate(_SUPERSCRIPT)
    m = re.match(r"^([+-]?[\d.]+(?:[eE][+-]?\d+)?)(?:×10(-?\d+))?\s*(.*)$", s)
    if not m:
        raise ValueError(text)
    value = float(m.group(1)) * (10.0 ** int(m.group(2)) if m.group(2) else 1.0)
    return value, m.group(3).strip()


def _jpk_si(text: str, base: str) -> float:
    """A JPK header value in unit ``<prefix><base>`` -> SI."""
    value, unit = _jpk_number(text)
    prefix = unit[: len(unit) - len(base)] if unit.endswith(base) else None
    if prefix is None or prefix not in _PREFIX:
        raise ValueError(f"{text!r}: expected a value in {base}")
    return value * _PREFIX[prefix]


def _try(parse, text):
    """``parse(text)``, or None for a missing or unreadable header value."""
    if text is None:
        return None
    try:
        return parse(text)
    except ValueError:
        return None


def _stored(parse, head: dict[str, str], key: str, path: Path):
    """``parse`` of the header value ``key``: None where the file does not store it (absent or
    empty); a value it stores but that cannot be read (or is not finite) is refused, never replaced
    by a default (a garbled temperature would silently become 295 K in k = kT/<x^2>)."""
    text = head.get(key)
    if text is None or not text.strip():
        return None
    try:
        value = parse(text)
    except ValueError:
        value = None
    if value is None or not math.isfinite(value[0] if isinstance(value, tuple) else value):
        raise FileFormatError(f"{path}: the header's {key!r} is {text.strip()[:40]!r}, not a number: the "
                              "file is damaged; repair the line or remove it to use the default")
    return value


#: How a .tnd header writes the units of its temperature.
_CELSIUS = ("℃", "°C", "C", "degC")
_KELVIN = ("K", "")


def _read_tnd(path: Path, text: str) -> ThermalSpectrum:
    head: dict[str, str] = {}
    rows = []
    for n, s in _lines(text, head):
        parts = s.split()
        try:
            rows.append([float(x) for x in parts[:4]])
        except ValueError:
            raise FileFormatError(f"{path}, line {n}: expected numbers, got {s[:60]!r}") from None
    if "thermal noise data" not in text[:200] or not rows:
        raise FileFormatError(f"{path}: not a JPK thermal noise data file (no '# thermal noise data' "
                              "header or no rows)")
    names = re.findall(r"'([^']*)'", head.get("Channels", ""))
    width = len(rows[0])
    short = next((i for i, r in enumerate(rows) if len(r) != width), None)
    if short is not None:   # a ragged row: never a spectrum silently cut where the file was cut
        where = "its last row" if short == len(rows) - 1 else f"data row {short + 1} of {len(rows)}"
        raise FileFormatError(f"{path}: {where} holds {len(rows[short])} of the {width} columns of the "
                              "others: the file is truncated or damaged; export the spectrum again")
    data = np.array(rows)
    if data.shape[1] < 2:
        raise FileFormatError(f"{path}: the rows hold one column; expected frequency and spectrum")
    col = names.index("average") if "average" in names and names.index("average") < data.shape[1] else 1
    units = re.findall(r"'([^']*)'", head.get("Units", ""))
    unit = units[col].replace("²", "^2") if col < len(units) else "V^2/Hz"
    if unit not in ("V^2/Hz", "m^2/Hz"):
        raise FileFormatError(f"{path}: the spectrum column is in {units[col]!r}; expected V²/Hz or m²/Hz")
    vendor: dict[str, Any] = {}
    sensitivity = _stored(lambda v: _jpk_si(v, "m/V"), head, "sensitivity", path)
    for key, name, base in (("spring constant", "spring_constant", "N/m"),
                            ("parameter.f", "resonance_frequency", "Hz"),
                            ("parameter.noise", "white", "V²/Hz")):
        try:
            vendor[name] = _jpk_si(head[key], base)
        except (KeyError, ValueError):
            pass
    quality = _try(_jpk_number, head.get("parameter.Q"))
    if quality is not None:
        vendor["quality_factor"] = quality[0]
    if sensitivity is not None:
        vendor["sensitivity"] = sensitivity
    temperature = None
    t = _stored(_jpk_number, head, "settings.temperature", path)
    if t is not None:
        if t[1] not in _CELSIUS + _KELVIN:   # never a number in an unknown unit taken for kelvin
            raise FileFormatError(f"{path}: the header's 'settings.temperature' is {head['settings.temperature']!r}: "
                                  "a temperature in kelvin or degrees Celsius was expected; correct that line")
        temperature = t[0] + 273.15 if t[1] in _CELSIUS else t[0]
    c = _stored(_jpk_number, head, "cantilever.correction factor", path)
    correction = c[0] if c is not None else None
    tilt = None
    if "cantilever.angle" in head:   # '10° + 0.0 °': nominal angle plus the user's offset
        degrees = [float(x) for x in re.findall(r"[-+]?\d+(?:\.\d+)?", head["cantilever.angle"])]
        tilt = math.radians(sum(degrees)) if degrees else None
    medium = head.get("settings.environment")
    for key, name, base in (("settings.environment density", "density", "kg/m³"),
                            ("settings.environment viscosity", "viscosity", "Pa·s"),
                            ("cantilever.width", "width", "m"), ("cantilever.length", "length", "m")):
        try:
            vendor[name] = _jpk_si(head[key], base)
        except (KeyError, ValueError):
            pass
    if "settings.method" in head:
        vendor["method"] = head["settings.method"]
    return ThermalSpectrum(data[:, 0], data[:, col], unit=unit, temperature=temperature,
                           medium=medium.lower() if medium else None, sensitivity=sensitivity,
                           correction=correction, tilt=tilt, vendor=vendor, source=str(path))


# -- plain two-column text (any instrument's export) -----------------------------------------

_UNIT_WORDS = (  # header text -> (unit of the PSD, squared: an amplitude spectral density)
    (r"m\^?2/Hz|m²/Hz", "m^2/Hz", False), (r"V\^?2/Hz|V²/Hz", "V^2/Hz", False),
    (r"m/(?:√|sqrt\(?)Hz", "m^2/Hz", True), (r"V/(?:√|sqrt\(?)Hz", "V^2/Hz", True))
#: the PSD units a plain text spectrum may state (``unit=`` of :func:`read_spectrum`)
TEXT_UNITS = ("m^2/Hz", "V^2/Hz", "m/sqrt(Hz)", "V/sqrt(Hz)")


def _read_text(path: Path, text: str, unit: str | None) -> ThermalSpectrum:
    """Two or more numeric columns (frequency, spectrum), any separators, header lines kept as text."""
    header, rows = [], []
    for line in text.splitlines():
        parts = re.split(r"[,;\t ]+", line.strip())
        try:
            values = [float(x) for x in parts if x]
        except ValueError:
            header.append(line)
            continue
        if len(values) >= 2:
            rows.append(values[:2])
    if len(rows) < 8:
        raise FileFormatError(f"{path}: not a thermal spectrum afmforce reads (JPK .tnd, the afmforce "
                              "spectrum format, or two numeric columns: frequency and spectrum)")
    data = np.array(rows)
    head = " ".join(header)
    squared = False
    if unit is None:
        for pattern, found, amp in _UNIT_WORDS:
            m = re.search(r"(?<![A-Za-z])([pnuµμm]?)(" + pattern + ")", head)
            if m and not m.group(1):
                unit, squared = found, amp
                break
        else:
            raise MissingMetadataError(f"{path}: two numeric columns, but the header states no spectrum "
                                       "unit (m^2/Hz, V^2/Hz, m/sqrt(Hz) or V/sqrt(Hz)); give it (psd_unit)",
                                       keys=("psd_unit",))
    elif unit in ("m/sqrt(Hz)", "V/sqrt(Hz)"):
        unit, squared = unit[0] + "^2/Hz", True
    elif unit not in ("m^2/Hz", "V^2/Hz"):
        raise ParameterError(f"psd_unit {unit!r}: choose one of {', '.join(TEXT_UNITS)}")
    psd = data[:, 1] ** 2 if squared else data[:, 1]
    return ThermalSpectrum(data[:, 0], psd, unit=unit, source=str(path))


def _is_nid(head: bytes) -> bool:
    from .nid import is_nid

    return is_nid(head)


# -- Nanosurf .nid thermal tune ---------------------------------------------------------------

def read_nid_spectrum(path: str | Path):
    """The thermal tune of a .nid (``Spectrum FFT`` frame, an amplitude spectral density in
    m/sqrt(Hz), squared here) with the tune's own results from ``[DataSet-Info]``
    (``Frequency:``, ``Q Factor:``, ``Spring Constant:``, ``Peak Value:``) as the vendor's values
    and its ``Cantilever temperature``.

    Raises
    ------
    FileFormatError
        Not a .nid, or no ``Spectrum FFT`` frame (an image or a force curve).
    """
    from .nid import _number, read_nid, si_value

    nid = read_nid(path)
    block = next((b for b in nid.blocks if b.frame == "Spectrum FFT"), None)
    if block is None:
        raise FileFormatError(f"{path}: this Nanosurf .nid holds no thermal tune ('Spectrum FFT' frame); it "
                              f"holds {', '.join(nid.frames()) or 'no data'}")
    unit = block.unit.replace(" ", "")
    squared = {"m/sqrt(Hz)": "m^2/Hz", "V/sqrt(Hz)": "V^2/Hz"}.get(unit)
    if squared is None:
        raise FileFormatError(f"{path}: the thermal tune is in {block.unit!r}; expected m/sqrt(Hz) or V/sqrt(Hz)")
    h = block.header
    f0, span = _number(h, "Dim0Min", nid.path, block.name), _number(h, "Dim0Range", nid.path, block.name)
    asd = nid.values(block)[0]
    frequency = f0 + span * np.arange(block.points) / max(block.points - 1, 1)
    info = nid.sections.get("DataSet-Info", {})
    vendor = {}
    for key, name, base in (("Spring Constant:", "spring_constant", "N/m"), ("Frequency:", "resonance_frequency", "Hz"),
                            ("Peak Value:", "peak_amplitude", "m/sqrt(Hz)")):
        v = si_value(info.get(key), base)
        if v is not None:
            vendor[name] = v
    q = si_value(info.get("Q Factor:"), "")
    if q is None and (info.get("Q Factor:") or "").strip().endswith("k"):
        q = si_value(info["Q Factor:"].strip()[:-1], "")
        q = None if q is None else q * 1e3
    if q is not None:
        vendor["quality_factor"] = q
    temperature = si_value(info.get("Cantilever temperature"), "°C")
    # The tune's "Averages" is kept as the vendor's word, not as the count of averaged periodograms the
    # fit's misfit check (thermal._require_described) trusts: the file stores an amplitude density whose
    # averaging (amplitudes or powers, overlap, smoothing) it does not describe, and its ACL-A tune states
    # 1000 while scattering about a good oscillator fit as 494 independent ones would, with neighbouring bins
    # correlated (0.44): taken as the count, the check refused this real spectrum.
    averages = info.get("Averages", "")
    if averages.isdigit():
        vendor["averages"] = int(averages)
    lo, hi = si_value(info.get("Peak fit min"), "Hz"), si_value(info.get("Peak fit max"), "Hz")
    window = (lo, hi) if lo is not None and hi is not None and 0 <= lo < hi else None
    return ThermalSpectrum(frequency, asd * asd, unit=squared,
                           temperature=None if temperature is None else temperature + 273.15,
                           medium=(info.get("Measurement environment") or "").lower() or None,
                           averages=None, vendor=vendor, source=str(path),
                           window=window)



def read_spectrum(path, unit: str | None = None) -> ThermalSpectrum:
    """Read a thermal spectrum: JPK ``.tnd``, a Nanosurf ``.nid`` thermal tune
    (:func:`afmforce.calibration.nid.read_nid_spectrum`), afmforce's own format, or two numeric columns
    (frequency [Hz], spectrum) whose header states the unit or ``unit`` gives it (one of
    :data:`TEXT_UNITS`; an amplitude spectral density is squared).

    Raises
    ------
    FileFormatError
        None of these, or malformed rows.
    """
    path = Path(path)
    try:
        with open(path, "rb") as fh:
            if _is_nid(fh.read(4096)):
                return read_nid_spectrum(path)
        text = path.read_text(encoding="utf-8", errors="replace")
    except OSError as exc:
        raise FileFormatError(f"cannot read {path}: {exc.strerror or exc}") from None
    first = text.lstrip()[:200]
    if first.startswith(_MAGIC):
        return _checked(path, _read_own(path, text))
    if first.startswith("# thermal noise data"):
        return _checked(path, _read_tnd(path, text))
    return _checked(path, _read_text(path, text, unit))


def _checked(path: Path, spectrum: ThermalSpectrum) -> ThermalSpectrum:
    """``spectrum`` when every bin is a power (finite, >= 0) at a finite frequency; else the file is
    damaged: a FileFormatError naming the bins (the fit would drop them silently -- a NaN or a
    negative bin at the peak moved k by 0.6 %, and nothing said so)."""
    for key, value in (("sensitivity", spectrum.sensitivity), ("temperature", spectrum.temperature),
                       ("correction", spectrum.correction)):
        if value is not None and not (math.isfinite(value) and value > 0):
            raise FileFormatError(f"{path}: its {key} is {value:g}, not a positive number: the file is damaged; "
                                  "correct that header line")
    bad = ~(np.isfinite(spectrum.frequency) & np.isfinite(spectrum.psd) & (spectrum.psd >= 0))
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise FileFormatError(
            f"{path}: {int(bad.sum())} spectrum bin(s) are not a power (NaN, infinite or negative; the first: "
            f"{float(spectrum.psd[i]):g} at {float(spectrum.frequency[i]):.6g} Hz, bin {i + 1}): the file is damaged; "
            "export the spectrum again")
    return spectrum
