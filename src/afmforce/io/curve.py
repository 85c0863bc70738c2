"""The raw force curve: what an instrument records (or the virtual AFM emulates).

A :class:`RawCurve` is the common currency between the virtual AFM
(:mod:`afmforce.instrument`), the file readers (:mod:`afmforce.io`) and the
analysis pipeline (:mod:`afmforce.analysis.pipeline`).

Conventions (spec section 1)
----------------------------
* ``piezo_nominal`` and ``piezo_measured`` are the substrate position z [m],
  increasing as the substrate moves *towards* the probe (the inward run,
  ``segment == 0``, has z increasing). Readers of vendor files convert their
  height/Z channels to this convention.
* ``deflection_signal`` is the photodiode signal in ``deflection_unit``:
  ``"V"`` (raw volts), ``"m"`` (a deflection already calibrated by the
  instrument) or ``"N"`` (a force; some vendors store only force). Positive
  deflection is *up* (away from the substrate); an attraction gives a negative
  deflection.
* ``segment`` is 0 on the inward (approach) run and 1 on the outward
  (retract) run; a dwell, if any, carries 2.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Mapping

import numpy as np

from ..errors import AnalysisError, FileFormatError
from .deflection import signal_factor
from .._fields import ANALYSIS_CHOICES

__all__ = ["RawCurve", "SEGMENT_APPROACH", "SEGMENT_RETRACT", "SEGMENT_DWELL", "DEFLECTION_UNITS",
           "POSITION_CHANNELS"]

SEGMENT_APPROACH = 0
SEGMENT_RETRACT = 1
SEGMENT_DWELL = 2
DEFLECTION_UNITS = ("V", "m", "N")
#: The position channels one may ask for: ``auto`` is the measured one when recorded, else the nominal.
POSITION_CHANNELS = ANALYSIS_CHOICES["channel"].choices     # declared once with its help (afmforce._fields)


@dataclass(frozen=True)
class RawCurve:
    """One force curve as recorded.

    Attributes
    ----------
    time : ndarray
        Time since the start of the curve [s].
    piezo_nominal : ndarray
        Commanded substrate position z (piezo voltage times its nominal gain) [m].
    piezo_measured : ndarray or None
        Position read by the scanner's position detector [m], if the instrument has one.
    deflection_signal : ndarray
        Photodiode signal [V], or deflection [m], or force [N]: see ``deflection_unit``.
    segment : ndarray of int8
        0 inward (approach), 1 outward (retract), 2 dwell.
    metadata : mapping
        SI values with keys such as ``spring_constant`` [N/m], ``sensitivity``
        [m/V] (InvOLS), ``velocity`` [m/s], ``sample_rate`` [Hz], ``instrument``,
        ``source_file``. Unknown keys are kept.
    truth : mapping or None
        Ground truth for simulated curves (arrays and values of the underlying
        trajectory and instrument); ``None`` for measured curves.
    deflection_unit : str
        ``"V"``, ``"m"`` or ``"N"``.
    """

    time: np.ndarray
    piezo_nominal: np.ndarray
    deflection_signal: np.ndarray
    segment: np.ndarray
    piezo_measured: np.ndarray | None = None
    metadata: Mapping[str, Any] = field(default_factory=dict)
    truth: Mapping[str, Any] | None = None
    deflection_unit: str = "V"

    def __post_init__(self) -> None:
        n = len(self.time)
        cols = {"time": self.time, "piezo_nominal": self.piezo_nominal,
                "deflection_signal": self.deflection_signal, "segment": self.segment}
        if self.piezo_measured is not None:
            cols["piezo_measured"] = self.piezo_measured
        for name, col in cols.items():
            arr = np.asarray(col)
            if arr.ndim != 1 or len(arr) != n:
                raise FileFormatError(
                    f"column {name!r} has shape {arr.shape}, expected ({n},) like 'time'")
        if n < 2:
            raise FileFormatError("a force curve needs at least two samples")
        if self.deflection_unit not in DEFLECTION_UNITS:
            raise FileFormatError(
                f"deflection_unit must be one of {DEFLECTION_UNITS}, got {self.deflection_unit!r}")

    def __len__(self) -> int:
        return len(self.time)

    @property
    def approach(self) -> np.ndarray:
        """Boolean mask of the inward (approach) samples."""
        return np.asarray(self.segment) == SEGMENT_APPROACH

    @property
    def retract(self) -> np.ndarray:
        """Boolean mask of the outward (retract) samples."""
        return np.asarray(self.segment) == SEGMENT_RETRACT

    def position_channel(self, channel: str = "auto") -> str:
        """The position channel a request reads: ``"measured"`` or ``"nominal"``.

        Parameters
        ----------
        channel : str
            ``"auto"`` (the measured position when the curve has one, else the nominal),
            ``"measured"`` or ``"nominal"``.

        Raises
        ------
        AnalysisError
            An unknown channel, or ``"measured"`` for a curve without a measured position.
        """
        if channel not in POSITION_CHANNELS:
            raise AnalysisError(f"position channel must be auto, measured or nominal, got {channel!r}")
        if channel == "measured" and self.piezo_measured is None:
            raise AnalysisError("the curve has no measured position channel; use the nominal one")
        return "measured" if self.piezo_measured is not None and channel != "nominal" else "nominal"

    def position(self, channel: str = "auto") -> np.ndarray:
        """The substrate position z of :meth:`position_channel` ``(channel)`` [m] (the column
        itself, not a copy)."""
        return np.asarray(self.piezo_measured if self.position_channel(channel) == "measured"
                          else self.piezo_nominal)

    def deflection_factor(self, sensitivity: float | None = None, spring_constant: float | None = None) -> float:
        """Deflection per unit of ``deflection_signal`` [m/V, 1 or m/N]: the sensitivity (InvOLS)
        [m/V] for volts, 1 for metres, 1/k [m/N] for newtons.

        ``sensitivity`` [m/V] and ``spring_constant`` [N/m] default to the curve's metadata;
        NaN when the one the unit needs is unknown (None, 0 or missing).
        """
        md = self.metadata or {}
        return signal_factor(self.deflection_unit,
                             sensitivity if sensitivity is not None else md.get("sensitivity"),
                             spring_constant if spring_constant is not None else md.get("spring_constant"))

    def force_factor(self, sensitivity: float | None = None, spring_constant: float | None = None) -> float:
        """Force per unit of ``deflection_signal`` [N/V, N/m or 1]: sensitivity x k for volts, k for
        metres, 1 for newtons (defaults and NaN as :meth:`deflection_factor`)."""
        md = self.metadata or {}
        return signal_factor(self.deflection_unit,
                             sensitivity if sensitivity is not None else md.get("sensitivity"),
                             spring_constant if spring_constant is not None else md.get("spring_constant"),
                             to="force")
