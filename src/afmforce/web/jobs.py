"""Jobs: fits and sweeps run in child processes, with progress, cancel, budget and resume.

Jobs run in spawned processes (nothing shared with the server's threads); one spare process
is kept warm, the compiled integrator loaded, so that a job starts at once. A job is a record (``jobs/<id>.json`` in the data folder, written atomically on every
change of state): kind, owner session (hashed), parameters, state, progress, result or
error. Its process reports through a queue (:func:`~.tasks.run_task`); a watcher thread
applies the reports, and terminates the process on cancel or when the job's time budget
is spent. On start the manager marks the jobs a previous server left running:
sweeps are started again and resume from their store (as ``afmforce sweep`` does on a
rerun), fits are marked ``interrupted``.

No process outlives its job: a job that cannot be started or saved is failed and its process
terminated (:class:`~.replies.JobStartError`); a watcher that meets an error fails its job and
reaps its process; :meth:`JobManager.shutdown` terminates every process the manager started
(killed when it does not stop), spares included.
"""

from __future__ import annotations

import json
import multiprocessing
import queue as _queue
import secrets
import threading
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from .._files import atomic_write_text
from .limits import (FIT_RESULT_BYTES_PER_CURVE, JOB_RECORD_BYTES, MAX_JOBS, MAX_SESSION_JOBS,
                     SWEEP_BYTES_PER_VALUE)
from .replies import JobStartError, TooManyJobs
from .sessions import StorageFull, session_key
from .tasks import standby

__all__ = ["Job", "JobManager", "FINISHED", "fit_reserve", "sweep_reserve"]

FINISHED = ("done", "failed", "cancelled", "interrupted")
_NONE = object()  # no result received


def fit_reserve(n_curves: int) -> int:
    """The most bytes a fit of ``n_curves`` curves stores (its record with the result) [bytes]."""
    return JOB_RECORD_BYTES + FIT_RESULT_BYTES_PER_CURVE * max(int(n_curves), 1)


def sweep_reserve(n_runs: int, n_parameters: int) -> int:
    """The most bytes a sweep of ``n_runs`` runs of ``n_parameters`` parameters stores (its store, its
    result files and its record) [bytes]."""
    from ..sweep.simulation import OUTPUT_UNITS

    columns = n_parameters + len(OUTPUT_UNITS) + 2          # and the run's error and index
    return JOB_RECORD_BYTES + SWEEP_BYTES_PER_VALUE * max(int(n_runs), 1) * columns


def owner_of(session: str) -> str:
    """The stored owner of a session's jobs (a hash: the cookie itself is never written; the name
    of the session's folder, :func:`~.sessions.session_key`)."""
    return session_key(session)


@dataclass
class Job:
    """One fit or sweep.

    Attributes
    ----------
    id, kind, owner : str
    params : dict  the task's parameters (SI)
    state : str  queued, running, done, failed, cancelled or interrupted
    progress : dict  the last :class:`~afmforce.progress.Progress` as a dict
    result : dict or None
    error : str or None
    created, updated : float  [s since the epoch]
    resumed : int  times a server restart started it again
    """

    id: str
    kind: str
    owner: str
    params: dict[str, Any]
    state: str = "queued"
    progress: dict[str, Any] = field(default_factory=dict)
    result: dict[str, Any] | None = None
    error: str | None = None
    created: float = field(default_factory=time.time)
    updated: float = field(default_factory=time.time)
    resumed: int = 0

    def public(self, result: bool = True) -> dict[str, Any]:
        """What the API shows (no owner)."""
        d = asdict(self)
        d.pop("owner")
        d["params"] = {k: v for k, v in self.params.items() if k not in ("files", "store", "reserve")}
        if not result:
            d.pop("result")
        return d


