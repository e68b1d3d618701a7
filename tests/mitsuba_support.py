"""Mitsuba 3 in the tests: one variant for a block of code, the one before it restored.

Mitsuba's variant is process-wide state: a test that sets one and leaves it would change the
next test's Mitsuba (``tests/export/test_export_rgl.py``, ``test_export_rgl_render.py`` and
``tests/core/test_mueller.py`` use different variants in the same worker).
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any


@contextmanager
def mitsuba_variant(mi: Any, name: str) -> Iterator[None]:
    """Mitsuba's variant ``name`` inside the block; the variant before it (if any) after."""
    before = mi.variant()
    mi.set_variant(name)
    try:
        yield
    finally:
        if before is not None:
            mi.set_variant(before)
