r"""Reader of Bruker NanoScope binary force files (``.spm``, ``.pfc``, ``.000``-``.999``).

A NanoScope file (versions 5 to 9) is a text header followed by binary data::

    \*Force file list                 first line (files of images start \*File list)
    \Version: 0x0920B046
    \Data length: 80960               the header's length [bytes]
    \*Scanner list ... \@Sens. Zsens: V 13.20300 nm/V
    \*Ciao scan list ... \@Sens. DeflSens: V 27.39000      (nm/V; v5: \@Sens. Deflection)
    \*Ciao force list
    \Scan rate: 1.01725               ramps per second
    \Forward vel.: 462.282            [V/s] of the Z piezo (x Zsens = m/s)
    \Samps/line: 1024 1024            points of the approach and the retract (v5/v6 with a trigger:
                                      "1024 896", slots of each run, points the approach recorded)
    \*Ciao force image list           one per channel
    \Data offset: 80960               where the channel's numbers start [bytes]
    \Data length: 8192                [bytes], all curves of the channel
    \Spring Constant: 0.1332          [N/m]
    \@4:Image Data: S [DeflectionError] "Deflection Error"
    \@4:Z scale: V [Sens. DeflSens] (0.0003750000 V/LSB) 2.500000 V
    \@4:Ramp Size: V [Sens. Zsens] (0.006713765 V/LSB) 227.2211 V
    \*File list end

Each channel holds, per curve, the approach then the retract as little-endian
integers of ``Data length / (curves x points)`` bytes (2, or 4 from version 9 on,
whatever ``Bytes/pixel`` says: the sample width comes from the data length and the
number of curves); value [V] = integer x the channel's ``V/LSB``; deflection [m] =
value x DeflSens. The ``V/LSB`` is that of the 16-bit ADC: 4-byte samples beyond its
range whose low bits carry nothing (v9 force volumes: every value a multiple of 256,
or one less for negatives) are those 16-bit numbers shifted, and are shifted back; a
signal still beyond the ADC's range is refused rather than read 256 x too large.

A force volume (``\Start context: FVOL``) holds ``Samps/line x Number of lines`` curves
of its own images (the ``\*Ciao image list`` after the force data, one value per curve), else
``Samps/line x Lines`` of the ``\*Ciao scan list`` (the topography image's, which may be finer:
64 x 64 pixels over 16 x 16 curves in a NanoScope 8.15 file); one grid point each, row by row from
the first line;
each curve carries its grid indices (``map_x``, ``map_y``, ``map_nx``, ``map_ny``)
and its position (``position_x``, ``position_y`` [m]: the grid point's centre in
the ``Scan Size`` square). The spring constant is the deflection channel's (other
channels' lists may hold stale values). Image files (first line ``\*File list``)
are refused by name: they hold no force curve. Both runs are indexed from the turning point
(the piezo's extended end): the approach is reversed into time order. Z is the
nominal ramp (``Ramp Size`` [V] x Zsens, evenly spaced), or the Z-sensor channel
(``ZSensor``, value x ZsensSens) when recorded. Time comes from the ramp size and
the forward/reverse velocities, else from the scan rate.

The reader returns the deflection in volts with ``sensitivity`` = DeflSens,
``spring_constant``, ``radius`` (``\Tip Radius`` [nm]) and ``poisson`` (``\Sample Poisson's
Ratio``, the indentation step's default) from the header (the user's ``meta_override`` wins).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Mapping

import numpy as np

from ..errors import FileFormatError
from .curve import RawCurve
from ._meta import METADATA, finalize_curve, sensor_note

__all__ = ["load_nanoscope", "NanoscopeFile", "detect_nanoscope", "parse_header", "count_curves", "MAX_HEADER", "ADC_COUNTS"]

#: Headers longer than this are not NanoScope force files (v9 headers are ~40-90 kB).
MAX_HEADER = 4 * 2**20
_NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
_SCALE = re.compile(rf"\[(?:Sens\.\s*)?([^\]]*)\]\s*\(({_NUMBER})\s*([^)/]*)/LSB\)\s*({_NUMBER})?")
_PLAIN = re.compile(rf"\(({_NUMBER})\s*([^)/]*)/LSB\)\s*({_NUMBER})?")
_ENTRY = re.compile(r"^\\@?((?:\d+:)?[^:]*):\s*(.*)$")  # \@4:Z scale: V ... -> ("4:Z scale", "V ...")
_UNITS = {"nm": 1e-9, "um": 1e-6, "µm": 1e-6, "m": 1.0, "pm": 1e-12, "V": 1.0, "mV": 1e-3}


def detect_nanoscope(path: Path) -> bool:
    r"""True if the file starts with ``\*Force file list`` (a NanoScope force file) or ``\*File list``
    (a NanoScope image: accepted here so that the reader refuses it by name)."""
    try:
        with open(path, "rb") as fh:
            head = fh.read(64)
    except OSError:
        return False
    head = head.lstrip(b"\"\xef\xbb\xbf")
    return head.startswith(b"\\*Force file list") or head.startswith(b"\\*File list")  # images: refused by name


def parse_header(data: bytes, where: str) -> list[tuple[str, dict[str, str]]]:
    r"""Sections of the header: ``[(name, {key: value})]`` in file order (``\*Name`` opens one)."""
    end = data.find(b"\\*File list end")
    if end < 0:
        raise FileFormatError(f"{where}: NanoScope header without '\\*File list end' (truncated?)")
    if end > MAX_HEADER:
        raise FileFormatError(f"{where}: NanoScope header longer than {MAX_HEADER} bytes; damaged file")
    sections: list[tuple[str, dict[str, str]]] = []
    for raw in data[:end].decode("latin-1").split("\n"):
        line = raw.strip().strip('"').strip()
        if not line.startswith("\\"):
            continue
        if line.startswith("\\*"):
            sections.append((line[2:].strip(), {}))
        elif sections and (m := _ENTRY.match(line)) is not None:
            sections[-1][1].setdefault(m.group(1).strip(), m.group(2).strip())
    if sections and sections[0][0].lower() == "file list" and any(
            name.lower() == "ciao force image list" for name, _ in sections):
        raise FileFormatError(
            f"{where}: a Bruker PeakForce capture file (first line '\\*File list' with force image lists: a "
            "force curve per image pixel), a layout afmforce does not read (no public file of it to check the "
            "sample layout against); export the curves from NanoScope Analysis as force files or as text")
    if sections and sections[0][0].lower() == "file list":
        raise FileFormatError(
            f"{where}: a Bruker NanoScope image file (first line '\\*File list'), not a force file: it holds "
            "images, no force curve; export the force curves from NanoScope as a force file ('\\*Force file "
            "list', .spm/.pfc/.000) or as NanoScope Analysis text")
    if not sections or sections[0][0].lower() != "force file list":
        raise FileFormatError(f"{where}: not a NanoScope force file (no '\\*Force file list')")
    return sections


def _number(text: str | None, where: str, key: str, index: int = -1) -> float:
    nums = re.findall(_NUMBER, text or "")
    if not nums:
        raise FileFormatError(f"{where}: NanoScope header entry {key!r} missing or not a number ({text!r})")
    return float(nums[index])


def _find(sections, key: str, section: str | None = None) -> str | None:
    for name, entries in sections:
        if section is None or name.lower() == section.lower():
            for k, v in entries.items():
                if k.lower() == key.lower():
                    return v
    return None


def sample_poisson(sections) -> float | None:
    """The header's ``\\Sample Poisson's Ratio`` (the sample's Poisson ratio NanoScope's own modulus
    fits use), or None where it is missing or not a ratio in (-1, 0.5]."""
    text = _find(sections, "Sample Poisson's Ratio")
    if text is None or not re.search(_NUMBER, text):
        return None
    try:
        return METADATA["poisson"].validate(float(re.search(_NUMBER, text).group(0)))
    except ValueError:
        return None


def _sens(sections, name: str) -> tuple[float, str] | None:
    r"""``\@Sens. NAME: V 27.39 nm/V`` -> (27.39, 'nm'); unit of the numerator."""
    text = _find(sections, f"Sens. {name}")
    if text is None:
        return None
    m = re.search(rf"({_NUMBER})\s*([^\s/]*)", text.split(" ", 1)[1] if text.startswith("V ") else text)
    if m is None:
        return None
    return float(m.group(1)), m.group(2)


def _channel_scale(entries: dict[str, str], sections, where: str) -> tuple[float, float, str]:
    """(V per LSB, sensitivity in SI per V, sensitivity name) of one channel."""
    text = entries.get("4:Z scale") or entries.get("Z scale")
    if text is None:
        raise FileFormatError(f"{where}: channel without a 'Z scale' entry")
    m = _SCALE.search(text)
    if m is None:
        p = _PLAIN.search(text)
        if p is None:
            raise FileFormatError(f"{where}: cannot read the channel scale {text!r}")
        return float(p.group(1)) * _UNITS.get(p.group(2).strip(), 1.0), 1.0, ""
    name = m.group(1).strip()
    vlsb = float(m.group(2)) * _UNITS.get(m.group(3).strip(), 1.0)
    sens = _sens(sections, name)
    factor = sens[0] * _UNITS.get(sens[1], 1.0) if sens and sens[1] in _UNITS else (
        sens[0] * 1e-9 if sens else 1.0)  # DeflSens is written without its unit (nm/V) in v9
    return vlsb, factor, name


def _channels(sections) -> list[dict[str, str]]:
    return [entries for name, entries in sections if name.lower() == "ciao force image list"]


def _channel_name(entries: dict[str, str]) -> str:
    text = entries.get("4:Image Data") or entries.get("Image Data") or ""
    m = re.search(r"\[([^\]]*)\]", text)
    return m.group(1) if m else text.strip().strip('"')



def _other_spring_constants(sections, used: dict[str, str], k: float) -> str | None:
    r"""What the analysis says when the header's lists hold other spring constants than the deflection
    channel's (``k`` [N/m], from ``used``): each list has its own ``\Spring Constant``, typed when it was
    captured or changed later offline (NanoScope Analysis keeps one per channel; Bruker's own toolbox,
    PyPI ``nanoscope``, gives a file's as channel 0's, the first list). None when all agree."""
    others = []
    for name, entries in sections:
        text = entries.get("Spring Constant")
        if entries is used or text is None or not re.search(_NUMBER, text):
            continue
        value = float(re.search(_NUMBER, text).group(0))
        if math.isfinite(value) and abs(value - k) > 1e-6 * abs(k):
            what = _channel_name(entries) if name.lower() == "ciao force image list" else ""
            where_ = f"the {what} list" if what else f"the {name}"
            if entries.get("Data offset"):
                where_ += f" at byte {entries['Data offset'].strip()}"
            others.append(f"{value:.6g} N/m in {where_}")
    if not others:
        return None
    read = f"the {_channel_name(used)} list" + (f" at byte {used['Data offset'].strip()}" if used.get("Data offset")
                                                else "")
    return (f"the header holds {len(others) + 1} spring constants: {k:.6g} N/m in {read} (the deflection "
            f"channel read, used) and {', '.join(others)}; each list keeps the value typed when it was captured "
            f"or changed offline: give `spring_constant` if the lever's calibrated value is another")


#: The ADC's range in the units of a channel's ``V/LSB`` (16-bit signed numbers).
ADC_COUNTS = 2**15


def _grid(sections, where: str) -> tuple[int, int, float] | None:
    r"""``(nx, ny, scan size [m])`` of a force volume (``\Start context: FVOL``); None for single curves."""
    if (_find(sections[:1], "Start context") or "").strip().upper() != "FVOL":
        return None
    nx = _find(sections, "Samps/line", "Ciao scan list")
    ny = _find(sections, "Lines", "Ciao scan list")
    if nx is None or ny is None:
        raise FileFormatError(f"{where}: NanoScope force volume without 'Samps/line' and 'Lines' in its "
                              "'\\*Ciao scan list': the grid of curves is unknown")
    size = _find(sections, "Scan Size", "Ciao scan list")
    width = math.nan
    if size is not None and re.search(_NUMBER, size):
        unit = size.strip().split()[-1] if len(size.split()) > 1 else "nm"
        width = _number(size, where, "Scan Size", 0) * _UNITS.get(unit, 1e-9)
    nx, ny = int(_number(nx, where, "Samps/line")), int(_number(ny, where, "Lines"))
    return (*(_volume_image_grid(sections, where) or (nx, ny)), width)


def _volume_image_grid(sections, where: str) -> tuple[int, int] | None:
    r"""``(nx, ny)`` of a force volume's own images: the ``\*Ciao image list`` sections after its force data
    (one value per curve, e.g. the Deflection Error or Height at each grid point), or None where it has none.
    The scan list's ``Samps/line`` x ``Lines`` is the topography image's, which may be finer than the grid of
    curves (NanoScope 8.15, JSotres/FSAS ``Test.003``: a 64 x 64 height image, 16 x 16 curves)."""
    after = False
    for name, entries in sections:
        if name.lower() == "ciao force image list":
            after = True
        elif after and name.lower() == "ciao image list":
            nx, ny = _find([("", entries)], "Samps/line"), _find([("", entries)], "Number of lines")
            if nx is not None and ny is not None and re.search(_NUMBER, nx) and re.search(_NUMBER, ny):
                return int(_number(nx, where, "Samps/line")), int(_number(ny, where, "Number of lines"))
    return None


def count_curves(path: Path) -> int | None:
    """Curves in a NanoScope force volume, from its header and its size alone (None: a single-curve file):
    those the file holds whole (a volume cut short, or a channel holding fewer than its grid, counts its
    complete curves as :class:`NanoscopeFile` reads them)."""
    path = Path(path)
    with open(path, "rb") as fh:
        head = fh.read(MAX_HEADER + 64)
    lay = _layout(parse_header(head, str(path)), path.stat().st_size, str(path))
    return None if lay.grid is None else lay.whole


def _grid_point(grid, i: int) -> dict[str, Any]:
    """Grid indices (row by row) and the position [m] of curve ``i`` of a force volume."""
    if grid is None:
        return {}
    nx, ny, width = grid
    x, y = i % nx, i // nx
    out: dict[str, Any] = {"map_x": x, "map_y": y, "map_nx": nx, "map_ny": ny}
    if math.isfinite(width) and width > 0:
        out.update(map_width=width, map_height=width * ny / nx, position_x=(x + 0.5) * width / nx,
                   position_y=(y + 0.5) * width / nx)
    return out


def _sample_width(length: int, per: int, n_curves: int, entries: Mapping[str, str], where: str) -> int:
    """Bytes per sample: from the data length and the number of curves (the header's ``Bytes/pixel``
    is 2 in v9 files whose data are 4-byte integers)."""
    said = entries.get("Bytes/pixel")
    said_bpp = int(_number(said, where, "Bytes/pixel")) if said is not None else None
    if length % (per * n_curves) == 0 and length // (per * n_curves) in (2, 4):
        return length // (per * n_curves)
    if n_curves > 1:  # a force volume whose channel holds fewer curves than its grid: a width giving more is wrong
        fits = [bpp for bpp in (2, 4) if length % (per * bpp) == 0 and length // (per * bpp) <= n_curves]
        if len(fits) == 1:
            return fits[0]
        raise FileFormatError(
            f"{where}: channel length {length} bytes is not the force volume's {n_curves} curves of {per} points"
            + (f", and {length // (per * 2)} curves of 2-byte or {length // (per * 4)} of 4-byte samples both "
               "fit in it: the sample width, hence the curves, cannot be told; damaged file" if fits else
               " in 2- or 4-byte samples, nor fewer of them; damaged file"))
    for bpp in (said_bpp, 4, 2):  # curves of unknown number: the header's width first
        if bpp in (2, 4) and length % (per * bpp) == 0:
            return bpp
    raise FileFormatError(f"{where}: channel length {length} bytes is not a whole number of curves of {per} "
                          f"points ({n_curves} curve(s) expected) in 2- or 4-byte samples; damaged file")


def _adc_counts(ints: np.ndarray, bpp: int, channel: str, where: str) -> np.ndarray:
    """The samples in 16-bit ADC counts (the unit of the channel's ``V/LSB``).

    4-byte samples beyond the 16-bit range whose low 8 (or 16) bits carry nothing (all 0, or all 1
    for negatives: an arithmetic shift) are those counts shifted; they are shifted back. Samples
    still beyond the range are refused: read with the 16-bit scale they would put the signal
    far outside what the photodiode's ADC can give (a v9 force volume read so: approach 312 V).
    """
    return ints.astype(float) / _adc_shift([ints], bpp, channel, where)


#: a V/LSB whose 32-bit full scale (x 2^31) is below this [V] is the scale of 32-bit samples (v9.3 files'
#: Height Sensor: 0.00000000572205 V/LSB, +-12.3 V), not of the 16-bit ADC's counts (0.000375 V/LSB)
SCALE_32BIT_VOLTS = 1000.0


def _adc_shift(chunks, bpp: int, channel: str, where: str, vlsb: float | None = None) -> float:
    """The divisor (1, 256 or 65536) turning a channel's samples into the counts of its ``V/LSB``, decided
    on all its samples (given in chunks) as :func:`_adc_counts` describes; 1 for 4-byte samples whose
    ``V/LSB`` is itself a 32-bit scale (``vlsb`` x 2^31 < :data:`SCALE_32BIT_VOLTS`)."""
    if bpp == 2 or (bpp == 4 and vlsb is not None and 0 < vlsb * 2.0**31 < SCALE_32BIT_VOLTS):
        return 1.0
    peak, aligned = 0, {16: True, 8: True}
    for ints in chunks:
        if not ints.size:
            continue
        peak = max(peak, int(np.abs(ints.astype(np.int64)).max()))
        for shift in aligned:
            low = ints & ((1 << shift) - 1)
            aligned[shift] = aligned[shift] and bool(np.all((low == 0) | (low == (1 << shift) - 1)))
    if peak <= ADC_COUNTS:
        return 1.0
    divisor = next((float(1 << shift) for shift in (16, 8) if aligned[shift]), 1.0)
    if peak / divisor > ADC_COUNTS:
        raise FileFormatError(
            f"{where}: channel {channel!r} holds 4-byte samples up to {peak / divisor:.0f} counts, beyond the 16-bit "
            f"ADC range ({ADC_COUNTS}) its V/LSB scale is for, and their low bits carry data: the scale of this "
            "NanoScope version is not known to afmforce; export the curves as NanoScope Analysis text")
    return divisor


def _triggered_approach(counts: list[int], defl: Mapping[str, str], n_curves: int, where: str) -> int | None:
    r"""Samples the approach recorded in a v5/v6 file whose ``Samps/line`` gives two unequal numbers
    (``\Samps/line: 1024 896``, NanoScope 6.13 PicoForce, relative trigger): each run has the first
    number of slots in the data (the deflection channel's ``Data length`` fits two runs of it, not
    the sum of the two numbers) and the approach, stopped at its trigger, filled only the second
    number of them from the turning point (the rest hold leftovers: -1 every other sample). The
    Z sensor of such files steps the same distance per sample on both runs (3.42-3.47 nm = Ramp size
    x Zsens / 1024). None where the numbers are equal or the data length is the sum's."""
    if len(counts) < 2 or not counts[1] < counts[0]:
        return None
    length = defl.get("Data length")
    if length is None or not re.search(_NUMBER, length):
        return None
    length = int(_number(length, where, "Data length"))

    def fits(per: int) -> bool:
        return length % (per * n_curves) == 0 and length // (per * n_curves) in (2, 4)
    return counts[1] if fits(2 * counts[0]) and not fits(counts[0] + counts[1]) else None


def _recorded(counts: np.ndarray, n_app: int, n_ret: int, app_recorded: int | None = None) -> np.ndarray:
    """False for the samples a run did not record, in storage order: a ramp stopped at its trigger
    leaves the far end of its run (stored last, from the turning point) at the ADC's most negative
    count, -32768 (Bruker's v8.15 force volume example: 14-174 such samples before the approach's first
    real one, -12.288 V, then -0.45 V). Only that trailing run of each run is dropped; a -32768 inside a
    run is a clipped sample and is kept. ``app_recorded``: the approach's recorded samples where the
    header says how many (v5/v6, :func:`_triggered_approach`); its slots after them are dropped."""
    keep = np.ones(counts.size, dtype=bool)
    if app_recorded is not None:
        keep[app_recorded:n_app] = False
    for start, stop in ((0, n_app), (n_app, n_app + n_ret)):
        run = counts[start:stop]
        filler = run == -ADC_COUNTS
        if filler.size and filler[-1]:
            n = int(np.argmin(filler[::-1])) if not filler.all() else filler.size
            if n < filler.size:  # a run of fillers alone is left to the checks that follow
                keep[stop - n:stop] = False
    return keep


def _refuse_ramp_script(sections, where: str) -> None:
    """A ramp-script file (``Use Ramp Script: Yes``: NanoScope's scripted segments, e.g. tip-bias sweeps
    at a held height, SECM approaches) stores the script's segments one after the other, not an
    approach and a retract of ``Samps/line`` points each: read as force curves its samples would be cut
    into curves that are not there. It is refused by name."""
    use = _find(sections, "Use Ramp Script", "Ciao force list")
    if use is None or not use.strip().lower().startswith("yes"):
        return
    kinds = [k.strip() for k in (_find(sections, "Segment Ramp Type", "Ciao force list") or "").split(",")]
    n = len([k for k in (_find(sections, "Segment Type", "Ciao force list") or "").split(",") if k.strip()])
    what = (f"{n} scripted segments (ramps: {', '.join(k or '-' for k in kinds[:n])})" if n
            else "Use Ramp Script: Yes")
    raise FileFormatError(f"{where}: a NanoScope ramp-script file ({what}): its data follow the script's segments, "
                          "not an approach and a retract, a layout afmforce does not read; export the ramps from "
                          "NanoScope Analysis as text (read by 'bruker-ascii')")


def _hold_samples(sections, defl: Mapping[str, str], per: int, n_curves: int, where: str) -> int:
    """The samples of a force hold (``Hold Samples``, the piezo stopped at the turning point for ``Hold
    Time``), stored after the approach and the retract of each curve; 0 without a hold, or when the
    deflection channel's length holds the two runs alone (2- or 4-byte samples)."""
    said = _find(sections, "Hold Samples", "Ciao force list")
    if said is None or not re.search(_NUMBER, said):
        return 0
    hold = int(_number(said, where, "Hold Samples"))
    length = defl.get("Data length")
    if hold <= 0 or length is None or not re.search(_NUMBER, length):
        return 0
    length = int(_number(length, where, "Data length"))
    fits = [length % (p * n_curves) == 0 and length // (p * n_curves) in (2, 4) for p in (per + hold, per)]
    return hold if fits[0] and not fits[1] else 0


def _sensor_note(zm: np.ndarray, zn: np.ndarray, seg: np.ndarray) -> str | None:
    """What the analysis says when the Z sensor (``zm`` [m], the measured position: counts x V/LSB x
    ZsensSens, Bruker's scale) spans the approach more than :data:`~afmforce.io._meta.SENSOR_RAMP_TOLERANCE`
    off the nominal ramp (``zn``: Ramp size x Zsens): :func:`~afmforce.io._meta.sensor_note` (a BioScope
    Catalyst's open-loop piezo: 1.12-1.19 x, then 1.23-1.42 x); None within it."""
    return sensor_note(zm, zn, seg, sensor="the Z sensor", nominal="Ramp size x Zsens",
                       used="the sensor (counts x V/LSB x ZsensSens)",
                       scales="the sensor's ZsensSens and the ramp's Zsens disagree")


def _truncation(rows: int, whole: int, volume: bool, size: int, where: str) -> str | None:
    """The one line that says a force volume's file ends before its last curve (``rows`` stated by the
    header, ``whole`` complete in the file): its complete curves are read, the rest are not (a cut
    curve's missing samples are never made up). None for a whole file; a single-curve file cut short,
    or a volume without one complete curve, is refused."""
    if whole == rows:
        return None
    if not volume or whole == 0:
        what = "its curve's data" if rows == 1 else f"the data of its first curve (of {rows})"
        raise FileFormatError(f"{where}: the file ({size} bytes) ends inside {what}; truncated: no complete curve "
                              "to read")
    return (f"the file ({size} bytes) ends inside curve {whole} of the force volume's {rows} (counted from 0): "
            f"truncated; curves 0-{whole - 1} read, curves {whole}-{rows - 1} not read")


@dataclass(frozen=True)
class _Layout:
    """Where a NanoScope force file's curves lie: the runs' samples, the channels read and how many
    curves the file holds whole (see :func:`_layout`)."""

    grid: tuple[int, int, float] | None
    app_recorded: int | None
    n_app: int
    n_ret: int
    n_hold: int
    per: int
    defl: dict
    zsen: dict | None
    d_place: tuple
    z_place: tuple | None
    whole: int
    truncated: str | None


def _layout(sections, size: int, where: str) -> _Layout:
    """The layout of the curves from the header and the file's ``size`` [bytes] (no sample read): the
    complete curves (``whole``; a force volume cut short keeps those, :func:`_truncation`)."""
    chans = _channels(sections)
    if not chans:
        raise FileFormatError(f"{where}: no '\\*Ciao force image list' (no curve data) in the header")
    _refuse_ramp_script(sections, where)
    samps = _find(sections, "Samps/line", "Ciao force list") or _find(sections, "Samps/line", "Ciao force image list")
    counts = [int(float(v)) for v in re.findall(_NUMBER, samps or "")]
    if not counts or min(counts) < 2 or max(counts) > 10**7:
        raise FileFormatError(f"{where}: NanoScope header 'Samps/line' missing or invalid ({samps!r})")
    n_app, n_ret = (counts[0], counts[1]) if len(counts) >= 2 else (counts[0], counts[0])
    defl = next((c for c in chans if "defl" in _channel_name(c).lower()), chans[0])
    zsen = next((c for c in chans if _channel_name(c).lower() in ("zsensor", "height sensor", "heightsensor")), None)

    grid = _grid(sections, where)
    n_curves = grid[0] * grid[1] if grid is not None else 1
    app_recorded = _triggered_approach(counts, defl, n_curves, where)
    if app_recorded is not None:  # v5/v6: two runs of Samps/line slots, the approach cut short
        n_app = n_ret = counts[0]
    n_hold = _hold_samples(sections, defl, n_app + n_ret, n_curves, where)
    per = n_app + n_ret + n_hold

    def place(entries) -> tuple[int, int, int, int, float, float]:
        """(offset, bytes per sample, curves the header states, complete curves in the file, V/LSB,
        sensitivity) of a channel."""
        offset = int(_number(entries.get("Data offset"), where, "Data offset"))
        length = int(_number(entries.get("Data length"), where, "Data length"))
        if length <= 0 or offset < 0 or offset >= size:
            raise FileFormatError(f"{where}: channel data ({length} bytes at {offset}) lies outside the file "
                                  f"({size} bytes); truncated or damaged")
        bpp = _sample_width(length, per, n_curves, entries, where)
        rows = length // (bpp * per)
        vlsb, sens, _ = _channel_scale(entries, sections, where)
        return offset, bpp, rows, min(rows, (size - offset) // (bpp * per)), vlsb, sens

    d_place = place(defl)
    rows, whole = d_place[2], d_place[3]
    z_place = place(zsen) if zsen is not None else None
    if z_place is not None and z_place[2] == rows:  # the Z sensor's curves are the deflection's
        whole = min(whole, z_place[3])
    truncated = _truncation(rows, whole, grid is not None, size, where)
    if grid is not None and rows < n_curves:  # the header's own data length holds fewer curves than the grid
        truncated = "; ".join(filter(None, [
            f"the deflection channel's data length holds {rows} of the {grid[0]} x {grid[1]} grid's {n_curves} "
            f"curves (a capture stopped early?): grid points {rows}-{n_curves - 1} have no curve", truncated]))
    z_ok = z_place is not None and z_place[2] == rows
    return _Layout(grid, app_recorded, n_app, n_ret, n_hold, per, defl, zsen if z_ok else None, d_place,
                   z_place if z_ok else None, whole, truncated)


class NanoscopeFile:
    """An open NanoScope force file whose curves are read one at a time (:meth:`curve`): a force
    volume of any size in the memory of one curve (the header is parsed once, each curve's samples
    are read from their place in the file). :func:`load_nanoscope` reads every curve through it."""

    def __init__(self, path: Path, meta_override: Mapping[str, Any] | None = None) -> None:
        path = Path(path)
        where = self.where = str(path)
        try:
            self._fh = open(path, "rb")
            size = path.stat().st_size
            head = self._fh.read(MAX_HEADER + 64)
        except OSError as exc:
            raise FileFormatError(f"{where}: cannot read ({exc})") from None
        try:
            self._open(head, size, meta_override)
        except BaseException:
            self._fh.close()
            raise

    def _open(self, head: bytes, size: int, meta_override) -> None:
        where = self.where
        sections = parse_header(head, where)
        lay = _layout(sections, size, where)
        self._grid = lay.grid
        self._app_recorded = lay.app_recorded
        n_app, n_ret, n_hold, per, defl, zsen, whole, truncated = (lay.n_app, lay.n_ret, lay.n_hold, lay.per,
                                                                   lay.defl, lay.zsen, lay.whole, lay.truncated)
        d_off, d_bpp, _, _, d_vlsb, _ = lay.d_place
        z_place = lay.z_place
        self._defl = (d_off, d_bpp, self._divisor(d_off, d_bpp, whole * per, _channel_name(defl), d_vlsb), d_vlsb)
        self._zsen = None
        if z_place is not None:
            z_off, z_bpp, _, _, z_vlsb, z_sens = z_place
            self._zsen = (z_off, z_bpp, self._divisor(z_off, z_bpp, whole * per, _channel_name(zsen), z_vlsb),
                          z_vlsb, z_sens)
        self.n_curves, self._n = whole, (n_app, n_ret, n_hold)
        meta: dict[str, Any] = {"instrument": _find(sections, "Microscope") or "Bruker NanoScope",
                                "nanoscope_version": _find(sections, "Version") or ""}
        if truncated:
            meta["file_truncated"] = truncated
        k = _find([("", defl)], "Spring Constant") or _find(sections, "Spring Constant")  # the deflection's list
        if k is not None:  # as stated: finalize_curve refuses an impossible one (<= 0), as every reader does
            meta["spring_constant"] = _number(k, where, "Spring Constant")
            note = _other_spring_constants(sections, defl, meta["spring_constant"])
            if note:
                meta["spring_constant_note"] = note
        sens = _sens(sections, "DeflSens") or _sens(sections, "Deflection")
        if sens is not None and sens[0] > 0:
            meta["sensitivity"] = sens[0] * 1e-9  # [nm/V]
        tip = _find(sections, "Tip Radius", "Ciao scan list")  # [nm], as typed into NanoScope
        if tip is not None and re.search(_NUMBER, tip) and _number(tip, where, "Tip Radius", 0) > 0:
            meta["radius"] = _number(tip, where, "Tip Radius", 0) * 1e-9
        nu = sample_poisson(sections)
        if nu is not None:
            meta["poisson"] = nu
        corr = _find(sections, "Deflection Sensitivity Correction")
        if corr is not None:
            meta["nanoscope_deflection_sensitivity_correction"] = _number(corr, where, "Deflection Sensitivity Correction")
        zsens = _sens(sections, "Zsens") or _sens(sections, "Zscan")
        ramp = defl.get("4:Ramp Size") or defl.get("Ramp Size") or _find(sections, "4:Ramp Size Zsweep")
        if zsens is None or ramp is None:
            raise FileFormatError(f"{where}: NanoScope header lacks the Z sensitivity or the ramp size")
        ramp_m = _number(ramp, where, "Ramp Size") * zsens[0] * 1e-9  # [V] x [nm/V]
        if not (0 < ramp_m < 1e-3):
            raise FileFormatError(f"{where}: ramp size {ramp_m!r} m is not plausible; damaged header")
        fwd, rev = _find(sections, "Forward vel."), _find(sections, "Reverse vel.")
        if fwd is not None and rev is not None and _number(fwd, where, "Forward vel.") > 0 \
                and _number(rev, where, "Reverse vel.") > 0:
            v_app = _number(fwd, where, "Forward vel.") * zsens[0] * 1e-9  # [V/s] x [nm/V]
            v_ret = _number(rev, where, "Reverse vel.") * zsens[0] * 1e-9
        else:
            rate = _number(_find(sections, "Scan rate"), where, "Scan rate")
            if not rate > 0:
                raise FileFormatError(f"{where}: no velocity and no scan rate in the header")
            v_app = v_ret = 2 * ramp_m * rate
        meta.update(velocity=v_app, retract_velocity=v_ret, sample_rate=v_app * n_app / ramp_m,
                    adc_range=ADC_COUNTS * d_vlsb)  # [V]: the deflection channel's 16-bit ADC
        dt_app, dt_ret = ramp_m / (v_app * n_app), ramp_m / (v_ret * n_ret)
        hold_time = _find(sections, "Hold Time", "Ciao force list")
        dt_hold = dt_app
        if n_hold:  # a force hold: the piezo stops at the turning point for Hold Time [s]
            t_hold = _number(hold_time, where, "Hold Time") if hold_time is not None else math.nan
            dt_hold = t_hold / n_hold if t_hold > 0 else dt_app
            meta.update(segment_types=["extend", "hold", "retract"])
        t_ret0 = dt_app * n_app + dt_hold * n_hold
        self._time = np.concatenate([dt_app * np.arange(n_app), dt_app * n_app + dt_hold * np.arange(n_hold),
                                     t_ret0 + dt_ret * np.arange(n_ret)])
        z_app = np.linspace(0.0, ramp_m, n_app, endpoint=False) + ramp_m / n_app  # towards the sample
        z_ret = ramp_m - np.arange(n_ret) * (ramp_m / n_ret)
        self._z = np.concatenate([z_app, np.full(n_hold, ramp_m), z_ret])
        self._seg = np.concatenate([np.zeros(n_app, np.int8), np.full(n_hold, 2, np.int8), np.ones(n_ret, np.int8)])
        meta.update(dict(meta_override or {}))
        meta.update(source_file=where, reader="bruker-nanoscope", format="Bruker NanoScope binary force file",
                    position_sign=1.0)
        self._meta = meta

    def _samples(self, offset: int, bpp: int, first: int, count: int) -> np.ndarray:
        self._fh.seek(offset + first * bpp)
        raw = self._fh.read(count * bpp)
        if len(raw) != count * bpp:
            raise FileFormatError(f"{self.where}: the file ends inside its curve data; truncated")
        return np.frombuffer(raw, dtype=f"<i{bpp}")

    def _divisor(self, offset: int, bpp: int, total: int, channel: str, vlsb: float | None = None) -> float:
        step = 2**22  # samples per chunk: the decision sees every sample, in bounded memory
        chunks = (self._samples(offset, bpp, i, min(step, total - i)) for i in range(0, total, step))
        return _adc_shift(chunks, bpp, channel, self.where, vlsb)

    def __len__(self) -> int:
        return self.n_curves

    def curve(self, i: int) -> RawCurve:
        """Curve ``i`` (in file order: row by row in a force volume)."""
        if not 0 <= i < self.n_curves:
            raise FileFormatError(f"{self.where}: no curve {i} (the file holds {self.n_curves})")
        n_app, n_ret, n_hold = self._n
        per = n_app + n_ret + n_hold

        def in_time_order(x: np.ndarray) -> np.ndarray:
            """Stored: the approach and the retract from the turning point, then a force hold's samples."""
            return np.concatenate([x[:n_app][::-1], x[n_app + n_ret:], x[n_app:n_app + n_ret]])

        off, bpp, div, vlsb = self._defl
        counts = self._samples(off, bpp, i * per, per).astype(float) / div
        volts = counts * vlsb
        signal = in_time_order(volts)
        keep = in_time_order(_recorded(counts, n_app, n_ret, self._app_recorded))
        zm = None
        if self._zsen is not None:
            off, bpp, div, vlsb, sens = self._zsen
            zr = self._samples(off, bpp, i * per, per).astype(float) / div * vlsb * sens
            zm = in_time_order(zr)
            first = int(np.argmax(keep[:n_app]))  # the approach's first recorded sample (not a filler slot)
            if zm[n_app - 1] < zm[first]:
                zm = -zm
        meta = {**self._meta, "curve_index": i, **_grid_point(self._grid, i)} if self.n_curves > 1 \
            else dict(self._meta)
        if zm is not None:
            note = _sensor_note(zm[keep], self._z[keep], self._seg[keep])
            if note:
                meta["position_note"] = note
        if not keep.all():  # a triggered ramp's unrecorded samples (-32768 fillers) are no data
            meta["unrecorded_samples"] = int((~keep).sum())
        curve = RawCurve(time=self._time[keep], piezo_nominal=self._z[keep],
                         piezo_measured=None if zm is None else zm[keep], deflection_signal=signal[keep],
                         segment=self._seg[keep], metadata=meta, deflection_unit="V")
        return finalize_curve(curve, self.where)

    def close(self) -> None:
        self._fh.close()

    def __enter__(self) -> "NanoscopeFile":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def load_nanoscope(path: Path, *, meta_override: Mapping[str, Any] | None = None,
                   callback: Callable | None = None) -> list[RawCurve]:
    """Read every force curve of a NanoScope binary force file (see module docstring)."""
    with NanoscopeFile(path, meta_override) as f:
        out = []
        for i in range(len(f)):
            out.append(f.curve(i))
            if callback is not None:
                callback((i + 1) / len(f))
    return out
