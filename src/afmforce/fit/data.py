"""Curves prepared for the dynamic fit: approach samples, noise, mask, static guesses.

A measured curve enters the fit as its inward (approach) run: time since the
start of the run, nominal piezo position, calibrated apparent deflection [m].
From the data alone (no model) we estimate the noise, find the jump-in and the
contact, and take the static first guesses of the per-curve nuisance
parameters: the baseline offset and drift (zero-force region), and the zero of
position (constant-compliance line: in contact the deflection follows z).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

from ..errors import AnalysisError, FileFormatError, ParameterError
from ..raw import RawCurve

__all__ = ["FitCurve", "prepare_curves", "check_consistent"]

#: Spring constants or sensitivities of the curves may differ by this fraction at most.
CALIBRATION_TOLERANCE = 0.02


@dataclass
class FitCurve:
    """One approach run ready for fitting (SI units).

    Attributes
    ----------
    name : str
        Label (file name).
    time : ndarray
        Time since the first approach sample [s].
    position : ndarray
        Nominal piezo position z [m] (unknown zero).
    deflection : ndarray
        Calibrated apparent deflection [m] (unknown baseline offset).
    velocity, sample_rate : float
        Driving speed [m/s] and sample rate [Hz].
    sigma : float
        Noise rms estimated from the zero-force region [m].
    jump_index : int
        Index of the first sample after the jump-in (largest drop).
    mask : ndarray of bool
        Samples used by the fit: all but the jump-in and the landing transient.
    guess : dict
        Static guesses: ``shift`` (nominal position of the true z = 0) [m],
        ``offset`` [m], ``drift`` [m/s], ``min_deflection`` [m] (before the jump,
        baseline removed).
    metadata : dict
        The curve's metadata.
    """

    name: str
    time: np.ndarray
    position: np.ndarray
    deflection: np.ndarray
    velocity: float
    sample_rate: float
    sigma: float
    jump_index: int
    mask: np.ndarray
    guess: dict = field(default_factory=dict)
    metadata: dict = field(default_factory=dict)

    @property
    def n(self) -> int:
        return len(self.time)


def _meta_value(curve: RawCurve, key: str, override, name: str, unit: str) -> float:
    value = override if override is not None else (curve.metadata or {}).get(key)
    if value is None:
        raise FileFormatError(f"{name}: no {key} [{unit}] in the file; give it "
                              f"(--{key.replace('_', '-')})")
    value = float(value)
    if not math.isfinite(value) or value <= 0:
        raise FileFormatError(f"{name}: {key} must be positive, got {value!r} {unit}")
    return value


def _noise_sigma(y: np.ndarray) -> float:
    """White-noise rms from second differences (var = 6 sigma^2), outliers beyond 4 MADs dropped."""
    d = np.diff(y, 2)
    mad = 1.4826 * np.median(np.abs(d - np.median(d)))
    d = d[np.abs(d - np.median(d)) < 4 * mad] if mad > 0 else d
    return float(np.std(d) / math.sqrt(6.0))


def prepare_curve(curve: RawCurve, name: str = "curve", *, velocity: float | None = None,
                  sample_rate: float | None = None, jump_window: float = 2e-3) -> FitCurve:
    """Prepare the approach run of ``curve`` (see the module docstring).

    Raises
    ------
    FileFormatError
        The deflection is not calibrated in metres, or speed/sample rate are missing.
    AnalysisError
        Too few approach samples, or no contact (no constant-compliance region).
    """
    meta = curve.metadata or {}
    unit = curve.deflection_unit
    need = {"N": "spring_constant", "V": "sensitivity"}.get(unit)
    if unit != "m" and (need is None or not meta.get(need)):
        raise FileFormatError(
            f"{name}: the deflection is in {unit} and the file has no {need}; the fit needs a "
            "calibrated deflection in metres (deflection_signal [m]); calibrate it first")
    # force / k or volts x sensitivity: the file's own calibration
    scale = 1.0 if unit == "m" else (1.0 / float(meta[need]) if unit == "N" else float(meta[need]))
    v = _meta_value(curve, "velocity", velocity, name, "m/s")
    fs = _meta_value(curve, "sample_rate", sample_rate, name, "Hz")
    app = np.asarray(curve.segment) == 0
    idx = np.flatnonzero(app)
    if idx.size < 30:
        raise AnalysisError(f"{name}: only {idx.size} approach samples; the fit needs >= 30")
    idx = idx[: np.flatnonzero(np.diff(idx) != 1)[0] + 1] if np.any(np.diff(idx) != 1) else idx
    t = np.asarray(curve.time, float)[idx]
    z = np.asarray(curve.piezo_nominal, float)[idx]
    y = np.asarray(curve.deflection_signal, float)[idx] * scale
    t = t - t[0]
    n = len(t)
    if not (np.all(np.isfinite(y)) and np.all(np.isfinite(z))):
        raise FileFormatError(f"{name}: the approach contains NaN or infinite values")
    # constant compliance: the rising tail where the deflection follows z
    dy, dz = np.diff(y), np.diff(z)
    i_c = n - 1
    while i_c > 0 and dy[i_c - 1] > 0.5 * dz[i_c - 1]:
        i_c -= 1
    if n - i_c < 5:     # noisy positions break the chain: the last 10 % of the approach
        i_c = int(0.9 * n)
    n_tail = n - i_c
    a = np.polyfit(z[i_c + n_tail // 3:], y[i_c + n_tail // 3:], 1)[0] if n_tail >= 3 else 0.0
    if 0.05 < a <= 0.5 or a >= 2.0:
        raise AnalysisError(
            f"{name}: in contact the deflection follows the position with slope {a:.3g}, not ~1: "
            "a deformable sample or a wrong deflection calibration; the dynamic model assumes "
            "rigid surfaces (eq 2), so this curve cannot be fitted")
    if not 0.5 < a < 2.0:
        raise AnalysisError(
            f"{name}: no contact on the approach (no constant-compliance region at its end, "
            f"where the deflection should follow the position with slope ~1; found "
            f"{n_tail} rising samples, slope {a:.3g}); the fit needs curves that reach contact")
    # jump-in: the largest change before the compliance region (a drop, or the spike of
    # the apparent deflection of a tilting beam held back by friction)
    j = int(np.argmax(np.abs(dy[: max(i_c, 1)]))) + 1 if i_c > 1 else 1
    j = min(j, i_c)
    sigma = max(_noise_sigma(y[: max(12, int(0.8 * j))]), 1e-15)
    j_drop = int(np.argmin(dy[: max(j, 1)])) + 1
    if j_drop < j and -dy[j_drop - 1] > 8 * sigma and j - j_drop <= 3 + jump_window * fs:
        j = j_drop          # the drop of the jump-in came first, then the spike
    win = int(math.ceil(jump_window * fs))
    mask = np.ones(n, bool)
    mask[max(j - 2, 0): min(max(j, i_c) + win + 2, n)] = False
    if mask.sum() < 20:
        raise AnalysisError(f"{name}: only {int(mask.sum())} samples left outside the jump-in "
                            "window; record a longer approach or a higher sample rate")
    base = slice(0, max(10, int(0.6 * j)))
    drift, offset = np.polyfit(t[base], y[base], 1)
    ybl = y - offset - drift * t
    post = slice(min(max(j, i_c) + win + 2, n - 3), n)
    shift = float(np.median(z[post] - ybl[post]))
    return FitCurve(name=name, time=t, position=z, deflection=y, velocity=v, sample_rate=fs,
                    sigma=sigma, jump_index=j, mask=mask,
                    guess={"shift": shift, "offset": float(offset), "drift": float(drift),
                           "min_deflection": float(np.min(ybl[max(j - 3, 0):j]))},
                    metadata=dict(curve.metadata or {}))


def check_consistent(curves: Sequence[RawCurve], names: Sequence[str]) -> None:
    """Refuse curves whose calibrations disagree (spring constant, sensitivity).

    Raises
    ------
    ParameterError
        Two curves differ by more than :data:`CALIBRATION_TOLERANCE`.
    """
    for key, unit in (("spring_constant", "N/m"), ("sensitivity", "m/V")):
        vals = [(nm, float(c.metadata[key])) for c, nm in zip(curves, names)
                if (c.metadata or {}).get(key) is not None]
        if len(vals) < 2:
            continue
        ref_name, ref = vals[0]
        for nm, v in vals[1:]:
            if abs(v / ref - 1.0) > CALIBRATION_TOLERANCE:
                raise ParameterError(
                    f"inconsistent calibrations: {key} is {ref:.4g} {unit} in {ref_name} but "
                    f"{v:.4g} {unit} in {nm}; a joint fit needs one probe and one calibration "
                    "(recalibrate, or fit the curves separately)")


def prepare_curves(curves: Sequence[RawCurve | FitCurve], names: Sequence[str] | None = None,
                   *, velocities: Sequence[float] | None = None,
                   sample_rates: Sequence[float] | None = None,
                   jump_window: float = 2e-3) -> list[FitCurve]:
    """Prepare several curves (see :func:`prepare_curve`) and check their calibrations."""
    if len(curves) == 0:
        raise ParameterError("give at least one curve")
    names = list(names) if names is not None else [f"curve {i + 1}" for i in range(len(curves))]
    raws = [c for c in curves if isinstance(c, RawCurve)]
    check_consistent(raws, [nm for c, nm in zip(curves, names) if isinstance(c, RawCurve)])
    out = []
    for i, (c, nm) in enumerate(zip(curves, names)):
        if isinstance(c, FitCurve):
            out.append(c)
            continue
        out.append(prepare_curve(c, nm, velocity=None if velocities is None else velocities[i],
                                 sample_rate=None if sample_rates is None else sample_rates[i],
                                 jump_window=jump_window))
    return out
