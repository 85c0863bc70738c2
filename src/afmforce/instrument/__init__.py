"""The virtual AFM: emulate the instrument so that simulated runs produce raw signals.

Paper section 3 (spec section 6): a nonlinear, hysteretic piezo, a position
detector with backlash and digitisation steps, interference fringes from the
substrate, thermal drift, noise and finite sampling. Compose components into
an :class:`Instrument` (or take a preset from :data:`PRESETS`) and call
:meth:`Instrument.record` on a :class:`afmforce.dynamics.Trajectory`::

    from afmforce.instrument import get_preset
    raw = get_preset("paper").record(trajectory, seed=1)
"""

from __future__ import annotations

from .acquisition import Acquisition
from .config import build_instrument, load_config
from .detector import PAPER_BACKLASH, PositionDetector, fit_backlash_law
from .instrument import Instrument
from .noise import Drift, Noise
from .photodiode import Photodiode, fringe_length
from .piezo import Piezo
from .presets import PRESETS, Preset, get_preset
from .protocols import out_then_in

__all__ = [
    "Acquisition",
    "Drift",
    "Instrument",
    "Noise",
    "PAPER_BACKLASH",
    "PRESETS",
    "Photodiode",
    "Piezo",
    "PositionDetector",
    "Preset",
    "build_instrument",
    "fit_backlash_law",
    "fringe_length",
    "get_preset",
    "load_config",
    "out_then_in",
]
