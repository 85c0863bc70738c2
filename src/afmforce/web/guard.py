"""Security of every request, as one ASGI middleware: token, session cookie, upload limit.

* A token, when the server has one, must come with every request: header
  ``Authorization: Bearer T``, or ``?token=T`` (the printed URL; it is then kept
  in an HttpOnly cookie so that the page's own requests carry it). Otherwise 401.
* Every browser gets a random session id in an HttpOnly, SameSite=Strict cookie;
  uploads and jobs belong to it, so two users never see each other's data.
  The cookie lives as long as a session (``--session-ttl``); a cookie costs the server
  nothing until the session stores something (:mod:`.sessions`).
* A request body larger than the limit gets 413 (from ``Content-Length`` before it
  is read, and while it is read when the length is not announced: a chunked upload).
  The bytes of the bodies being received (Starlette spools an upload to its temporary folder
  before any route runs) count against the session's storage with what it keeps stored: a body
  that would pass it is refused 413 ``storage_full`` before it is read (or, chunked, as it
  grows past it), and past :data:`afmforce.limits.SERVER_BODIES_IN_FLIGHT` received at once
  for all sessions a request waits for none: 429 ``busy``.
* Requests sent by another web site are refused (403): a browser's ``Origin`` must be this
  server's own or one given with ``--allow-origin``; ``Origin: null`` (a sandboxed frame, a
  file, a redirect across sites) is refused, and a write without ``Origin`` whose
  ``Sec-Fetch-Site`` says another site sent it too. Bound to loopback, the ``Host`` must be a
  loopback name (DNS rebinding). Clients that are not browsers (curl, scripts) send no
  ``Origin`` and pass.
* Every refusal has the one shape ``{"error": {"type", "message", "field"}}`` (:mod:`.replies`).
"""

from __future__ import annotations

import hmac
import re
import secrets
from http.cookies import SimpleCookie
from urllib.parse import parse_qs, urlsplit

from .replies import error_bytes

__all__ = ["Guard", "SESSION_COOKIE", "TOKEN_COOKIE", "normal_origin"]

SESSION_COOKIE = "afmforce_session"
TOKEN_COOKIE = "afmforce_token"
_SESSION = re.compile(r"^[A-Za-z0-9_-]{32,64}$")
_LOOPBACK_NAMES = ("127.0.0.1", "localhost", "::1")
_SAFE = ("GET", "HEAD", "OPTIONS")
_TYPES = {401: "unauthorized", 403: "forbidden", 413: "too_large", 429: "busy"}
#: A chunked body's share of the bodies in flight is checked against the storage each time it grows this much [bytes].
_STEP = 8_000_000
#: Bytes of a request body not counted as stored: a multipart body's boundaries and part headers (a
#: 900-byte upload is a body of ~1,100 bytes) [bytes].
_FRAMING = 65_536


def normal_origin(text: str) -> str | None:
    """``"HTTP://Lab.example:8443/"`` -> ``"http://lab.example:8443"``; None when ``text`` is not an
    origin (``scheme://host[:port]`` with http or https, no path, query or user)."""
    try:
        parts = urlsplit(str(text).strip())
        port = parts.port
    except ValueError:
        return None
    if parts.scheme not in ("http", "https") or not parts.hostname or parts.path not in ("", "/") \
            or parts.query or parts.fragment or parts.username or parts.password:
        return None
    host = f"[{parts.hostname}]" if ":" in parts.hostname else parts.hostname
    return f"{parts.scheme}://{host.lower()}" + (f":{port}" if port is not None else "")


class _TooLarge(Exception):
    pass


async def _reply_type(send, status: int, kind: str, message: str) -> None:
    body = error_bytes(kind, message)
    await send({"type": "http.response.start", "status": status,
                "headers": [(b"content-type", b"application/json"), (b"content-length", str(len(body)).encode())]})
    await send({"type": "http.response.body", "body": body})


async def _reply(send, status: int, message: str) -> None:
    body = error_bytes(_TYPES.get(status, "error"), message)
    await send({"type": "http.response.start", "status": status,
                "headers": [(b"content-type", b"application/json"), (b"content-length", str(len(body)).encode())]})
    await send({"type": "http.response.body", "body": body})


