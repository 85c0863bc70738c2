"""Caps on the work one request may ask for, declared once for every face.

The command line, the web application and the Python records
(:class:`~afmforce.dynamics.SimulationConfig`) refuse the same sizes with the
same message, before anything is allocated or computed. A cap is a size no
force measurement needs (a real force curve has at most ~1e6 samples) and
that would exhaust the memory or the patience of the machine.

This module imports nothing heavy: the command line checks with it while parsing.
"""

from __future__ import annotations

import math

from .errors import ParameterError

__all__ = ["MAX_SAMPLES", "MAX_MEMBER_BYTES", "CONFIG_BYTES", "SERVER_MAX_SAMPLES", "SERVER_MAX_CURVES", "BATCH_MAX_CURVES", "SERVER_SESSION_STORAGE", "SERVER_STORAGE", "SERVER_MAX_UPLOAD", "SERVER_BODIES_IN_FLIGHT", "CONFIRM_RUNS", "MAX_RUNS", "MAX_DESIGN_CURVES", "MAX_SPEEDS", "MAX_PLAN_SAMPLES",
           "MAX_DESIGNS", "MAX_STARTS", "simulation_samples", "check_samples", "check_count", "check_design", "caps_markdown"]

#: The most samples one simulated cycle may have (records, CLI, sweeps): the paper's slowest run
#: (Fig 9 at 1 nm/s, 4.3e6 samples) fits; a real force curve has at most ~1e6.
MAX_SAMPLES = 10_000_000
#: The most bytes one member of a zip archive (a channel of a JPK file) may unpack to: the
#: samples of the longest cycle, 8 bytes each. A 1.5 MB JPK file whose deflection member unpacked
#: to 800 MB of zeros (a zip bomb) took 6 GB and minutes before its channels were found to differ.
MAX_MEMBER_BYTES = MAX_SAMPLES * 8
#: The most bytes of a settings file read whole (a sweep or instrument TOML file, a calibration
#: JSON): the largest written is a few kB; ``sweep --config /dev/zero`` filled the memory until the
#: kernel killed the process (67 s, exit 137).
CONFIG_BYTES = 1_000_000
#: The most samples of one cycle a request to ``afmforce serve`` may simulate: a server shares its
#: memory among its clients (about 90 MB of trajectory per request; issue 33). Declared here, beside
#: :data:`MAX_SAMPLES`, so that every face reads its caps from one module.
SERVER_MAX_SAMPLES = 1_000_000
#: The most curves one analysis request to ``afmforce serve`` takes, all its files together (a 256 x 256
#: map, the largest grid of a JPK QI map; a real map's count is read from its header before any curve
#: is read): an ARDF file of 68 kB whose 1,000 line pointers all named its one line declared 999,001
#: curves, and the server made a work item for each and analysed for its whole budget (504).
SERVER_MAX_CURVES = 65_536
#: The most curves ``afmforce analyze`` (and :func:`afmforce.sweep.files.plan_curves`, ``analyze_files``)
#: takes from its files together unless told more (``--max-curves``, ``max_curves=``): sixteen 256 x 256
#: maps. A map's count is read from its header (each reader bounds it by the bytes the file holds)
#: before any work item is made; a 68 kB ARDF file whose 1,000 line pointers named its one line made
#: 999,001 items and analysed on (killed after 90 s, 365 MB).
BATCH_MAX_CURVES = 1_048_576
#: The most bytes one session of ``afmforce serve`` may keep stored: its uploads, its jobs' records
#: with their results and its sweeps' stores (ten uploads of the largest size a request may carry,
#: 200 MB). One more upload or job is refused (413) until the session deletes files or jobs or
#: expires; nothing stored is ever evicted.
SERVER_SESSION_STORAGE = 2_000_000_000
#: The most bytes ``afmforce serve`` keeps stored for all its sessions together (uploads, job results, sweep stores).
SERVER_STORAGE = 20_000_000_000
#: The most bytes of one request's body to ``afmforce serve`` (its setting ``max_upload``, ``--max-upload``):
#: refused 413 from its ``Content-Length`` before it is read, or as a chunked body grows past it.
SERVER_MAX_UPLOAD = 200_000_000
#: The most bytes of request bodies ``afmforce serve`` receives at once, all sessions together (five
#: uploads of the largest size): Starlette spools each to its temporary folder before any route runs,
#: so these bytes are on disk before a session's storage counts them; past it a request is 429 ``busy``.
#: A session's bodies in flight count against its storage with what it keeps (413 ``storage_full``).
SERVER_BODIES_IN_FLIGHT = 5 * SERVER_MAX_UPLOAD
#: Sweeps (and precomputed grids) of more runs than this need an explicit yes (``--yes``).
CONFIRM_RUNS = 100_000
#: The most runs of one sweep, even with a yes (its parameter table is built before any run).
MAX_RUNS = 5_000_000
#: The most curves one measurement design (``plan``) may choose.
MAX_DESIGN_CURVES = 20
#: The most candidate speeds one measurement design may weigh.
MAX_SPEEDS = 40
#: The most designs (choices of curves among the candidate speeds, repeats allowed) one plan weighs.
MAX_DESIGNS = 1_000_000
#: The most samples of all candidate curves of one design together (``plan``; each is simulated).
MAX_PLAN_SAMPLES = 20_000_000

#: The most local fits one dynamic fit starts from the best points of its scan (``fit --starts``,
#: the web's ``starts``, ``fit_dynamic(starts=)``): the scan keeps a few best points, so more starts only
#: re-fit the same ones (the command line took 100,000,000 and ran, the web refused 7).
MAX_STARTS = 6

