"""Compute the grid behind the interactive page and write the HTML file."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from .. import constants as C
from .._files import atomic_write_text
from ..errors import ParameterError
from ..limits import MAX_GRID_POINTS, check_count

__all__ = ["ExploreGrid", "compute_grid", "build_page", "DEFAULT_VELOCITIES", "DEFAULT_XIS"]

DEFAULT_VELOCITIES = (0.1e-6, 0.3e-6, 1e-6, 3e-6, 10e-6)  # [m/s]
DEFAULT_XIS = (0.001, 0.01, 0.1)  # [kg/s]
_TEMPLATE = Path(__file__).with_name("template.html")


@dataclass(frozen=True)
class ExploreGrid:
    """Downsampled trajectories on a velocity x xi grid (SI, lists for JSON).

    Attributes
    ----------
    velocities : list of float  [m/s]
    xis : list of float  [kg/s]
    runs : list of dict
        One per (velocity, xi), row-major in velocity: approach columns
        ``h``, ``z2``, ``h_app``, ``z2_app`` [m] up to shortly after contact, the cycle
        ``z``, ``theta`` [m, rad], and the summary numbers of the run.
    static : dict
        The static curve ``h``, ``z2`` [m] and its ``stable`` mask.
    """

    velocities: list
    xis: list
    runs: list
    static: dict
    parameters: dict = field(default_factory=dict)

    def to_json(self) -> str:
        return json.dumps(self.__dict__, allow_nan=False, separators=(",", ":"))


def _thin(mask: np.ndarray, n: int) -> np.ndarray:
    idx = np.flatnonzero(mask)
    if len(idx) <= n:
        return idx
    return idx[np.linspace(0, len(idx) - 1, n).round().astype(int)]


def _num(x) -> float | None:
    x = float(x)
    return round(x, 15) if math.isfinite(x) else None


def _r(a, scale=1.0, digits=5) -> list:
    return [None if not math.isfinite(v) else float(f"{v * scale:.{digits}g}") for v in np.asarray(a, float)]


def compute_grid(velocities: Sequence[float] = DEFAULT_VELOCITIES, xis: Sequence[float] = DEFAULT_XIS, *,
                 points: int = 600, progress: Callable[[float], None] | None = None) -> ExploreGrid:
    """Simulate the grid (beam model, the paper's Fig 5 parameters otherwise).

    Parameters
    ----------
    velocities : sequence of float
        Driving speeds [m/s].
    xis : sequence of float
        Viscous friction coefficients [kg/s].
    points : int
        Points kept per curve (the page stays small).
    """
    from ..dynamics import simulate, static_curve

    if not velocities or not xis:
        raise ParameterError("the explore grid needs at least one velocity and one xi")
    runs = []
    n = len(velocities) * len(xis)
    check_count("velocities x xis", n, MAX_GRID_POINTS, "grid points (one simulation each)")
    k = None
    for i, v in enumerate(velocities):
        for j, xi in enumerate(xis):
            tr = simulate(velocity=float(v), xi=float(xi), sample_rate=max(20e3, 2e5 * v / 1e-6))
            k = tr.spring_constant
            ev = tr.events
            appr = tr.segment == 0
            if math.isfinite(ev.contact_time):
                appr &= tr.time <= ev.contact_time + 2e-3 * (1e-7 / v)
            ia = _thin(appr & (tr.separation < 25e-9), points)
            ic = _thin(np.ones(len(tr), bool), points * 2)
            runs.append({
                "velocity": float(v), "xi": float(xi),
                "h": _r(tr.separation[ia]), "z2": _r(tr.deflection[ia]),
                "h_app": _r(tr.apparent_separation[ia]), "z2_app": _r(tr.apparent_deflection[ia]),
                "z": _r(tr.piezo_position[ic]), "theta": _r(tr.angle[ic]), "seg": tr.segment[ic].tolist(),
                "summary": {
                    "min_apparent_deflection": _num(ev.min_apparent_deflection),
                    "min_deflection": _num(ev.min_deflection),
                    "hysteresis_offset": _num(ev.hysteresis_offset),
                    "spike_height": _num(ev.spike_height),
                    "pull_off_position": _num(ev.pull_off_position),
                    "jumped": ev.jumped, "jump_in_note": ev.jump_in_note,
                },
            })
            if progress:
                progress(len(runs) / n)
    curve = static_curve(k, C.FIG5["radius"], h_max=25e-9, n=400)
    static = {"h": _r(curve.separation), "z2": _r(curve.deflection), "stable": curve.stable.tolist(),
              "jump_in_separation": _num(curve.jump_in_separation)}
    params = {"spring_constant": k, "radius": C.FIG5["radius"], "hamaker": C.FIG5["hamaker"],
              "theta0": C.FIG5["theta0"], "B": C.FIG5["B"]}
    return ExploreGrid([float(v) for v in velocities], [float(x) for x in xis], runs, static, params)


def build_page(out: str | Path = "afmforce-explore.html", grid: ExploreGrid | None = None, *,
               force: bool = True, progress: Callable[[float], None] | None = None) -> Path:
    """Write the self-contained interactive HTML page; returns its path."""
    grid = grid if grid is not None else compute_grid(progress=progress)
    html = _TEMPLATE.read_text(encoding="utf-8").replace("/*__DATA__*/null", grid.to_json())
    return atomic_write_text(out, html, force=force)
