# The two commands of the README, `make demo` and `make test`, and `make lint` (style and
# types), which CI runs as well.
# Each creates .venv from pyproject.toml when it is missing or older than pyproject.toml.

PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed
JOBS ?= 2
CHROMIUM := /usr/bin/chromium

.PHONY: demo test lint clean venv chromium

venv: $(STAMP)

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[dev]'
	touch $(STAMP)

# The main job: probe the cat with the simulated robot, recognise it, save a recording.
demo: $(STAMP)
	$(PY) scripts/probe.py --object cat

# The web viewer test renders a recording in headless Chromium (Debian's package; CI is
# Debian and runs as root).
chromium:
	@test -x $(CHROMIUM) || { \
		export DEBIAN_FRONTEND=noninteractive; \
		apt-get install -y chromium \
		|| { apt-get update && apt-get install -y chromium; }; }

test: $(STAMP) chromium
	$(PY) -m ruff check .
	$(PY) -m pytest -n $(JOBS)

lint: $(STAMP)
	$(PY) -m ruff check .
	$(PY) -m ruff format --check .
	$(PY) -m mypy

clean:
	rm -rf $(VENV) .pytest_cache .ruff_cache
