"""The result of a simulation: sampled columns, events, solver statistics."""

from __future__ import annotations

import io
import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .._json import to_jsonable
from .._files import atomic_path, atomic_write_text, check_writable
from ..errors import FileFormatError, MissingDependencyError
from .config import SimulationConfig
from .events import Events

__all__ = ["Trajectory", "SolverStats", "COLUMNS"]

#: Column name -> unit, in output order.
COLUMNS: dict[str, str] = {
    "time": "s",
    "piezo_position": "m",
    "deflection": "m",
    "apparent_deflection": "m",
    "separation": "m",
    "apparent_separation": "m",
    "angle": "rad",
    "lateral_position": "m",
    "normal_force": "N",
    "friction_force": "N",
    "segment": "1",
}


@dataclass(frozen=True)
class SolverStats:
    """Statistics of the integrator over all segments.

    Attributes
    ----------
    status : str
        "success" or why the solve stopped (a failed solve raises instead).
    method : str
        The integrator ("Radau IIA order 5, compiled").
    steps, accepted, rejected : int
        Attempted, accepted and rejected steps.
    rhs_evaluations, jacobian_evaluations, lu_decompositions : int
        Work counters.
    damping_steps : int
        Steps accepted to damp the in-contact ringing (``ringing="damp"``).
    newton_failures : int
        Rejected steps whose Newton iteration did not converge (or that
        tried a state with h below the force-law guard).
    wall_time : float
        Wall-clock time of the whole simulation [s].
    event_errors : dict
        Estimated error of each key event [m, N for the force]: its difference
        to a 10x tighter second solve (``check=``; empty when not checked).
    check : str
        What the convergence guard did.
    """

    status: str
    method: str
    steps: int
    accepted: int
    rejected: int
    rhs_evaluations: int
    jacobian_evaluations: int
    lu_decompositions: int
    damping_steps: int
    newton_failures: int
    wall_time: float
    event_errors: dict = field(default_factory=dict)
    check: str = "not checked"

    def to_dict(self) -> dict:
        """Plain dict of the fields."""
        return {k: getattr(self, k) for k in self.__dataclass_fields__}


