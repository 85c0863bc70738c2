"""Resumable on-disk store of a sweep or batch: one Parquet file per chunk.

Layout of a store folder (``<parent>/<kind>-<key>``, the key a hash of what is
run)::

    manifest.json          what runs, the chunk size, the number of items
    parameters.parquet     the parameter table (sweeps)
    chunks/chunk-000012.parquet   results of chunk 12, written atomically
    failed/chunk-000007.json      a chunk that raised: its items and the error
    lock                   pid of the process writing the store

A chunk file exists only once its chunk has finished, so a rerun skips the
chunks present and runs the others (failed chunks included).
"""

from __future__ import annotations

import json
import os
import socket
from pathlib import Path
from typing import Any, Iterator

from .._files import atomic_path, atomic_write_text, pid_alive
from ..errors import AfmforceError, ParameterError

__all__ = ["SweepStore", "StoreBusyError"]

_CHUNK = "chunk-{:06d}"


class StoreBusyError(AfmforceError):
    """Another live process is writing the same store."""


class SweepStore:
    """A store folder for one sweep or batch (see the module docstring).

    Use :meth:`open` to create or resume one; it checks that the manifest of
    an existing store describes the same work.
    """

    def __init__(self, root: str | os.PathLike) -> None:
        self.root = Path(root)
        self.chunk_dir = self.root / "chunks"
        self.failed_dir = self.root / "failed"
        self._locked = False

    # -- creation and checks --------------------------------------------------
    @classmethod
    def open(cls, parent: str | os.PathLike, key: str, manifest: dict[str, Any], *,
             kind: str = "sweep", chunk_size: int | None = None,
             default_chunk_size: int | None = None) -> "SweepStore":
        """Create ``<parent>/<kind>-<key[:12]>`` or resume it.

        ``manifest`` describes the work (it must contain ``n_items``); on resume
        the stored chunk size is kept unless ``chunk_size`` asks for another,
        which is refused because the chunks would not line up. A new store
        uses ``chunk_size``, else ``default_chunk_size``.
        """
        store = cls(Path(parent) / f"{kind}-{key[:12]}")
        stored = store.manifest()
        if stored is not None:
            if stored.get("key") != key or stored.get("n_items") != manifest.get("n_items"):
                raise ParameterError(f"{store.root} holds different work (key or size differ); use another `store`")
            if chunk_size is not None and chunk_size != stored["chunk_size"]:
                raise ParameterError(
                    f"{store.root} was started with chunk size {stored['chunk_size']}; rerun with "
                    f"`chunk_size` {stored['chunk_size']} (or leave it out) to resume, or use another `store`"
                )
            return store
        chunk_size = chunk_size if chunk_size is not None else default_chunk_size
        if chunk_size is None or chunk_size < 1:
            raise ParameterError(f"chunk size must be a positive integer, got {chunk_size}")
        store.chunk_dir.mkdir(parents=True, exist_ok=True)
        record = dict(manifest, key=key, kind=kind, chunk_size=int(chunk_size))
        atomic_write_text(store.root / "manifest.json", json.dumps(record, indent=2, default=repr))
        store.created = True
        return store

    #: Whether :meth:`open` created this store in this process (a new, not a resumed, store).
    created: bool = False

    def discard_if_empty(self) -> bool:
        """Remove a store this process created if it holds no chunk and no failure record
        (a run that failed before any work: no manifest is left behind). Returns whether it did."""
        if not self.created or self.completed() or self.failures():
            return False
        import shutil

        shutil.rmtree(self.root, ignore_errors=True)
        return True

    def manifest(self) -> dict | None:
        """The stored manifest, or None for a new store."""
        path = self.root / "manifest.json"
        if not path.exists():
            return None
        return json.loads(path.read_text(encoding="utf-8"))

    @property
    def chunk_size(self) -> int:
        return int(self.manifest()["chunk_size"])

    # -- single writer ----------------------------------------------------------
    def lock(self) -> None:
        """Claim the store for this process; stale locks of dead processes are taken over."""
        path = self.root / "lock"
        host = socket.gethostname()
        if path.exists():
            try:
                info = json.loads(path.read_text())
            except (OSError, ValueError):
                info = {}
            pid = int(info.get("pid", -1))
            if info.get("host") == host and pid > 0 and pid != os.getpid() and pid_alive(pid):
                raise StoreBusyError(f"{self.root} is being written by process {pid}; wait for it or use "
                                     "another `store`")
        atomic_write_text(path, json.dumps({"pid": os.getpid(), "host": host}))
        self._locked = True
        for stale in self.chunk_dir.glob(".chunk-*"):  # temp files of an interrupted write
            stale.unlink(missing_ok=True)

    def unlock(self) -> None:
        if self._locked:
            (self.root / "lock").unlink(missing_ok=True)
            self._locked = False

    def __enter__(self):
        self.lock()
        return self

    def __exit__(self, *exc) -> None:
        self.unlock()

    # -- chunks -------------------------------------------------------------------
    def chunk_path(self, index: int) -> Path:
        return self.chunk_dir / (_CHUNK.format(index) + ".parquet")

    def completed(self) -> set[int]:
        """Indices of the chunks stored complete."""
        return {int(p.stem.split("-")[1]) for p in self.chunk_dir.glob("chunk-*.parquet")}

    def write_chunk(self, index: int, frame) -> Path:
        """Write a chunk's result table atomically and clear an earlier failure of it."""
        path = self.chunk_path(index)
        with atomic_path(path) as tmp:
            frame.to_parquet(tmp)
        (self.failed_dir / (_CHUNK.format(index) + ".json")).unlink(missing_ok=True)
        return path

    def chunk_paths(self) -> list[Path]:
        """Chunk files in chunk order."""
        return sorted(self.chunk_dir.glob("chunk-*.parquet"))

    def iter_chunks(self) -> Iterator:
        """Yield each stored chunk as a pandas DataFrame, in chunk order."""
        import pandas as pd

        for path in self.chunk_paths():
            yield pd.read_parquet(path)

    # -- failures -------------------------------------------------------------------
    def write_failure(self, index: int, record: dict[str, Any]) -> Path:
        """Record a chunk that raised (its items and the error) as JSON."""
        self.failed_dir.mkdir(parents=True, exist_ok=True)
        path = self.failed_dir / (_CHUNK.format(index) + ".json")
        atomic_write_text(path, json.dumps(dict(record, chunk=index), indent=2, default=repr))
        return path

    def failures(self) -> list[dict[str, Any]]:
        """Failure records of chunks that raised and have not completed since."""
        if not self.failed_dir.exists():
            return []
        done = self.completed()
        out = []
        for path in sorted(self.failed_dir.glob("chunk-*.json")):
            record = json.loads(path.read_text(encoding="utf-8"))
            if record.get("chunk") not in done:
                out.append(record)
        return out

    # -- parameter table ----------------------------------------------------------------
    def write_parameters(self, frame) -> None:
        path = self.root / "parameters.parquet"
        if not path.exists():
            with atomic_path(path) as tmp:
                frame.to_parquet(tmp)

    def __repr__(self) -> str:
        return f"SweepStore({str(self.root)!r})"
