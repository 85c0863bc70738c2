"""Dynamics engine: simulate a dynamic AFM force measurement (spec sections 3 and 5).

Public API::

    from afmforce.dynamics import simulate, SimulationConfig
    traj = simulate()                      # the paper's Fig 5 (beam, xi = 0.1 kg/s, 0.1 um/s)
    traj = simulate(xi=0.01, velocity=1e-6)
    traj = simulate(model="spring", mass=1e-8, spring_constant=0.21, velocity=10e-6)
    trajs = simulate_many([dict(xi=x) for x in (0.01, 0.1)])   # many runs, one call
    cfg = SimulationConfig(probe=SpringProbe(mass=1e-9), drive=Drive(velocity=7.2e-6))  # by parts
    traj.summary(); traj.events; traj.write("run.csv")

Modules: :mod:`.config` (``SimulationConfig`` and its flat names) and
:mod:`.parts` (its parts: probe, surface, friction, drive, solver options),
:mod:`.models` (vector fields, Jacobians, friction registry),
:mod:`.drive` (protocols), :mod:`.radau` (compiled Radau IIA integrator),
:mod:`.events`, :mod:`.trajectory`, :mod:`.simulate`, :mod:`.batch`, :mod:`.static`
(quasi-static curves), :mod:`.reference` (a plain scipy implementation used as
an independent cross-check).
"""

from .config import DEFAULT_B, MODELS, SAMPLING, SimulationConfig
from .parts import BeamProbe, Drive, Friction, SolverOptions, SpringProbe, Surface
from .events import Events
from .registries import FRICTION_LAWS, RINGING, FrictionLaw, RingingTreatment
from .guard import ConvergenceWarning
from .simulate import DynamicsWarning, simulate
from ._helper import BEFORE_COMPILE
from .batch import simulate_many
from .static import StaticCurve, static_curve, static_deflection, static_jump_in
from .trajectory import COLUMNS, SolverStats, Trajectory

# numba keys integrate_segment's cache on radau.py alone, yet it inlines models.py and the pieces:
# a change in any source of the package must recompile (_jit.purge_stale_cache; a stale cache once
# silently ran the undamped vector field). Here, before anything compiled is called.
# The laws' kernels (afmforce.surface_laws) are inlined too: their sources are in the digest.
from ._jit import cache_sources as _sources
from ._jit import purge_stale_cache as _purge
from .radau import integrate_segment as _entry

_purge(_entry, _sources())
del _sources, _purge, _entry

__all__ = [
    "BEFORE_COMPILE",
    "simulate",
    "simulate_many",
    "SimulationConfig",
    "BeamProbe",
    "SpringProbe",
    "Surface",
    "Friction",
    "Drive",
    "SolverOptions",
    "Trajectory",
    "Events",
    "SolverStats",
    "DynamicsWarning",
    "ConvergenceWarning",
    "FRICTION_LAWS",
    "FrictionLaw",
    "RINGING",
    "SAMPLING",
    "RingingTreatment",
    "MODELS",
    "DEFAULT_B",
    "COLUMNS",
    "StaticCurve",
    "static_curve",
    "static_deflection",
    "static_jump_in",
]
