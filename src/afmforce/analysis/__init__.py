"""Force-curve analysis: small functions for each step of the paper's recipe (section 3).

The pipeline that chains them is :mod:`afmforce.analysis.pipeline`, its typed inputs
(the probe record and one options record per step) :mod:`afmforce.analysis.options`; many
files or the curves of a force map go through it in chunks with
:func:`afmforce.sweep.files.analyze_files`; :mod:`afmforce.analysis.maps` turns their summary
table into map images.
"""

from __future__ import annotations

from ._numeric import largest_step, robust_line, robust_line_thin
from ._units import units_of
from .compliance import _fit_line as compliance_line  # its public name (compliance.py: rename after issue 31)
from .compliance import (CalibrationResult, ComplianceLine, ComplianceResult, FrictionSignature, ShiftResult,
                         calibrate, compliance_shift, fit_compliance, friction_signature)
from .drift import DriftResult, fit_baseline, remove_drift
from .dynamic import DynamicDiagnosis, diagnose_curve, run_velocity
from .fringes import FringeResult, FringeRun, fit_fringes, fringe_baseline, fringe_signal, loop_width, position_map
from .jumps import (AdhesionResult, JumpIn, PullOff, adhesion, find_jump_in, find_pull_off, jump_warnings,
                    pull_off_estimate)
from .options import (OPTIONS, AdhesionOptions, CalibrationOptions, ComplianceOptions, ContactOptions,
                      DiagnosisOptions, DriftOptions, ForceOptions, FrictionOptions, FringesOptions, JumpsOptions,
                      KindOptions, OscillationOptions, ProbeCalibration, ShiftOptions, SmoothOptions, StepOptions,
                      SurfaceEnergyOptions, VdwOptions, ZeroOptions)
from .oscillation import OscillationPeak, OscillationResult, find_peak, oscillation_origin
from .regions import RunRegions, check_compliance, contact_slopes, find_run_regions, saturated_mask
from .result import AnalysisResult
from .separation import ForceConversion, ZeroResult, effective_spring_constant, zero_of_separation
from .vdw import VdwFit, fit_vdw

__all__ = [
    "OPTIONS", "AdhesionOptions", "CalibrationOptions", "ComplianceOptions", "ContactOptions", "DiagnosisOptions",
    "DriftOptions", "ForceOptions", "FrictionOptions", "FringesOptions", "JumpsOptions", "KindOptions",
    "OscillationOptions", "ProbeCalibration", "ShiftOptions", "SmoothOptions", "StepOptions",
    "SurfaceEnergyOptions", "VdwOptions", "ZeroOptions",
    "AdhesionResult", "AnalysisResult", "CalibrationResult", "ComplianceLine", "ComplianceResult",
    "DriftResult", "DynamicDiagnosis", "ForceConversion", "FrictionSignature", "FringeResult", "FringeRun",
    "JumpIn", "OscillationPeak", "OscillationResult", "PullOff", "RunRegions", "ShiftResult", "VdwFit",
    "ZeroResult", "adhesion", "calibrate", "check_compliance", "compliance_shift", "contact_slopes",
    "diagnose_curve", "effective_spring_constant", "find_jump_in", "find_peak", "find_pull_off",
    "find_run_regions", "fit_baseline", "fit_compliance", "fit_fringes", "fit_vdw", "friction_signature",
    "fringe_baseline", "fringe_signal", "jump_warnings", "loop_width", "oscillation_origin", "position_map",
    "pull_off_estimate", "remove_drift", "run_velocity", "saturated_mask", "zero_of_separation",
    "compliance_line", "largest_step", "robust_line", "robust_line_thin", "units_of",
]
