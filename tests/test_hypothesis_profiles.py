"""The suite's Hypothesis profiles (tests/hypothesis_profiles.py): CI draws the same examples on
every run, a local run draws fresh ones."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import hypothesis_profiles
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

HERE = Path(__file__).resolve()
#: where :func:`test_draws_recorded` appends its draws; set only by the subprocess runs below
DRAWS_FILE = "ROUGHBRDF_TEST_DRAWS_FILE"


@pytest.mark.parametrize(("environ", "expected"), [
    ({}, "dev"),
    ({"CI": ""}, "dev"),
    ({"CI": "true"}, "ci"),
    ({"CI": "1"}, "ci"),
    ({"HYPOTHESIS_PROFILE": "ci"}, "ci"),
    ({"HYPOTHESIS_PROFILE": "dev", "CI": "true"}, "dev"),
    ({"HYPOTHESIS_PROFILE": "", "CI": "true"}, "ci"),
    ({"NUMBA_DISABLE_JIT": "1"}, "nojit"),
    ({"NUMBA_DISABLE_JIT": "1", "CI": "true"}, "nojit"),
    ({"NUMBA_DISABLE_JIT": " 2 "}, "nojit"),
    ({"NUMBA_DISABLE_JIT": "0", "CI": "true"}, "ci"),
    ({"NUMBA_DISABLE_JIT": ""}, "dev"),
    ({"NUMBA_DISABLE_JIT": "yes"}, "dev"),  # not an integer: Numba ignores it, the JIT runs
    ({"NUMBA_DISABLE_JIT": "1", "HYPOTHESIS_PROFILE": "dev"}, "dev"),
])
def test_the_environment_selects_the_profile(environ, expected):
    assert hypothesis_profiles.select(environ) == expected


def test_an_unknown_profile_is_refused_by_name():
    with pytest.raises(ValueError, match="HYPOTHESIS_PROFILE='nightly'"):
        hypothesis_profiles.select({"HYPOTHESIS_PROFILE": "nightly"})


def test_the_ci_profile_is_derandomized_and_the_dev_profile_is_not():
    ci, dev = settings.get_profile("ci"), settings.get_profile("dev")
    assert ci.derandomize and ci.database is None and ci.deadline is None and ci.print_blob
    assert not dev.derandomize and dev.print_blob and dev.database is not None


def test_the_nojit_profile_is_the_ci_profile_with_few_examples():
    ci, nojit = settings.get_profile("ci"), settings.get_profile("nojit")
    assert nojit.derandomize and nojit.database is None and nojit.deadline is None
    assert nojit.max_examples == hypothesis_profiles.NOJIT_MAX_EXAMPLES < ci.max_examples
    assert nojit.suppress_health_check == ci.suppress_health_check


def test_capped_lowers_a_tests_own_count_and_keeps_its_other_settings():
    @settings(max_examples=40, deadline=1000, derandomize=True)
    @given(st.integers())
    def many(x):
        pass

    @settings(max_examples=2)
    @given(st.integers())
    def few(x):
        pass

    assert hypothesis_profiles.capped(many, 3) and hypothesis_profiles.capped(few, 3)
    own = many._hypothesis_internal_use_settings
    assert own.max_examples == 3 and own.derandomize
    assert own.deadline is not None and own.deadline.total_seconds() == 1
    assert few._hypothesis_internal_use_settings.max_examples == 2  # never raised
    assert not hypothesis_profiles.capped(lambda: None, 3)  # not a Hypothesis test


def test_this_run_loaded_the_profile_its_environment_selects():
    # conftest.py loads it before the test modules are imported; the default settings (the
    # parent of every @settings(...) of the suite) are the loaded profile's
    expected = settings.get_profile(hypothesis_profiles.select(os.environ))
    assert settings.default.derandomize == expected.derandomize
    assert settings.default.database == expected.database


@settings(max_examples=5, deadline=None)  # a test's own settings keep the profile's randomness
@given(st.integers())
def test_draws_recorded(x):
    path = os.environ.get(DRAWS_FILE)
    if path:
        with open(path, "a") as f:
            f.write(f"{x}\n")


def _draws(tmp_path: Path, run: int, **env: str) -> list[str]:
    """The draws of :func:`test_draws_recorded` in a fresh pytest process with ``env`` added to
    an environment without ``CI``, ``HYPOTHESIS_PROFILE`` and ``NUMBA_DISABLE_JIT``."""
    out = tmp_path / f"draws{run}.txt"
    base = {k: v for k, v in os.environ.items()
            if k not in ("CI", "HYPOTHESIS_PROFILE", "NUMBA_DISABLE_JIT")}
    proc = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-p", "no:randomly",
         f"{HERE}::test_draws_recorded"],
        env={**base, **env, DRAWS_FILE: str(out)}, cwd=tmp_path, capture_output=True,
        text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    return out.read_text().split()


def test_ci_draws_the_same_examples_on_every_run_and_dev_does_not(tmp_path):
    ci = [_draws(tmp_path, 0, CI="true"), _draws(tmp_path, 1, HYPOTHESIS_PROFILE="ci")]
    dev = [_draws(tmp_path, 2), _draws(tmp_path, 3)]
    assert len(ci[0]) == 5 and ci[0] == ci[1]
    # 5 draws of an integer each from a random seed: two runs agree by chance with a
    # probability far below 1e-12
    assert len(dev[0]) == 5 and dev[0] != dev[1]


def test_a_nojit_run_draws_the_same_few_examples_whatever_the_test_asks(tmp_path):
    # test_draws_recorded asks for 5 examples; a run with NUMBA_DISABLE_JIT=1 (or the profile
    # named) draws NOJIT_MAX_EXAMPLES, the same ones every time: the cap of tests/conftest.py
    # reaches a test's own @settings (a Hypothesis release that reads the settings elsewhere
    # fails here)
    runs = [_draws(tmp_path, 0, NUMBA_DISABLE_JIT="1"),
            _draws(tmp_path, 1, HYPOTHESIS_PROFILE="nojit")]
    assert len(runs[0]) == hypothesis_profiles.NOJIT_MAX_EXAMPLES and runs[0] == runs[1]


def _documented(name: str) -> object:
    """The module, class or function a doctest's name names (the longest importable module,
    then attributes)."""
    import importlib

    parts = name.split(".")
    for cut in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:cut]))
        except ImportError:
            continue
        for attr in parts[cut:]:
            obj = getattr(obj, attr)
        return obj
    raise ImportError(name)


@pytest.mark.parametrize("name", sorted(__import__("conftest").NOJIT_HEAVY_DOCTESTS))
def test_each_doctest_marked_heavy_without_the_jit_exists(name):
    # a renamed function would leave its mark on nothing and its doctest back in test-nojit
    assert ">>>" in (_documented(name).__doc__ or ""), name


def test_a_nojit_run_deselects_the_heavy_doctests():
    # collected as make test-nojit selects (their modules only, and a test file so that
    # tests/conftest.py is loaded): the marked doctests are the deselected ones
    import inspect

    import conftest

    root = HERE.parents[1]
    files = sorted({str(Path(inspect.getfile(_documented(nm))).relative_to(root))
                    for nm in conftest.NOJIT_HEAVY_DOCTESTS})
    env = dict(os.environ, NUMBA_DISABLE_JIT="1")
    env.pop("HYPOTHESIS_PROFILE", None)
    res = subprocess.run([sys.executable, "-m", "pytest", "-p", "no:cacheprovider",
                          "--collect-only", "-q", "-m", "jit_heavy", *files,
                          "tests/test_suite_rules.py"],
                         cwd=root, env=env, capture_output=True, text=True, timeout=300)
    got = sorted(line.split("::")[-1] for line in res.stdout.splitlines()
                 if line.startswith("src/"))
    assert got == sorted(conftest.NOJIT_HEAVY_DOCTESTS), res.stdout[-2000:] + res.stderr[-2000:]
