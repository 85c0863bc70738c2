"""Requests that compute (an analysis, a simulation, a raw export): how many at once, and their end.

* At most :data:`~.limits.MAX_COMPUTING` compute at once; up to :data:`~.limits.MAX_WAITING` more wait
  for a slot (within their budget), and one more is refused (429 ``busy``). A slot is held until the
  computation's thread has ended, not until its reply: the memory of the requests computing at once is
  bounded (24 simulations of 775,001 samples sent together held 2.2 GB at once; 40, the thread pool's
  size, would hold about 4 GB).
* A computation stops when its client has gone (the request aborted, the page closed) or its budget is
  spent: :func:`compute` sets the ``stop`` event it hands the work, which checks it between curves (an
  analysis) or steps of the integrator (a simulation). Before, an analysis of six 10 x 10 maps went on
  computing for the whole of its budget after its client had left.
"""

from __future__ import annotations

import asyncio
import threading
import time
from typing import Any, Callable

from starlette.concurrency import run_in_threadpool

from .limits import MAX_COMPUTING, MAX_WAITING
from .replies import Busy, ClientGone, PastBudget   # the replies' exceptions, raised here

__all__ = ["Gate", "Busy", "ClientGone", "compute"]

#: How often a waiting request looks for a free slot, and a computing one for its client [s].
_POLL = 0.1


class Gate:
    """At most ``slots`` computations at once, at most ``queue`` requests waiting for one.

    A plain counter under a thread lock, polled by the waiting requests: it works across the event
    loops of several test clients of one application (an ``asyncio.Semaphore`` is bound to one loop).
    """

    def __init__(self, slots: int = MAX_COMPUTING, queue: int = MAX_WAITING):
        self.slots, self.queue = int(slots), int(queue)
        self.running = 0
        self.waiting = 0
        self._lock = threading.Lock()

    def _take(self) -> bool:
        with self._lock:
            if self.running < self.slots:
                self.running += 1
                return True
            return False

    async def enter(self, patience: float) -> None:
        """Take a slot, waiting at most ``patience`` [s]; :class:`Busy` when the queue is full or the wait
        runs out."""
        if self._take():
            return
        with self._lock:
            if self.waiting >= self.queue:
                raise Busy(f"the server computes {self.running} requests and {self.waiting} wait for their "
                           f"turn, the most it takes ({self.slots} computing, {self.queue} waiting; "
                           "afmforce.web.limits): try again in a few seconds")
            self.waiting += 1
        try:
            deadline = time.monotonic() + patience
            while not self._take():
                if time.monotonic() > deadline:
                    raise Busy(f"no turn to compute within {patience:g} s: the server computes {self.slots} "
                               "requests at once and every one was busy; try again in a few seconds")
                await asyncio.sleep(_POLL)
        finally:
            with self._lock:
                self.waiting -= 1

    def leave(self) -> None:
        """Give the slot back (the computation's thread has ended)."""
        with self._lock:
            self.running -= 1


async def compute(request, work: Callable[[threading.Event], Any], budget: float, what: str) -> Any:
    """``work(stop)`` in a worker thread holding one of the server's slots (``request.app.state.gate``).

    ``stop`` is set when the client disconnects (:class:`ClientGone` is raised) or ``budget`` [s] has
    passed (:class:`~.replies.PastBudget`, "cancelled: the ``what`` ran past its budget"); ``work`` must
    check it and return (or raise) soon after. The slot is freed when ``work`` has returned.
    """
    gate: Gate = request.app.state.gate
    await gate.enter(budget)
    stop = threading.Event()

    def run() -> Any:
        try:
            return work(stop)
        finally:
            gate.leave()

    task = asyncio.ensure_future(run_in_threadpool(run))
    # a task left behind (client gone, past budget) ends by itself; its outcome is read so that asyncio
    # never logs it as "never retrieved"
    task.add_done_callback(lambda t: t.cancelled() or t.exception())
    deadline = time.monotonic() + budget
    try:
        while True:
            done, _ = await asyncio.wait({task}, timeout=_POLL)
            if done:
                return task.result()
            if await request.is_disconnected():
                raise ClientGone(f"the client left before the {what} ended; it was stopped")
            if time.monotonic() > deadline:
                raise PastBudget(f"cancelled: the {what} ran past its budget of {budget:g} s")
    finally:
        if not task.done():
            stop.set()
