# maglevkit: every target sets itself up (creates .venv and installs the package) on first use.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
# test/lint/bench environment: the package with its test, distributed and FEM extras
STAMP  := $(VENV)/.installed-stamp
# demo: the package alone (same .venv; `make demo` does not install the extras)
DEMO_STAMP := $(VENV)/.demo-stamp
OUT    ?= out

.PHONY: demo test test-all lint bench mutation docs clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip

$(STAMP): $(BIN)/python pyproject.toml Makefile
	$(BIN)/python -m pip install --quiet -e ".[test,distributed,validation]"
	touch $(STAMP)

$(DEMO_STAMP): $(BIN)/python pyproject.toml Makefile
	$(BIN)/python -m pip install --quiet -e .
	touch $(DEMO_STAMP)

## demo: run the main job on the bundled default magnet (figures and report in ./out)
demo: $(DEMO_STAMP)
	$(BIN)/maglevkit demo --out $(OUT)

## test: lint (ruff), type-check (mypy), the layers contract (import-linter) and the default
## test suite (two workers, one per core;
## a test file stays on one worker, so its module fixtures are built once; files are handed
## out in collection order, the heaviest first: tests/conftest.py HEAVY_FILES)
test: $(STAMP) lint
	$(BIN)/python -m pytest -q -n 2 --dist loadfile --no-loadscope-reorder

## test-all: also the slow validation tests
test-all: $(STAMP) lint
	$(BIN)/python -m pytest -q -m "slow or not slow"

## lint: ruff, mypy and the layers contract (import-linter, pyproject.toml [tool.importlinter])
lint: $(STAMP)
	$(BIN)/ruff check src tests benchmarks
	$(BIN)/mypy src
	$(BIN)/lint-imports --no-cache

## mutation: deliberate small errors in the physics core, one at a time; reports which the tests catch
mutation: $(STAMP)
	$(BIN)/python tools/mutation.py

## docs: build the HTML documentation (user guide, API reference, example gallery) in docs/_build/html
DOCS_STAMP := $(VENV)/.docs-stamp
$(DOCS_STAMP): $(BIN)/python pyproject.toml Makefile
	$(BIN)/python -m pip install --quiet -e ".[docs]"
	touch $(DOCS_STAMP)

docs: $(DOCS_STAMP)
	MPLBACKEND=Agg $(BIN)/sphinx-build -q -b html docs docs/_build/html
	@echo "docs: open docs/_build/html/index.html"

## bench: run the benchmarks and rewrite BENCHMARKS.md
bench: $(STAMP)
	$(BIN)/python benchmarks/run.py --output BENCHMARKS.md

clean:
	rm -rf $(VENV) $(OUT) .pytest_cache .mypy_cache .ruff_cache docs/_build docs/api docs/gallery
