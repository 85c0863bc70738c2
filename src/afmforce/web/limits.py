"""What one request may cost the server: every size limit of ``afmforce serve``, in one place.

Time is bounded by the settings (``--budget``, the job budget); these bound memory: how many
samples a simulation may have, how many values a response may carry, how many runs a sweep may
have, how many requests compute at once, how long the lists of a request may be and how many bytes of uploads a session and the
server keep stored (the disk). A request over a limit gets 422 naming the field
before anything is computed.
"""

from __future__ import annotations

__all__ = ["MAX_SAMPLES", "RESPONSE_POINTS", "ANALYSIS_POINTS", "ANALYSIS_CURVES", "RAW_SAMPLES", "MAX_RUNS", "MAX_ITEMS",
           "MAX_CURVES", "CALIBRATION_BYTES", "SESSION_TTL", "SESSION_STORAGE", "SERVER_STORAGE", "MAX_JOBS", "MAX_SESSION_JOBS",
           "MAX_COMPUTING", "MAX_WAITING",
           "JOB_RECORD_BYTES", "FIT_RESULT_BYTES_PER_CURVE", "SWEEP_BYTES_PER_VALUE"]

#: Samples one simulated cycle may have: the library's cap for a server (``afmforce.limits``).
from ..limits import SERVER_MAX_SAMPLES as MAX_SAMPLES  # noqa: E402
#: Samples per column one simulation response may carry (``max_points``; the page draws 2,000-5,000).
RESPONSE_POINTS = 20_000
#: Per-sample values (all curves together) one analysis response may carry with ``arrays``.
ANALYSIS_POINTS = 2_000_000
#: Curves one analysis request takes, its files together: the library's cap for a server
#: (``afmforce.limits``), counted from the maps' headers before any curve is read.
from ..limits import SERVER_MAX_CURVES as ANALYSIS_CURVES  # noqa: E402
#: Samples of a raw file exported by the virtual AFM (about 100 bytes a row: 25 MB).
RAW_SAMPLES = 250_000
#: Runs one sweep may have (grid points times samples); ``afmforce sweep`` runs more.
MAX_RUNS = 20_000
#: Entries of a list in a request (grid items, file ids, options, metadata).
MAX_ITEMS = 64
#: Virtual curves of one fit.
MAX_CURVES = 8
#: Fits and sweeps running at once on the server (each is a process holding one core and up to
#: about a GB); one more is refused (429) until one ends or is cancelled.
MAX_JOBS = 4
#: Fits and sweeps one session may have running at once.
MAX_SESSION_JOBS = 2
#: Analyses, simulations and raw exports computing at once on the server (each holds up to about 100 MB
#: of trajectory, or its uploads and their curves): the others wait for a slot (:mod:`.compute`).
MAX_COMPUTING = 4
#: Requests waiting for a slot to compute; one more is refused (429 ``busy``) until one ends.
MAX_WAITING = 64
#: Bytes of an uploaded probe calibration file (``afmforce calibrate --out`` writes about 1 kB).
CALIBRATION_BYTES = 65_536
#: Default bytes one session may keep stored (``--session-storage``): uploads, sweep stores and job
#: records; its next upload or job is refused (413 ``storage_full``) until it deletes files or jobs or
#: expires: stored files are never evicted.
from ..limits import SERVER_SESSION_STORAGE as SESSION_STORAGE  # noqa: E402
#: Default bytes the server keeps stored for all sessions together (``--server-storage``).
from ..limits import SERVER_STORAGE  # noqa: E402
#: The most bytes a job's record holds besides its result (parameters, progress, error) [bytes].
JOB_RECORD_BYTES = 200_000
#: The most bytes one fitted curve adds to a fit's result (its plot: at most 1,500 samples of position,
#: data, mask and model as JSON, ~100 kB, and its row of the tables) [bytes]; measured: 25 kB for the
#: whole result of a fit of two virtual curves (1 and 4 um/s, profiles and model comparison).
FIT_RESULT_BYTES_PER_CURVE = 250_000
#: The most bytes one value of a sweep's table (a run times a column) takes on disk, all its copies
#: together: the stored chunk and results.parquet, results.csv, results.nc, results.html and the
#: rows the job's record shows [bytes].
SWEEP_BYTES_PER_VALUE = 160
#: Default lifetime of an unused session (its uploads and jobs) [s].
SESSION_TTL = 24 * 3600.0
