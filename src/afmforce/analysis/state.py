"""Working state carried through the pipeline steps (internal).

A frozen dataclass replaced (never mutated) by each step; arrays are new
arrays, never edited in place, so the input :class:`~afmforce.io.curve.RawCurve`
is untouched.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any, Mapping, Sequence

import numpy as np

from .._fields import QUANTITIES
from ..errors import AnalysisError
from ..io.curve import RawCurve
from ..io.given import GIVEN_NOTE
from ._glue_kernel import COMPILED, robust_line_ab
from ._median import median
from ._numeric import ptp
from ._speed_kernel import dead_zone as _dead_zone
from .dynamic import drive_start_slopes, run_velocity
from .glitches import remove_glitches
from .options import ContactOptions, ProbeCalibration
from .regions import RunRegions, run_indices
from ._units import unit as _u

__all__ = ["State", "prepare", "ContactSummary", "SmoothResult", "NoContact"]


class NoContact(AnalysisError):
    """The approach never reaches the surface (contact kind ``"none"``): not a failure of the analysis."""


@dataclass(frozen=True)
class ContactSummary:
    """Where contact starts and ends (indices into the curve) and region sizes [-]."""

    contact_index: int = _u("")
    pull_off_region_end: int = _u("")
    zero_force_approach: int = _u("")
    zero_force_retract: int = _u("")
    compliance_approach: int = _u("")
    compliance_retract: int = _u("")
    saturated: int = _u("")


@dataclass(frozen=True)
class SmoothResult:
    """Running average of the position channel.

    Attributes
    ----------
    window : int  points [-]
    channel : str
    max_change : float  largest change of a position [m]
    """

    window: int = _u("")
    channel: str
    max_change: float = _u("m")


@dataclass(frozen=True)
class State:
    """Arrays and results of the steps so far (SI; ``signal`` in ``unit``).

    ``probe`` is the user's probe record (a field left ``None`` takes the file's
    value: :meth:`ProbeCalibration.value`); ``details`` maps a step to its result
    dataclass; ``skipped`` a step that does not apply to this curve to the reason.
    """

    curve: RawCurve
    time: np.ndarray
    z: np.ndarray
    signal: np.ndarray
    unit: str
    channel: str
    time_known: bool
    approach: RunRegions | None = None
    retract: RunRegions | None = None
    noise: float = math.nan
    factor: float = math.nan
    deflection: np.ndarray | None = None
    separation: np.ndarray | None = None
    position: np.ndarray | None = None
    force: np.ndarray | None = None
    spring_constant: float = math.nan
    details: Mapping[str, Any] = field(default_factory=dict)
    warnings: tuple[str, ...] = ()
    probe: ProbeCalibration = field(default_factory=ProbeCalibration)
    skipped: Mapping[str, str] = field(default_factory=dict)
    #: Intermediate values several steps share (e.g. a run's velocity), keyed by the arrays they were
    #: computed from (identity): one dict shared by every state of one curve's analysis.
    cache: dict = field(default_factory=dict, compare=False, repr=False)

    def velocity(self, index: np.ndarray) -> float:
        """Speed of the run ``index`` [m/s] (:func:`~.dynamic.run_velocity` of the current time and
        position; a measured channel's dead zone left out: :func:`~.dynamic.drive_start`), computed once per curve for the same arrays."""
        hit = self.cache.get(("velocity", id(index)))
        if hit is not None and hit[0] is index and hit[1] is self.time and hit[2] is self.z:
            return hit[3]
        t, z = self.time[index], self.z[index]
        v = None
        if self.channel == "measured":
            # the dead zone read off the recorded channel (the running average of ``smooth`` blurs its
            # kink over half a window); where there is one, the speed is the fit's: the line through the
            # recorded positions after it (:func:`afmforce.fit.ramp.drive_line`)
            zm = np.asarray(self.curve.piezo_measured, float)[index]
            dead = _dead_zone(zm) if COMPILED and zm.dtype == np.float64 else -1
            k, whole, rest = drive_start_slopes(t, zm, None if dead < 0 else dead)
            # the speed is the slope drive_start fitted to the same samples where it fitted one (the same
            # robust line, so the same number: one fit of the run instead of three)
            if k:
                v = abs(rest)
            elif not math.isnan(whole) and np.array_equal(z, zm):
                v = abs(whole)
        if v is None:
            v = _velocity(t, z)
        self.cache[("velocity", id(index))] = (index, self.time, self.z, v)
        return v

    @property
    def metadata(self) -> Mapping[str, Any]:
        return self.curve.metadata

    def update(self, step: str | None = None, detail: Any = None, warn: str | Sequence[str] | None = None,
               **changes) -> "State":
        """A new state with ``changes``, ``detail`` stored under ``step`` and ``warn`` (one or several) appended."""
        if step is not None:
            changes["details"] = {**self.details, step: detail}
        if warn:
            new = (warn,) if isinstance(warn, str) else tuple(w for w in warn if w)
            if new:
                changes["warnings"] = self.warnings + new
        if not changes.keys() <= _FIELDS:
            raise TypeError(f"State has no field(s) {', '.join(sorted(changes.keys() - _FIELDS))}")
        # the instance dict copied: dataclasses.replace re-runs the frozen __init__ over all 21 fields
        # (a curve's 24 updates were 4 % of its analysis; issue 35)
        out = object.__new__(type(self))
        object.__setattr__(out, "__dict__", {**self.__dict__, **changes})
        return out

    @property
    def missing_run(self) -> str | None:
        """``"approach"`` or ``"retract"`` when the curve holds the other run only (an export of one run:
        the steps that need the missing one are skipped), else None."""
        for which, word in ((0, "approach"), (1, "retract")):
            if self.run_index(which).size == 0:
                return word
        return None

    def run_index(self, which: int) -> np.ndarray:
        """Indices of the curve's segment ``which`` (0 approach, 1 retract), in time order
        (:func:`~.regions.run_indices`, found once per curve: read it, do not change it)."""
        hit = self.cache.get(("run", which))
        if hit is not None and hit[0] is self.curve.segment:
            return hit[1]
        idx = run_indices(self.curve.segment, which)
        self.cache[("run", which)] = (self.curve.segment, idx)
        return idx

    def require(self, *names: str, step: str) -> None:
        """Raise AnalysisError if a needed intermediate result is missing."""
        for name in names:
            if getattr(self, name) is None:
                raise AnalysisError(f"step {step!r} needs {name}, computed by an earlier step")


def _velocity(t: np.ndarray, z: np.ndarray) -> float:
    """:func:`~.dynamic.run_velocity` (the same number): its robust line by the fused kernel when compiled."""
    if COMPILED and 3 <= t.size <= 4001 and t.dtype == np.float64 and z.dtype == np.float64 and ptp(t) != 0:
        _, b, _, ok = robust_line_ab(t - t[0], z)
        if ok:
            return float(abs(b))
    return run_velocity(t, z)


#: The state's field names (what :meth:`State.update` may change).
_FIELDS = frozenset(f.name for f in dataclasses.fields(State))


def prepare(curve: RawCurve, channel: str = "auto", probe: ProbeCalibration | None = None, *,
            scan: tuple | None = None) -> State:
    """Check the curve and choose the position channel.

    Parameters
    ----------
    channel : str
        ``"auto"`` (measured if recorded, else nominal), ``"measured"`` or ``"nominal"``.
    probe : ProbeCalibration, optional
        The user's probe record (None: everything from the file).
    scan : tuple, optional
        :func:`~.orientation.plain_scan` ``(curve, channel)`` where it is not None (the pipeline's): the position
        spans, its direction and the sign check's screen read from it, the same answers as computed here.

    Raises
    ------
    AnalysisError
        Non-finite samples, a missing run, or a requested channel that is absent.
    """
    use_measured = curve.position_channel(channel) == "measured"   # RawCurve's one choice (and its refusals)
    z = np.array(curve.piezo_measured if use_measured else curve.piezo_nominal, dtype=float)
    s = np.array(curve.deflection_signal, dtype=float)
    t = np.array(curve.time, dtype=float)
    # a sum is finite only if every sample is (a finite sum that overflows is checked sample by sample)
    if not math.isfinite(float(np.add.reduce(z)) + float(np.add.reduce(s)) + float(np.add.reduce(t))):
        for name, arr in (("position", z), ("deflection signal", s), ("time", t)):
            bad = ~np.isfinite(arr)
            if bad.any():
                raise AnalysisError(f"the {name} has {int(bad.sum())} NaN or infinite samples "
                                    f"(first at {int(np.argmax(bad))}); clean the data first")
    seg = np.asarray(curve.segment)
    runs = {("run", which): (curve.segment, run_indices(seg, which)) for which in (0, 1)}
    sizes = [runs[("run", which)][1].size for which in (0, 1)]
    single = curve.metadata.get("single_run")   # an export of one run (the readers say which)
    for which, word in ((0, "approach"), (1, "retract")):
        if sizes[which] == 0 and not (single and sizes[1 - which]):
            raise AnalysisError(f"the curve has no {word} segment (one segment only); the analysis needs "
                                "both runs: split the curve at its turning point")
    for which, word in ((0, "approach"), (1, "retract")):
        if 0 < sizes[which] < MIN_RUN_SAMPLES:
            flags = curve.metadata.get("recording_flags")
            said = f"; the file says: {flags}" if flags else ""
            raise AnalysisError(f"the {word} holds only {sizes[which]} sample(s) (the "
                                f"{('retract', 'approach')[which]} {sizes[1 - which]}): not a force curve, "
                                f"the recording stopped at once{said}; record the curve again (a "
                                "larger z range, or a setpoint the sample can reach)")
    probe = probe if probe is not None else _default_probe()
    _check_calibration(curve.metadata, probe, curve.deflection_unit)
    notes: list[str] = []
    if curve.metadata.get("recording_flags"):  # the instrument's own word on the recording (JPK force-scan flags)
        notes.append(f"the file flags its recording: {curve.metadata['recording_flags']}")
    s, glitches = remove_glitches(s)
    if glitches:   # the steps that read the recorded signal read the repaired one too
        notes.append(glitches)
        curve = dataclasses.replace(curve, deflection_signal=s)
    z, use_measured = _moving_position(curve, z, use_measured, channel, runs, notes,
                                       None if scan is None else (scan[5], scan[6]))
    # the scan's screen read the recorded signal: a repaired one is checked here
    inverted = None if scan is not None and scan[7] and not glitches else \
        _check_sign(s, runs[("run", 0)][1], runs[("run", 1)][1])
    if inverted:
        notes.append(inverted)
    k_note = curve.metadata.get("spring_constant_note")   # a header with several spring constants (the reader's)
    if k_note and probe.spring_constant is None:
        notes.append(str(k_note))
    if curve.metadata.get(GIVEN_NOTE):   # a given value not applied (afmforce.io.given)
        notes.append(str(curve.metadata[GIVEN_NOTE]))
        if curve.metadata.get("sensitivity") is None:   # none of its own: the forces' sensitivity is unknown, and
            probe = probe.without("sensitivity")      # the given one is not reported as used ("30 (user)" before)
    if curve.metadata.get("approach_steps"):  # a step indentation: its later extends are holds (io._meta)
        notes.append(str(curve.metadata["approach_steps"]))
    if curve.metadata.get("file_truncated"):  # a force volume read up to where its file ends (io.nanoscope)
        notes.append(str(curve.metadata["file_truncated"]))
    if use_measured and curve.metadata.get("position_note"):  # a sensor far off the nominal ramp (io.nanoscope)
        notes.append(str(curve.metadata["position_note"]))
    processed = curve.metadata.get("processed")  # a vendor's processed export (force vs separation)
    if processed:
        notes.insert(0, f"read as a processed export: {processed}")
    return State(curve=curve, time=t, z=z, signal=s, unit=curve.deflection_unit,
                 channel="measured" if use_measured else "nominal",
                 time_known=not bool(curve.metadata.get("time_is_sample_index", False)),
                 probe=probe, warnings=tuple(notes), cache=runs)


#: Fewest samples a run (approach or retract) must hold [-]: what the contact step's two-line split needs
#: (``2 * min_points + 2`` at its default ``min_points``: 12). A JPK curve whose piezo ran out of range
#: before the setpoint stores an extend of 1 to 3 samples (nanite's `fmt-jpk-fd_single_bad_*` files).
MIN_RUN_SAMPLES = 2 * ContactOptions().min_points + 2


#: No AFM scanner's z axis travels this far [m] (long-range heads move 100 um): a position spanning
#: more is read with a wrong scale (a column in um or nm taken for metres).
MAX_POSITION_SPAN = 1e-2


def _check_calibration(metadata: Mapping[str, Any], probe: ProbeCalibration, unit: str) -> None:
    """Refuse a spring constant or sensitivity (the user's, else the file's) that no lever has:
    outside its declared range (``_fields.QUANTITIES``: infinite, zero, negative, absurd; ``None``
    or NaN: unknown, left to the steps that need it). A force signal's own spring constant is
    checked even when the user gives one: it is what turns the file's forces back into deflections."""
    for key in ("spring_constant", "sensitivity"):
        values = [probe.value(key, metadata)]
        if key == "spring_constant" and unit == "N" and probe.spring_constant is not None:
            values.append(metadata.get(key))
        for value in values:
            if value is None or isinstance(value, (str, bytes, bool)):
                continue
            try:
                v = float(value)
            except (TypeError, ValueError):
                continue
            spec = QUANTITIES[key]
            if math.isnan(v) or spec.contains(v):
                continue
            raise AnalysisError(f"the curve's {spec.help} is {spec.show(v)}, outside {spec.range_text()} (no "
                                f"cantilever has it: a damaged, unset or mis-scaled header value); give `{key}`")


#: How far below its free baseline [robust noise sigmas] a deflection that ends the approach and
#: starts the retract there, never rising above it by half as much, says its sign is inverted.
INVERTED_SIGMAS = 20.0


def _check_sign(s: np.ndarray, approach: np.ndarray, retract: np.ndarray) -> str | None:
    """A warning when the deflection signal's sign looks inverted: pressed on the sample, a lever bends
    away from it (the signal rises); one that ends the approach and starts the retract far below its
    free baseline, never having risen above it by half as much, was stored with the other sign -- or
    turned round before contact, held by an attraction (a curve that never reaches the sample looks
    the same: tests/fit/test_fit_bad_input.py's). So a warning, not a refusal: the analysis goes on and
    says what to check."""
    n = approach.size
    if n < 20 or retract.size < 3:
        return None
    a = s[approach]
    head = a[: max(5, n // 3)]
    base = median(head)
    tail = median(a[-max(3, n // 50):]) - base
    start = median(s[retract[: max(3, retract.size // 50)]]) - base
    peak = float(a.max()) - base
    if not (tail < 0.0 and start < 0.0 and peak < 0.5 * -tail):
        return None  # (the test below needs all three for any noise > 0: a normal curve pays no noise estimate)
    step = np.diff(head)
    noise = 1.4826 * median(np.abs(step - median(step))) / math.sqrt(2.0)
    if not noise > 0.0:      # quieter than its digitisation (most steps equal): one quantum, the least step
        moved = np.abs(step[step != 0.0])
        if not moved.size:
            return None
        noise = float(moved.min())
    if tail < -INVERTED_SIGMAS * noise and start < -INVERTED_SIGMAS * noise:
        return (f"the deflection signal falls as the tip approaches the sample: it ends the approach "
                f"{-tail / noise:.3g} noise sigmas below its free baseline and never rises above it by half "
                "as much: either the approach stopped before contact, held by an attraction, or the signal's "
                "sign is inverted (stored with the other sign convention: the contact and the adhesion are "
                "then wrong; negate the deflection signal, the deflection away from the sample positive as "
                "the readers give it, and analyse it again)")
    return None


def _moving_position(curve: RawCurve, z: np.ndarray, use_measured: bool, channel: str, runs: dict,
                     notes: list[str], plain: tuple[float, float] | None = None) -> tuple[np.ndarray, bool]:
    """The position ``z`` checked to move in both runs, towards the sample on the approach.

    ``plain``: the runs' position spans of a curve :func:`~.orientation.plain_scan` showed to move in both
    runs, towards the sample on the approach (the trends are then not computed again: the same answer).

    A measured channel that stands still (a position sensor switched off or not connected) gives way
    to the nominal one when the channel was not chosen; a position that does not move, or spans more
    than :data:`MAX_POSITION_SPAN`, is refused; a position that falls on the approach and rises on the
    retract (stored as the distance from the sample) is turned round, with a note.
    """
    present = [(runs[("run", which)][1], word) for which, word in ((0, "approach"), (1, "retract"))
               if runs[("run", which)][1].size]   # a curve of one run: that run's checks only
    idx, words = [i for i, _ in present], tuple(w for _, w in present)
    if plain is not None and len(idx) == 2:
        if max(plain) > MAX_POSITION_SPAN:
            _too_far(use_measured, max(plain))
        return z, use_measured
    spans = [float(ptp(z[i])) if i.size else 0.0 for i in idx]
    if min(spans) <= 0.0 and use_measured and channel == "auto":
        nominal = np.array(curve.piezo_nominal, dtype=float)
        if np.isfinite(nominal).all() and all(i.size and float(ptp(nominal[i])) > 0.0 for i in idx):
            notes.append(f"the measured position does not move during the {words[spans.index(min(spans))]} "
                         "(a position sensor off?): the nominal (piezo) position is used")
            return _moving_position(curve, nominal, False, "nominal", runs, notes)
    name = "measured (sensor)" if use_measured else "nominal (piezo)"
    for word, span in zip(words, spans):
        if span <= 0.0:
            raise AnalysisError(f"the {name} position does not move during the {word}: no force curve comes from "
                                "it; check the file's position channel (`channel`)")
    if max(spans) > MAX_POSITION_SPAN:
        _too_far(use_measured, max(spans))
    trend = []
    for i in idx:
        n = max(1, i.size // 10)
        trend.append(median(z[i[-n:]]) - median(z[i[:n]]))
    signs = {"approach": -1.0, "retract": 1.0}   # the position falls on the approach, rises on the retract
    if all(signs[w] * t > 0.0 for w, t in zip(words, trend)):
        moved = (" and ".join(f"{'falls' if w == 'approach' else 'rises'} during the {w}" for w in words))
        notes.append(f"the position {moved} (stored as the distance from the sample): turned round to grow "
                     "towards the sample")
        return -z, use_measured
    return z, use_measured


def _too_far(use_measured: bool, span: float) -> None:
    """Refuse a position that spans more than :data:`MAX_POSITION_SPAN` [m]."""
    name = "measured (sensor)" if use_measured else "nominal (piezo)"
    raise AnalysisError(f"the {name} position spans {span:.3g} m, beyond any AFM scanner's travel "
                        f"({MAX_POSITION_SPAN * 1e3:g} mm; long-range heads move 0.1 mm): the file is read with a wrong position scale "
                        "(a column in nm taken for metres?) or is damaged")


_PROBE: list[ProbeCalibration] = []


def _default_probe() -> ProbeCalibration:
    """The empty probe record (everything from the file): frozen, so one serves every curve (its
    construction validates eight fields: a few per cent of a small curve's analysis)."""
    if not _PROBE:
        _PROBE.append(ProbeCalibration())
    return _PROBE[0]