@dataclass(frozen=True)
class Trajectory:
    """A simulated approach-retract cycle sampled like an instrument.

    Attributes
    ----------
    time : ndarray
        Time since the start [s], at the configured sample rate.
    piezo_position : ndarray
        Drive (substrate) position z [m]; increasing on the approach.
    deflection : ndarray
        Actual vertical tip deflection z2 [m] (negative: towards the substrate).
    apparent_deflection : ndarray
        beta * theta [m] with beta of eq 15 (eq 29): what an optical lever
        calibrated on constant compliance reports. The spring model has no
        angle: there it equals the deflection.
    separation : ndarray
        h = z2 - z [m].
    apparent_separation : ndarray
        apparent_deflection - z [m] (eq 29).
    angle : ndarray
        theta [rad] (NaN for the spring model).
    lateral_position : ndarray
        y2 [m] (0 for the spring model).
    normal_force : ndarray
        Fz = Fs + Fd [N] (negative: attraction).
    friction_force : ndarray
        Fy [N].
    segment : ndarray of int8
        0 approach, 1 retract, 2 dwell.
    calibration_factor : float
        beta of eq 15 [m/rad] (NaN for the spring model).
    spring_constant : float
        Force-measuring spring constant k [N/m] (eq 13 for the beam).
    config : SimulationConfig
        The configuration that produced it.
    events : Events
        Jump-in, contact, pull-off, spike, compliance offset.
    solver : SolverStats
        Integrator statistics.
    """

    time: np.ndarray
    piezo_position: np.ndarray
    deflection: np.ndarray
    apparent_deflection: np.ndarray
    separation: np.ndarray
    apparent_separation: np.ndarray
    angle: np.ndarray
    lateral_position: np.ndarray
    normal_force: np.ndarray
    friction_force: np.ndarray
    segment: np.ndarray
    calibration_factor: float
    spring_constant: float
    config: SimulationConfig = field(repr=False)
    events: Events = field(repr=False)
    solver: SolverStats = field(repr=False)

    def __len__(self) -> int:
        return int(self.time.size)

    @property
    def resonance_frequency(self) -> float:
        """The probe's first free resonance [Hz]: ``sqrt(k/m) / (2 pi)`` for the spring, the beam's
        first mode (:func:`afmforce.dynamics.thermal.free_resonance`)."""
        from .thermal import free_resonance

        return free_resonance(self.config.probe)[0]

    @property
    def quality_factor(self) -> float | None:
        """Quality factor of that resonance (the lever damping's ``quality_factor``) [-]; None for
        the paper's undamped lever."""
        from .thermal import free_resonance

        return free_resonance(self.config.probe)[1]

    @property
    def lever_drag(self) -> float | None:
        """Drag coefficient of the lever body (the surface's ``lever_drag``) [N s/m]; None without
        one (in air)."""
        return self.config.surface.lever_drag or None

    @property
    def lever_height(self) -> float | None:
        """Lever height above the substrate at contact [m] (drag ``c H/(h + H)``); None: the drag is
        constant, or there is none."""
        return (self.config.surface.lever_height or None) if self.config.surface.lever_drag else None

    def columns(self) -> dict[str, np.ndarray]:
        """The sampled columns by name (see :data:`COLUMNS`)."""
        return {name: getattr(self, name) for name in COLUMNS}

    def summary(self) -> dict[str, Any]:
        """Summary of the run (SI values; NaN where an event did not occur: a retract that ends in
        contact has no pull-off position and no pull-off force).

        Keys: ``jump_in`` {time, piezo_position, separation}, ``pull_off``
        {piezo_position, force}, ``min_deflection``, ``min_apparent_deflection``,
        ``hysteresis_offset``, ``spike_height``, ``solver`` {status, steps,
        rhs_evaluations, wall_time, check: the convergence check's note, e.g. "not checked
        (risky regime: ...)"}.
        """
        e, s = self.events, self.solver
        return {
            "jump_in": {"time": e.jump_in_time, "piezo_position": e.jump_in_position,
                        "separation": e.jump_in_separation},
            # no pull-off (the retract ends in contact): no pull-off force either; the events keep the
            # most negative force in contact (what the convergence check compares)
            "pull_off": {"piezo_position": e.pull_off_position,
                         "force": e.pull_off_force if math.isfinite(e.pull_off_position) else math.nan},
            "min_deflection": e.min_deflection,
            "min_apparent_deflection": e.min_apparent_deflection,
            "hysteresis_offset": e.hysteresis_offset,
            "spike_height": e.spike_height,
            "solver": {"status": s.status, "steps": s.steps, "rhs_evaluations": s.rhs_evaluations,
                       "wall_time": s.wall_time, "check": s.check},
        }

    def segment_slice(self, kind: int) -> np.ndarray:
        """Boolean mask of the samples of one segment kind (0, 1, 2)."""
        return self.segment == kind

    # --- output --------------------------------------------------------------
    def _metadata(self) -> dict[str, Any]:
        return {
            "calibration_factor": self.calibration_factor,
            "spring_constant": self.spring_constant,
            "config": self.config.to_dict(),
            "events": self.events.to_dict(),
            "solver": self.solver.to_dict(),
        }

    def write(self, path, force: bool = True) -> Path:
        """Write the trajectory atomically as ``.csv`` or ``.h5``/``.hdf5``.

        CSV: ``# key: value unit`` header lines (calibration factor, spring
        constant, events and configuration as JSON), then one header row
        ``name [unit],...`` and the data. HDF5: one dataset per column with a
        ``unit`` attribute; metadata as JSON attributes of the root group.

        Raises
        ------
        OutputExistsError
            If ``path`` exists and ``force`` is false.
        FileFormatError
            For an unknown suffix.
        """
        path = Path(path)
        suffix = path.suffix.lower()
        if suffix == ".csv":
            check_writable(path, force)
            return atomic_write_text(path, self._csv_text(), force)
        if suffix in (".h5", ".hdf5"):
            try:
                import h5py
            except ImportError as exc:  # pragma: no cover
                raise MissingDependencyError("writing .h5 needs h5py: pip install h5py") from exc
            with atomic_path(path, force) as tmp:
                with h5py.File(tmp, "w") as f:
                    f.attrs["format"] = "afmforce trajectory 1"
                    for key, value in self._metadata().items():
                        f.attrs[key] = json.dumps(to_jsonable(value))
                    for name, unit in COLUMNS.items():
                        ds = f.create_dataset(name, data=getattr(self, name))
                        ds.attrs["unit"] = unit
            return path
        raise FileFormatError(f"cannot write {path}: use a .csv or .h5 suffix")

    def _csv_text(self) -> str:
        buf = io.StringIO()
        buf.write("# afmforce trajectory 1\n")
        buf.write(f"# calibration_factor: {float(self.calibration_factor)!r} m/rad\n")
        buf.write(f"# spring_constant: {float(self.spring_constant)!r} N/m\n")
        buf.write(f"# model: {self.config.model}\n")
        buf.write(f"# events: {json.dumps(to_jsonable(self.events.to_dict()))}\n")
        buf.write(f"# solver: {json.dumps(to_jsonable(self.solver.to_dict()))}\n")
        buf.write(f"# config: {json.dumps(to_jsonable(self.config.to_dict()))}\n")
        buf.write(",".join(f"{n} [{u}]" for n, u in COLUMNS.items()) + "\n")
        data = np.column_stack([getattr(self, n).astype(float) for n in COLUMNS])
        np.savetxt(buf, data, delimiter=",", fmt=["%.10g"] * (len(COLUMNS) - 1) + ["%d"])
        return buf.getvalue()