class JobManager:
    """Runs jobs in child processes (``spawn``: no state shared with the server's threads).

    Parameters
    ----------
    root : Path
        Data folder (``jobs/`` and ``sweeps/`` inside).
    budget : float
        Time budget of one job [s].
    spare : bool
        Keep a warm spare process for the next job.
    """

    def __init__(self, root: Path, budget: float = 3600.0, spare: bool = True):
        self.root = Path(root)
        self.folder = self.root / "jobs"
        self.folder.mkdir(parents=True, exist_ok=True)
        self.budget = budget
        self._jobs: dict[str, Job] = {}
        self._procs: dict[str, Any] = {}
        self._cancel: set[str] = set()
        self._lock = threading.Lock()
        self._ctx = multiprocessing.get_context("spawn")
        self._closing = False
        self._spare = None
        self._keep_spare = spare
        self._all: list = []         # every process started: shutdown stops each one
        #: ``room(owner, bytes, what)``: why ``bytes`` more would pass the owner's or the server's
        #: storage total, or None (the app sets :meth:`~.sessions.Sessions.room_refusal`)
        self.room = None

    # -- records -----------------------------------------------------------------------
    def _save(self, job: Job) -> None:
        job.updated = time.time()
        atomic_write_text(self.folder / f"{job.id}.json", json.dumps(asdict(job), allow_nan=False), force=True)

    def _save_failed(self, job: Job, error: str) -> None:
        """Fail ``job`` with ``error`` and save it; a record that cannot be written stays in memory."""
        job.state, job.error, job.result = "failed", error, None
        try:
            self._save(job)
        except (OSError, ValueError, TypeError):
            pass

    def running(self) -> int:
        """Jobs running now."""
        return sum(1 for j in list(self._jobs.values()) if j.state == "running")

    def processes(self) -> list:
        """The job processes alive now (spare included)."""
        return [p for p in self._all if p.is_alive()]

    def stored_bytes(self, owner: str | None = None) -> int:
        """Bytes the records of ``owner``'s jobs (None: every job) take on disk, a running job at its
        declared most (``params["reserve"]``, :func:`fit_reserve`, :func:`sweep_reserve`) on top:
        what a session may not fill with uploads while it runs [bytes]."""
        total = 0
        for job in list(self._jobs.values()):
            if owner is not None and job.owner != owner:
                continue
            try:
                total += (self.folder / f"{job.id}.json").stat().st_size
            except OSError:
                pass
            if job.state not in FINISHED:
                total += int(job.params.get("reserve", 0))
        return total

    def delete(self, job_id: str, session: str) -> Job | None:
        """Remove a finished job of ``session``: its record and its sweep's store (None: not the session's).

        Raises
        ------
        ParameterError
            The job is still running (cancel it first).
        """
        from ..errors import ParameterError

        job = self.get(job_id, session)
        if job is None:
            return None
        if job.state not in FINISHED:
            raise ParameterError(f"job {job_id} is {job.state}; cancel it first (POST /api/jobs/{job_id}/cancel), "
                                 "then delete it")
        self._jobs.pop(job.id, None)
        (self.folder / f"{job.id}.json").unlink(missing_ok=True)
        self._remove_store(job)
        return job

    @staticmethod
    def _remove_store(job: Job) -> None:
        """Remove the job's own sweep store (``<sweeps>/<job id>``; a store shared by an older layout stays)."""
        import shutil

        store = job.params.get("store")
        if job.kind == "sweep" and store and Path(store).name == job.id:
            shutil.rmtree(store, ignore_errors=True)

    def expire(self, owners, ttl: float, live=(), now: float | None = None) -> list[str]:
        """Remove the finished jobs of expired sessions (``owners``: their keys) and the finished jobs
        of sessions not ``live`` (no folder) not updated for longer than ``ttl`` [s]; returns their ids."""
        now = time.time() if now is None else now
        owners, live = set(owners), set(live)
        gone = []
        for job in list(self._jobs.values()):
            if job.state in FINISHED and (job.owner in owners
                                          or (job.owner not in live and now - job.updated > ttl)):
                self._jobs.pop(job.id, None)
                (self.folder / f"{job.id}.json").unlink(missing_ok=True)
                gone.append(job.id)
        return gone

    def load(self) -> list[Job]:
        """Read the stored jobs; restart the sweeps a previous server left unfinished."""
        restarted = []
        for path in sorted(self.folder.glob("*.json")):
            try:
                job = Job(**json.loads(path.read_text(encoding="utf-8")))
            except (ValueError, TypeError):
                continue
            self._jobs[job.id] = job
            if job.state not in FINISHED:
                if job.kind == "sweep":
                    job.resumed += 1
                    restarted.append(job)
                else:
                    job.state, job.error = "interrupted", "the server stopped while this job ran; start it again"
                    self._save(job)
        for job in restarted:
            self._start(job)
        return restarted

    # -- API ---------------------------------------------------------------------------
    def submit(self, kind: str, session: str, params: dict[str, Any], *, reserve: int = 0,
               store: Path | None = None) -> Job:
        """Start a job for ``session``; returns it (state ``running``).

        ``reserve`` [bytes]: the most the job stores (:func:`fit_reserve`, :func:`sweep_reserve`),
        held against the session's and the server's storage totals while it runs; ``store``: the
        folder of the session's sweep stores (the sweep's own is ``store/<job id>``).

        Raises :class:`~.replies.TooManyJobs` when the server runs :data:`~.limits.MAX_JOBS` jobs or
        the session :data:`~.limits.MAX_SESSION_JOBS` (each job is a process: without a cap, a client
        posting fits in a loop would start a process each, until the machine's memory ran out), and
        :class:`~.sessions.StorageFull` when ``reserve`` would pass a storage total (413)."""
        job = Job(secrets.token_hex(8), kind, owner_of(session), dict(params))
        job.params["reserve"] = int(reserve)
        if kind == "sweep":
            job.params["store"] = str(Path(store if store is not None else self.root / "sweeps") / job.id)
        with self._lock:
            live = [j for j in self._jobs.values() if j.state not in FINISHED]
            mine = sum(1 for j in live if j.owner == job.owner)
            if mine >= MAX_SESSION_JOBS or len(live) >= MAX_JOBS:
                raise TooManyJobs(
                    f"{mine} of this session's jobs and {len(live)} in all are running; a session may run "
                    f"{MAX_SESSION_JOBS} and the server {MAX_JOBS} fits and sweeps at once: wait for one to "
                    "end or cancel one (POST /api/jobs/ID/cancel)")
            why = self.room(job.owner, int(reserve), f"this {kind}'s results, at most") if self.room else None
            if why:
                raise StorageFull(why)
            self._jobs[job.id] = job
        self._start(job)
        return job

    def get(self, job_id: str, session: str) -> Job | None:
        """The job, if it belongs to ``session``."""
        job = self._jobs.get(job_id)
        return job if job is not None and job.owner == owner_of(session) else None

    def list(self, session: str) -> list[Job]:
        """The session's jobs, newest first."""
        mine = [j for j in self._jobs.values() if j.owner == owner_of(session)]
        return sorted(mine, key=lambda j: -j.created)

    def cancel(self, job_id: str, session: str) -> Job | None:
        """Ask the job's process to stop (terminated at once); None when not the session's."""
        job = self.get(job_id, session)
        if job is not None and job.state not in FINISHED:
            self._cancel.add(job_id)
        return job

    def start_spare(self) -> None:
        """Start a spare job process now, so that the next job skips its start-up (~5 s)."""
        with self._lock:
            if self._spare is None:
                self._spare = self._new_spare()

    def _new_spare(self, warm: bool = True):
        import os

        inbox, q = self._ctx.Queue(), self._ctx.Queue()
        proc = self._ctx.Process(target=standby, args=(inbox, q, os.getpid(), warm), daemon=False,
                                 name="afmforce-job")
        proc.start()
        self._all = [p for p in self._all if p.is_alive()] + [proc]
        return proc, inbox, q

    @staticmethod
    def _reap(proc, wait: float = 5.0) -> None:
        """Stop ``proc``: terminate, then kill when it does not end within ``wait`` [s]."""
        if proc.is_alive():
            proc.terminate()
        proc.join(timeout=wait)
        if proc.is_alive():
            proc.kill()
            proc.join(timeout=wait)

    def shutdown(self) -> None:
        """Stop every job process the manager started (spares too); the running jobs stay
        ``running`` on disk, so that the next server resumes the sweeps."""
        with self._lock:
            self._closing = True
            self._spare = None
        procs = list(self._all)
        for proc in procs:
            if proc.is_alive():
                proc.terminate()
        for proc in procs:
            self._reap(proc, 3.0)

    # -- running -----------------------------------------------------------------------
    def _start(self, job: Job) -> None:
        """Hand ``job`` to a process; on any failure the job is failed, the process reaped, and
        :class:`~.replies.JobStartError` raised."""
        proc = None
        try:
            with self._lock:   # take the warm spare, start the next one
                if self._closing:
                    raise JobStartError("the server is stopping")
                spare, self._spare = self._spare, None
                if spare is None or not spare[0].is_alive():
                    spare = self._new_spare(warm=False)
                if self._keep_spare:
                    self._spare = self._new_spare()
            proc, inbox, q = spare
            job.state, job.error = "running", None
            self._save(job)
            inbox.put((job.kind, job.params))
            self._procs[job.id] = proc
            # the queues live as long as the watcher: a queue collected here would vanish under the child
            threading.Thread(target=self._watch, args=(job, proc, q, inbox), daemon=True,
                             name=f"afmforce-job-{job.id}").start()
        except Exception as exc:
            self._procs.pop(job.id, None)
            if proc is not None:
                self._reap(proc)
            self._save_failed(job, f"the job could not start: {exc}")
            raise JobStartError(f"the {job.kind} could not start: {exc}") from None

    def _watch(self, job: Job, proc, q, inbox) -> None:
        """Apply the process's reports to ``job`` until it ends; whatever happens, the process is
        reaped and the job left in a finished state (or ``running`` on disk at shutdown)."""
        try:
            self._follow(job, proc, q)
        except Exception as exc:   # a report that cannot be applied or saved: the job fails
            self._reap(proc)
            self._save_failed(job, f"the job failed on the server: {type(exc).__name__}: {exc}")
        finally:
            if not self._closing:     # at shutdown, shutdown() stops the processes
                self._reap(proc)
                self._procs.pop(job.id, None)
                self._cancel.discard(job.id)

    def _keep_result(self, job: Job, value) -> None:
        """``job`` done with ``value``, unless its record would take its session or the server past
        the storage totals (its reserve under-counted: a map's many curves): then it fails saying
        so and its sweep store is removed (nothing over the totals stays on disk)."""
        size = len(json.dumps(value, allow_nan=True)) if self.room is not None else 0
        reserve = int(job.params.get("reserve", 0))
        job.params["reserve"] = 0            # its own hold no longer counts against itself
        why = self.room(job.owner, size, f"this {job.kind}'s results") if self.room is not None else None
        if why:
            job.params["reserve"] = reserve
            job.state, job.result, job.error = "failed", None, f"the {job.kind}'s results were not kept: {why}"
            self._remove_store(job)
            job.params["reserve"] = 0
            return
        job.state, job.result = "done", value

    def _follow(self, job: Job, proc, q) -> None:
        deadline = time.monotonic() + self.budget
        last_save = 0.0
        result = _NONE  # kept once the process has ended: "done" is shown with its record and store complete
        while True:
            if self._closing:
                return
            try:
                kind, value = q.get(timeout=0.1)
            except _queue.Empty:
                kind, value = None, None
            if kind == "progress":
                job.progress = value
                if time.monotonic() - last_save > 1.0:
                    self._save(job)
                    last_save = time.monotonic()
                continue
            if kind == "result":
                result = value
                break
            if kind == "error":
                job.state, job.error = "failed", value
                break
            if job.id in self._cancel or time.monotonic() > deadline:
                proc.terminate()
                job.state = "cancelled"
                job.error = ("cancelled" if job.id in self._cancel
                             else f"cancelled: past its time budget of {self.budget:g} s")
                break
            if not proc.is_alive():
                try:  # a last report may still be in the queue
                    kind, value = q.get(timeout=0.5)
                    if kind == "result":
                        result = value
                        break
                    if kind == "error":
                        job.state, job.result, job.error = "failed", None, value
                        break
                    continue
                except _queue.Empty:
                    job.state, job.error = "failed", f"the job's process ended (exit code {proc.exitcode})"
                    break
        self._reap(proc)
        if result is not _NONE:
            self._keep_result(job, result)
        try:
            self._save(job)
        except (ValueError, TypeError) as exc:   # a result JSON cannot carry (NaN): the job fails
            self._save_failed(job, f"the job's result could not be saved: {exc}")
