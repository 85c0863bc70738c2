"""A swept function that presses Ctrl-C: it sends SIGINT to its process group, as a terminal does.

Used by tests/cli/test_interrupt.py in a subprocess (importable by Dask workers through PYTHONPATH).
"""

import os
import signal
import time


def interrupting_run(**parameters) -> dict:
    """Send SIGINT to the whole process group (the command and its workers), then wait to be stopped."""
    os.killpg(os.getpgrp(), signal.SIGINT)
    time.sleep(60)
    return {"never": 0.0}
