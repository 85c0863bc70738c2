"""The position detector on the scanner: linear, with backlash and a digitisation step.

The paper's Park Autoprobe measures the scanner's motion with a
position-sensitive photodetector attached to the piezo tube (section 3.1,
Fig 7B-C). Interferometry showed it to be linear, but

* on the inward run the true position was larger than the measured one, so
  that the inward run had to be shifted by ``+b`` to overlay the outward run:
  ``b`` = +57 nm at 17 um/s, +33 at 8.4, +27 at 6.6 and about 0 at 0.4 um/s
  (Figs 7C and 8; uncertainty about +-10 nm). The paper suggests the
  detector rubs against the housing and is displaced by about +-b/2 on the
  two runs. We model it as **backlash**: a play operator of half width
  ``b(v)/2`` between the true position and the reading, with a
  speed-dependent width ``b(v) = b_ref (v / v_ref)^p`` (``v`` the mean drive
  speed of the run: each block of equal ``segment`` is one run). A least-squares fit of this smooth monotone law to the
  paper's four points gives ``b_ref = 37.3 nm`` at ``v_ref = 10 um/s`` and
  ``p = 0.817`` (:func:`fit_backlash_law`; residuals 0.5-2.7 nm, well inside
  the paper's +-10 nm). The play makes the reading lag by ``b/2`` in the
  direction of motion: ``reading = z - b/2`` inward, ``z + b/2`` outward,
  continuous through the turning point (a dead band of width ``b``), and it
  vanishes at rest.
* its output is digitised in steps that an 11-point running average smooths
  away (Fig 7C). **Decision**: the step is 5 nm in the ``paper`` preset: the
  paper says the average is equivalent to interpolating between successive
  levels, i.e. about 11 samples per level, and its Fig 9 runs advance about
  0.5 nm per sample (0.82 um/s at 1.6 kHz ... 2.0 um/s at 4 kHz).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .._fields import meta as _meta
from .._validate import non_negative, positive
from ..errors import ParameterError

__all__ = ["PositionDetector", "PAPER_BACKLASH", "fit_backlash_law", "run_bounds", "run_speeds"]

#: Paper section 3.1, Figs 7C and 8: drive speed [m/s] -> shift of the inward run [m]
#: needed to overlay the constant-compliance lines (+-10 nm).
PAPER_BACKLASH: tuple[tuple[float, float], ...] = (
    (17e-6, 57e-9),   # Fig 7C
    (8.4e-6, 33e-9),  # text, "not shown"
    (6.6e-6, 27e-9),  # Fig 8A
    (0.4e-6, 0.0),    # Fig 8B, "no shift appeared to be necessary"
)


@dataclass(frozen=True)
class PositionDetector:
    """Scanner position detector (see the module docstring).

    Parameters
    ----------
    gain : float
        Reading per true displacement [-] (> 0).
    backlash : float
        Backlash width b_ref at the reference speed [m] (0: none). The inward
        run reads ``b/2`` low, the outward run ``b/2`` high.
    backlash_speed : float
        Reference speed v_ref [m/s].
    backlash_exponent : float
        p in ``b(v) = b_ref (v / v_ref)^p`` [-] (>= 0; 0: speed independent).
    step : float
        Digitisation step of the reading [m] (0: none).
    noise : float
        White noise added before digitisation, rms [m].
    """

    gain: float = field(default=1.0, metadata=_meta("dimensionless", "", "reading per true displacement"))
    backlash: float = field(default=0.0,
          metadata=_meta("length", "m", "backlash width b_ref at backlash_speed"))
    backlash_speed: float = field(default=10e-6,
          metadata=_meta("velocity", "m/s", "reference speed v_ref of the backlash law"))
    backlash_exponent: float = field(default=1.0,
          metadata=_meta("dimensionless", "", "exponent p of b(v) = b_ref (v/v_ref)^p"))
    step: float = field(default=0.0, metadata=_meta("length", "m", "digitisation step of the reading"))
    noise: float = field(default=0.0, metadata=_meta("length", "m", "white noise rms before digitisation"))

    def __post_init__(self) -> None:
        set_ = lambda n, v: object.__setattr__(self, n, v)  # noqa: E731
        set_("gain", positive("detector gain", self.gain))
        set_("backlash", non_negative("detector backlash", self.backlash, "m"))
        set_("backlash_speed", positive("detector backlash_speed", self.backlash_speed, "m/s"))
        set_("backlash_exponent", non_negative("detector backlash_exponent", self.backlash_exponent))
        set_("step", non_negative("detector step", self.step, "m"))
        set_("noise", non_negative("detector noise", self.noise, "m"))

    def backlash_width(self, speed) -> np.ndarray | float:
        """b(v) [m]: the shift of the inward run that overlays the outward run."""
        v = np.abs(np.asarray(speed, float))
        b = self.backlash * (v / self.backlash_speed) ** self.backlash_exponent
        return float(b) if b.ndim == 0 else b

    def analog(self, time, true, segment=None) -> np.ndarray:
        """Reading before noise and digitisation, on the trajectory's grid [m].

        ``segment`` splits the curve into runs (blocks of equal value); the
        backlash width of each run follows its mean speed. Without it the
        whole curve is one run.
        """
        t = np.asarray(time, float)
        z = np.asarray(true, float)
        if self.backlash > 0.0 and z.size > 1:
            speed = run_speeds(t, z, segment)
            from . import _kernels  # numba: imported on first use

            z = _kernels.variable_play(np.ascontiguousarray(z), 0.5 * self.backlash_width(speed), float(z[0]))
        return z * self.gain if self.gain != 1.0 else z.copy()

    def digitise(self, reading: np.ndarray, rng: np.random.Generator | None) -> np.ndarray:
        """Add white noise and round to the digitisation step [m]."""
        out = np.asarray(reading, float)
        if self.noise > 0.0:
            if rng is None:
                raise ParameterError("detector noise needs a random generator")
            out = out + rng.normal(0.0, self.noise, out.size)
        if self.step > 0.0:
            out = self.step * np.round(out / self.step)
        return out

    @property
    def is_identity(self) -> bool:
        """True when the reading equals the true position exactly."""
        return self.gain == 1.0 and self.backlash == 0.0 and self.step == 0.0 and self.noise == 0.0


def run_bounds(segment, n: int) -> list[tuple[int, int]]:
    """``[(start, stop), ...]`` index ranges of the blocks of equal ``segment``."""
    if segment is None:
        return [(0, n)]
    seg = np.asarray(segment)
    cuts = np.flatnonzero(seg[1:] != seg[:-1]) + 1
    edges = np.concatenate(([0], cuts, [n]))
    return [(int(a), int(b)) for a, b in zip(edges[:-1], edges[1:])]


def run_speeds(time, position, segment=None) -> np.ndarray:
    """Mean drive speed of the run each sample belongs to [m/s].

    A run is a block of equal ``segment``; its speed is the net displacement
    over its duration (the boundary sample before it is included).
    """
    t = np.asarray(time, float)
    z = np.asarray(position, float)
    out = np.zeros(z.size)
    for a, b in run_bounds(segment, z.size):
        i = max(a - 1, 0)
        dt = t[b - 1] - t[i]
        out[a:b] = abs(z[b - 1] - z[i]) / dt if dt > 0 else 0.0
    return out


def fit_backlash_law(speeds, widths, reference_speed: float = 10e-6) -> tuple[float, float]:
    """Least-squares fit of ``b = b_ref (v / v_ref)^p`` to measured backlash widths.

    Parameters
    ----------
    speeds : array_like
        Drive speeds [m/s].
    widths : array_like
        Shifts of the inward run that overlay the runs [m].
    reference_speed : float
        v_ref [m/s].

    Returns
    -------
    (b_ref, p) : tuple of float
        [m], [-].
    """
    from scipy.optimize import curve_fit

    v = np.asarray(speeds, float) / reference_speed
    b = np.asarray(widths, float)
    if v.size < 2 or v.shape != b.shape or np.any(v <= 0):
        raise ParameterError("fit_backlash_law needs at least two positive speeds with one width each")
    scale = max(float(np.max(np.abs(b))), 1e-300)
    popt, _ = curve_fit(lambda x, a, p: a * x**p, v, b / scale, p0=(1.0, 1.0))
    if not all(math.isfinite(x) for x in popt):
        raise ParameterError("the backlash law fit did not converge")
    return float(popt[0] * scale), float(popt[1])
