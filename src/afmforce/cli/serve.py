"""``afmforce serve``: the web application (analyse, simulate, fit, sweep) on a local server.

Binds to 127.0.0.1 by default; bound to any other address it requires a token
(--token, or one generated and printed) on every request. Everything the page
needs ships inside the package: it works without network. See docs/web.md.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from ..limits import SERVER_MAX_UPLOAD


def register(sub) -> None:
    p = sub.add_parser("serve", help="a local web application: analyse, simulate, fit and sweep in the browser",
                       description=__doc__.split("\n\n")[1].replace("\n", " "))
    p.add_argument("--host", default="127.0.0.1", help="address to bind (default %(default)s; any other "
                   "address requires a token)")
    p.add_argument("--port", type=int, default=8765, help="TCP port (default %(default)s; 0: any free port)")
    p.add_argument("--token", default=None, help="token every request must carry (default: none on "
                   "loopback, generated and printed otherwise)")
    p.add_argument("--max-upload", default=f"{SERVER_MAX_UPLOAD // 1_000_000}MB", metavar="SIZE",
                   help="largest upload (default %(default)s); larger ones get HTTP 413")
    p.add_argument("--data", type=Path, default=None, metavar="DIR", help="folder for uploads, jobs and sweeps "
                   "(default ~/.afmforce/serve); sweeps left running resume from it")
    p.add_argument("--budget", type=float, default=60.0, metavar="SECONDS",
                   help="time budget of one analysis or simulation request (default %(default)g s)")
    p.add_argument("--allow-origin", action="append", default=[], metavar="ORIGIN",
                   help="an origin (https://lab.example.org) besides the server's own whose pages may send "
                        "requests (repeatable); every other origin, 'null' included, gets HTTP 403")
    p.add_argument("--session-ttl", default="24h", metavar="TIME",
                   help="a browser session's uploads and jobs are removed this long after its last use "
                        "(default %(default)s; units: s, min, h, d)")
    from ..limits import SERVER_SESSION_STORAGE, SERVER_STORAGE

    p.add_argument("--session-storage", default=None, metavar="SIZE",
                   help=f"bytes one browser session may keep stored: uploads, job results, sweep stores (default "
                        f"{SERVER_SESSION_STORAGE / 1e9:g}GB); its next upload or job gets HTTP 413 until it deletes "
                        "files or jobs")
    p.add_argument("--server-storage", default=None, metavar="SIZE",
                   help=f"bytes all sessions together may keep stored: uploads, job results, sweep stores (default "
                        f"{SERVER_STORAGE / 1e9:g}GB)")
    p.set_defaults(func=run)


def session_ttl(text: str) -> float:
    """``--session-ttl`` as seconds (``"24h"``, ``"30min"``, ``"2d"``, a plain number: seconds)."""
    from ..errors import ParameterError
    from ..units import parse_quantity

    try:
        return parse_quantity(text, "time", "--session-ttl")
    except ParameterError as exc:
        raise ParameterError(f"{exc}; give e.g. 24h, 30min or 2d") from None


def run(args: argparse.Namespace) -> int:
    import math
    import socket

    from ..errors import ParameterError

    if not 0 <= args.port <= 65535:
        raise ParameterError(f"--port {args.port} is out of range: give 0 (any free port) to 65535")
    if not (math.isfinite(args.budget) and args.budget > 0):
        raise ParameterError(f"--budget {args.budget} s is out of range: give a time > 0 s")
    import uvicorn

    from ..web import create_app
    from ..web.settings import Settings, parse_size

    if args.data is not None:       # before any folder is made in it ("/etc/passwd: File exists" said before)
        from ._validate import check_output

        check_output(args.data, flag="--data", folder=True)
    kw = {"data": args.data} if args.data is not None else {}
    for flag, name in (("--session-storage", "session_storage"), ("--server-storage", "server_storage")):
        if getattr(args, name) is not None:
            kw[name] = parse_size(getattr(args, name), flag)
    settings = Settings(host=args.host, port=args.port, token=args.token, max_upload=parse_size(args.max_upload),
                        request_budget=args.budget, allow_origins=tuple(args.allow_origin),
                        session_ttl=session_ttl(args.session_ttl), **kw).resolved()
    sock = socket.socket(socket.AF_INET6 if ":" in settings.host else socket.AF_INET)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        sock.bind((settings.host, settings.port))
    except OSError as exc:
        import errno

        from ..errors import ParameterError

        sock.close()
        # an address this machine does not have (or a name that resolves to none) is the host's
        # fault, not the port's: "choose another --port" sent users to the wrong flag
        host = isinstance(exc, socket.gaierror) or exc.errno == errno.EADDRNOTAVAIL
        raise ParameterError(f"cannot listen on {settings.host}:{settings.port}: {exc.strerror}; "
                             + ("give an address of this machine as --host (127.0.0.1: this machine only)"
                                if host else "choose another --port")) from None
    from dataclasses import replace

    settings = replace(settings, port=sock.getsockname()[1])
    # listening before the URL is printed: a request sent at once (a browser, a script reading the first line)
    # waits in the backlog until the server accepts it, not "connection refused" (uvicorn listens again: harmless)
    sock.listen(2048)
    app = create_app(settings)
    print(f"afmforce serve: {settings.url()}", flush=True)
    if settings.token and not settings.loopback:
        print(f"  token: {settings.token} (required on every request)", flush=True)
    if settings.allow_origins:
        print(f"  pages of {', '.join(settings.allow_origins)} may send requests", flush=True)
    print(f"  data in {settings.data}; sessions kept {settings.session_ttl / 3600:g} h after their last use; "
          "Ctrl-C stops", flush=True)
    server = uvicorn.Server(uvicorn.Config(app, log_level="warning", timeout_graceful_shutdown=3))
    server.run(sockets=[sock])
    return 0
