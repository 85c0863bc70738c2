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
from ._units import units_of

__all__ = ["AnalysisResult", "SUMMARY_FIELDS"]

#: Summary fields shown in tables: (attribute, label, SI unit).
SUMMARY_FIELDS: tuple[tuple[str, str, str], ...] = (
    ("sensitivity_used", "sensitivity used (the forces'; calibration source says which)", "m/V"),
    ("sensitivity", "sensitivity (file or user)", "m/V"),
    ("sensitivity_fit", "sensitivity from the compliance slope", "m/V"),
    ("spring_constant", "spring constant", "N/m"),
    ("adhesion_force", "adhesion (deepest retract dip)", "N"),
    ("adhesion_distance", "adhesion position from contact", "m"),
    ("rupture_distance", "last rupture from contact", "m"),
    ("indentation", "indentation (soft contact)", "m"),
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
    ("force_gradient", "force gradient at contact", "N/m"),
    ("inertia_parameter", "inertia parameter", ""),
    ("youngs_modulus", "Young's modulus (indentation fit)", "Pa"),
    ("youngs_modulus_se", "its standard error", "Pa"),
    ("contact_point", "contact point (indentation fit; piezo position)", "m"),
    ("work_of_adhesion", "work of adhesion (JKR, DMT, Maugis fit)", "J/m^2"),
    ("drag_offset", "drag offset (approach - retract far out; liquid)", "m"),
    ("lever_drag", "lever drag (liquid)", "N s/m"),
    ("surface_potential", "surface potential (DLVO fit)", "V"),
    ("debye_length", "Debye length (DLVO fit)", "m"),
    ("dlvo_hamaker", "Hamaker constant (DLVO fit)", "J"),
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
    contact_kind : str
        ``"hard"`` (jump-in, or a straight compliance line), ``"soft"`` (curved: the
        tip indents) or ``"none"`` (no contact reached); the steps that fit it ran.
    contact_kind_reason : str
        The evidence for the kind, with its numbers.
    not_applicable : mapping
        Step -> why it did not apply to this curve (e.g. the van der Waals fit on a soft contact).
    sensitivity : float
        Deflection sensitivity (InvOLS) the file or the user gives [m/V] (NaN if none).
    sensitivity_fit : float
        Sensitivity implied by the constant-compliance slope [m/V] (rigid contact assumed).
    calibration_source : str
        ``"metadata"`` (the file's or user's calibration) or ``"fit"`` (the compliance slope).
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
    adhesion_force : float
        Deepest retract force below the retract's own baseline [N], always <= 0; NaN
        unless it exceeds the stated multiple of the noise (every contact kind).
    adhesion_deflection : float  the same as a deflection [m]
    adhesion_distance : float  its distance from the contact point [m]
    adhesion_noise : float  baseline noise of the retract [N]
    rupture_distance : float  distance from contact of the last rupture [m]
    unbinding_steps : int  unbinding steps found between the deepest point and the last rupture [-]
    adhesion_verdict : str  plain words with the numbers
    indentation : float  soft contact: indentation at the turning point [m]
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
    oscillation_verdict : str
        Plain words with the false-alarm probabilities of both runs.
    velocity : float
        Approach speed [m/s].
    force_gradient : float
        Measured |dF/dh| where the tip meets the surface [N/m].
    resonance_frequency : float
        Used for eq 3 [Hz] (from the file or the user).
    inertia_parameter : float
        eq 3 at contact [-].
    friction : str
        Friction signature of the compliance lines (``"not assessed"`` unless the contact is
        hard with straight lines in both runs).
    friction_verdict : str
        Plain words, with the reason when not assessed.
    dynamic : bool
        The run is flagged as dynamic (the static fit is not trustworthy).
    dynamic_assessed : bool
        The diagnosis had the evidence to judge (see :class:`~.dynamic.DynamicDiagnosis`);
        False: ``dynamic`` False means "not assessed", not "quasi-static".
    verdict : str
        Plain-words dynamic diagnosis.
    indentation_model : str
        Key of the indentation model fitted (docs/contact.md; empty if none).
    youngs_modulus, youngs_modulus_se : float
        Young's modulus of a soft contact and its standard error [Pa].
    youngs_modulus_low, youngs_modulus_high : float
        Its 95 % interval [Pa].
    contact_point : float
        Piezo position at contact from the indentation fit [m].
    work_of_adhesion, work_of_adhesion_se : float
        w from an adhesive model (JKR, DMT, Maugis) [J/m^2].
    drag_offset, lever_drag : float
        Liquid curves (step ``liquid``): approach minus retract far-field deflection [m] and the
        lever drag from it and the speed [N s/m].
    surface_potential, surface_potential_se, debye_length, debye_length_se, dlvo_hamaker, dlvo_hamaker_se : float
        The DLVO fit of the static force: psi [V], 1/kappa [m], A [J] and standard errors.
    warnings : tuple of str
    time, position, separation, deflection, force : ndarray
        Per sample [s], [m], [m], [m], [N].
    segment : ndarray of int8
        0 approach, 1 retract, 2 dwell.
    details : mapping
        Step identifier -> that step's result dataclass; its fields' units are their
        metadata (JSON: ``details_units``, the raw signal's unit filled in).
    """

    source: str
    steps_run: tuple[str, ...]
    deflection_unit: str
    position_channel: str
    contact_kind: str = ""
    contact_kind_reason: str = ""
    sensitivity: float = math.nan
    sensitivity_fit: float = math.nan
    calibration_source: str = ""
    spring_constant: float = math.nan
    adhesion_force: float = math.nan
    adhesion_deflection: float = math.nan
    adhesion_distance: float = math.nan
    adhesion_noise: float = math.nan
    rupture_distance: float = math.nan
    unbinding_steps: int = 0
    adhesion_verdict: str = ""
    indentation: float = math.nan
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
    oscillation_verdict: str = ""
    velocity: float = math.nan
    force_gradient: float = math.nan
    resonance_frequency: float = math.nan
    inertia_parameter: float = math.nan
    friction: str = ""
    friction_verdict: str = ""
    dynamic: bool = False
    dynamic_assessed: bool = False
    verdict: str = ""
    indentation_model: str = ""
    youngs_modulus: float = math.nan
    youngs_modulus_se: float = math.nan
    youngs_modulus_low: float = math.nan
    youngs_modulus_high: float = math.nan
    contact_point: float = math.nan
    work_of_adhesion: float = math.nan
    work_of_adhesion_se: float = math.nan
    drag_offset: float = math.nan
    lever_drag: float = math.nan
    surface_potential: float = math.nan
    surface_potential_se: float = math.nan
    debye_length: float = math.nan
    debye_length_se: float = math.nan
    dlvo_hamaker: float = math.nan
    dlvo_hamaker_se: float = math.nan
    warnings: tuple[str, ...] = ()
    not_applicable: Mapping[str, str] = field(default_factory=dict)
    time: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    position: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    separation: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    deflection: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    force: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    segment: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int8), repr=False)
    details: Mapping[str, Any] = field(default_factory=dict, repr=False)

    ARRAYS = ("time", "position", "separation", "deflection", "force", "segment")
    UNITS = {"sensitivity": "m/V", "sensitivity_fit": "m/V", "sensitivity_used": "m/V", "spring_constant": "N/m", "adhesion_force": "N",
             "adhesion_deflection": "m", "adhesion_distance": "m", "adhesion_noise": "N", "rupture_distance": "m",
             "unbinding_steps": "", "indentation": "m", "force_gradient": "N/m", "resonance_frequency": "Hz",
             "shift": "m", "contact_separation": "m", "jump_in_separation": "m", "jump_in_force": "N",
             "jump_in_deflection": "m", "contact_onset_separation": "m", "pull_off_force": "N",
             "pull_off_force_extrapolated": "N", "pull_off_position": "m",
             "jump_out_distance": "m", "surface_energy": "J/m^2", "radius": "m", "hamaker_radius": "J m",
             "hamaker_radius_se": "J m", "hamaker": "J", "hamaker_se": "J", "oscillation_frequency": "Hz",
             "velocity": "m/s", "inertia_parameter": "", "youngs_modulus": "Pa", "youngs_modulus_se": "Pa",
             "youngs_modulus_low": "Pa", "youngs_modulus_high": "Pa", "contact_point": "m",
             "work_of_adhesion": "J/m^2", "work_of_adhesion_se": "J/m^2", "drag_offset": "m", "lever_drag": "N s/m",
             "surface_potential": "V", "surface_potential_se": "V", "debye_length": "m", "debye_length_se": "m",
             "dlvo_hamaker": "J", "dlvo_hamaker_se": "J", "time": "s", "position": "m", "separation": "m",
             "deflection": "m", "force": "N"}

    def to_dict(self, arrays: bool = False) -> dict[str, Any]:
        """JSON-ready dict (NaN -> None); the per-sample arrays only if ``arrays``."""
        out: dict[str, Any] = {}
        for f in dataclasses.fields(self):
            if f.name in self.ARRAYS and not arrays:
                continue
            out[f.name] = to_jsonable(getattr(self, f.name), use_to_dict=False)
        out["sensitivity_used"] = to_jsonable(self.sensitivity_used, use_to_dict=False)
        out["units"] = dict(self.UNITS)
        out["details_units"] = {step: units_of(d, self.deflection_unit) for step, d in self.details.items()}
        return out

    @property
    def sensitivity_used(self) -> float:
        """The sensitivity the forces were computed with [m/V]: ``sensitivity_fit`` when
        ``calibration_source`` is ``"fit"``, else ``sensitivity`` (NaN if none)."""
        return self.sensitivity_fit if self.calibration_source == "fit" else self.sensitivity

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
        rows.append(("contact kind", f"{self.contact_kind or '-'}: {self.contact_kind_reason}", ""))
        for attr, label, unit in SUMMARY_FIELDS:
            rows.append((label, getattr(self, attr), unit))
        rows.append(("adhesion", self.adhesion_verdict or "-", ""))
        rows.append(("oscillation", self.oscillation_verdict or "-", ""))
        rows.append(("friction", f"{self.friction or '-'}: {self.friction_verdict}", ""))
        rows.append(("diagnosis", self.verdict or "-", ""))
        return rows
