"""Shared fixtures. Tests that need the real measurements in ../shared/data skip without them.

* ``shared_data``: the folder ../shared/data (``ROUGHBRDF_SHARED_DATA`` overrides it);
* ``paints``: the three Mini-Diff paints of :data:`MINIDIFF_PAINTS`, read once per test module.

Hypothesis's profile is loaded here, before any test module is imported
(tests/hypothesis_profiles.py): derandomized when ``CI`` is set, random otherwise; with
``NUMBA_DISABLE_JIT=1`` (``make test-nojit``) derandomized and capped at a few examples per
test, a test's own ``max_examples`` included (:func:`pytest_collection_modifyitems`).
"""

from __future__ import annotations

import os
from pathlib import Path

import hypothesis_profiles
import matplotlib
import pytest
from hypothesis import settings

import roughbrdf as rb

matplotlib.use("Agg")  # figures are written to files; no display in CI
#: "ci" (derandomized: the same draws on every run) when CI is set, "dev" (random) otherwise;
#: HYPOTHESIS_PROFILE names one and wins
HYPOTHESIS_PROFILE = hypothesis_profiles.load()

ROOT = Path(__file__).resolve().parents[1]
SHARED_DATA = Path(os.environ.get("ROUGHBRDF_SHARED_DATA", ROOT.parent / "shared" / "data"))
#: the Mini-Diff paints (``minidiff/NAME.astm``) of the real-data tests: black, silver, olive drab
MINIDIFF_PAINTS = ("C2_Black", "C8_Silver", "C12_OliveDrab")


@pytest.fixture(scope="session")
def shared_data() -> Path:
    """Path of ../shared/data (real measurements); skips the test when it is absent."""
    if not SHARED_DATA.is_dir():
        pytest.skip(f"real measurement data not found at {SHARED_DATA} (the ../shared folder "
                    "beside the checkout); set ROUGHBRDF_SHARED_DATA to run these tests")
    return SHARED_DATA


@pytest.fixture(scope="module")
def paints(shared_data: Path) -> dict[str, rb.Measurement]:
    """``{name: Measurement}`` of the :data:`MINIDIFF_PAINTS`, read once per test module (a
    module's tests may keep what they read); skips without ../shared/data."""
    return {name: rb.read(shared_data / "minidiff" / f"{name}.astm") for name in MINIDIFF_PAINTS}


#: the doctests of ``src/`` too slow without the JIT (seconds in plain Python, one process,
#: 2026-12-07: 583 of the 820 s that all 272 doctests and README's took): marked
#: ``jit_heavy`` under ``NUMBA_DISABLE_JIT=1`` (:func:`pytest_collection_modifyitems`), so
#: ``make test-nojit`` deselects them; with the JIT they run in ``make test`` as any other
NOJIT_HEAVY_DOCTESTS: dict[str, str] = {
    "roughbrdf.fitting.choice.compare.compare": "fits every candidate (198 s)",
    "roughbrdf.export.rgl.to_rgl": "the tensor file's NDF and tables (116 s)",
    "roughbrdf.explore.notebook": "a fit and every figure of the explorer (103 s)",
    "roughbrdf.export.mitsuba.exporting.to_mitsuba": "tabulates a fitted model (65 s)",
    "roughbrdf.export.mitsuba.emulation.mitsuba_values": "tabulates a fitted model (54 s)",
    "roughbrdf.export.mitsuba.exporting.export_mitsuba": "tabulates a fitted model (47 s)",
}


@pytest.hookimpl(tryfirst=True)  # before -m deselects by mark
def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Under the ``"nojit"`` profile every Hypothesis test draws at most
    :data:`hypothesis_profiles.NOJIT_MAX_EXAMPLES` examples, its own ``@settings`` included
    (the kernels run as plain Python there; tests/hypothesis_profiles.py), and the doctests of
    :data:`NOJIT_HEAVY_DOCTESTS` are marked ``jit_heavy``. Other profiles leave every test's
    own count and marks as they are."""
    if HYPOTHESIS_PROFILE != "nojit":
        return
    cap = settings.get_profile("nojit").max_examples
    for item in items:
        why = NOJIT_HEAVY_DOCTESTS.get(item.name) if item.nodeid.startswith("src/") else None
        if why is not None:
            item.add_marker(pytest.mark.jit_heavy(reason=f"doctest, plain Python: {why}"))
        fn = getattr(item, "function", None)  # a doctest or a non-Python item has none
        if fn is not None:
            hypothesis_profiles.capped(fn, cap)


_LAST_TEST: list[str] = ["(none: inherited from the process that started pytest)"]


def pytest_runtest_setup(item: pytest.Item) -> None:
    """Every test starts with Python's own SIGINT handler, which the tests of Ctrl-C handling
    assume. A pytest started as a background job of a non-interactive shell (``cmd &`` in a
    script: POSIX shells start those with SIGINT ignored) inherits SIG_IGN, and five tests of
    Ctrl-C handling failed for it; a handler left changed between tests (a module-scoped
    fixture's teardown, which no test owns) would do the same. Either is put back, with a
    warning naming the test after which it was found."""
    import signal
    import warnings

    handler = signal.getsignal(signal.SIGINT)
    if handler is not signal.default_int_handler:
        signal.signal(signal.SIGINT, signal.default_int_handler)
        warnings.warn(f"the SIGINT handler was {handler!r} before {item.nodeid} (after "
                      f"{_LAST_TEST[0]}): put back", stacklevel=1)


def pytest_runtest_teardown(item: pytest.Item) -> None:
    _LAST_TEST[0] = item.nodeid


@pytest.fixture(autouse=True)
def _sigint_handler_kept():
    """Every test leaves the SIGINT handler as it found it; one that does not fails, and the
    handler is put back so that the tests after it (Ctrl-C handling, tests/core/test_output.py,
    tests/cli/test_cli_interrupts.py) are not failed by it."""
    import signal

    before = signal.getsignal(signal.SIGINT)
    yield
    after = signal.getsignal(signal.SIGINT)
    if after is not before:
        signal.signal(signal.SIGINT, before)
        pytest.fail(f"the test left the SIGINT handler changed ({after!r}; was {before!r})")