class Guard:
    """ASGI middleware: token check, session cookie, request size limit.

    Parameters
    ----------
    app : ASGI application
    token : str or None
        Required token (None: none required).
    max_body : int
        Largest request body [bytes].
    loopback : bool
        Bound to loopback only (then the ``Host`` must be a loopback name).
    allow_origins : sequence of str
        Origins besides the server's own whose pages may send requests (``--allow-origin``).
    session_ttl : float
        Lifetime of the session cookie [s].
    seen : callable, optional
        ``seen(session)`` for every accepted request of a known session (renews its lifetime).
    room : callable, optional
        ``room(session, adding)``: why ``adding`` more bytes would pass the session's or the server's
        storage, or None (:meth:`afmforce.web.sessions.Sessions.room_refusal`); the session's bodies
        in flight are added to each request's.
    max_flight : int
        Bytes of request bodies received at once, all sessions together (:data:`afmforce.limits.
        SERVER_BODIES_IN_FLIGHT`).
    framing : int
        Bytes of each body not counted (a multipart body's boundaries and part headers around the
        files the session will store) [bytes].
    """

    def __init__(self, app, token: str | None, max_body: int, loopback: bool = True, allow_origins=(),
                 session_ttl: float = 24 * 3600.0, seen=None, room=None, max_flight: int | None = None,
                 framing: int = _FRAMING):
        from ..limits import SERVER_BODIES_IN_FLIGHT

        self.app, self.token, self.max_body, self.loopback = app, token, max_body, loopback
        self.seen, self.room = seen, room
        self.max_flight = SERVER_BODIES_IN_FLIGHT if max_flight is None else max_flight
        self.framing = framing
        self._flight: dict[str, int] = {}   # bytes of bodies being received, per session (one event loop)
        self._flight_total = 0
        self.allow_origins = frozenset(o for o in (normal_origin(a) for a in allow_origins) if o)
        self.max_age = max(1, int(session_ttl))

    def _foreign(self, method: str, headers: dict) -> str | None:
        """Why a request comes from elsewhere (another site's page, a sandboxed frame, a rebound
        DNS name), or None."""
        host = headers.get(b"host", b"").decode("latin-1")
        try:
            name = (urlsplit(f"//{host}").hostname or "") if host else ""
        except ValueError:      # "[::1", "[zz]": urlsplit raised, and the request answered 500
            return f"host {host[:100]!r} is not a host name (the request's Host header is malformed)"
        if self.loopback and host and name not in _LOOPBACK_NAMES:
            return f"host {host!r} is not this loopback server"
        origin = headers.get(b"origin", b"").decode("latin-1").strip()
        if origin:
            if origin.lower() == "null":
                return ("request from an opaque origin (Origin: null: a sandboxed frame, a file or a "
                        "redirect) refused")
            try:
                own = urlsplit(origin).netloc == host
            except ValueError:
                own = False
            if not own and normal_origin(origin) not in self.allow_origins:
                return f"cross-site request from {origin[:100]} refused (afmforce serve --allow-origin)"
            return None
        site = headers.get(b"sec-fetch-site", b"").decode("latin-1")
        if method not in _SAFE and site in ("cross-site", "same-site"):
            return "cross-site request refused (Sec-Fetch-Site: " + site + ")"
        return None

    def _token_ok(self, headers: dict, cookies: dict, query: dict) -> tuple[bool, bool]:
        """(accepted, came in the query: set the cookie)."""
        if self.token is None:
            return True, False
        auth = headers.get(b"authorization", b"").decode("latin-1")
        given = [auth[7:] if auth.lower().startswith("bearer ") else "", cookies.get(TOKEN_COOKIE, ""),
                 (query.get("token") or [""])[0]]
        ok = [bool(g) and hmac.compare_digest(g.encode(), self.token.encode()) for g in given]
        return any(ok), ok[2] and not ok[1]

    async def __call__(self, scope, receive, send):
        if scope["type"] != "http":
            return await self.app(scope, receive, send)
        headers = dict(scope.get("headers") or [])
        jar = SimpleCookie()
        try:
            jar.load(headers.get(b"cookie", b"").decode("latin-1"))
        except Exception:  # a malformed cookie header is no cookie
            pass
        cookies = {k: m.value for k, m in jar.items()}
        query = parse_qs(scope.get("query_string", b"").decode("latin-1"))
        foreign = self._foreign(scope.get("method", "GET"), headers)
        if foreign:
            return await _reply(send, 403, foreign)
        ok, set_token = self._token_ok(headers, cookies, query)
        if not ok:
            return await _reply(send, 401, "this server needs its token: open the URL it printed "
                                           "(…/?token=…) or send 'Authorization: Bearer TOKEN'")
        sid = cookies.get(SESSION_COOKIE, "")
        new_session = not _SESSION.match(sid)
        if new_session:
            sid = secrets.token_urlsafe(32)
        elif self.seen is not None:
            self.seen(sid)
        scope.setdefault("state", {})["session"] = sid
        length = headers.get(b"content-length")
        if length is not None and length.isdigit() and int(length) > self.max_body:
            return await _reply(send, 413, f"upload too large: {int(length):,} bytes; the limit is "
                                           f"{self.max_body:,} (afmforce serve --max-upload)")
        seen = 0
        too_large = False
        too_large_text = f"upload too large: more than {self.max_body:,} bytes (afmforce serve --max-upload)"
        refusal: tuple[int, str, str] | None = None     # (status, type, message) of a body refused as it grew
        reserved = 0

        checked = -_STEP

        def admit(more: int) -> tuple[int, str, str] | None:
            """Reserve ``more`` bytes of this request's body in flight, or why not (checked when the body
            started, and then each :data:`_STEP` bytes: the session's room is a walk of its folder)."""
            nonlocal reserved, checked
            if reserved + more - checked < _STEP:
                reserved += more
                self._flight[sid] = self._flight.get(sid, 0) + more
                self._flight_total += more
                return None
            checked = reserved + more
            if self._flight_total + more > self.max_flight:
                return (429, "busy", f"the server is receiving {self._flight_total:,} bytes of uploads; "
                                     f"{more:,} more would pass the {self.max_flight:,} it receives at once "
                                     "(afmforce.limits.SERVER_BODIES_IN_FLIGHT): try again in a moment")
            why = self.room(sid, self._flight.get(sid, 0) + more) if self.room is not None else None
            if why:
                return (413, "storage_full", why)
            reserved += more
            self._flight[sid] = self._flight.get(sid, 0) + more
            self._flight_total += more
            return None

        announced = int(length) if length is not None and length.isdigit() else 0
        if announced > self.framing:
            why = admit(announced - self.framing)
            if why:
                return await _reply_type(send, *why)

        async def limited():
            nonlocal seen, too_large, refusal
            if too_large:      # the app asks again after the refusal: the body has ended for it
                return {"type": "http.disconnect"}
            message = await receive()
            if message["type"] == "http.request":
                seen += len(message.get("body", b""))
                if seen > self.max_body:
                    too_large = True
                    raise _TooLarge()
                if seen - self.framing > reserved:    # a body longer than announced, or chunked: it grows
                    refusal = admit(seen - self.framing - reserved)
                    if refusal:
                        too_large = True
                        raise _TooLarge()
            return message

        started = False

        async def send_with_cookies(message):
            nonlocal started
            if too_large:
                # the body outgrew the limit while the app read it (a chunked upload): whatever the app
                # makes of the interrupted body (FastAPI: 400), the client is told 413
                if message["type"] == "http.response.start" and not started:
                    started = True
                    await (_reply_type(send, *refusal) if refusal else _reply(send, 413, too_large_text))
                return
            if message["type"] == "http.response.start":
                started = True
                # sent on every response: the cookie lives --session-ttl after the last request, as the
                # session's folder does (a new id for a cookie-less request costs nothing on disk)
                extra = [(b"set-cookie", f"{SESSION_COOKIE}={sid}; HttpOnly; SameSite=Strict; Path=/; "
                                                 f"Max-Age={self.max_age}".encode())]
                if set_token:
                    extra.append((b"set-cookie",
                                  f"{TOKEN_COOKIE}={self.token}; HttpOnly; SameSite=Strict; Path=/".encode()))
                message = {**message, "headers": list(message.get("headers", [])) + extra}
            await send(message)

        try:
            await self.app(scope, limited, send_with_cookies)
        except _TooLarge:
            if not started:
                started = True
                await (_reply_type(send, *refusal) if refusal else _reply(send, 413, too_large_text))
        finally:     # the body's bytes are the route's now (stored, counted as the session's) or gone
            if reserved:
                left = self._flight.get(sid, 0) - reserved
                if left > 0:
                    self._flight[sid] = left
                else:
                    self._flight.pop(sid, None)
                self._flight_total -= reserved
