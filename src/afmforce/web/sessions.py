"""Per-session upload folders: uploaded names never reach the file system.

Each session (the browser's random cookie) has a folder named by a hash of its id;
an upload is stored as ``<random hex id><suffix>``, the suffix kept only when it is
a plain file-type suffix (readers detect the format by it: ``.jpk-force``, ``.ibw``);
the name the user gave is kept in the session's index, for display only.
"""

from __future__ import annotations

import hashlib
import json
import re
import secrets
import threading
from pathlib import Path
from typing import Any

from .._files import atomic_write_text
from ..errors import ParameterError

__all__ = ["Sessions", "safe_suffix"]

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


class Sessions:
    """Uploads by session, under ``root/sessions/<hash of the session id>/``."""

    def __init__(self, root: Path):
        self.root = Path(root) / "sessions"
        self._lock = threading.Lock()

    def folder(self, session: str) -> Path:
        """The session's folder (created)."""
        key = hashlib.sha256(session.encode()).hexdigest()[:32]
        path = self.root / key
        path.mkdir(parents=True, exist_ok=True)
        return path

    def _index(self, session: str) -> dict[str, Any]:
        path = self.folder(session) / "index.json"
        return json.loads(path.read_text(encoding="utf-8")) if path.exists() else {}

    def save(self, session: str, name: str, data: bytes) -> dict[str, Any]:
        """Store an upload; returns ``{"id", "name", "size"}`` (``name``: as given, display only)."""
        file_id = secrets.token_hex(16)
        folder = self.folder(session)
        (folder / f"{file_id}{safe_suffix(name)}").write_bytes(data)
        shown = re.split(r"[\\/]", name or "")[-1][:200] or "upload"
        with self._lock:
            index = self._index(session)
            index[file_id] = {"name": shown, "suffix": safe_suffix(name), "size": len(data)}
            atomic_write_text(folder / "index.json", json.dumps(index), force=True)
        return {"id": file_id, "name": shown, "size": len(data)}

    def mark_read(self, session: str, file_ids) -> None:
        """Record that these uploads were read once without failing: later analyses of them
        skip the forked time-guarded reader (a re-run after an option change stays fast)."""
        with self._lock:
            index = self._index(session)
            for fid in file_ids:
                if fid in index:
                    index[fid]["read"] = True
            atomic_write_text(self.folder(session) / "index.json", json.dumps(index), force=True)

    def was_read(self, session: str, file_id: str) -> bool:
        """Whether the upload was read once without failing (:meth:`mark_read`)."""
        return bool(self._index(session).get(file_id, {}).get("read"))

    def files(self, session: str) -> list[dict[str, Any]]:
        """The session's uploads: ``[{"id", "name", "size"}]``."""
        return [{"id": k, "name": v["name"], "size": v["size"]} for k, v in self._index(session).items()]

    def path(self, session: str, file_id: str) -> tuple[Path, str]:
        """``(stored path, name given)`` of one of the session's uploads (ParameterError: not this session's)."""
        entry = self._index(session).get(file_id) if _ID.match(file_id or "") else None
        if entry is None:
            raise ParameterError(f"no uploaded file {file_id!r} in this session; upload it again")
        return self.folder(session) / f"{file_id}{entry['suffix']}", entry["name"]
