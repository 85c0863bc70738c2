"""The ASGI application: FastAPI with one router per view, behind :class:`~.guard.Guard`."""

from __future__ import annotations

import threading
from contextlib import asynccontextmanager

from fastapi import FastAPI, Request
from fastapi.responses import JSONResponse

from .. import __version__
from ..errors import AfmforceError
from .guard import Guard
from .jobs import JobManager
from .sessions import Sessions
from .settings import Settings

__all__ = ["create_app"]


def create_app(settings: Settings | None = None) -> FastAPI:
    """Build the application (``settings.resolved()`` is applied: a token when bound beyond loopback)."""
    from . import routes_analyze, routes_fit, routes_jobs, routes_main, routes_simulate, routes_sweep

    settings = (settings or Settings()).resolved()
    settings.data.mkdir(parents=True, exist_ok=True)
    jobs = JobManager(settings.data, budget=settings.job_budget, spare=settings.spare_job)

    warm = threading.Event()

    def warm_up():  # load the compiled integrator and the unit parser before the first request needs them
        from ..dynamics import simulate
        from ..units import parse_quantity

        try:
            parse_quantity("1 nm", "length")     # pint's registry: 2-5 s on its first use
            simulate(velocity=1e-5)
        finally:
            warm.set()

    @asynccontextmanager
    async def lifespan(app):
        threading.Thread(target=warm_up, daemon=True, name="afmforce-warm-up").start()
        jobs.load()          # sweeps left running by a previous server resume
        if settings.spare_job:
            jobs.start_spare()
        yield
        jobs.shutdown()

    app = FastAPI(title="afmforce", version=__version__, lifespan=lifespan, docs_url=None, redoc_url=None,
                  description="Analyse force curves, simulate the dynamic AFM, fit and sweep "
                              "(afmforce serve; docs/web.md). Values are SI. (No Swagger page: it loads "
                              "its script from a CDN, and this server works offline.)")
    app.state.settings = settings
    app.state.sessions = Sessions(settings.data)
    app.state.jobs = jobs
    app.state.warm = warm

    @app.exception_handler(AfmforceError)
    async def _bad_input(request: Request, exc: AfmforceError):  # one readable line, as the CLI prints
        return JSONResponse({"error": str(exc)}, status_code=422)

    for module in (routes_main, routes_analyze, routes_simulate, routes_fit, routes_sweep, routes_jobs):
        app.include_router(module.router)
    app.add_middleware(Guard, token=settings.token, max_body=settings.max_upload, loopback=settings.loopback)
    return app
