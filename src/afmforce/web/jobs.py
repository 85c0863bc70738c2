"""Jobs: fits and sweeps run in child processes, with progress, cancel, budget and resume.

Jobs run in spawned processes (nothing shared with the server's threads); one spare process
is kept warm, the compiled integrator loaded, so that a job starts at once. A job is a record (``jobs/<id>.json`` in the data folder, written atomically on every
change of state): kind, owner session (hashed), parameters, state, progress, result or
error. Its process reports through a queue (:func:`~.tasks.run_task`); a watcher thread
applies the reports, and terminates the process on cancel or when the job's time budget
is spent. On start the manager marks the jobs a previous server left running:
sweeps are started again and resume from their store (as ``afmforce sweep`` does on a
rerun), fits are marked ``interrupted``.
"""

from __future__ import annotations

import hashlib
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
from .tasks import standby

__all__ = ["Job", "JobManager", "FINISHED"]

FINISHED = ("done", "failed", "cancelled", "interrupted")


def owner_of(session: str) -> str:
    """The stored owner of a session's jobs (a hash: the cookie itself is never written)."""
    return hashlib.sha256(session.encode()).hexdigest()[:32]


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
        d["params"] = {k: v for k, v in self.params.items() if k not in ("files", "store")}
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

    # -- records -----------------------------------------------------------------------
    def _save(self, job: Job) -> None:
        job.updated = time.time()
        atomic_write_text(self.folder / f"{job.id}.json", json.dumps(asdict(job), allow_nan=False), force=True)

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
    def submit(self, kind: str, session: str, params: dict[str, Any]) -> Job:
        """Start a job for ``session``; returns it (state ``running``)."""
        job = Job(secrets.token_hex(8), kind, owner_of(session), dict(params))
        if kind == "sweep":
            job.params["store"] = str(self.root / "sweeps")
        with self._lock:
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
        return proc, inbox, q

    def shutdown(self) -> None:
        """Terminate the running processes; their jobs stay ``running`` on disk, so that the
        next server resumes the sweeps."""
        self._closing = True
        procs = list(self._procs.values()) + ([self._spare[0]] if self._spare else [])
        for proc in procs:
            if proc.is_alive():
                proc.terminate()
        for proc in procs:
            proc.join(timeout=5)

    # -- running -----------------------------------------------------------------------
    def _start(self, job: Job) -> None:
        with self._lock:   # take the warm spare, start the next one
            spare, self._spare = self._spare, None
            if spare is None or not spare[0].is_alive():
                spare = self._new_spare(warm=False)
            if not self._closing and self._keep_spare:
                self._spare = self._new_spare()
        proc, inbox, q = spare
        job.state, job.error = "running", None
        self._save(job)
        inbox.put((job.kind, job.params))
        self._procs[job.id] = proc
        # the queues live as long as the watcher: a queue collected here would vanish under the child
        threading.Thread(target=self._watch, args=(job, proc, q, inbox), daemon=True).start()

    def _watch(self, job: Job, proc, q, inbox) -> None:
        deadline = time.monotonic() + self.budget
        last_save = 0.0
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
                job.state, job.result = "done", value
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
                    if kind in ("result", "error"):
                        job.state = "done" if kind == "result" else "failed"
                        job.result, job.error = (value, None) if kind == "result" else (None, value)
                        break
                    continue
                except _queue.Empty:
                    job.state, job.error = "failed", f"the job's process ended (exit code {proc.exitcode})"
                    break
        proc.join(timeout=5)
        self._procs.pop(job.id, None)
        self._cancel.discard(job.id)
        self._save(job)
