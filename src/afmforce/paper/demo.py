"""The demo's virtual experiment: virtual AFM -> raw file -> analysis -> Hamaker constant vs truth.

Two runs of the paper's inclined cantilever (R = 100 nm, A = 5e-19 J) recorded
with the ``typical`` instrument and analysed by the pipeline as if they were
measured curves: a slow run without friction, where the van der Waals fit
recovers the true Hamaker constant, and the same run with tip friction
(xi v = 1e-9 N, spec section 7), where the apparent attraction is weaker and
the fit underestimates A: the paper's warning, measured end to end.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

from .. import constants as C

__all__ = ["VirtualExperiment", "virtual_experiment", "virtual_runs", "draw_virtual", "DEMO_RUNS"]

#: (label, simulation overrides) of the demo's two runs.
DEMO_RUNS = (
    ("quasi-static, no friction", dict(friction="none", velocity=0.2e-6)),
    ("with friction, xi v = 1e-9 N", dict(friction="viscous", xi=0.005, velocity=0.2e-6)),
)
_COMMON = dict(model="beam", start=-60e-9, turn=30e-9, end=-250e-9, sample_rate=5e3)


@dataclass(frozen=True)
class VirtualExperiment:
    """One analysed virtual run.

    Attributes
    ----------
    label : str
    hamaker_true, hamaker_fit, hamaker_se : float  [J]
    relative_error : float  fit/true - 1 [-]
    calibration_factor_true, calibration_factor_fit : float  [m/rad], [m/V]
    friction : str  friction signature found by the analysis
    verdict : str  the analysis's dynamic diagnosis
    raw_file, figure : Path or None  what was written
    """

    label: str
    hamaker_true: float
    hamaker_fit: float
    hamaker_se: float
    relative_error: float
    jump_in_separation: float
    friction: str
    verdict: str
    warnings: tuple[str, ...]
    raw_file: Path | None = None
    figure: Path | None = None


def virtual_experiment(out_dir: str | Path | None = None, seed: int = 1) -> list[VirtualExperiment]:
    """Simulate, record, write, read back and analyse the demo's runs (with figures).

    Parameters
    ----------
    out_dir : path, optional
        Where to write the raw files (afmforce raw text) and analysis figures.
    seed : int
        Seed of the instrument's noise and drift.
    """
    runs = virtual_runs(out_dir, seed)
    draw_virtual(runs)
    return [r for r, _, _ in runs]


def virtual_runs(out_dir: str | Path | None = None, seed: int = 1) -> list[tuple]:
    """:func:`virtual_experiment` without drawing: ``(result, analysis, raw curve)`` per run,
    ``result.figure`` the path :func:`draw_virtual` writes (None without ``out_dir``)."""
    from ..dynamics import simulate
    from ..instrument import get_preset
    from ..analysis.options import ProbeCalibration
    from ..analysis.pipeline import analyze
    from ..io.native.rawfile import read_raw, write_raw

    out = Path(out_dir) if out_dir is not None else None
    results = []
    for i, (label, kw) in enumerate(DEMO_RUNS):
        tr = simulate(**_COMMON, **kw)
        raw = get_preset("typical").record(tr, seed=seed + i)
        raw_file = fig_file = None
        if out is not None:
            out.mkdir(parents=True, exist_ok=True)
            raw_file = out / f"virtual_run_{i + 1}.txt"
            write_raw(raw, raw_file, force=True)
            raw = read_raw(raw_file)  # analyse what a user would: the file
            fig_file = out / f"virtual_run_{i + 1}_analysis.png"
        res = analyze(raw, probe=ProbeCalibration(radius=C.FIG5["radius"], spring_constant=tr.spring_constant))
        a_true = tr.config.hamaker
        results.append((VirtualExperiment(
            label=label, hamaker_true=a_true, hamaker_fit=res.hamaker, hamaker_se=res.hamaker_se,
            relative_error=res.hamaker / a_true - 1.0 if math.isfinite(res.hamaker) else math.nan,
            jump_in_separation=res.jump_in_separation, friction=res.friction, verdict=res.verdict,
            warnings=tuple(res.warnings), raw_file=raw_file, figure=fig_file), res, raw))
    return results


def draw_virtual(runs: list[tuple]) -> None:
    """Write the analysis figure of each of :func:`virtual_runs`' runs that has a path."""
    for result, analysis, raw in runs:
        if result.figure is not None:
            _figure(analysis, raw, result.figure)


def _figure(result, raw, path: Path) -> Path:
    from .._files import atomic_path
    from ..plotting import plot_summary

    fig = plot_summary(result, raw)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=90, format="png")
    return path
