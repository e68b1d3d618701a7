"""Hypothesis profiles of the suite: the same draws on every CI run, fresh draws locally.

* ``"ci"``: derandomized (each test's draws follow from the test itself, so every run of CI,
  on any machine, tries the same examples), no example database (nothing carried over from
  an earlier run), no deadline and no ``too_slow`` health check (a loaded 2-core runner is
  slow, not wrong), and a failure prints the blob that replays it (``@reproduce_failure``).
  It is Hypothesis's own built-in ``"ci"`` profile, stated here so that it does not change
  with a Hypothesis release and is selected by the rule below.
* ``"dev"``: Hypothesis's defaults, random draws as before, a failure's blob printed too.
* ``"nojit"``: the ``"ci"`` profile with at most :data:`NOJIT_MAX_EXAMPLES` examples per test,
  for runs with ``NUMBA_DISABLE_JIT=1`` (``make test-nojit``: the kernels run as plain Python,
  100 to 1000 times slower). Derandomized, so a no-JIT run tries the same few examples every
  time. The cap also applies to a test's own ``@settings(max_examples=...)``, which would
  otherwise win over a profile: ``tests/conftest.py`` lowers it with :func:`capped` at
  collection. Runs with the JIT keep each test's own count.

Both start from Hypothesis's ``"default"`` profile, not from whatever is loaded: Hypothesis
itself loads its ``"ci"`` profile at import when ``CI`` is set, and a ``"dev"`` profile built
on that would be derandomized too.

:func:`load` is called by ``tests/conftest.py`` before any test module is imported, so a
test's own ``@settings(...)`` starts from the loaded profile and overrides only what it names.
``NUMBA_DISABLE_JIT`` set to a non-zero integer (as Numba reads it) selects ``"nojit"``;
otherwise ``CI`` set to any non-empty value (``.ci/run`` exports ``CI=true``) selects ``"ci"``;
``HYPOTHESIS_PROFILE`` names a profile and wins over both. CI's draws are reproduced
locally with ``CI=1 make test`` or ``HYPOTHESIS_PROFILE=ci``.
"""

from __future__ import annotations

import os
from collections.abc import Mapping

from hypothesis import HealthCheck, settings

#: the profiles registered by :func:`register`
PROFILES = ("ci", "dev", "nojit")
#: the most examples a test draws under the ``"nojit"`` profile: enough to run each property
#: on a few drawn inputs besides its ``@example``\ s, few enough that the slowest (an albedo
#: per example, ``tests/models/test_coated_energy.py``) keeps to minutes in plain Python
NOJIT_MAX_EXAMPLES = 3


def register() -> None:
    """Register the ``"ci"``, ``"dev"`` and ``"nojit"`` profiles with Hypothesis (idempotent)."""
    base = settings.get_profile("default")
    settings.register_profile("ci", base, derandomize=True, database=None, deadline=None,
                              print_blob=True, suppress_health_check=[HealthCheck.too_slow])
    settings.register_profile("dev", base, print_blob=True)
    settings.register_profile("nojit", settings.get_profile("ci"),
                              max_examples=NOJIT_MAX_EXAMPLES)


def jit_disabled(environ: Mapping[str, str]) -> bool:
    """Whether ``environ`` disables Numba's JIT, read as Numba reads ``NUMBA_DISABLE_JIT``: an
    integer, true when non-zero; a value that is not an integer is ignored (Numba warns and
    keeps the JIT on)."""
    try:
        return int(environ.get("NUMBA_DISABLE_JIT", "0").strip() or "0") != 0
    except ValueError:
        return False


def capped(test: object, max_examples: int) -> bool:
    """Lower the example count of the Hypothesis test ``test`` to at most ``max_examples``,
    whatever its own ``@settings`` say; other settings are kept. Returns whether ``test`` is a
    Hypothesis test.

    A test's ``@settings(max_examples=...)`` wins over the loaded profile, and ``@settings``
    cannot be applied twice; Hypothesis reads the settings a ``@given`` test runs with from its
    ``_hypothesis_internal_use_settings`` attribute when it is called (hypothesis/core.py,
    unchanged since 2018), so that attribute is replaced. ``tests/test_hypothesis_profiles.py``
    checks that the cap takes effect, so a Hypothesis release that reads it elsewhere fails
    there rather than silently running every example.
    """
    if not getattr(test, "is_hypothesis_test", False):
        return False
    own = getattr(test, "_hypothesis_internal_use_settings", None) or settings.default
    if own.max_examples > max_examples:
        test._hypothesis_internal_use_settings = settings(  # type: ignore[attr-defined]
            own, max_examples=max_examples)
    return True


def select(environ: Mapping[str, str]) -> str:
    """The name of the profile an environment selects.

    Parameters
    ----------
    environ : Mapping[str, str]
        The environment (``os.environ``).

    Returns
    -------
    str
        ``HYPOTHESIS_PROFILE`` when it is set and non-empty; otherwise ``"nojit"`` when
        ``NUMBA_DISABLE_JIT`` disables the JIT (:func:`jit_disabled`), ``"ci"`` when ``CI`` is
        set and non-empty, ``"dev"`` when neither.

    Raises
    ------
    ValueError
        When ``HYPOTHESIS_PROFILE`` names no profile of :data:`PROFILES`.
    """
    name = environ.get("HYPOTHESIS_PROFILE", "").strip()
    if name:
        if name not in PROFILES:
            raise ValueError(f"HYPOTHESIS_PROFILE={name!r} names no profile of the suite "
                             f"(one of {', '.join(PROFILES)}; tests/hypothesis_profiles.py)")
        return name
    if jit_disabled(environ):
        return "nojit"
    return "ci" if environ.get("CI", "") else "dev"


def load(environ: Mapping[str, str] | None = None) -> str:
    """Register the profiles and load the one ``environ`` selects (:func:`select`).

    Parameters
    ----------
    environ : Mapping[str, str], optional
        The environment; ``os.environ`` when omitted.

    Returns
    -------
    str
        The name of the loaded profile.
    """
    register()
    name = select(os.environ if environ is None else environ)
    settings.load_profile(name)
    return name
