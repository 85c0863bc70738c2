"""numba's cache of afmforce's kernels never runs old code (issue 35, item 4).

numba keys a ``cache=True`` function's cache on the content of *its own* source file. A kernel
that calls a compiled function of another file (``analysis._fringe_kernel.lm_fit`` and
``contact._adhesive_kernels.adhesive_lm`` call ``_linalg_small``'s solver; the integrator
inlines the vector field and the surface force laws) or reads a module-level constant of
another module holds that code in its cache too: edit only the other file and numba loads the
old code (tested: ``tests/cli/test_coldstart.py``). The locators here give every afmforce
kernel the source stamp ``(digest of its own file, digest of every source a kernel may
reach)``: any edit of any of them recompiles every afmforce kernel, once. The sources a kernel
may reach are those of the layers at or below the analysis (docs/architecture.md; the layers
above may not be imported by them, tested): the top-level modules and the packages of
:data:`KERNEL_SOURCES`.

:func:`install` puts the locators first in numba's list (this module imports no numba);
``afmforce/__init__.py`` calls it as soon as numba's caching module is imported, before any
kernel is decorated (an import hook: ``import afmforce`` still loads no numba). Functions
outside the afmforce package keep numba's own locators. Where the cache lives is numba's choice, as
before (``NUMBA_CACHE_DIR``, else ``__pycache__`` beside the source, else the user's cache).
"""

from __future__ import annotations

import hashlib
import os
from functools import lru_cache
from pathlib import Path

#: Packages of afmforce whose sources a kernel may reach (with the top-level modules).
KERNEL_SOURCES = ("analysis", "calibration", "contact", "dynamics", "instrument", "io",
                  "surface_laws")

PACKAGE = Path(__file__).resolve().parent

#: numba's locators that ours wrap, in numba's order (``numba.core.caching``)
_BASES = ("UserProvidedCacheLocator", "InTreeCacheLocator", "UserWideCacheLocator")
#: Our locators, made by :func:`install` (importing this module imports no numba)
LOCATORS: tuple = ()


def kernel_source_files(root: Path = PACKAGE) -> list[Path]:
    """The sources a kernel may reach: the top-level modules of ``root`` and every module of
    the packages :data:`KERNEL_SOURCES` (sorted)."""
    files = sorted(root.glob("*.py"))
    for name in KERNEL_SOURCES:
        files += sorted((root / name).rglob("*.py"))
    return files


def sources_digest(root: Path = PACKAGE) -> str:
    """Digest of :func:`kernel_source_files` (relative names and contents) [hex]."""
    h = hashlib.blake2b(digest_size=16)
    for f in kernel_source_files(root):
        h.update(f.relative_to(root).as_posix().encode())
        h.update(b"\0")
        h.update(f.read_bytes())
        h.update(b"\0")
    return h.hexdigest()


@lru_cache(maxsize=None)
def _digest_of(root: str) -> str:
    return sources_digest(Path(root))


def _package_root(py_file: str) -> Path | None:
    """The afmforce package folder that holds ``py_file`` (a copy of the package counts), or
    None for a file outside afmforce."""
    path = Path(os.path.abspath(py_file))
    for parent in path.parents:
        if parent.name == "afmforce" and (parent / "_jitcache.py").is_file():
            return parent
    return None


def _locator(base):
    class Locator(base):
        """numba's ``{base}`` for afmforce's kernels: the stamp also covers every source a
        kernel may reach."""

        def get_source_stamp(self):
            root = _package_root(self._py_file)
            own = super().get_source_stamp()
            return own if root is None else (own, _digest_of(str(root)))

        @classmethod
        def from_function(cls, py_func, py_file):
            if _package_root(py_file) is None:
                return None                     # not ours: numba's own locators
            return super().from_function(py_func, py_file)

    Locator.__name__ = Locator.__qualname__ = f"Afmforce{base.__name__}"
    Locator.__doc__ = Locator.__doc__.format(base=base.__name__)
    return Locator


def install() -> tuple:
    """Put the locators first in numba's list (once; imports numba). Returns them; ``()`` where
    this numba's caching module has another shape (its own locators then, as before)."""
    global LOCATORS
    from numba.core import caching

    try:
        if not LOCATORS:
            LOCATORS = tuple(_locator(getattr(caching, name)) for name in _BASES)
        classes = caching.CacheImpl._locator_classes
    except AttributeError:              # pragma: no cover - another numba
        return ()
    if classes[:len(LOCATORS)] != list(LOCATORS):
        classes[:0] = LOCATORS
    return LOCATORS
