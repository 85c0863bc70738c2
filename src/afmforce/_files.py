"""Atomic output: write to a temporary file in the target folder, then rename.

Inputs are never modified; an interrupted write never leaves a partial file
under the final name.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from pathlib import Path
from typing import Iterator

from .errors import FileFormatError, OutputExistsError, ParameterError

__all__ = ["pid_alive", "read_settings", "atomic_path", "atomic_write_bytes", "atomic_write_text", "check_writable", "display_path",
           "LISTENERS"]

def read_settings(path: str | os.PathLike, what: str) -> str:
    """The UTF-8 text of a small settings file (``what``: "a TOML sweep file"), read whole but never
    more than :data:`afmforce.limits.CONFIG_BYTES`: a larger file or a device that never ends
    (``/dev/zero``) is refused before it fills the memory.

    Raises
    ------
    FileFormatError
        Larger than the cap. (``OSError`` and ``UnicodeDecodeError`` as reading raises them.)
    """
    from .limits import CONFIG_BYTES

    with open(path, "rb") as fh:
        data = fh.read(CONFIG_BYTES + 1)
    if len(data) > CONFIG_BYTES:
        raise FileFormatError(f"{display_path(path)}: more than {CONFIG_BYTES:,} bytes, not {what} (such a file "
                              "holds a few kB); give the settings file itself")
    return data.decode("utf-8")


#: Callables ``f(path)`` told of every file written (in this process): the command line lists them.
LISTENERS: list = []


def display_path(path: str | os.PathLike) -> str:
    """``path`` (or any text quoting one: an error message) as text every writer takes (tables, Parquet, JSON, the terminal).

    A file name that is not UTF-8 (bytes from another system; Python keeps them
    as lone surrogates) shows its undecodable bytes as ``\\xNN``: ``curve-\\xff.ibw``.
    The file itself is still opened by its real name; only the text shown changes.
    """
    text = os.fspath(path)
    if isinstance(text, bytes):
        return text.decode("utf-8", "backslashreplace")
    try:
        return text.encode("utf-8", "surrogateescape").decode("utf-8", "backslashreplace")
    except UnicodeEncodeError:      # a surrogate no file system made: keep it visible, escaped
        return text.encode("utf-8", "backslashreplace").decode("utf-8")


def check_writable(path: str | os.PathLike, force: bool = True) -> Path:
    """Raise :class:`OutputExistsError` if ``path`` exists and ``force`` is false.

    Raises :class:`~afmforce.errors.ParameterError` for an empty name, a folder
    (even with ``force``: a folder is never replaced by a file) or anything else that is not a
    plain file (a device such as ``/dev/full``, a pipe, a socket): the atomic rename would
    replace that node by a file, not write into it.
    """
    if not str(path).strip():
        raise ParameterError("empty output file name; give a file name")
    path = Path(path)
    if path.is_dir():
        raise ParameterError(f"{path} is a folder; give a file name (a folder is never replaced by a file)")
    if path.exists() and not path.is_file():
        raise ParameterError(f"{path} is not a plain file (a device, pipe or socket); give a file name "
                             "(outputs are written to a new file and renamed, which would replace it)")
    if path.exists() and not force:
        raise OutputExistsError(f"{path} exists; choose another name or pass `force` to overwrite")
    return path


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike, force: bool = True) -> Iterator[Path]:
    """Yield a temporary path next to ``path``; rename it to ``path`` on success.

    Use it for writers that want a file name (h5py, matplotlib)::

        with atomic_path("out.h5") as tmp:
            write_hdf5(tmp)
    """
    path = check_writable(path, force)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=path.suffix or ".tmp", dir=path.parent)
    os.close(fd)
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp, 0o666 & ~umask)  # mkstemp creates 0600; give the file normal permissions
    tmp_path = Path(tmp)
    try:
        yield tmp_path
        os.replace(tmp_path, path)
        for listener in tuple(LISTENERS):
            listener(path)
    finally:
        if tmp_path.exists():
            tmp_path.unlink()


def atomic_write_bytes(path: str | os.PathLike, data: bytes, force: bool = True) -> Path:
    """Write ``data`` to ``path`` atomically."""
    with atomic_path(path, force) as tmp:
        tmp.write_bytes(data)
    return Path(path)


def atomic_write_text(path: str | os.PathLike, text: str, force: bool = True) -> Path:
    """Write UTF-8 ``text`` to ``path`` atomically (a file name in it that is not UTF-8 keeps its
    own bytes, as the file system has them)."""
    return atomic_write_bytes(path, text.encode("utf-8", "surrogateescape"), force)


def pid_alive(pid: int) -> bool:
    """Whether process ``pid`` of this machine still runs (a lock's or a store's writer). On Windows,
    where ``os.kill(pid, 0)`` would end the process, always True: the caller's lock age decides."""
    if os.name == "nt":
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True
