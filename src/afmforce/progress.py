"""One progress contract for everything that takes a while (issue 11, item 9).

Long-running functions take ``progress: Callable[[Progress], None] | None`` and
call it with a :class:`Progress` record: :func:`afmforce.dynamics.simulate`
(simulated time), :func:`afmforce.io.load` (fraction of a file),
:func:`afmforce.sweep.run_sweep` / ``run_batch`` (chunks, with runs as items)
and :func:`afmforce.paper.reproduce` (figures). The command line turns the
records into one kind of bar (``cli.common.progress_bar``).

>>> from afmforce.progress import Progress
>>> Progress(done=3, total=12, unit="chunk").fraction
0.25
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["Progress"]


@dataclass(frozen=True)
class Progress:
    """How far a long computation is.

    Attributes
    ----------
    done : float
        Work done, in ``unit``.
    total : float or None
        Total work in ``unit``; None when unknown (a batch of unknown length).
    unit : str
        What ``done`` counts: ``"s"`` (simulated time), ``"chunk"``,
        ``"file"`` (fraction of one file), ``"figure"``.
    what : str
        The item being worked on (a file name, a figure key); may be empty.
    failed, skipped : int
        Units that failed, or were found done already (a resumed sweep).
    items_done, items_total : int or None
        Finer items inside the units (the runs of a sweep's chunks).
    """

    done: float
    total: float | None
    unit: str = ""
    what: str = ""
    failed: int = 0
    skipped: int = 0
    items_done: int | None = None
    items_total: int | None = None

    @property
    def fraction(self) -> float | None:
        """``done / total`` in [0, 1], or None when the total is unknown [-]."""
        if self.total is None or not self.total > 0:
            return None
        return min(1.0, max(0.0, float(self.done) / float(self.total)))

    @property
    def finished(self) -> bool:
        """True once ``done`` reaches a known ``total``."""
        return self.total is not None and math.isclose(float(self.done), float(self.total)) or (
            self.total is not None and self.done >= self.total)
