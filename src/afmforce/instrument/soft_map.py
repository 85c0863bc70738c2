"""A virtual QI map of a soft, adhesive sample: known modulus, topography and adhesion fields.

Each pixel is a quasi-static force curve of a spherical tip (radius R) on an elastic half-space,
recorded by a virtual AFM (:class:`~afmforce.instrument.Instrument`: photodiode, white noise, ADC):

* approach: Hertz, ``F = 4/3 E/(1 - nu^2) sqrt(R) delta^(3/2)`` with ``delta = (z - z_c) - d``
  the indentation, ``d = F/k`` the deflection and ``z_c = -h`` the piezo position at contact
  (h: the topography); the piezo turns when the force reaches the setpoint (as QI does);
* retract: DMT (Derjaguin, Muller & Toporov 1975), the same Hertz force minus the adhesion
  ``F_ad = 2 pi R w`` while in contact, then free (pull-off at ``delta = 0``): the retract dips
  ``F_ad`` below the baseline, and ``w = F_ad / (2 pi R)``.

:func:`soft_map_curves` yields the curves one at a time (a map of any size in constant memory),
with ``map_x``, ``map_y``, ``position_x``, ``position_y`` and the tip's ``radius`` in their metadata and the pixel's truth
(``youngs_modulus``, ``topography``, ``adhesion``, ``work_of_adhesion``) in ``truth``;
:func:`soft_map_fields` gives the fields themselves;
:func:`write_soft_map` writes them to an afmforce map file (:mod:`afmforce.io.native.rawmap`), JPK QI data
or a Bruker force volume (:mod:`afmforce.io.writers`).
"""

from __future__ import annotations

import dataclasses
import math
import os
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from types import SimpleNamespace

import numpy as np

from ..errors import ParameterError
from ..io.curve import RawCurve
from .acquisition import Acquisition
from .instrument import Instrument
from .noise import Noise
from .photodiode import Photodiode

__all__ = ["SoftMapConfig", "soft_map_fields", "soft_map_curves", "soft_curve", "write_soft_map", "config_of",
           "SOFT_MAP_FORMATS"]


@dataclass(frozen=True)
class SoftMapConfig:
    """The virtual map: grid, fields, probe and recording (SI).

    Attributes
    ----------
    nx, ny : int  pixels per row and per column [-]
    step : float  pixel size [m]
    modulus : tuple of float  E from the first to the second value across the map [Pa]
    topography : float  height range of the sample (a tilted, bumped surface) [m]
    work_of_adhesion : tuple of float  w range [J/m^2]
    radius : float  tip radius [m]
    poisson : float  Poisson's ratio of the sample [-]
    spring_constant : float  [N/m]
    sensitivity : float  photodiode sensitivity (InvOLS) [m/V]
    setpoint : float  force at which the approach turns [N]
    ramp : float  piezo travel of each run [m]
    points : int  samples per run [-]
    velocity : float  piezo speed [m/s]
    noise : float  deflection noise rms [m]
    seed : int  noise seed of the map
    """

    nx: int = 8
    ny: int = 8
    step: float = 0.5e-6
    modulus: tuple[float, float] = (2e3, 20e3)
    topography: float = 0.4e-6
    work_of_adhesion: tuple[float, float] = (5e-6, 20e-6)
    radius: float = 5e-6
    poisson: float = 0.5
    spring_constant: float = 0.1
    sensitivity: float = 50e-9
    setpoint: float = 2e-9
    ramp: float = 1.5e-6
    points: int = 300
    velocity: float = 50e-6
    noise: float = 0.05e-9
    seed: int = 0

    def __post_init__(self) -> None:
        if self.nx < 1 or self.ny < 1 or self.points < 50:
            raise ParameterError("soft map: nx, ny >= 1 and points >= 50")
        if not (min(self.modulus) > 0 and min(self.work_of_adhesion) >= 0 and self.radius > 0
                and self.spring_constant > 0 and self.setpoint > 0 and self.ramp > 0 and 0 <= self.poisson < 0.5001):
            raise ParameterError("soft map: modulus, radius, spring_constant, setpoint, ramp > 0; "
                                 "work_of_adhesion >= 0; poisson in [0, 0.5]")


