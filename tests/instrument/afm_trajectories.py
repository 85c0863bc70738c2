"""Trajectory-like objects for the virtual-AFM tests (no dynamics engine needed).

A quasi-static curve: the piezo visits waypoints at constant speed; out of
contact the force is zero (deflection 0), in contact (z above ``contact``)
the tip follows the substrate (constant compliance, deflection z - contact).
"""

from __future__ import annotations

import types
from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class FakeTrajectory:
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
    config: object = field(repr=False)


def ramp_trajectory(waypoints, velocity, sample_rate, contact=None, beta=1.3e-4, k=0.21):
    """Piecewise-linear drive through ``waypoints`` [m] at ``velocity`` [m/s].

    Segment 0 where z increases (inward), 1 where it decreases (outward).
    """
    wp = np.asarray(waypoints, float)
    legs = np.diff(wp)
    t_wp = np.concatenate(([0.0], np.cumsum(np.abs(legs) / velocity)))
    n = int(np.floor(t_wp[-1] * sample_rate + 1e-9)) + 1
    t = np.arange(n) / sample_rate
    z = np.interp(t, t_wp, wp)
    leg = np.clip(np.searchsorted(t_wp[1:-1], t, side="left"), 0, legs.size - 1)
    seg = np.where(legs[leg] > 0, 0, 1).astype(np.int8)
    defl = np.zeros(n) if contact is None else np.maximum(z - contact, 0.0)
    h = defl - z
    config = types.SimpleNamespace(velocity=velocity, sample_rate=sample_rate, retract_velocity=None)
    return FakeTrajectory(time=t, piezo_position=z, deflection=defl, apparent_deflection=defl.copy(),
                          separation=h, apparent_separation=h.copy(), angle=defl / beta,
                          lateral_position=np.zeros(n), normal_force=k * defl, friction_force=np.zeros(n),
                          segment=seg, calibration_factor=beta, spring_constant=k, config=config)

