# Set-up contract: `make demo` and `make test` work on a fresh machine with only Python 3.11+.
# Each target creates .venv and installs what it needs by itself.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed-$(shell cat pyproject.toml | cksum | cut -d' ' -f1)

.PHONY: demo test test-avx2 test-nojit bench lint clean venv browser

$(STAMP): pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q -e '.[test,explore]'
	rm -f $(VENV)/.installed-*
	touch $(STAMP)

venv: $(STAMP)

demo: $(STAMP)
	$(PY) -m roughbrdf.demo --out out --force

# Debian's Chromium and chromedriver for the browser tests
# (tests/catalogue/test_catalogue_summary.py): installed quietly when missing and running as root
# with apt-get; nothing is downloaded by a test tool. Elsewhere those tests skip and say why.
browser:
	@if [ ! -x /usr/bin/chromium ] || [ ! -x /usr/bin/chromedriver ]; then \
	  if [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then \
	    echo "installing Debian's chromium and chromium-driver (browser tests)"; \
	    export DEBIAN_FRONTEND=noninteractive; \
	    apt-get install -y -qq chromium chromium-driver >/dev/null 2>&1 \
	    || { apt-get update -qq >/dev/null 2>&1 \
	         && apt-get install -y -qq chromium chromium-driver >/dev/null 2>&1; } \
	    || echo "could not install chromium and chromium-driver: the browser tests will skip"; \
	  else \
	    echo "no /usr/bin/chromium or /usr/bin/chromedriver (not root): the browser tests will skip"; \
	  fi; \
	fi

# the suite (tests/), every docstring example in src/ and the README's examples (pyproject.toml),
# in TEST_JOBS processes (pytest-xdist; one per core by default, TEST_JOBS=0 for one process:
# the order of a plain run, e.g. to debug); --dist loadfile keeps a test file's tests (and its
# module fixtures: the fits it shares) in one process; the 15 slowest tests are listed (the
# suite keeps within 15 minutes on a 2-core CI machine)
TEST_JOBS ?= auto
test: $(STAMP) browser
	$(PY) -m pytest -q -p no:cacheprovider -n $(TEST_JOBS) --dist loadfile --durations=15

# The tests whose outcome could hang on the kernels' rounding (every fit of the shared paints and
# the solvers), run again with the kernels compiled for an AVX2 processor without AVX-512 and
# OpenBLAS's Haswell kernels, as on such a machine (docs/fitting.md, "The same answer on every
# machine"). NUMBA_CPU_FEATURES is set empty on purpose: numba otherwise keeps the host's
# features (AVX-512) under NUMBA_CPU_NAME=haswell. A machine's own OPENBLAS_CORETYPE stands.
ROUNDING_TESTS := tests/fitting/test_auto_energy.py tests/fitting/test_energy_constraint.py \
	tests/fitting/test_fitting_real.py tests/fitting/test_constrained.py \
	tests/fitting/test_bounded.py tests/fitting/test_fitting.py tests/fitting/test_compare.py \
	tests/fitting/test_fit_limits.py tests/fitting/test_fit_energy.py \
	tests/fitting/test_fit_scale_hold.py tests/fitting/test_same_answer.py \
	tests/fitting/test_auto_stages.py
# On a processor without AVX-512 the suite has just run with that processor's own AVX2 (or
# narrower) kernels: the pass is not repeated (and haswell code could not run on a processor
# without AVX2); it says so.
test-avx2: $(STAMP)
	@if grep -qw avx512f /proc/cpuinfo 2>/dev/null; then \
	  set -x; NUMBA_CPU_NAME=haswell NUMBA_CPU_FEATURES= \
	  OPENBLAS_CORETYPE=$${OPENBLAS_CORETYPE:-Haswell} \
	  $(PY) -m pytest -q -p no:cacheprovider -n $(TEST_JOBS) --dist loadfile $(ROUNDING_TESTS); \
	else \
	  echo "test-avx2: this processor has no AVX-512: 'make test' ran these tests with its own" \
	       "AVX2 (or narrower) kernels; not repeated"; \
	fi

# The suite with Numba's JIT off: every kernel runs as plain Python (the debugging and coverage
# mode the project keeps working). Hypothesis draws a few derandomized examples per test there
# (the "nojit" profile, tests/hypothesis_profiles.py) and the tests marked jit_heavy (whole fits
# of the measured paints, big catalogues, browser tests that fit: each mark gives its reason)
# are deselected; a test over 5 min fails (mark it, with its reason). One process: slow (tens
# of minutes), not part of `make test`.
test-nojit: $(STAMP)
	NUMBA_DISABLE_JIT=1 $(PY) -m pytest -q -p no:cacheprovider -m "not jit_heavy" --timeout=300 --durations=15

# BENCH_ARGS: e.g. --skip-worker-memory (the slow worker-memory figure), or benchmark names
bench: $(STAMP)
	$(PY) benchmarks/run.py $(BENCH_ARGS)

lint: $(STAMP)
	$(PY) -m ruff check src tests benchmarks
	$(PY) -m mypy

clean:
	rm -rf out build *.egg-info src/*.egg-info
