"""Exceptions raised by afmforce.

Every error afmforce raises on purpose derives from :class:`AfmforceError`
(itself an :class:`Exception`), so a caller can catch them all at once. Each
message says what is wrong and what to do about it.
"""

from __future__ import annotations

__all__ = [
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


class AfmforceError(Exception):
    """Base class of every error raised by afmforce."""


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
        self.keys = tuple(keys)
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