#: Bytes per sample of a trajectory (its eleven float64 columns), for the message.
_BYTES_PER_SAMPLE = 88


def simulation_samples(start: float, turn: float, end: float, velocity: float,
                       retract_velocity: float | None, dwell: float, sample_rate: float) -> float:
    """Samples of one cycle: (approach + retract) / speed + dwell, times the sample rate [-]."""
    retract = velocity if retract_velocity is None else retract_velocity
    return ((turn - start) / velocity + (turn - end) / retract + dwell) * sample_rate


def _memory(n_bytes: float) -> str:
    return next(f"{n_bytes / f:.3g} {u}" for f, u in ((1e15, "PB"), (1e12, "TB"), (1e9, "GB"), (1e6, "MB"))
                if n_bytes >= f or u == "MB")


def check_samples(n: float, where: str = "") -> None:
    """Refuse a cycle of more than :data:`MAX_SAMPLES` samples before anything is allocated.

    Raises
    ------
    ParameterError
        Naming the quantities that set the count (sample_rate, velocity, the drive).
    """
    if not math.isfinite(n) or n > MAX_SAMPLES:
        raise ParameterError(
            f"{where}the cycle would have about {n:.3g} samples ({_memory(n * _BYTES_PER_SAMPLE)} of "
            f"trajectory), more than the {MAX_SAMPLES:.0e} a run may have; lower `sample_rate`, raise "
            "`velocity`, shorten the drive (`start`, `turn`, `end`) or the `dwell`")


def check_count(name: str, n: float, cap: int, what: str) -> None:
    """Refuse ``n`` > ``cap`` (``name``: what is counted, a quantity as `` `key` ``, e.g. `` `n_curves` ``;
    ``what``: the unit counted)."""
    if not math.isfinite(n) or n > cap:
        raise ParameterError(f"{name}: {n:,.0f} {what} is more than the {cap:,} one request may ask for")


def check_design(n_speeds: int, n_curves: int, samples: float) -> None:
    """Refuse a measurement design too large to weigh, before any curve is simulated.

    Parameters
    ----------
    n_speeds : int
        Candidate speeds (at most :data:`MAX_SPEEDS`).
    n_curves : int
        Curves in a design (at most :data:`MAX_DESIGN_CURVES`); the designs,
        ``C(n_speeds + n_curves - 1, n_curves)``, at most :data:`MAX_DESIGNS`.
    samples : float
        Samples of all candidate curves together (at most :data:`MAX_PLAN_SAMPLES`).
    """
    check_count("`speeds`", n_speeds, MAX_SPEEDS, "candidate speeds")
    check_count("`n_curves`", n_curves, MAX_DESIGN_CURVES, "curves in a design")
    designs = math.comb(n_speeds + n_curves - 1, n_curves) if n_speeds > 0 and n_curves > 0 else 0
    if designs > MAX_DESIGNS:
        raise ParameterError(f"{n_curves} curves among {n_speeds} candidate speeds make {designs:,} designs to "
                             f"weigh, more than {MAX_DESIGNS:,}; give fewer speeds or curves")
    if not math.isfinite(samples) or samples > MAX_PLAN_SAMPLES:
        raise ParameterError(f"the candidate curves would have about {samples:.3g} samples together, more than "
                             f"{MAX_PLAN_SAMPLES:.0e}; lower `points_per_nm` (or the sample rates) or shorten the "
                             "drive (`start`, `turn`)")


def caps_markdown() -> str:
    """The docs table of the caps (docs/ranges.md holds it verbatim)."""
    rows = [("samples of one simulated cycle", MAX_SAMPLES, "simulate, sweep, the records"),
            ("bytes one member of a JPK archive unpacks to", MAX_MEMBER_BYTES, "the JPK readers"),
            ("bytes of a settings file (sweep or instrument TOML, calibration JSON)", CONFIG_BYTES,
             "sweep and simulate (their settings files), the probe calibration record"),
            ("samples of one cycle a web request simulates", SERVER_MAX_SAMPLES, "afmforce serve"),
            ("curves one web analysis request takes (all its files)", SERVER_MAX_CURVES, "afmforce serve"),
            ("curves one analysis of files takes (all its files), unless raised", BATCH_MAX_CURVES,
             "analyze, plan_curves, analyze_files (their `max_curves`)"),
            ("bytes of one web request's body", SERVER_MAX_UPLOAD, "afmforce serve (its setting `max_upload`)"),
            ("bytes of request bodies the web receives at once (all sessions)", SERVER_BODIES_IN_FLIGHT,
             "afmforce serve"),
            ("bytes one web session keeps stored (uploads, job results, sweep stores)", SERVER_SESSION_STORAGE,
             "afmforce serve (its setting `session_storage`)"),
            ("bytes all web sessions keep stored together", SERVER_STORAGE, "afmforce serve (its setting `server_storage`)"),
            ("runs of one sweep run without asking for a yes", CONFIRM_RUNS, "sweep"),
            ("runs of one sweep", MAX_RUNS, "sweep"),
            ("curves in a design", MAX_DESIGN_CURVES, "plan"),
            ("candidate speeds of a design", MAX_SPEEDS, "plan"),
            ("designs weighed (curves among speeds, repeats allowed)", MAX_DESIGNS, "plan"),
            ("samples of all candidate curves of a design", MAX_PLAN_SAMPLES, "plan"),
            ("local fits started by one dynamic fit", MAX_STARTS, "fit, the web's fit, fit_dynamic")]
    lines = ["| what | at most | where |", "|---|---|---|"]
    lines += [f"| {what} | {cap:,} | {where} |" for what, cap, where in rows]
    return "\n".join(lines)
