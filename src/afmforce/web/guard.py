"""Security of every request, as one ASGI middleware: token, session cookie, upload limit.

* A token, when the server has one, must come with every request: header
  ``Authorization: Bearer T``, or ``?token=T`` (the printed URL; it is then kept
  in an HttpOnly cookie so that the page's own requests carry it). Otherwise 401.
* Every browser gets a random session id in an HttpOnly, SameSite=Strict cookie;
  uploads and jobs belong to it, so two users never see each other's data.
* A request body larger than the limit gets 413 (from ``Content-Length`` before it
  is read, and while it is read when the length is not announced).
* Requests sent by another web site are refused (403): a browser's ``Origin`` must be this
  server's own; bound to loopback, the ``Host`` must be a loopback name (DNS rebinding).
"""

from __future__ import annotations

import hmac
import json
import re
import secrets
from http.cookies import SimpleCookie
from urllib.parse import parse_qs, urlsplit

__all__ = ["Guard", "SESSION_COOKIE", "TOKEN_COOKIE"]

SESSION_COOKIE = "afmforce_session"
TOKEN_COOKIE = "afmforce_token"
_SESSION = re.compile(r"^[A-Za-z0-9_-]{32,64}$")
_LOOPBACK_NAMES = ("127.0.0.1", "localhost", "::1")


class _TooLarge(Exception):
    pass


async def _reply(send, status: int, message: str) -> None:
    body = json.dumps({"error": message}).encode()
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
    """

    def __init__(self, app, token: str | None, max_body: int, loopback: bool = True):
        self.app, self.token, self.max_body, self.loopback = app, token, max_body, loopback

    def _foreign(self, headers: dict) -> str | None:
        """Why a request comes from elsewhere (another site's page, a rebound DNS name), or None."""
        host = headers.get(b"host", b"").decode("latin-1")
        name = (urlsplit(f"//{host}").hostname or "") if host else ""
        if self.loopback and host and name not in _LOOPBACK_NAMES:
            return f"host {host!r} is not this loopback server"
        origin = headers.get(b"origin", b"").decode("latin-1")
        if origin and origin != "null" and urlsplit(origin).netloc != host:
            return f"cross-site request from {origin} refused"
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
        foreign = self._foreign(headers)
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
        scope.setdefault("state", {})["session"] = sid
        length = headers.get(b"content-length")
        if length is not None and length.isdigit() and int(length) > self.max_body:
            return await _reply(send, 413, f"upload too large: {int(length):,} bytes; the limit is "
                                           f"{self.max_body:,} (afmforce serve --max-upload)")
        seen = 0

        async def limited():
            nonlocal seen
            message = await receive()
            if message["type"] == "http.request":
                seen += len(message.get("body", b""))
                if seen > self.max_body:
                    raise _TooLarge()
            return message

        started = False

        async def send_with_cookies(message):
            nonlocal started
            if message["type"] == "http.response.start":
                started = True
                extra = []
                if new_session:
                    extra.append((b"set-cookie", f"{SESSION_COOKIE}={sid}; HttpOnly; SameSite=Strict; Path=/".encode()))
                if set_token:
                    extra.append((b"set-cookie",
                                  f"{TOKEN_COOKIE}={self.token}; HttpOnly; SameSite=Strict; Path=/".encode()))
                message = {**message, "headers": list(message.get("headers", [])) + extra}
            await send(message)

        try:
            await self.app(scope, limited, send_with_cookies)
        except _TooLarge:
            if not started:
                await _reply(send, 413, f"upload too large: more than {self.max_body:,} bytes "
                                        "(afmforce serve --max-upload)")
