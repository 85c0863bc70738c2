"""Per-session upload folders: uploaded names never reach the file system.

Each session (the browser's random cookie) has a folder named by a hash of its id;
an upload is stored as ``<random hex id><suffix>``, the suffix kept only when it is
a plain file-type suffix (readers detect the format by it: ``.jpk-force``, ``.ibw``);
the name the user gave is kept in the session's index, for display only. An Asylum wave of
one channel (``...Point0000Defl.ibw``, ``...Point0000ZSnsr.ibw``: :data:`afmforce.io.igor.CHANNELS`,
``POSITIONS``) is stored as ``<hash of the session and its prefix><channel>.ibw``, so that the
waves of one curve sit side by side under one stored prefix and the reader pairs them, as it
does in a folder (:func:`afmforce.io.igor.load_channel_pair`); an upload of the same wave name
replaces the earlier one, as a copy into a folder would.

A session costs nothing until it stores something: its folder is made by the first
upload (or job, :meth:`Sessions.touch`), never by a request that only reads. It lives
``ttl`` seconds after its last use (the folder's ``last-used`` stamp, renewed at most once
a minute); :meth:`Sessions.expire` removes the folders of sessions past it (the server runs
it at start and then every few minutes, with the jobs of those sessions).

Disk is bounded: a session keeps at most ``session_bytes`` and all sessions together
``server_bytes`` (:data:`~.limits.SESSION_STORAGE`, :data:`~.limits.SERVER_STORAGE`) of everything
the server writes for them: uploads, the stores of their sweeps (``<session folder>/sweeps/<job
id>/``) and the records of their jobs (with the results; ``jobs/<id>.json``, counted by the job
manager through ``extra``, a running job at its declared most, :func:`~.jobs.job_reserve`). The
bytes stored are counted from the files themselves at each upload or job, so a deleted upload, a
deleted job or an expired session frees its space at once; an upload or a job over either total is
refused (:class:`StorageFull`) before anything is written, all the files of one request or none.
Stored files are never evicted.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import secrets
import shutil
import threading
import time
from pathlib import Path
from typing import Any, Callable

from .._files import atomic_write_text
from ..errors import AfmforceError, ParameterError
from .limits import SERVER_STORAGE, SESSION_STORAGE

__all__ = ["Sessions", "StorageFull", "channel_name", "safe_suffix", "session_key"]


class StorageFull(AfmforceError):
    """An upload that would take a session (or the server) past the bytes it may keep stored (413)."""


def _bytes(n: float) -> str:
    """``1234`` -> ``'1,234 bytes'``; ``2e9`` -> ``'2 GB'`` (decimal units, as ``--max-upload``)."""
    return next((f"{n / f:.3g} {u}" for f, u in ((1e12, "TB"), (1e9, "GB"), (1e6, "MB")) if n >= f),
                f"{n:,.0f} bytes")

def _size(data) -> int:
    """Bytes of an upload: ``bytes``, or a binary file (the request's spooled part: never read whole into memory)."""
    if isinstance(data, (bytes, bytearray, memoryview)):
        return len(data)
    data.seek(0, os.SEEK_END)
    n = data.tell()
    data.seek(0)
    return n


def _write(path: Path, data) -> None:
    """Store an upload (``bytes`` or a binary file, copied 1 MB at a time)."""
    if isinstance(data, (bytes, bytearray, memoryview)):
        path.write_bytes(data)
        return
    data.seek(0)
    with open(path, "wb") as out:
        shutil.copyfileobj(data, out, 1 << 20)


_SUFFIX = re.compile(r"^\.[A-Za-z0-9][A-Za-z0-9-]{0,19}$")
_ID = re.compile(r"^[0-9a-f]{32}$")


def safe_suffix(name: str) -> str:
    """The file-type suffix of an uploaded name, or "" when it is not a plain one
    (``'../../x.ibw' -> '.ibw'``, ``'a.jpk-force-map' -> '.jpk-force-map'``, ``'x/..' -> ''``)."""
    base = re.split(r"[\\/]", name or "")[-1]
    if "." not in base.strip("."):
        return ""
    suffix = "." + base.rsplit(".", 1)[1]
    return suffix.lower() if _SUFFIX.match(suffix) else ""


def channel_name(name: str, session: str) -> str | None:
    """The stored name of a one-channel Asylum wave (``'Map1Point0000Defl.ibw' -> '<hex>Defl.ibw'``:
    the hex a hash of the session and the prefix ``Map1Point0000``), None for any other file."""
    from ..io.igor import CHANNELS, POSITIONS

    base = re.split(r"[\\/]", name or "")[-1]
    suffix = safe_suffix(base)
    if suffix != ".ibw":
        return None
    stem = base[: -len(suffix)]
    for channel in (*CHANNELS, *POSITIONS):
        if stem.endswith(channel) and len(stem) > len(channel):
            prefix = stem[: -len(channel)]
            key = hashlib.sha256(f"{session_key(session)}/{prefix}".encode()).hexdigest()[:32]
            return f"{key}{channel}{suffix}"
    return None


def session_key(session: str) -> str:
    """The stored name of a session (a hash: the cookie itself is never written); also the owner
    of its jobs (:func:`afmforce.web.jobs.owner_of`)."""
    return hashlib.sha256(session.encode()).hexdigest()[:32]


_STAMP = "last-used"
_TOUCH_EVERY = 60.0


class Sessions:
    """Uploads by session, under ``root/sessions/<hash of the session id>/``.

    Parameters
    ----------
    root : Path
        The data folder.
    ttl : float
        Lifetime of a session after its last use [s].
    session_bytes : int
        Bytes of uploads one session may keep stored [bytes].
    server_bytes : int
        Bytes of uploads all sessions together may keep stored [bytes].
    """

    def __init__(self, root: Path, ttl: float = 24 * 3600.0, session_bytes: int = SESSION_STORAGE,
                 server_bytes: int = SERVER_STORAGE, extra: Callable[[str | None], int] | None = None):
        self.root = Path(root) / "sessions"
        self.ttl = float(ttl)
        self.session_bytes = int(session_bytes)
        self.server_bytes = int(server_bytes)
        #: bytes stored for a session outside its folder (its key; None: all sessions): its jobs' records
        self.extra = extra
        self._lock = threading.Lock()
        self._touched: dict[str, float] = {}

    def folder(self, session: str, create: bool = True) -> Path:
        """The session's folder (made when ``create``, and its use recorded)."""
        key = session_key(session)
        path = self.root / key
        if create:
            path.mkdir(parents=True, exist_ok=True)
            self._stamp(key, path)
        return path

    def _stamp(self, key: str, path: Path) -> None:
        now = time.monotonic()
        if now - self._touched.get(key, -1e9) >= _TOUCH_EVERY or not (path / _STAMP).exists():
            (path / _STAMP).touch()
            self._touched[key] = now

    def exists(self, session: str) -> bool:
        """Whether the session has stored anything."""
        return (self.root / session_key(session)).is_dir()

    def touch(self, session: str) -> None:
        """Record a use of the session (its folder made: a job or an upload belongs to it now)."""
        self.folder(session)

    def seen(self, session: str) -> None:
        """A request of the session: renew its lifetime if it has a folder (nothing made otherwise)."""
        path = self.root / session_key(session)
        if path.is_dir():
            self._stamp(session_key(session), path)

    def last_used(self, session: str) -> float | None:
        """When the session was last used [s since the epoch], None when it has no folder."""
        stamp = self.root / session_key(session) / _STAMP
        try:
            return stamp.stat().st_mtime
        except OSError:
            return None

    def expire(self, now: float | None = None) -> list[str]:
        """Remove the folders of sessions unused for longer than ``ttl``; returns their keys."""
        now = time.time() if now is None else now
        gone = []
        if not self.root.is_dir():
            return gone
        for path in self.root.iterdir():
            if not path.is_dir():
                continue
            try:
                used = max((path / _STAMP).stat().st_mtime if (path / _STAMP).exists() else 0.0,
                           path.stat().st_mtime)
            except OSError:
                continue
            if now - used > self.ttl:
                with self._lock:
                    shutil.rmtree(path, ignore_errors=True)
                self._touched.pop(path.name, None)
                gone.append(path.name)
        return gone

    def keys(self) -> list[str]:
        """The stored names of the sessions that have a folder."""
        return [p.name for p in self.root.iterdir() if p.is_dir()] if self.root.is_dir() else []

    def _index(self, session: str) -> dict[str, Any]:
        path = self.folder(session, create=False) / "index.json"
        try:
            return json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            return {}

    @staticmethod
    def _folder_bytes(path: Path) -> int:
        """Bytes of everything stored in one session's folder, sub-folders included (its uploads and
        its sweeps' stores; the index and the stamp not counted)."""
        total = 0
        for folder, _, names in os.walk(path):
            for name in names:
                if folder == str(path) and (name in ("index.json", _STAMP) or name.startswith(".")):
                    continue
                try:
                    total += os.lstat(os.path.join(folder, name)).st_size
                except OSError:
                    pass
        return total

    def stored_bytes(self, session: str | None = None) -> int:
        """Bytes the session keeps stored, uploads, sweep stores and job records (None: all sessions
        together) [bytes], counted from the files (a deleted upload or job, an expired session is freed
        at once)."""
        return self._key_bytes(None if session is None else session_key(session))

    def _key_bytes(self, key: str | None) -> int:
        extra = self.extra(key) if self.extra is not None else 0
        if key is not None:
            return self._folder_bytes(self.root / key) + extra
        return sum(self._folder_bytes(p) for p in (self.root.iterdir() if self.root.is_dir() else ())
                   if p.is_dir()) + extra

    def sweeps(self, session: str) -> Path:
        """The folder of the session's sweep stores (inside its folder: counted, and removed with it)."""
        return self.root / session_key(session) / "sweeps"

    def room_refusal(self, key: str, adding: int, what: str = "uploads") -> str | None:
        """Why ``adding`` more bytes for the session ``key`` would pass the session's or the server's
        total (one line saying what to do), or None when they fit. ``what``: what would be added."""
        if adding <= 0:
            return None
        mine = self._key_bytes(key)
        if mine + adding > self.session_bytes:
            return (f"this session keeps {_bytes(mine)} of uploads and job results; {_bytes(adding)} more would "
                    f"pass the {_bytes(self.session_bytes)} a session may store ({what}): delete uploads or finished "
                    "jobs you no longer need (Your uploads, DELETE /api/files/ID, DELETE /api/jobs/ID) or start "
                    "a new session, then try again")
        everyone = self._key_bytes(None)
        if everyone + adding > self.server_bytes:
            return (f"the server keeps {_bytes(everyone)} of uploads and job results for all sessions; "
                    f"{_bytes(adding)} more would pass the {_bytes(self.server_bytes)} it may store ({what}): "
                    "delete uploads or finished jobs you no longer need, or ask its operator to free space "
                    "(afmforce serve --server-storage), then try again")
        return None

    def check_room(self, session: str, adding: int, what: str) -> None:
        """Refuse (:class:`StorageFull`) ``adding`` more bytes (``what``: e.g. "this fit's result, at most")."""
        why = self.room_refusal(session_key(session), adding, what)
        if why:
            raise StorageFull(why)

    def _check_room(self, session: str, planned: list[tuple[str, int]]) -> None:
        """Refuse (:class:`StorageFull`) uploads ``[(stored name, bytes)]`` that would take the session
        or the server past its total; a stored name already there (a replaced wave) frees its bytes."""
        folder = self.root / session_key(session)
        adding = 0
        for stored, size in planned:
            try:
                adding += size - (folder / stored).stat().st_size
            except OSError:
                adding += size
        self.check_room(session, adding, "uploads")

    def save(self, session: str, name: str, data: bytes) -> dict[str, Any]:
        """Store an upload; returns ``{"id", "name", "size"}`` (``name``: as given, display only).
        Raises :class:`StorageFull` past the session's or the server's total (nothing is written)."""
        return self.save_all(session, [(name, data)])[0]

    def save_all(self, session: str, uploads: list[tuple[str, Any]]) -> list[dict[str, Any]]:
        """Store the uploads of one request (``[(name, bytes or a binary file)]``), all or none:
        :class:`StorageFull` (nothing written) when together they would take the session or the server
        past its total; else :meth:`save`'s answer for each."""
        planned = []
        for name, data in uploads:
            file_id = secrets.token_hex(16)
            paired = channel_name(name, session)     # one channel of an Asylum curve: beside its partner
            planned.append((file_id, name, data, paired, paired or f"{file_id}{safe_suffix(name)}"))
        answers = []
        with self._lock:
            self._check_room(session, [(stored, _size(data)) for _, _, data, _, stored in planned])
            if not planned:
                return answers
            folder = self.folder(session)
            index = self._index(session)
            for file_id, name, data, paired, stored in planned:
                shown = re.split(r"[\\/]", name or "")[-1][:200] or "upload"
                size = _size(data)
                _write(folder / stored, data)
                if paired:       # the same wave name uploaded again replaces the earlier upload
                    index = {k: v for k, v in index.items() if v.get("stored") != paired}
                index[file_id] = {"name": shown, "suffix": safe_suffix(name), "size": size,
                                  "uploaded": time.time(), **({"stored": paired} if paired else {})}
                answers.append({"id": file_id, "name": shown, "size": size})
            atomic_write_text(folder / "index.json", json.dumps(index), force=True)
        return answers

    def mark_read(self, session: str, file_ids) -> None:
        """Record that these uploads were read once without failing: later analyses of them
        skip the forked time-guarded reader (a re-run after an option change stays fast)."""
        with self._lock:
            index = self._index(session)
            if not any(fid in index for fid in file_ids):
                return
            for fid in file_ids:
                if fid in index:
                    index[fid]["read"] = True
            atomic_write_text(self.folder(session) / "index.json", json.dumps(index), force=True)

    def was_read(self, session: str, file_id: str) -> bool:
        """Whether the upload was read once without failing (:meth:`mark_read`)."""
        return bool(self._index(session).get(file_id, {}).get("read"))

    def files(self, session: str) -> list[dict[str, Any]]:
        """The session's uploads, oldest first: ``[{"id", "name", "size", "uploaded"}]``
        (``uploaded``: s since the epoch)."""
        return [{"id": k, "name": v["name"], "size": v["size"], "uploaded": v.get("uploaded")}
                for k, v in self._index(session).items()]

    def path(self, session: str, file_id: str) -> tuple[Path, str]:
        """``(stored path, name given)`` of one of the session's uploads (ParameterError: not this session's)."""
        entry = self._index(session).get(file_id) if _ID.match(file_id or "") else None
        if entry is None:
            raise ParameterError(f"no uploaded file {file_id!r} in this session; upload it again")
        stored = entry.get("stored") or f"{file_id}{entry['suffix']}"
        return self.folder(session, create=False) / stored, entry["name"]

    def remove(self, session: str, file_id: str) -> None:
        """Remove one upload of the session (ParameterError: not this session's)."""
        path, _ = self.path(session, file_id)
        with self._lock:
            index = self._index(session)
            index.pop(file_id, None)
            path.unlink(missing_ok=True)
            atomic_write_text(self.folder(session) / "index.json", json.dumps(index), force=True)
