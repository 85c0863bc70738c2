"""The ASGI application: FastAPI with one router per view, behind :class:`~.guard.Guard`."""

from __future__ import annotations

import logging
import threading
from contextlib import asynccontextmanager

from fastapi import FastAPI

from .. import __version__
from . import openapi, replies
from .compute import Gate
from .guard import Guard
from .jobs import JobManager
from .sessions import Sessions, session_key
from .settings import Settings

__all__ = ["create_app", "warm_up_steps"]

_LOG = logging.getLogger("afmforce.web")


def create_app(settings: Settings | None = None) -> FastAPI:
    """Build the application (``settings.resolved()`` is applied: a token when bound beyond loopback)."""
    from . import routes_analyze, routes_fit, routes_jobs, routes_main, routes_simulate, routes_sweep

    settings = (settings or Settings()).resolved()
    settings.data.mkdir(parents=True, exist_ok=True)
    jobs = JobManager(settings.data, budget=settings.job_budget, spare=settings.spare_job)
    sessions = Sessions(settings.data, ttl=settings.session_ttl, session_bytes=settings.session_storage,
                        server_bytes=settings.server_storage, extra=jobs.stored_bytes)
    jobs.room = sessions.room_refusal     # a job's results count against the same totals as uploads
    stop = threading.Event()

    def expire() -> None:   # sessions unused past --session-ttl: their uploads and finished jobs go
        gone = sessions.expire()
        jobs.expire(gone, settings.session_ttl, live=sessions.keys())

    def expiry_loop() -> None:
        while not stop.wait(min(600.0, settings.session_ttl / 10)):
            try:
                expire()
            except OSError:
                pass

    warm = threading.Event()
    warming = threading.Event()     # set when the warm-up starts (the lifespan ran): only then is it waited for

    def warm_up():
        try:
            warm_up_steps()
        finally:
            warm.set()

    @asynccontextmanager
    async def lifespan(app):
        import_library()     # before any thread: never two threads importing one package (see there)
        warming.set()
        threading.Thread(target=warm_up, daemon=True, name="afmforce-warm-up").start()
        jobs.load()          # sweeps left running by a previous server resume
        expire()
        threading.Thread(target=expiry_loop, daemon=True, name="afmforce-expiry").start()
        if settings.spare_job:
            jobs.start_spare()
        try:
            yield
        finally:
            stop.set()
            jobs.shutdown()

    app = FastAPI(title="afmforce", version=__version__, lifespan=lifespan, docs_url=None, redoc_url=None,
                  description="Analyse force curves, simulate the dynamic AFM, fit and sweep "
                              "(afmforce serve; docs/web.md). Values are SI. (No Swagger page: it loads "
                              "its script from a CDN, and this server works offline.)")
    app.state.settings = settings
    app.state.sessions = sessions
    app.state.jobs = jobs
    app.state.gate = Gate()      # analyses and simulations computing at once (afmforce.web.limits)
    app.state.warm = warm
    app.state.warming = warming
    app.state.expire = expire
    replies.install(app)     # every refusal: 422 {"error": {"type", "message", "field"}}
    openapi.install(app)     # typed request and response models from the declarations

    for module in (routes_main, routes_analyze, routes_simulate, routes_fit, routes_sweep, routes_jobs):
        app.include_router(module.router)
    if settings.allow_origins:      # pages of the origins given with --allow-origin may read the answers
        from starlette.middleware.cors import CORSMiddleware

        app.add_middleware(CORSMiddleware, allow_origins=list(settings.allow_origins), allow_methods=["*"],
                           allow_headers=["content-type", "authorization"], allow_credentials=True)
    app.add_middleware(Guard, token=settings.token, max_body=settings.max_upload, loopback=settings.loopback,
                       allow_origins=settings.allow_origins, session_ttl=settings.session_ttl, seen=sessions.seen,
                       room=lambda sid, adding: sessions.room_refusal(session_key(sid), adding, "uploads being received"))
    return app


#: The modules the warm-up thread and the first requests import, imported by the lifespan before either
#: runs. A request imported ``afmforce.dynamics`` while the warm-up thread was importing it too: Python's
#: per-module import locks then hand one thread the other's half-initialised module (``ImportError:
#: cannot import name 'SolverStats' from partially initialized module``, then ``KeyError:
#: 'afmforce.dynamics'``: a 500 for ``POST /api/simulate`` sent at start, 1 run in 2 on this machine).
LIBRARY_MODULES = ("afmforce.units", "afmforce.dynamics", "afmforce.dynamics.trajectory", "afmforce.io",
                   "afmforce.analysis.pipeline", "afmforce.fit", "afmforce.sweep", "afmforce.web.schema")


def import_library() -> None:
    """Import :data:`LIBRARY_MODULES` in this thread (no compile: ~1-2 s the first time in a process,
    nothing after). One that fails is left to the warm-up and the request that needs it to report."""
    import importlib

    for name in LIBRARY_MODULES:
        try:
            importlib.import_module(name)
        except Exception:       # noqa: BLE001 -- the warm-up step or the request says what is wrong
            pass


def warm_up_steps() -> list[str]:
    """Load what the first requests need before they come (the page's controls, plotly, the unit
    parser, the compiled integrator and analysis kernels). A step that fails is logged as a warning
    on ``afmforce.web`` with its reason and the others still run: the server keeps serving, and the
    request that needs the failed part says what is wrong. Returns the warnings logged."""
    from .routes_main import plotly_js
    from .schema import schema

    def units():
        from ..units import parse_quantity
        parse_quantity("1 nm", "length")     # pint's registry: 2-5 s on its first use

    def integrator():
        from ..dynamics import simulate
        simulate(velocity=1e-5)

    steps = (("the page's controls", schema), ("plotly", plotly_js), ("the unit parser", units),
             ("the integrator", integrator), ("the analysis", _warm_analysis))
    failed = []
    for name, step in steps:
        try:
            step()
        except Exception as exc:       # noqa: BLE001 -- a warm-up only: logged, the server goes on
            text = (f"warm-up of {name} failed ({type(exc).__name__}: {exc}); serving on, the first "
                    "request that needs it loads it")
            _LOG.warning(text)
            failed.append(text)
    return failed


def _warm_analysis() -> None:
    """Run the default analysis once on a shipped curve: its compiled kernels are loaded (or, with
    an empty numba cache, compiled) here, at start, not in the first upload's request -- which, with
    a cold cache on a busy machine, ran past the request's budget (504 for a 221-sample file that
    takes 6 s once compiled)."""
    from ..analysis.pipeline import analyze
    from ..datasets import path
    from ..io import load

    analyze(load(path("asylum-air"))[0])
