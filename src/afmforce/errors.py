"""Exceptions raised by afmforce.

Every error afmforce raises on purpose derives from :class:`AfmforceError`
(itself an :class:`Exception`), so a caller can catch them all at once. Each
message says what is wrong and what to do about it.
"""

from __future__ import annotations

import re
from typing import Callable

__all__ = [
    "QUANTITY_KEY",
    "render_keys",
    "AfmforceError",
    "ParameterError",
    "UnitError",
    "SolverError",
    "FileFormatError",
    "MissingMetadataError",
    "AnalysisError",
    "MemoryLimitError",
    "OutputExistsError",
    "MissingDependencyError",
]


#: How a library message names a quantity the user can give: its key in backquotes
#: (``give `spring_constant```). Each face renders it its own way: the command line as its
#: flag (``--spring-constant``), the web as its form field; Python users read the key they
#: pass (``ProbeCalibration(spring_constant=...)``, ``meta_override={"spring_constant": ...}``).
QUANTITY_KEY = re.compile(r"`([A-Za-z_][A-Za-z0-9_.]*)`")


def render_keys(text: str, render: Callable[[str], str | None]) -> str:
    """``text`` with every `` `key` `` of :data:`QUANTITY_KEY` replaced by ``render(key)``
    (``None``: the key stays as written, without the backquotes)."""
    return QUANTITY_KEY.sub(lambda m: render(m.group(1)) or m.group(1), str(text))


class AfmforceError(Exception):
    """Base class of every error raised by afmforce.

    ``keys``: the quantities the message asks the user to give (its `` `key` `` marks,
    :data:`QUANTITY_KEY`), for a face to render as its own flags or fields
    (:func:`render_keys`).
    """

    @property
    def keys(self) -> tuple[str, ...]:
        """The quantity keys the message names (`` `key` ``), in order."""
        explicit = self.__dict__.get("_keys")
        if explicit:
            return explicit
        return tuple(dict.fromkeys(QUANTITY_KEY.findall(str(self))))


class ParameterError(AfmforceError, ValueError):
    """A physical or numerical parameter is out of its valid range."""


class UnitError(ParameterError):
    """A value with units could not be parsed or has the wrong dimension."""


class SolverError(AfmforceError, RuntimeError):
    """The dynamics solver failed or stopped before the end of the protocol."""


class FileFormatError(AfmforceError):
    """An input file is unreadable, truncated or not in the expected format."""


class MissingMetadataError(FileFormatError):
    """A file lacks metadata (spring constant, sensitivity, ...) that the user must give.

    ``keys`` lists the metadata keys and ``flags`` the command-line options that supply them.
    """

    def __init__(self, message: str, keys: tuple[str, ...] = (), flags: tuple[str, ...] = ()) -> None:
        super().__init__(message)
        self._keys = tuple(keys)
        self.flags = tuple(flags)


class AnalysisError(AfmforceError):
    """A force curve cannot be analysed (no contact region, flat curve, ...)."""


class OutputExistsError(AfmforceError, FileExistsError):
    """An output file exists already and overwriting was not requested."""


class MissingDependencyError(AfmforceError, ImportError):
    """An optional dependency needed for this feature is not installed."""


class MemoryLimitError(AfmforceError, MemoryError):
    """A computation would need more memory than the machine (or its limits) can give: raised
    from an estimate before it allocates, so the kernel does not have to stop it."""
