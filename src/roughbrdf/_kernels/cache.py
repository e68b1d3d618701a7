"""On-disk cache of compiled kernels that notices edits of the parts they are built from.

Numba keys a cached function on its *own* source file only, so a model kernel cached before an
edit of ``geometry.py`` or ``fresnel.py`` would keep running the old parts (they are compiled
into it). For files of this package, the key installed here also covers every module outside
``models/`` that defines compiled parts; a model module's cache then follows the parts it uses.

This uses Numba's cache-locator extension point (``numba.core.caching.CacheImpl``), an internal
interface: ``pyproject.toml`` therefore bounds ``numba`` from above, and
:func:`locator_installed` lets the test suite check that the patch is in place. If the
interface ever changes, Numba's default locators apply (correct, but an edit of a part would
not invalidate the kernels built from it).
"""

from __future__ import annotations

import functools
import hashlib
import os

__all__ = ["install_cache_locators", "locator_installed", "part_files"]

#: the package root (``src/roughbrdf``): only functions defined below it use these locators
_PKG_DIR = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
_PART_MARKERS = ("@jit", "@ufunc", "@driver", "@njit", "@vectorize")
_PREFIX = "Roughbrdf"


@functools.lru_cache(maxsize=1)
def part_files() -> tuple[str, ...]:
    """The package's modules (outside ``models/``) that define compiled parts."""
    files = []
    for root, dirs, names in os.walk(_PKG_DIR):
        dirs[:] = [d for d in dirs if d not in ("models", "__pycache__")]
        for nm in sorted(names):
            if nm.endswith(".py"):
                path = os.path.join(root, nm)
                with open(path, encoding="utf-8") as fh:
                    if any(m in fh.read() for m in _PART_MARKERS):
                        files.append(path)
    return tuple(sorted(files))


@functools.lru_cache(maxsize=8)
def _hash_files(stats: tuple) -> str:
    h = hashlib.sha256()
    for path, *_ in stats:
        with open(path, "rb") as fh:
            h.update(path.encode() + b"\0" + fh.read())
    return h.hexdigest()


def _parts_stamp() -> str:
    stats = []
    for path in part_files():
        st = os.stat(path)
        stats.append((path, st.st_mtime_ns, st.st_size))
    return _hash_files(tuple(stats))


def _registry() -> list | None:
    try:
        from numba.core import caching

        return caching.CacheImpl._locator_classes
    except (ImportError, AttributeError):  # pragma: no cover - other Numba versions
        return None


def install_cache_locators() -> None:
    """Put this package's cache locators in front of Numba's own (idempotent)."""
    registry = _registry()
    if registry is None or locator_installed():  # pragma: no cover - other Numba versions
        return
    from numba.core import caching

    bases = [caching.UserProvidedCacheLocator, caching.InTreeCacheLocator,
             caching.UserWideCacheLocator]

    def make(base: type) -> type:
        class Locator(base):  # type: ignore[misc, valid-type]
            def get_source_stamp(self):
                return (super().get_source_stamp(), _parts_stamp())

            @classmethod
            def from_function(cls, py_func, py_file):
                if not os.path.abspath(py_file).startswith(_PKG_DIR + os.sep):
                    return None
                return super().from_function(py_func, py_file)

        Locator.__name__ = Locator.__qualname__ = _PREFIX + base.__name__
        return Locator

    registry[0:0] = [make(b) for b in bases]


def locator_installed() -> bool:
    """Whether Numba's locator registry starts with this package's locators."""
    registry = _registry()
    if not registry:
        return False
    return getattr(registry[0], "__name__", "").startswith(_PREFIX)
