"""Waiting for the server's warm-up (``app.state.warm``, set by :func:`afmforce.web.app.create_app`'s lifespan).

Its own module: the routes import it, and :mod:`afmforce.web.app` imports the routes (no import cycle).
"""

from __future__ import annotations

__all__ = ["wait_until_warm", "WARM_WAIT_MAX"]


def wait_until_warm(app) -> None:
    """Block until the server's warm-up has ended (``app.state.warm``; failed steps included).

    A request with a time budget (an analysis, a simulation) calls this before its budget starts:
    the compile of the kernels at start is the server's cost, not the request's. Before, a request
    sent while the warm-up was still compiling (cold numba cache, busy machine) waited for numba's
    compile lock inside its own 60 s and came back 504 past_budget
    (``test_a_session_survives_a_reload_and_lists_its_uploads`` failed so under load).

    An app whose lifespan never ran (a ``TestClient`` used without ``with``, an ASGI server started with
    its lifespan off) has no warm-up to wait for: the request goes on at once (it waited forever: the
    suite hung in ``test_declared_ranges``). The wait is bounded by :data:`WARM_WAIT_MAX`."""
    if app.state.warming.is_set():
        app.state.warm.wait(WARM_WAIT_MAX)


#: The longest a request waits for the server's warm-up [s] (a cold numba cache on a busy 2-core machine
#: compiles for ~1-3 min); past it, the request goes on and compiles what it needs inside its own budget.
WARM_WAIT_MAX = 600.0
