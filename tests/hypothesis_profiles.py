"""Hypothesis profiles of the suite: the same draws on every CI run, fresh draws locally.

* ``"ci"``: derandomized (each test's draws follow from the test itself, so every run of CI,
  on any machine, tries the same examples), no example database (nothing carried over from
  an earlier run), no deadline and no ``too_slow`` health check (a loaded 2-core runner is
  slow, not wrong), and a failure prints the blob that replays it (``@reproduce_failure``).
  It is Hypothesis's own built-in ``"ci"`` profile, stated here so that it does not change
  with a Hypothesis release and is selected by the rule below.
* ``"dev"``: Hypothesis's defaults, random draws as before, a failure's blob printed too.

Both start from Hypothesis's ``"default"`` profile, not from whatever is loaded: Hypothesis
itself loads its ``"ci"`` profile at import when ``CI`` is set, and a ``"dev"`` profile built
on that would be derandomized too.

:func:`load` is called by ``tests/conftest.py`` before any test module is imported, so a
test's own ``@settings(...)`` starts from the loaded profile and overrides only what it names.
``CI`` set to any non-empty value (``.ci/run`` exports ``CI=true``) selects ``"ci"``;
``HYPOTHESIS_PROFILE`` names a profile and wins over ``CI``. CI's draws are reproduced
locally with ``CI=1 make test`` or ``HYPOTHESIS_PROFILE=ci``.
"""

from __future__ import annotations

import os
from collections.abc import Mapping

from hypothesis import HealthCheck, settings

#: the profiles registered by :func:`register`
PROFILES = ("ci", "dev")


def register() -> None:
    """Register the ``"ci"`` and ``"dev"`` profiles with Hypothesis (idempotent)."""
    base = settings.get_profile("default")
    settings.register_profile("ci", base, derandomize=True, database=None, deadline=None,
                              print_blob=True, suppress_health_check=[HealthCheck.too_slow])
    settings.register_profile("dev", base, print_blob=True)


def select(environ: Mapping[str, str]) -> str:
    """The name of the profile an environment selects.

    Parameters
    ----------
    environ : Mapping[str, str]
        The environment (``os.environ``).

    Returns
    -------
    str
        ``HYPOTHESIS_PROFILE`` when it is set and non-empty; otherwise ``"ci"`` when ``CI``
        is set and non-empty, ``"dev"`` when it is not.

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