def soft_map_fields(cfg: SoftMapConfig) -> dict[str, np.ndarray]:
    """The known fields, each ``[y, x]``: ``youngs_modulus`` [Pa], ``topography`` [m] (height),
    ``work_of_adhesion`` [J/m^2], ``adhesion`` [N] (= 2 pi R w, DMT)."""
    y, x = np.mgrid[0:cfg.ny, 0:cfg.nx].astype(float)
    u = (x + 0.5) / cfg.nx
    v = (y + 0.5) / cfg.ny
    e_lo, e_hi = cfg.modulus
    modulus = e_lo * (e_hi / e_lo) ** (0.5 + 0.5 * np.sin(2 * math.pi * u) * np.cos(math.pi * v))  # log pattern
    bump = np.exp(-((u - 0.5) ** 2 + (v - 0.5) ** 2) / 0.05)  # a cell on a tilted dish
    topography = cfg.topography * (0.3 * (u + v) / 2 + 0.7 * bump)
    w_lo, w_hi = cfg.work_of_adhesion
    w = w_lo + (w_hi - w_lo) * (0.5 + 0.5 * np.cos(2 * math.pi * v) * (u > 0.5))
    return {"youngs_modulus": modulus, "topography": topography, "work_of_adhesion": w,
            "adhesion": 2 * math.pi * cfg.radius * w}


def _instrument(cfg: SoftMapConfig) -> Instrument:
    s = cfg.sensitivity
    return Instrument(name="virtual QI", detector=None, photodiode=Photodiode(sensitivity=s),
                      noise=Noise(white=cfg.noise / s), acquisition=Acquisition(adc_bits=16, adc_range=10.0))


def soft_curve(cfg: SoftMapConfig, modulus: float, height: float, work: float, *,
               instrument: Instrument | None = None, seed: int = 0) -> RawCurve:
    """One pixel's curve (approach Hertz, retract DMT) recorded by the virtual AFM.

    Parameters
    ----------
    modulus : float  Young's modulus [Pa]
    height : float  the sample's height here (piezo position at contact = -height) [m]
    work : float  work of adhesion [J/m^2]
    """
    k, R = cfg.spring_constant, cfg.radius
    e_star = modulus / (1 - cfg.poisson ** 2)
    hertz = 4.0 / 3.0 * e_star * math.sqrt(R)
    f_ad = 2 * math.pi * R * work
    zc = -height
    delta_max = (cfg.setpoint / hertz) ** (2 / 3)
    z_top = zc + delta_max + cfg.setpoint / k  # the turning point: the force at the setpoint
    n = cfg.points
    z_app = np.linspace(z_top - cfg.ramp, z_top, n)
    z_ret = z_app[::-1]
    # approach: z = zc + delta + F(delta)/k, monotone in delta; invert on a fine delta grid
    delta = delta_max * np.linspace(0.0, 1.0, 4001) ** 2
    f = hertz * delta ** 1.5
    d_app = np.interp(z_app, zc + delta + f / k, f / k, left=0.0)
    d_app[z_app < zc] = 0.0
    # retract (DMT): F = F_H(delta) - F_ad in contact down to delta = 0, then free
    fr = f - f_ad
    d_ret = np.interp(z_ret, zc + delta + fr / k, fr / k)
    d_ret[z_ret < zc - f_ad / k] = 0.0
    t_run = cfg.ramp / cfg.velocity
    time = np.concatenate([np.linspace(0.0, t_run, n), t_run * (1 + np.arange(1, n + 1) / n)])
    traj = SimpleNamespace(time=time, piezo_position=np.concatenate([z_app, z_ret]),
                           segment=np.repeat(np.array([0, 1], dtype=np.int8), n),
                           deflection=np.concatenate([d_app, d_ret]), spring_constant=k)
    return (instrument or _instrument(cfg)).record(traj, seed=seed)


