"""Rearranging simulated runs into the paper's measurement protocol.

The dynamics engine simulates approach then retract, starting out of
contact. The paper's Fig 7 measurement "commences with the surfaces in
contact, first driving out beyond the point where the surfaces jump apart
and then immediately reversing for the inward run". For a cycle that ends
where it started (``end == start``), :func:`out_then_in` puts the retract run
first and the approach run second, so the instrument starts at rest in
contact and the constant-compliance regime lies at both ends of the record,
as in the paper. (With contact at the turning point instead, any hysteresis
loop closes there and the nominal-position shift of the compliance lines is
small: see docs/instrument.md.)
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import ParameterError
from ..io.curve import SEGMENT_APPROACH, SEGMENT_RETRACT
from .instrument import TRUTH_COLUMNS

__all__ = ["ReorderedTrajectory", "out_then_in"]


@dataclass(frozen=True)
class ReorderedTrajectory:
    """A trajectory-like object (the columns of :class:`afmforce.dynamics.Trajectory`)."""

    time: np.ndarray
    piezo_position: np.ndarray
    segment: np.ndarray
    columns: dict[str, np.ndarray] = field(repr=False)
    calibration_factor: float | None = None
    spring_constant: float | None = None
    config: Any = field(default=None, repr=False)

    def __getattr__(self, name: str):
        cols = object.__getattribute__(self, "columns")
        if name in cols:
            return cols[name]
        raise AttributeError(name)


def out_then_in(trajectory, tolerance: float | None = None) -> ReorderedTrajectory:
    """Retract run first, then the approach run (the paper's Fig 7 order).

    Parameters
    ----------
    trajectory : Trajectory-like
        With ``time``, ``piezo_position``, ``segment`` and the other columns.
        Its approach must start where its retract ends (``start == end``);
        dwell samples are dropped.
    tolerance : float, optional
        Allowed mismatch of the two positions [m]; default: 1.5 times the
        largest drive step between two samples (the sampled runs need not
        land exactly on ``start`` and ``end``).

    Returns
    -------
    ReorderedTrajectory
        Time runs on continuously from the retract run into the approach run.
    """
    t = np.asarray(trajectory.time, float)
    z = np.asarray(trajectory.piezo_position, float)
    seg = np.asarray(trajectory.segment)
    app = np.flatnonzero(seg == SEGMENT_APPROACH)
    ret = np.flatnonzero(seg == SEGMENT_RETRACT)
    if app.size < 2 or ret.size < 2:
        raise ParameterError("out_then_in needs an approach and a retract run")
    if tolerance is None:
        tolerance = 1.5 * float(np.max(np.abs(np.diff(z))))
    if abs(z[app[0]] - z[ret[-1]]) > tolerance:
        raise ParameterError(
            f"out_then_in needs the retract to end where the approach starts (end == start); "
            f"got {z[ret[-1]]:.6g} m and {z[app[0]]:.6g} m")
    dt = float(np.median(np.diff(t)))
    t_ret = t[ret] - t[ret[0]]
    t_app = t[app] - t[app[0]] + t_ret[-1] + dt
    order = np.concatenate((ret, app))
    cols = {}
    for name in TRUTH_COLUMNS:
        value = getattr(trajectory, name, None)
        if value is not None:
            cols[name] = np.asarray(value)[order]
    return ReorderedTrajectory(
        time=np.concatenate((t_ret, t_app)), piezo_position=z[order], segment=seg[order],
        columns=cols, calibration_factor=getattr(trajectory, "calibration_factor", None),
        spring_constant=getattr(trajectory, "spring_constant", None),
        config=getattr(trajectory, "config", None))
