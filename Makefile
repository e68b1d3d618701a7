# Set-up contract: `make demo` and `make test` work on a fresh machine with only Python 3.11+.
# Each target creates .venv and installs what it needs by itself.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed-$(shell cat pyproject.toml | cksum | cut -d' ' -f1)

.PHONY: demo test bench lint clean venv browser

$(STAMP): pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q -e '.[test,explore]'
	rm -f $(VENV)/.installed-*
	touch $(STAMP)

venv: $(STAMP)

demo: $(STAMP)
	$(PY) -m roughbrdf.demo --out out --force

# Debian's Chromium and chromedriver for the browser tests (tests/test_catalogue_summary.py):
# installed quietly when missing and running as root with apt-get; nothing is downloaded by a
# test tool. Elsewhere those tests skip and say why.
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

# the suite (tests/), every docstring example in src/ and the README's examples (pyproject.toml)
test: $(STAMP) browser
	$(PY) -m pytest -q -p no:cacheprovider

# BENCH_ARGS: e.g. --skip-worker-memory (the slow worker-memory figure), or benchmark names
bench: $(STAMP)
	$(PY) benchmarks/run.py $(BENCH_ARGS)

lint: $(STAMP)
	$(PY) -m ruff check src tests benchmarks
	$(PY) -m mypy

clean:
	rm -rf out build *.egg-info src/*.egg-info
