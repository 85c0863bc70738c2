"""The result of analysing one force curve: numbers with units, arrays, step details."""

from __future__ import annotations

import dataclasses
import io
import json
import math
import os
from dataclasses import dataclass, field
from typing import Any, Mapping

import numpy as np

from .._files import atomic_write_text
from .._json import to_jsonable

__all__ = ["AnalysisResult", "SUMMARY_FIELDS"]

#: Summary fields shown in tables: (attribute, label, SI unit).
SUMMARY_FIELDS: tuple[tuple[str, str, str], ...] = (
    ("calibration_factor", "calibration factor", "m/V"),
    ("spring_constant", "spring constant", "N/m"),
    ("shift", "inward shift", "m"),
    ("jump_in_separation", "jump-in separation", "m"),
    ("jump_in_force", "jump-in force", "N"),
    ("contact_onset_separation", "contact onset separation", "m"),
    ("pull_off_force", "pull-off force", "N"),
    ("pull_off_force_extrapolated", "pull-off force (extrapolated past clipping)", "N"),
    ("pull_off_position", "pull-off position", "m"),
    ("jump_out_distance", "jump-out distance", "m"),
    ("surface_energy", "surface energy", "J/m^2"),
    ("radius", "radius", "m"),
    ("hamaker_radius", "A R", "J m"),
    ("hamaker", "Hamaker constant", "J"),
    ("oscillation_frequency", "oscillation", "Hz"),
    ("velocity", "approach speed", "m/s"),
    ("inertia_parameter", "inertia parameter", ""),
)


