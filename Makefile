# radtree — two commands do everything on a fresh machine:
#   make demo   create .venv, install radtree, build + simulate + report the Mendoza example
#   make test   same install, then lint, type check and the whole test suite
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
EXAMPLE := examples/mendoza-street
# engine of the demo's hourly runs and -ab convergence check: numpy (the built-in engine: the
# same numbers within their Monte Carlo error, ~2.5x faster here; the whole -ab ladder from one
# trace) or radiance / auto (rtrace on the build folders, one run per -ab).
# benchmarks/demo.py times every step.
DEMO_ENGINE ?= numpy

.PHONY: install demo test lint typecheck pytest bench clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet -e ".[dev,sweep,honeybee]"
	touch $(STAMP)

install: $(STAMP)

demo: $(STAMP)
	$(BIN)/radtree doctor
	$(BIN)/radtree build $(EXAMPLE)
	$(BIN)/radtree simulate $(EXAMPLE) --engine $(DEMO_ENGINE)
	$(BIN)/radtree simulate $(EXAMPLE) --convergence -s A -s C -s E -s F --engine $(DEMO_ENGINE)
	$(BIN)/radtree permeability $(EXAMPLE) -s A --rays 1024
	$(BIN)/radtree diagnose $(EXAMPLE) -s A
	$(BIN)/radtree hemi check $(EXAMPLE)
	$(BIN)/radtree report $(EXAMPLE)
	@echo ""
	@echo "Results: $(EXAMPLE)/results/illuminance.csv"
	@echo "Report:  $(EXAMPLE)/report/index.html"

lint: $(STAMP)
	$(BIN)/ruff check radtree tests benchmarks
	$(BIN)/lint-imports

typecheck: $(STAMP)
	$(BIN)/mypy radtree

pytest: $(STAMP)
	$(BIN)/python -m pytest -q -x -n 2 --durations=15

test: lint typecheck pytest

bench: $(STAMP)
	for b in benchmarks/*.py; do $(BIN)/python $$b || exit 1; done

clean:
	rm -rf $(EXAMPLE)/build $(EXAMPLE)/results $(EXAMPLE)/report $(EXAMPLE)/diagnose
