"""The run of a simulation sweep: one approach-retract cycle, one summary row.

:func:`simulate_run` calls :func:`afmforce.dynamics.simulate` with the run's
parameters (the flat names of :class:`~afmforce.dynamics.SimulationConfig`,
:data:`afmforce.dynamics.config.FLAT`, e.g. ``xi``, ``velocity``, ``friction``; every
other field keeps the paper's Fig 5 default), flattens
``Trajectory.summary()`` into ``a.b`` columns, and adds the error of the
apparent attraction against the static theory (spec sections 2 and 7): the
static jump-in separation ``h_s`` (largest h with ``Fs'(h) = k``), the static
deflection there ``d_s = Fs(h_s) / k``, and

- ``attraction_error = min_apparent_deflection - d_s`` [m] (> 0: the
  measurement underestimates the attraction, as the paper reports),
- ``attraction_ratio = min_apparent_deflection / d_s`` [-] (1: static theory).
"""

from __future__ import annotations

import functools
import math
import warnings

from .._fields import QUANTITIES
from ..errors import MissingDependencyError
from ..forces import static_jump_in_separation, vdw_force
from .chunks import flatten

__all__ = ["simulate_run", "simulate_runs", "simulation_dimensions", "OUTPUT_UNITS", "parameter_units",
           "check_runs", "invalid_run_causes", "CHECK_RUNS"]

#: How many of a sweep's runs :func:`check_runs` builds before any work (evenly spread over its table;
#: ~13 us each)
CHECK_RUNS = 2000

#: Output column -> SI unit ("" for plain numbers and text).
OUTPUT_UNITS: dict[str, str] = {
    "jump_in.time": "s", "jump_in.piezo_position": "m", "jump_in.separation": "m",
    "pull_off.piezo_position": "m", "pull_off.force": "N",
    "min_deflection": "m", "min_apparent_deflection": "m",
    "hysteresis_offset": "m", "spike_height": "m",
    "solver.status": "", "solver.steps": "", "solver.rhs_evaluations": "", "solver.wall_time": "s",
    "static_jump_in_separation": "m", "static_jump_in_deflection": "m",
    "attraction_error": "m", "attraction_ratio": "",
}


def _dynamics():
    try:
        from .. import dynamics
    except ImportError as exc:
        raise MissingDependencyError(
            f"afmforce.dynamics cannot be imported ({exc}); simulation sweeps need the dynamics engine"
        ) from exc
    return dynamics


def simulation_dimensions() -> dict[str, str | None]:
    """Dimension of every flat parameter name of :class:`SimulationConfig` (None: text), from
    the field metadata of its part (:data:`afmforce.dynamics.config.FLAT`)."""
    _dynamics()
    from ..dynamics.config import FLAT

    out = {}
    for name, where in FLAT.items():
        spec = where.spec
        if spec is None:
            out[name] = None if isinstance(where.default, str) else "dimensionless"
        else:
            out[name] = "dimensionless" if spec.dimension == "integer" else spec.dimension
    return out


def parameter_units(names) -> dict[str, str]:
    """SI unit of each parameter name ("" when plain or text), from :data:`afmforce._fields.QUANTITIES`."""
    return {n: QUANTITIES[n].unit if n in QUANTITIES else "" for n in names}


def simulate_run(**parameters) -> dict:
    """Simulate one cycle with these flat :class:`SimulationConfig` names; one summary row.

    Returns the flattened ``Trajectory.summary()`` plus ``static_jump_in_separation``,
    ``static_jump_in_deflection``, ``attraction_error`` [m], ``attraction_ratio`` [-]
    and ``warnings`` (text of warnings the run raised, or None).
    """
    dyn = _dynamics()
    config = dyn.SimulationConfig(**parameters)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        trajectory = dyn.simulate(config)
    return _row(config, trajectory, caught)


def check_runs(spec) -> None:
    """Refuse a sweep none of whose runs is a valid simulation, before anything is dispatched.

    Each value on its own may lie in its field's range while no run is a valid configuration
    (``--set start=1um`` with the default turn at 20 nm: the drive would move the wrong way), and
    every run would then fail one by one. Builds the :class:`SimulationConfig` of up to
    :data:`CHECK_RUNS` runs spread over the table; a sweep with at least one valid run goes on
    (its invalid runs are recorded with their error, as before).

    Raises
    ------
    ParameterError
        None of the runs checked is valid; the message is the first run's error.
    """
    import numpy as np

    from ..errors import AfmforceError, ParameterError

    dyn = _dynamics()
    table = spec.table()
    n = len(table)
    if n == 0:
        return
    picks = np.unique(np.linspace(0, n - 1, min(n, CHECK_RUNS)).round().astype(np.int64))
    first = None
    for i in picks:
        row = table.iloc[[int(i)]].to_dict("records")[0]
        try:
            dyn.SimulationConfig(**row)
            return
        except AfmforceError as exc:
            first = first or (int(i), exc)
    causes = invalid_run_causes(spec)
    words = {"sets": "the setting", "grid": "the grid of", "ranges": "the range of"}
    names = " or ".join(f"{words[kind]} {name}" for kind, i, name in causes)
    exc = ParameterError(f"no run of this sweep is a valid simulation ({len(picks)} of {n} checked; run "
                         f"{first[0]}: {first[1]}): change {names}")
    exc.causes = causes
    raise exc