@dataclass(frozen=True)
class AnalysisResult:
    """Analysis of one force curve (SI units; NaN where a step did not run or found nothing).

    Attributes
    ----------
    source : str
        File (or description) of the curve.
    steps_run : tuple of str
        Identifiers of the steps that ran, in order.
    deflection_unit : str
        Unit of the raw deflection signal (``"V"``, ``"m"``, ``"N"``).
    position_channel : str
        ``"measured"`` or ``"nominal"``.
    calibration_factor : float
        Deflection per signal unit used [m/V] (m/m or m/N for other units).
    calibration_factor_fit : float
        From the constant-compliance slope [m/V].
    spring_constant : float
        Force-measuring spring constant used [N/m].
    shift : float
        Shift of the inward run that overlays the compliance lines [m].
    contact_separation : float
        Separation given to the compliance line [m].
    jump_in_separation : float
        Separation just before the jump into contact [m] (NaN without a significant jump).
    jump_in_force : float
        Force the tip jumps to, relative to the baseline [N].
    jump_in_deflection : float
        Deflection the tip jumps to [m].
    contact_onset_separation : float
        Separation at the last sample before contact, jump or not [m] (a tip that
        creeps in, or jumps by less than the noise, has only this).
    pull_off_force : float
        Most negative force before pull-off, relative to the baseline [N]; a lower
        bound when ``pull_off_saturated``.
    pull_off_saturated : bool
        The photodiode clipped the bottom of the pull-off.
    pull_off_force_extrapolated : float
        With a clipped pull-off: the compliance line extrapolated to the pull-off
        position, times k [N] (NaN otherwise).
    pull_off_position : float
        Position at pull-off relative to contact [m].
    jump_out_distance : float
        |deflection| at pull-off [m].
    surface_energy : float
        gamma from the pull-off and the given radius [J/m^2].
    radius : float
        R from the jump-out distance and gamma = A/(16 pi z0^2) [m].
    hamaker_radius, hamaker_radius_se : float
        van der Waals fit A R and its standard error [J m].
    hamaker, hamaker_se : float
        A for a given R [J].
    oscillation_frequency : float
        Post-contact oscillation (approach run, else retract) [Hz].
    velocity : float
        Approach speed [m/s].
    inertia_parameter : float
        eq 3 at jump-in [-].
    friction : str
        Friction signature of the compliance lines.
    dynamic : bool
        The run is flagged as dynamic (the static fit is not trustworthy).
    verdict : str
        Plain-words dynamic diagnosis.
    warnings : tuple of str
    time, position, separation, deflection, force : ndarray
        Per sample [s], [m], [m], [m], [N].
    segment : ndarray of int8
        0 approach, 1 retract, 2 dwell.
    details : mapping
        Step identifier -> that step's result dataclass.
    """

    source: str
    steps_run: tuple[str, ...]
    deflection_unit: str
    position_channel: str
    calibration_factor: float = math.nan
    calibration_factor_fit: float = math.nan
    spring_constant: float = math.nan
    shift: float = math.nan
    contact_separation: float = math.nan
    jump_in_separation: float = math.nan
    jump_in_force: float = math.nan
    jump_in_deflection: float = math.nan
    contact_onset_separation: float = math.nan
    pull_off_force: float = math.nan
    pull_off_saturated: bool = False
    pull_off_force_extrapolated: float = math.nan
    pull_off_position: float = math.nan
    jump_out_distance: float = math.nan
    surface_energy: float = math.nan
    radius: float = math.nan
    hamaker_radius: float = math.nan
    hamaker_radius_se: float = math.nan
    hamaker: float = math.nan
    hamaker_se: float = math.nan
    oscillation_frequency: float = math.nan
    velocity: float = math.nan
    inertia_parameter: float = math.nan
    friction: str = ""
    dynamic: bool = False
    verdict: str = ""
    warnings: tuple[str, ...] = ()
    time: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    position: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    separation: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    deflection: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    force: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    segment: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int8), repr=False)
    details: Mapping[str, Any] = field(default_factory=dict, repr=False)

    ARRAYS = ("time", "position", "separation", "deflection", "force", "segment")
    UNITS = {"calibration_factor": "m/V", "calibration_factor_fit": "m/V", "spring_constant": "N/m",
             "shift": "m", "contact_separation": "m", "jump_in_separation": "m", "jump_in_force": "N",
             "jump_in_deflection": "m", "contact_onset_separation": "m", "pull_off_force": "N",
             "pull_off_force_extrapolated": "N", "pull_off_position": "m",
             "jump_out_distance": "m", "surface_energy": "J/m^2", "radius": "m", "hamaker_radius": "J m",
             "hamaker_radius_se": "J m", "hamaker": "J", "hamaker_se": "J", "oscillation_frequency": "Hz",
             "velocity": "m/s", "inertia_parameter": "", "time": "s", "position": "m", "separation": "m",
             "deflection": "m", "force": "N"}

    def to_dict(self, arrays: bool = False) -> dict[str, Any]:
        """JSON-ready dict (NaN -> None); the per-sample arrays only if ``arrays``."""
        out: dict[str, Any] = {}
        for f in dataclasses.fields(self):
            if f.name in self.ARRAYS and not arrays:
                continue
            out[f.name] = to_jsonable(getattr(self, f.name), use_to_dict=False)
        units = dict(self.UNITS)
        if self.deflection_unit != "V":
            units["calibration_factor"] = units["calibration_factor_fit"] = f"m/{self.deflection_unit}"
        out["units"] = units
        return out

    def to_json(self, arrays: bool = False, indent: int | None = 2) -> str:
        """The result as JSON text (SI values, units under ``"units"``)."""
        return json.dumps(self.to_dict(arrays=arrays), indent=indent, allow_nan=False)

    def table_csv(self) -> str:
        """Force against separation, one row per sample, units in the header."""
        buf = io.StringIO()
        buf.write("# afmforce force-vs-separation table; source: " + self.source.replace("\n", " ") + "\n")
        buf.write("segment,time [s],position [m],separation [m],deflection [m],force [N]\n")
        cols = [self.time, self.position, self.separation, self.deflection, self.force]
        for i in range(len(self.segment)):
            vals = ",".join("" if not math.isfinite(c[i]) else repr(float(c[i])) for c in cols)
            buf.write(f"{int(self.segment[i])},{vals}\n")
        return buf.getvalue()

    def write_table(self, path: str | os.PathLike, force: bool = True) -> None:
        """Write :meth:`table_csv` atomically."""
        atomic_write_text(path, self.table_csv(), force=force)

    def summary_rows(self) -> list[tuple[str, Any, str]]:
        """``(label, SI value, unit)`` rows for a printed summary."""
        rows = []
        for attr, label, unit in SUMMARY_FIELDS:
            if attr == "calibration_factor" and self.deflection_unit != "V":
                unit = f"m/{self.deflection_unit}"
            rows.append((label, getattr(self, attr), unit))
        rows.append(("friction", self.friction or "-", ""))
        rows.append(("diagnosis", self.verdict or "-", ""))
        return rows
