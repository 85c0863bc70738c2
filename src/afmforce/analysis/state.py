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

from ..errors import AnalysisError
from ..io.curve import RawCurve
from ._glue_kernel import COMPILED, robust_line_ab
from ._numeric import ptp
from .dynamic import run_velocity
from .options import ProbeCalibration
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
        position), computed once per curve for the same arrays."""
        hit = self.cache.get(("velocity", id(index)))
        if hit is not None and hit[0] is index and hit[1] is self.time and hit[2] is self.z:
            return hit[3]
        v = _velocity(self.time[index], self.z[index])
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


def prepare(curve: RawCurve, channel: str = "auto", probe: ProbeCalibration | None = None) -> State:
    """Check the curve and choose the position channel.

    Parameters
    ----------
    channel : str
        ``"auto"`` (measured if recorded, else nominal), ``"measured"`` or ``"nominal"``.
    probe : ProbeCalibration, optional
        The user's probe record (None: everything from the file).

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
    runs = {}
    for which, word in ((0, "approach"), (1, "retract")):
        runs[("run", which)] = (curve.segment, run_indices(seg, which))
        if runs[("run", which)][1].size == 0:
            single = curve.metadata.get("single_run")
            if single:  # an export of one run: nothing to split
                raise AnalysisError(f"the file holds the {single} run only (no {word}); the analysis needs both "
                                    "runs: export the whole curve (approach and retract)")
            raise AnalysisError(f"the curve has no {word} segment (one segment only); the analysis needs "
                                "both runs: split the curve at its turning point")
    processed = curve.metadata.get("processed")  # a vendor's processed export (force vs separation)
    return State(curve=curve, time=t, z=z, signal=s, unit=curve.deflection_unit,
                 channel="measured" if use_measured else "nominal",
                 time_known=not bool(curve.metadata.get("time_is_sample_index", False)),
                 probe=probe if probe is not None else _default_probe(),
                 warnings=(f"read as a processed export: {processed}",) if processed else (), cache=runs)


_PROBE: list[ProbeCalibration] = []


def _default_probe() -> ProbeCalibration:
    """The empty probe record (everything from the file): frozen, so one serves every curve (its
    construction validates eight fields: a few per cent of a small curve's analysis)."""
    if not _PROBE:
        _PROBE.append(ProbeCalibration())
    return _PROBE[0]