def invalid_run_causes(spec) -> list[tuple[str, int, str]]:
    """The inputs of a sweep none of whose runs is valid that make it so, as
    ``(kind, index, parameter)`` with ``kind`` one of ``"sets"``, ``"grid"``, ``"ranges"`` and
    ``index`` its place in that list (the order of :class:`~afmforce.sweep.SweepSpec`).

    The settings alone (every other parameter at its default) invalid: the settings without which
    they are valid (all of them when no single one is). Otherwise each grid axis or range all of
    whose values (a range: its ends and middle) are invalid with the settings; when none is on its
    own, the combination is: every grid axis and range."""
    dyn = _dynamics()
    from ..errors import AfmforceError

    def valid(values: dict) -> bool:
        try:
            dyn.SimulationConfig(**values)
            return True
        except AfmforceError:
            return False

    fixed = dict(spec.fixed)
    if not valid(fixed):
        sets = [("sets", j, name) for j, (name, _) in enumerate(spec.fixed)
                if valid({k: v for k, v in fixed.items() if k != name})]
        return sets or [("sets", j, name) for j, (name, _) in enumerate(spec.fixed)]
    swept = [("grid", i, axis.name, list(axis.values)) for i, axis in enumerate(spec.grid)]
    swept += [("ranges", i, r.name, [r.lo, 0.5 * (r.lo + r.hi), r.hi]) for i, r in enumerate(spec.ranges)]
    alone = [(kind, i, name) for kind, i, name, values in swept
             if not any(valid({**fixed, name: v}) for v in values)]
    return alone or [(kind, i, name) for kind, i, name, _ in swept]


def simulate_runs(parameter_rows: list[dict], threads: int | None = None) -> list:
    """:func:`simulate_run` for many rows in one call (:func:`afmforce.dynamics.simulate_many`).

    The sweep's chunk runner calls this (``simulate_run.batch``) instead of one
    :func:`simulate_run` per row: the same rows, the compiled integration of
    several runs on a thread pool (one thread per core, one inside a Dask
    worker). A run that fails gets its exception in its place of the result.
    """
    from ..dynamics.batch import run_many

    def finish(run):
        try:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                trajectory = run.finish()
            return _row(run.cfg, trajectory, caught)
        except Exception as exc:    # recorded in its row, like simulate_run's errors
            return exc

    out = [None] * len(parameter_rows)
    configs, where = [], []
    for i, kw in enumerate(parameter_rows):       # non-library errors (TypeError...) too
        try:
            configs.append(_dynamics().SimulationConfig(**kw))
            where.append(i)
        except Exception as exc:
            out[i] = exc
    for i, r in zip(where, run_many(configs, finish, threads=threads, on_error="return")):
        out[i] = r
    return out


def _batch_threads() -> int:
    from ..dynamics.batch import default_threads
    return default_threads()


#: the chunk runner's batched protocol (sweep.parametric): ``func.batch(rows)``, ``func.batch_threads()``
simulate_run.batch = simulate_runs
simulate_run.batch_threads = _batch_threads


@functools.lru_cache(maxsize=4096)
def _static_jump_in(k: float, radius: float, hamaker: float, z0: float) -> tuple[float, float]:
    """Static jump-in separation [m] and deflection there [m] (a root solve, 0.2 ms: a sweep
    that keeps the spring and the surface fixed solves it once, not once per run)."""
    h_s = float(static_jump_in_separation(k, radius, hamaker, z0))
    return h_s, float(vdw_force(h_s, radius, hamaker, z0)) / k


def _row(config, trajectory, caught) -> dict:
    row = flatten(trajectory.summary())
    k, s = config.force_constant, config.surface
    if s.eq2_only:
        h_s, d_s = _static_jump_in(k, s.paper_radius, s.hamaker, s.z0)
    else:   # issue 25: the double layer moves the static jump-in
        from ..dynamics.static import surface_jump_in
        h_s, _, d_s = surface_jump_in(k, s)
    measured = float(row.get("min_apparent_deflection", math.nan))
    row["static_jump_in_separation"] = h_s
    row["static_jump_in_deflection"] = d_s
    row["attraction_error"] = measured - d_s
    row["attraction_ratio"] = measured / d_s
    row["warnings"] = "; ".join(str(w.message) for w in caught) or None
    return row
