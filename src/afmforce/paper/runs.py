"""The simulations behind the paper's dynamic figures and numbers, cached per process.

Each run is named by the figure it serves and its parameters are the paper's
(spec sections 3, 5, 6). ``run(**overrides)`` memoises ``simulate`` so that the
report and the figures share one solve.
"""

from __future__ import annotations

import functools

from .. import constants as C

#: Fig 1: simple spring with a colloid probe (section 2.1).
FIG1_RUN = dict(model="spring", mass=C.FIG1["mass"], spring_constant=C.FIG1["spring_constant"],
                radius=C.FIG1["radius"], start=-30e-9, turn=2e-9, end=-150e-9, sample_rate=200e3)

#: Figs 5-6: inclined cantilever with viscous friction (section 2.3); defaults of SimulationConfig.
FIG5_RUN = dict(model="beam", sample_rate=100e3)

#: Figs 9-10 theory: simple spring, 1 ug, k = 0.21 N/m, R = 220 nm (section 3).
FIG9_RUN = dict(model="spring", mass=C.FIG9["mass"], spring_constant=C.FIG9["spring_constant"],
                radius=C.FIG9["radius"], start=-150e-9, turn=2e-9, end=-300e-9)

#: The experiments of Figs 9-10: (speed [m/s], sample rate [Hz]).
FIG9_EXPERIMENTS = ((0.82e-6, 1.6e3), (0.82e-6, 800.0), (1.36e-6, 2.7e3), (2.0e-6, 4e3), (7.2e-6, 1.6e3))


@functools.lru_cache(maxsize=64)
def _cached(items: tuple):
    from ..dynamics import simulate

    return simulate(**dict(items))


def run(**overrides):
    """Simulate with ``overrides`` (hashable values), memoised for this process."""
    return _cached(tuple(sorted(overrides.items())))
