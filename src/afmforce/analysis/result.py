"""The result of analysing one force curve: numbers with units, arrays, step details."""

from __future__ import annotations

import dataclasses
import io
import json
import math
import os
from dataclasses import dataclass, field
from typing import Any, ClassVar, Mapping

import numpy as np

from .._files import atomic_write_text
from .._json import to_jsonable
from ._units import units_of
from .registry import LiveDict, LiveTuple, result_fields

__all__ = ["AnalysisResult", "SUMMARY_FIELDS"]

def _summary_fields() -> tuple[tuple[str, str, str], ...]:
    return tuple((f.name, f.label, f.unit or "") for f in result_fields().values() if f.summary)


#: Summary fields shown in tables: (attribute, label, SI unit), from the steps' records
#: (:mod:`.registry`: the result fields marked ``summary``), in the pipeline's order.
SUMMARY_FIELDS: LiveTuple = LiveTuple(_summary_fields)

#: SI units of the per-sample arrays.
_ARRAY_UNITS = {"time": "s", "position": "m", "separation": "m", "deflection": "m", "force": "N"}


def _units() -> dict[str, str]:
    return {**{f.name: f.unit for f in result_fields().values() if f.unit is not None}, **_ARRAY_UNITS}


@dataclass(frozen=True, init=False)
class AnalysisResult:
    """Analysis of one force curve (SI units; NaN where a step did not run or found nothing).

    The fields after ``position_channel`` are the steps' (each declared by its step's record,
    :mod:`.registry`; ``UNITS`` and :data:`SUMMARY_FIELDS` come from there): they are attributes
    (``res.hamaker``), held in :attr:`values`, and take their declared default when their step
    did not fill them. Those of the built-in steps:

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
    sensitivity_used : float
        The sensitivity the forces were computed with [m/V]: ``sensitivity_fit`` when
        ``calibration_source`` is ``"fit"``, else ``sensitivity`` (computed, not stored).
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
    barrier_force : float
        A jump-in through a repulsive barrier (it starts at a repulsive force the approach rose to,
        a double layer's in liquid): the force at its start, the barrier's height [N] (NaN otherwise).
    barrier_jump_distance : float
        How far the tip jumps through that barrier, the deflection's fall [m] (NaN otherwise).
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
    adhesion_significance : float  the deepest retract dip in baseline noise sigmas, also under the threshold [-]
    adhesion_baseline_spread : float  the baseline model's systematic on ``adhesion_force`` (+-) [N]
    adhesion_return_distance : float  soft contact: where the retract comes back to its baseline for good [m]
        (``rupture_distance`` only when that return is a step; a gradual return is no rupture)
    rupture_distance : float
        Distance from contact of the last rupture [m]; on a hard contact its tip--sample separation
        (the pull-off's, about 0, when no tether holds the tip).
    unbinding_steps : int
        Unbinding steps found between the deepest point and the last rupture [-]; on a hard contact every
        rupture after the pull-off.
    tethers : int  hard contact: tethers pulled after the tip left the surface (details: ``adhesion.tethers``) [-]
    tether_force : float  hard contact: the largest tether pull at its rupture [N] (< 0)
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
    values : mapping
        The steps' fields that were filled (name -> value); the others take their declared defaults.
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
    warnings: tuple[str, ...] = ()
    not_applicable: Mapping[str, str] = field(default_factory=dict)
    time: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    position: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    separation: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    deflection: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    force: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    segment: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int8), repr=False)
    details: Mapping[str, Any] = field(default_factory=dict, repr=False)
    values: Mapping[str, Any] = field(default_factory=dict)

    ARRAYS = ("time", "position", "separation", "deflection", "force", "segment")
    #: SI unit of every numeric field (the steps' result fields and the arrays), from the registry.
    UNITS: ClassVar[LiveDict] = LiveDict(_units)

    def __init__(self, source: str, steps_run: tuple[str, ...], deflection_unit: str, position_channel: str, *,
                 warnings: tuple[str, ...] = (), not_applicable: Mapping[str, str] | None = None,
                 time: np.ndarray | None = None, position: np.ndarray | None = None,
                 separation: np.ndarray | None = None, deflection: np.ndarray | None = None,
                 force: np.ndarray | None = None, segment: np.ndarray | None = None,
                 details: Mapping[str, Any] | None = None, values: Mapping[str, Any] | None = None,
                 **fields: Any) -> None:
        known = result_fields()
        bad = [k for k in fields if k not in known or known[k].compute is not None]
        if bad:
            raise TypeError(f"AnalysisResult got unknown field(s) {', '.join(bad)} (not declared by any step)")
        z = lambda a, dtype=float: a if a is not None else np.zeros(0, dtype)  # noqa: E731
        for name, value in (("source", source), ("steps_run", tuple(steps_run)), ("deflection_unit", deflection_unit),
                            ("position_channel", position_channel), ("warnings", tuple(warnings)),
                            ("not_applicable", dict(not_applicable or {})), ("time", z(time)),
                            ("position", z(position)), ("separation", z(separation)),
                            ("deflection", z(deflection)), ("force", z(force)), ("segment", z(segment, np.int8)),
                            ("details", dict(details or {})), ("values", {**(values or {}), **fields})):
            object.__setattr__(self, name, value)

    def __getattr__(self, name: str) -> Any:
        """A step's result field: its value, or its declared default when its step did not fill it."""
        if name.startswith("__") or name == "values":
            raise AttributeError(name)
        f = result_fields().get(name)
        if f is None:
            raise AttributeError(f"{type(self).__name__} has no field {name!r}")
        if f.compute is not None:
            return f.compute(self)
        return self.values.get(name, f.default)

    def to_dict(self, arrays: bool = False) -> dict[str, Any]:
        """JSON-ready dict (NaN -> None); the per-sample arrays only if ``arrays``."""
        out: dict[str, Any] = {}
        head = ("source", "steps_run", "deflection_unit", "position_channel")
        for name in head:
            out[name] = to_jsonable(getattr(self, name), use_to_dict=False)
        for name in result_fields():
            out[name] = to_jsonable(getattr(self, name), use_to_dict=False)
        for f in dataclasses.fields(self):
            if f.name in head or f.name == "values" or (f.name in self.ARRAYS and not arrays):
                continue
            out[f.name] = to_jsonable(getattr(self, f.name), use_to_dict=False)
        out["units"] = dict(self.UNITS)
        out["details_units"] = {step: units_of(d, self.deflection_unit) for step, d in self.details.items()}
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
        rows.append(("contact kind", f"{self.contact_kind or '-'}: {self.contact_kind_reason}", ""))
        for attr, label, unit in SUMMARY_FIELDS:
            rows.append((label, getattr(self, attr), unit))
        rows.append(("adhesion", self.adhesion_verdict or "-", ""))
        rows.append(("oscillation", self.oscillation_verdict or "-", ""))
        rows.append(("friction", f"{self.friction or '-'}: {self.friction_verdict}", ""))
        rows.append(("diagnosis", self.verdict or "-", ""))
        return rows
