"""Cheap pure functions swept in the engine tests (importable by Dask workers)."""

from __future__ import annotations

import os
import time

from afmforce import forces

#: Calls made in this process (the serial executor runs here).
CALLS: list[tuple] = []


def jump_in(spring_constant: float, radius: float) -> dict:
    """Static jump-in of a spring of stiffness k towards a sphere of radius R (spec section 2)."""
    h = forces.static_jump_in_separation(spring_constant, radius)
    return {"jump_in": {"separation": h, "deflection": forces.vdw_force(h, radius) / spring_constant}}


def counted(x: float, y: float) -> dict:
    """x*y and x+y; records each call in CALLS."""
    CALLS.append((x, y))
    return {"product": x * y, "sum": x + y}


def slow(x: float, y: float) -> dict:
    """counted() after a pause of AFMFORCE_TEST_SLEEP seconds (for the kill test)."""
    time.sleep(float(os.environ.get("AFMFORCE_TEST_SLEEP", "0")))
    return counted(x, y)


class Interrupt:
    """counted() that raises KeyboardInterrupt on call number ``at`` (Ctrl-C mid-sweep)."""

    def __init__(self, at: int) -> None:
        self.at = at
        self.n = 0

    def __call__(self, x: float, y: float) -> dict:
        self.n += 1
        if self.n == self.at:
            raise KeyboardInterrupt
        return counted(x, y)


def fragile(x: float, y: float) -> dict:
    """counted(), except that x == 3 raises ValueError."""
    if x == 3:
        raise ValueError(f"cannot handle x = {x}")
    return counted(x, y)


def read_numbers(path) -> list[dict]:
    """A batch function: one record per number in a text file (like curves in a map file)."""
    values = [float(v) for v in open(path).read().split()]
    if not values:
        raise ValueError(f"{path} holds no numbers")
    return [{"value": v, "square": v * v} for v in values]


def square(item: float) -> dict:
    CALLS.append((item,))
    return {"square": item * item}


def mark_pid(folder: str) -> None:
    """Write an empty file named after this process's id into ``folder`` (warm-up test)."""
    open(os.path.join(folder, f"pid-{os.getpid()}"), "w").close()


def batched(x: float, y: float) -> dict:
    """counted() after 5 ms, with the batched protocol of simulate_run (``batch``, ``batch_threads``)."""
    time.sleep(0.005)
    return counted(x, y)


def _batched_rows(rows: list[dict]) -> list:
    return [batched(**row) for row in rows]


batched.batch = _batched_rows
batched.batch_threads = lambda: 2