def soft_map_curves(cfg: SoftMapConfig) -> Iterator[RawCurve]:
    """The map's curves, row by row (``map_y``), one at a time."""
    fields = soft_map_fields(cfg)
    inst = _instrument(cfg)
    for y in range(cfg.ny):
        for x in range(cfg.nx):
            truth = {name: float(values[y, x]) for name, values in fields.items()}
            c = soft_curve(cfg, truth["youngs_modulus"], truth["topography"], truth["work_of_adhesion"],
                           instrument=inst, seed=cfg.seed * 1_000_003 + y * cfg.nx + x)
            md = {**c.metadata, "map_x": x, "map_y": y, "position_x": x * cfg.step, "position_y": y * cfg.step,
                  "radius": cfg.radius}
            yield RawCurve(time=c.time, piezo_nominal=c.piezo_nominal, deflection_signal=c.deflection_signal,
                           segment=c.segment, piezo_measured=None, metadata=md, truth={**truth},
                           deflection_unit=c.deflection_unit)


#: Metadata every curve of a virtual map shares (written once per map file).
_SHARED = ("source", "instrument", "velocity", "sample_rate", "spring_constant", "sensitivity", "radius")


#: Formats :func:`write_soft_map` writes: afmforce's map, JPK QI data, a Bruker NanoScope force volume.
SOFT_MAP_FORMATS = ("afmforce-map", "jpk-qi", "bruker-fv")


def write_soft_map(cfg: SoftMapConfig, path: str | os.PathLike, *, format: str = "afmforce-map",
                   force: bool = False) -> Path:
    """Write the virtual map, streamed (constant memory), in afmforce's map format or a vendor's.

    ``format``: ``"afmforce-map"`` (HDF5; the calibration is stored once for the map with the
    configuration, ``soft_map``, from which :func:`config_of` and :func:`soft_map_fields` give the
    known fields; each curve keeps its place and noise seed), ``"jpk-qi"`` (``.jpk-qi-data``) or
    ``"bruker-fv"`` (NanoScope v9 force volume, ``.spm``; the deflection in the virtual ADC's counts,
    the piezo position in the Z-sensor channel): :mod:`afmforce.io.writers`. The vendor files
    record the spring constant, the sensitivity, the grid and (NanoScope) the tip radius, not the
    configuration: keep ``cfg`` to compare with the known fields.
    """
    if format not in SOFT_MAP_FORMATS:
        raise ParameterError(f"soft map format {format!r}: choose one of {', '.join(SOFT_MAP_FORMATS)}")
    if format != "afmforce-map":
        from ..io.writers import write_jpk_qi, write_nanoscope_fv

        shape = (cfg.ny, cfg.nx)
        if format == "jpk-qi":
            return write_jpk_qi(soft_map_curves(cfg), path, shape=shape, step=cfg.step, instrument="virtual QI",
                                force=force)
        reach = 1.5 * (cfg.ramp + cfg.topography) + 2 * cfg.setpoint / cfg.spring_constant
        return write_nanoscope_fv(soft_map_curves(cfg), path, shape=shape, step=cfg.step,
                                  deflection_lsb=_instrument(cfg).acquisition.lsb, z_range=reach,
                                  instrument="virtual force volume", force=force)
    from ..io.native.rawmap import write_map

    first = next(soft_map_curves(dataclasses.replace(cfg, nx=1, ny=1)))
    shared = {k: first.metadata[k] for k in _SHARED if k in first.metadata}
    shared["soft_map"] = {f.name: getattr(cfg, f.name) for f in dataclasses.fields(cfg)}

    def curves():
        for c in soft_map_curves(cfg):
            yield dataclasses.replace(c, truth=None,
                                      metadata={k: v for k, v in c.metadata.items() if k not in _SHARED})

    return write_map(curves(), path, shape=(cfg.ny, cfg.nx), metadata=shared, force=force)


def config_of(metadata) -> SoftMapConfig:
    """The :class:`SoftMapConfig` a virtual map file was written with (its ``soft_map`` metadata)."""
    raw = metadata.get("soft_map")
    if not isinstance(raw, dict):
        raise ParameterError("not a virtual soft map: no 'soft_map' metadata")
    return SoftMapConfig(**{k: tuple(v) if isinstance(v, list) else v for k, v in raw.items()})
