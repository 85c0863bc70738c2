"""``afmforce serve``: a local web application to analyse, simulate, fit and sweep in the browser.

:func:`create_app` builds the ASGI application (FastAPI on Starlette; uvicorn serves it).
One router per view (:mod:`.routes_analyze`, :mod:`.routes_simulate`, :mod:`.routes_fit`,
:mod:`.routes_sweep`) plus the jobs (:mod:`.routes_jobs`) and the page itself
(:mod:`.routes_main`). The page (``static/``) is plain HTML, CSS and JavaScript with
Plotly.js served from the installed ``plotly`` package: nothing is fetched from the
network. Security (token, session cookie, upload limit) is :mod:`.guard`; per-session
uploads are :mod:`.sessions`; fits and sweeps run as jobs in child processes
(:mod:`.jobs`, :mod:`.tasks`). See docs/web.md.
"""

from __future__ import annotations

__all__ = ["create_app", "Settings"]


def __getattr__(name: str):  # the app pulls in FastAPI: only when asked for
    if name == "create_app":
        from .app import create_app

        return create_app
    if name == "Settings":
        from .settings import Settings

        return Settings
    raise AttributeError(name)
