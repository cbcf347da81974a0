# gaitpref: `make demo` and `make test` are all a new machine needs.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
RUNTIME_STAMP := $(VENV)/.runtime-installed
DEV_STAMP     := $(VENV)/.dev-installed
DEMO_OUT ?= out/demo

.PHONY: demo test lint typecheck pytest bench system-deps clean venv

$(VENV)/bin/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install -qq --upgrade pip

# the runtime and the operator console (the `console` extra): what `make demo` and its hints use
$(RUNTIME_STAMP): pyproject.toml | $(VENV)/bin/python
	$(BIN)/pip install -qq -e '.[console]'
	touch $@

# the test tools; `dev` includes the `console` extra
$(DEV_STAMP): pyproject.toml | $(VENV)/bin/python
	$(BIN)/pip install -qq -e '.[dev]'
	touch $@ $(RUNTIME_STAMP)

venv: $(DEV_STAMP)

## demo: a full simulated experiment end to end (SQLite), with figures under $(DEMO_OUT)
demo: $(RUNTIME_STAMP)
	$(BIN)/gaitpref demo --out $(DEMO_OUT)

## test: lint, type-check and the whole test suite (installs PostgreSQL and Chromium as root)
test: $(DEV_STAMP) system-deps lint typecheck pytest docs

system-deps:
	bash .ci/system-deps

lint: $(DEV_STAMP)
	$(BIN)/ruff check src tests benchmarks
	$(BIN)/ruff format --check src tests benchmarks

typecheck: $(DEV_STAMP)
	$(BIN)/mypy

pytest: $(DEV_STAMP)
	$(BIN)/python -m pytest

## docs: the documentation site, built offline into site/ (strict: a broken link or reference fails)
.PHONY: docs
docs: $(DEV_STAMP)
	$(BIN)/mkdocs build --strict --site-dir site

## bench: speed benchmarks; results go to benchmarks/results/
bench: $(RUNTIME_STAMP)
	$(BIN)/python benchmarks/run_all.py

clean:
	rm -rf $(VENV) out .pytest_cache .mypy_cache .ruff_cache .hypothesis
