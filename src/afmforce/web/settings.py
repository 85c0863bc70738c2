"""The server's settings: address, token, upload limit, data folder and time budgets."""

from __future__ import annotations

import ipaddress
import re
import secrets
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import ParameterError
from ..limits import SERVER_MAX_UPLOAD
from .limits import SERVER_STORAGE, SESSION_STORAGE, SESSION_TTL

__all__ = ["Settings", "parse_size", "is_loopback"]

_SIZE = re.compile(r"^\s*(\d+(?:\.\d+)?)\s*([kMG]?i?B?)?\s*$", re.I)
_FACTOR = {"": 1, "b": 1, "kb": 1e3, "mb": 1e6, "gb": 1e9, "kib": 2**10, "mib": 2**20, "gib": 2**30,
           "k": 1e3, "m": 1e6, "g": 1e9}


def parse_size(text: str | int, flag: str = "--max-upload") -> int:
    """``"200MB"`` -> 200000000 [bytes]; plain numbers are bytes (kB/MB/GB decimal, KiB/MiB/GiB binary);
    ``flag`` names the option in the message."""
    if isinstance(text, int):
        value = text
    else:
        m = _SIZE.match(str(text))
        if not m or (m.group(2) or "").lower() not in _FACTOR:
            raise ParameterError(f"{flag} {text!r}: give a size such as 200MB, 1GB or 500kB")
        value = int(float(m.group(1)) * _FACTOR[(m.group(2) or "").lower()])
    if value < 1:
        raise ParameterError(f"{flag} must be at least 1 byte, got {text!r}")
    return value


def is_loopback(host: str) -> bool:
    """Whether ``host`` is a loopback address (127.0.0.0/8, ::1, localhost)."""
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


@dataclass(frozen=True)
class Settings:
    """How ``afmforce serve`` runs.

    Attributes
    ----------
    host : str
        Address to bind (loopback by default; any other address requires a token).
    port : int
        TCP port.
    token : str or None
        Required on every request when set (header ``Authorization: Bearer T``, query
        ``?token=T`` once, then a cookie). Bound to a non-loopback address without one,
        :meth:`resolved` generates one.
    max_upload : int
        Largest request body accepted [bytes]; larger uploads get 413.
    data : Path
        Folder of the sessions' uploads, the jobs and the sweeps' stores.
    request_budget : float
        Time budget of one analysis or simulation request [s]; a request past it is cancelled.
    job_budget : float
        Time budget of one fit or sweep job [s]; past it the job is cancelled.
    spare_job : bool
        Keep one job process warm (compiled integrator loaded), so that a fit or sweep starts at once.
    allow_origins : tuple of str
        Origins (``https://lab.example:8443``) besides the server's own whose pages may send
        requests (``--allow-origin``); every other origin, ``null`` included, gets 403.
    session_ttl : float
        Lifetime of a session after its last use [s] (``--session-ttl``): then its uploads and
        jobs are removed.
    session_storage : int
        Bytes one session may keep stored (``--session-storage``): uploads, job records and results,
        sweep stores; its next upload or job is refused (413) until it deletes files or jobs or expires.
    server_storage : int
        Bytes all sessions together may keep stored (``--server-storage``).
    """

    host: str = "127.0.0.1"
    port: int = 8765
    token: str | None = None
    max_upload: int = SERVER_MAX_UPLOAD
    data: Path = field(default_factory=lambda: Path.home() / ".afmforce" / "serve")
    request_budget: float = 60.0
    job_budget: float = 3600.0
    spare_job: bool = True
    allow_origins: tuple[str, ...] = ()
    session_ttl: float = SESSION_TTL
    session_storage: int = SESSION_STORAGE
    server_storage: int = SERVER_STORAGE

    def __post_init__(self) -> None:
        from .guard import normal_origin

        for origin in self.allow_origins:
            if normal_origin(origin) is None:
                raise ParameterError(f"--allow-origin {origin!r}: give an origin such as "
                                     "https://lab.example.org or http://127.0.0.1:9000 (scheme, host, port)")
        object.__setattr__(self, "allow_origins", tuple(normal_origin(o) for o in self.allow_origins))
        object.__setattr__(self, "data", Path(self.data))  # a folder given as text (create_app mkdirs it)
        if not (isinstance(self.session_ttl, (int, float)) and 60 <= self.session_ttl <= 365 * 86400):
            raise ParameterError(f"--session-ttl must lie in [1 min, 365 d], got {self.session_ttl!r} s")
        for flag, value in (("--session-storage", self.session_storage), ("--server-storage", self.server_storage)):
            if not (isinstance(value, int) and value >= 1):
                raise ParameterError(f"{flag} must be a whole number of bytes >= 1, got {value!r}")
        if not 0 <= self.port < 65536:
            raise ParameterError(f"--port must lie in [0, 65535], got {self.port}")
        if self.token is not None and len(self.token) < 8:
            raise ParameterError("--token must have at least 8 characters")
        if not (self.request_budget > 0 and self.job_budget > 0):
            raise ParameterError("time budgets must be positive [s]")

    @property
    def loopback(self) -> bool:
        """Bound to a loopback address only."""
        return is_loopback(self.host)

    def resolved(self) -> "Settings":
        """These settings with a generated token when bound beyond loopback without one."""
        if self.token is None and not self.loopback:
            from dataclasses import replace

            return replace(self, token=secrets.token_urlsafe(18))
        return self

    def url(self) -> str:
        """The page's address (with the token, when one is required)."""
        host = f"[{self.host}]" if ":" in self.host else self.host
        shown = "127.0.0.1" if host in ("0.0.0.0", "[::]") else host
        return f"http://{shown}:{self.port}/" + (f"?token={self.token}" if self.token else "")
