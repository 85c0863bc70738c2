"""The virtual AFM: turn a simulated trajectory into the raw signals an instrument records.

:class:`Instrument` composes the components (piezo, position detector,
photodiode, drift, noise, acquisition) and :meth:`Instrument.record` applies
them in the order of the signal chain:

1. on the trajectory's own time grid: the nominal piezo position from the
   true one (:class:`~afmforce.instrument.piezo.Piezo`, hysteresis and creep
   need the fine history) and the detector's analog reading (backlash);
2. sampling at the acquisition's sample rate (linear interpolation);
3. deflection signal = optical lever + interference + drift + noise, then
   amplifier saturation and the ADC; detector reading + noise, then its
   digitisation step.

Any object with the attributes of :class:`afmforce.dynamics.Trajectory`
works (duck typing): ``time``, ``piezo_position`` and ``segment`` are
required; ``apparent_deflection`` (else ``calibration_factor * angle``, else
``deflection``), ``separation`` (else ``deflection - piezo_position``) and
the other columns are used when present; ``spring_constant``,
``calibration_factor`` and ``config.velocity`` go into the metadata/truth, and the
lever's ``resonance_frequency`` [Hz] and ``quality_factor`` (its first free mode, as a
thermal tune records it) into the metadata when the trajectory has them (a Trajectory
does; a quasi-static curve without a lever mass does not), and so its body's ``lever_drag``
[N s/m] in a liquid (with ``lever_height`` [m] when the drag is not constant).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import ParameterError
from ..io.curve import RawCurve
from .acquisition import Acquisition, resample, resample_segment, trajectory_sample_rate
from .detector import PositionDetector, run_bounds, run_speeds
from .noise import Drift, Noise
from .photodiode import Photodiode
from .piezo import Piezo

__all__ = ["Instrument", "TRUTH_COLUMNS", "LEVER_KEYS", "trajectory_columns"]

#: The lever's properties a trajectory may carry that go into the metadata (a real file's header
#: records the first two from the thermal tune; the drag, of the lever body in a liquid, with them);
#: their units are :data:`afmforce._fields.QUANTITIES`' (declared once).
LEVER_KEYS = ("resonance_frequency", "quality_factor", "lever_drag", "lever_height")

#: Trajectory columns copied (resampled) into ``RawCurve.truth`` when present, with units.
TRUTH_COLUMNS: dict[str, str] = {
    "piezo_position": "m",
    "deflection": "m",
    "apparent_deflection": "m",
    "separation": "m",
    "apparent_separation": "m",
    "angle": "rad",
    "lateral_position": "m",
    "normal_force": "N",
    "friction_force": "N",
}

#: Component name -> class, in signal-chain order.
COMPONENTS: dict[str, type] = {
    "piezo": Piezo,
    "detector": PositionDetector,
    "photodiode": Photodiode,
    "drift": Drift,
    "noise": Noise,
    "acquisition": Acquisition,
}


@dataclass(frozen=True)
class Instrument:
    """A virtual AFM.

    Parameters
    ----------
    name : str
        Label written into the raw curve's metadata (preset name or "custom").
    piezo, detector, photodiode, drift, noise, acquisition
        The components; ``detector=None`` for an instrument without a
        position detector (``piezo_measured`` is then absent).
    """

    name: str = "custom"
    piezo: Piezo = field(default_factory=Piezo)
    detector: PositionDetector | None = field(default_factory=PositionDetector)
    photodiode: Photodiode = field(default_factory=Photodiode)
    drift: Drift = field(default_factory=Drift)
    noise: Noise = field(default_factory=Noise)
    acquisition: Acquisition = field(default_factory=Acquisition)

    def __post_init__(self) -> None:
        for name, cls in COMPONENTS.items():
            value = getattr(self, name)
            if value is None and name == "detector":
                continue
            if not isinstance(value, cls):
                raise ParameterError(f"instrument {name} must be a {cls.__name__}, got {type(value).__name__}")
        if self.photodiode.sensitivity is None and (
                not self.drift.is_zero or not self.noise.is_zero or self.acquisition.adc_bits is not None):
            raise ParameterError("drift, noise and the ADC act on volts: give the photodiode sensitivity [m/V] "
                                 "(or switch them off)")

    # --- parameters ------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        """All parameters as plain JSON-able values (SI), by component."""
        out: dict[str, Any] = {"name": self.name}
        for name in COMPONENTS:
            comp = getattr(self, name)
            out[name] = None if comp is None else {f.name: _plain(getattr(comp, f.name))
                                                   for f in dataclasses.fields(comp)}
        return out

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> "Instrument":
        """Inverse of :meth:`to_dict` (missing components take their defaults)."""
        kwargs: dict[str, Any] = {"name": str(data.get("name", "custom"))}
        unknown = set(data) - set(COMPONENTS) - {"name"}
        if unknown:
            raise ParameterError(f"unknown instrument component(s) {sorted(unknown)}; "
                                 f"valid: {', '.join(COMPONENTS)}")
        for name, comp_cls in COMPONENTS.items():
            if name not in data:
                continue
            if data[name] is None:
                if name != "detector":
                    raise ParameterError(f"instrument component {name} cannot be switched off")
                kwargs[name] = None
                continue
            kwargs[name] = _build(comp_cls, name, data[name])
        return cls(**kwargs)

    # --- recording -------------------------------------------------------------
    def record(self, trajectory, seed: int | None = None) -> RawCurve:
        """Record a trajectory as this instrument would.

        Parameters
        ----------
        trajectory : Trajectory-like
            See the module docstring.
        seed : int or None
            Seed of the noise and the random drift (``None``: fresh entropy;
            the seed used is written to ``metadata["seed"]`` either way).

        Returns
        -------
        RawCurve
            Raw signals, metadata and the ground truth (resampled trajectory
            columns, drift and interference signals, parameters).
        """
        cols = trajectory_columns(trajectory)
        t, z, seg = cols["time"], cols["piezo_position"], cols["segment"]
        native_rate = trajectory_sample_rate(t)
        configured = getattr(getattr(trajectory, "config", None), "sample_rate", None)
        if configured is not None and abs(float(configured) / native_rate - 1.0) < 1e-6:
            native_rate = float(configured)  # the nominal rate rather than 1/median(dt)
        nominal_fine = self.piezo.nominal_from_true(t, z)
        measured_fine = None if self.detector is None else self.detector.analog(t, z, seg)

        ts = self.acquisition.sample_times(t)
        time_out = t.copy() if ts is None else ts
        seg_out = resample_segment(t, seg, ts)
        nominal = resample(t, nominal_fine, ts)
        apparent = resample(t, cols["apparent_deflection"], ts)
        separation = resample(t, cols["separation"], ts)

        sseq = _seed_sequence(seed)
        rng_drift, rng_noise, rng_detector = (np.random.default_rng(s) for s in sseq.spawn(3))
        pd = self.photodiode
        signal = pd.optical(apparent)
        truth_extra: dict[str, Any] = {}
        if pd.interference_amplitude:
            interference = pd.interference(separation)
            signal = signal + interference
            truth_extra["interference"] = interference
        drift, rates = self.drift.signal(time_out, seg_out, rng_drift)
        if not self.drift.is_zero:
            signal = signal + drift
            truth_extra["drift"] = drift
        if not self.noise.is_zero:
            signal = signal + self.noise.sample(signal.size, rng_noise)
        signal = self.acquisition.quantise(pd.saturate(signal))

        measured = None
        if self.detector is not None:
            analog = resample(t, measured_fine, ts)
            if self.detector.backlash > 0:
                truth_extra["backlash_offset"] = analog - resample(t, z, ts)
            measured = self.detector.digitise(analog, rng_detector)

        velocity = _velocity(trajectory, t, z)
        sample_rate = native_rate if self.acquisition.sample_rate is None else self.acquisition.sample_rate
        metadata: dict[str, Any] = {
            "source": "afmforce virtual AFM",
            "instrument": self.name,
            "seed": int(sseq.entropy),
            "velocity": velocity,
            "sample_rate": float(sample_rate),
        }
        retract = getattr(getattr(trajectory, "config", None), "retract_velocity", None)
        if retract is not None:
            metadata["retract_velocity"] = float(retract)
        k = _scalar(trajectory, "spring_constant")
        if k is not None:
            metadata["spring_constant"] = k
        if pd.sensitivity is not None:
            metadata["sensitivity"] = pd.sensitivity
        for key in LEVER_KEYS:  # the lever's, as its thermal tune gives them, and its drag in a liquid
            value = _scalar(trajectory, key)
            if value is not None:
                metadata[key] = value

        truth: dict[str, Any] = {}
        for name in TRUTH_COLUMNS:
            if name in cols:
                truth[name] = resample(t, cols[name], ts)
        truth.update(truth_extra)
        run_speed = [float(run_speeds(t, z, seg)[a]) for a, _ in run_bounds(seg, t.size)]
        truth.update({
            "calibration_factor": _scalar(trajectory, "calibration_factor"),
            "spring_constant": k,
            "trajectory_sample_rate": native_rate,
            "fringe_period": pd.fringe_period,
            "run_speeds": run_speed,
            "drift_rates": [float(r) for r in rates],
            "backlash_widths": (None if self.detector is None
                                else [float(self.detector.backlash_width(v)) for v in run_speed]),
            "piezo_loop_width": self.piezo.steady_loop_width(velocity),
            "instrument": self.to_dict(),
        })
        truth = {key: value for key, value in truth.items() if value is not None}
        return RawCurve(time=time_out, piezo_nominal=nominal, deflection_signal=signal, segment=seg_out,
                        piezo_measured=measured, metadata=metadata, truth=truth, deflection_unit=pd.unit)


def trajectory_columns(trajectory) -> dict[str, np.ndarray]:
    """Validated 1-D float columns of a trajectory-like object (see the module docstring)."""
    def get(name):
        value = getattr(trajectory, name, None)
        return None if value is None else np.asarray(value)

    missing = [n for n in ("time", "piezo_position", "segment") if get(n) is None]
    if missing:
        raise ParameterError(f"the trajectory lacks {', '.join(missing)}: pass an afmforce.dynamics "
                             "Trajectory or an object with those arrays")
    t = get("time").astype(float)
    n = t.size
    cols: dict[str, np.ndarray] = {"time": t}
    for name in ("piezo_position", "segment", *TRUTH_COLUMNS):
        value = get(name)
        if value is None:
            continue
        if value.ndim != 1 or value.size != n:
            raise ParameterError(f"trajectory column {name} has shape {value.shape}, expected ({n},)")
        cols[name] = value if name == "segment" else value.astype(float)
    if n < 2 or not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
        raise ParameterError("trajectory time must be finite and strictly increasing, with at least two samples")
    if not np.all(np.isfinite(cols["piezo_position"])):
        raise ParameterError("trajectory piezo_position contains NaN or infinite values")
    if "apparent_deflection" not in cols:
        beta = _scalar(trajectory, "calibration_factor")
        if "angle" in cols and beta is not None and np.isfinite(beta):
            cols["apparent_deflection"] = beta * cols["angle"]
        elif "deflection" in cols:
            cols["apparent_deflection"] = cols["deflection"]
        else:
            raise ParameterError("the trajectory needs apparent_deflection, angle with calibration_factor, "
                                 "or deflection")
    if "separation" not in cols:
        base = cols.get("deflection", cols["apparent_deflection"])
        cols["separation"] = base - cols["piezo_position"]
    return cols


def _velocity(trajectory, t, z) -> float:
    v = getattr(getattr(trajectory, "config", None), "velocity", None)
    if v is not None:
        return float(v)
    speed = np.abs(np.diff(z) / np.diff(t))
    moving = speed[speed > 0]
    return float(np.median(moving)) if moving.size else 0.0


def _scalar(obj, name) -> float | None:
    value = getattr(obj, name, None)
    return None if value is None else float(value)


def _seed_sequence(seed) -> np.random.SeedSequence:
    if seed is not None:
        if isinstance(seed, bool) or not float(seed).is_integer() or int(seed) < 0:
            raise ParameterError(f"seed must be a whole number >= 0, got {seed!r}")
        seed = int(seed)
    return np.random.SeedSequence(seed)


def _plain(value):
    """Tuples -> lists, numpy scalars -> Python numbers (JSON-able, round-trips exactly)."""
    if isinstance(value, (tuple, list, np.ndarray)):
        return [_plain(v) for v in value]
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, np.floating):
        return float(value)
    return value


def _build(comp_cls, name: str, params) -> Any:
    if isinstance(params, comp_cls):
        return params
    if not isinstance(params, dict):
        raise ParameterError(f"instrument {name} parameters must be a table, got {params!r}")
    valid = {f.name for f in dataclasses.fields(comp_cls)}
    unknown = set(params) - valid
    if unknown:
        raise ParameterError(f"unknown {name} parameter(s) {sorted(unknown)}; valid: {', '.join(sorted(valid))}")
    kw = {k: tuple(v) if isinstance(v, list) else v for k, v in params.items()}
    return comp_cls(**kw)
