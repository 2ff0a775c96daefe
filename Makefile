# radtree — two commands do everything on a fresh machine:
#   make demo   create .venv, install radtree, build + simulate + report the Mendoza example
#   make test   same install, then lint, type check, the whole test suite and the guide
#   make docs   the user guide → site/index.html
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
# two stamps: radtree and what it runs on (the demo and every radtree command need no more),
# then the extras of the tests, the guide and the cross-checks (`make test`, `make docs`).
# A fresh `make demo` installs the first only: ~1 min of pip instead of ~2.5 (2 cores).
BASE   := $(VENV)/.installed-base
STAMP  := $(VENV)/.installed
EXAMPLE := examples/mendoza-street
# engine of the demo's hourly runs and -ab convergence check: numpy (the built-in engine: the
# same numbers within their Monte Carlo error, ~2.5x faster here; the whole -ab ladder from one
# trace) or radiance / auto (rtrace on the build folders, one run per -ab).
# benchmarks/demo.py times every step.
DEMO_ENGINE ?= numpy

$(BASE): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet -e .
	touch $(BASE)

$(STAMP): $(BASE)
	$(BIN)/pip install --quiet -e ".[dev,sweep,honeybee,docs,crosscheck]"
	touch $(STAMP)

# radtree with every extra (tests, guide, Honeybee, dask sweeps, frads); `make demo` needs only $(BASE)
install: $(STAMP)

# The demo's steps as targets: after the build, the scenario runs (simulate, then the -ab
# check: both write results/) and the analyses (permeability scan, diagnosis, the photo check
# on the built crowns) are independent, so `make demo` runs the two chains side by side (-j2)
# and prints each step's output as one block when it ends (-O). $(RUN) prefixes every step (benchmarks/demo.py
# sets it to time them).
RUN ?=
DEMO_STEPS := demo-doctor demo-build demo-simulate demo-convergence demo-permeability \
              demo-diagnose demo-hemi demo-report

.PHONY: install demo $(DEMO_STEPS) test lint shape typecheck pytest docs bench clean

demo: $(BASE)
	@$(MAKE) --no-print-directory -j2 -O demo-report
	@echo ""
	@echo "Results: $(EXAMPLE)/results/illuminance.csv"
	@echo "Report:  $(EXAMPLE)/report/index.html"

demo-doctor: $(BASE)
	$(RUN) $(BIN)/radtree doctor
demo-build: demo-doctor
	$(RUN) $(BIN)/radtree build $(EXAMPLE)
demo-simulate: demo-build
	$(RUN) $(BIN)/radtree simulate $(EXAMPLE) --engine $(DEMO_ENGINE)
demo-convergence: demo-simulate
	$(RUN) $(BIN)/radtree convergence $(EXAMPLE) -s A -s C -s E -s F --engine $(DEMO_ENGINE)
demo-permeability: demo-build
	$(RUN) $(BIN)/radtree permeability $(EXAMPLE) -s A --rays 512
demo-diagnose: demo-permeability
	$(RUN) $(BIN)/radtree diagnose run $(EXAMPLE) -s A --rays 512
demo-hemi: demo-diagnose
	$(RUN) $(BIN)/radtree hemi check $(EXAMPLE)
demo-report: demo-convergence demo-hemi
	$(RUN) $(BIN)/radtree report $(EXAMPLE)

lint: $(STAMP)
	$(BIN)/ruff check radtree tests benchmarks docs
	$(BIN)/lint-imports

# the code's shape: the longest and widest functions (the ratchet of tests/test_layers.py)
shape: $(STAMP)
	$(BIN)/python -m tests.shape

typecheck: $(STAMP)
	$(BIN)/mypy radtree

pytest: $(STAMP)
	$(BIN)/python -m pytest -q -x -n 2 --dist worksteal --durations=15

test: lint typecheck pytest docs

# the user guide: reference pages checked against the code, then the site built into site/
# (offline: no fonts or scripts from the network); open site/index.html
docs: $(STAMP)
	$(BIN)/python docs/gen_reference.py --check
	NO_MKDOCS_2_WARNING=1 $(BIN)/mkdocs build --strict --quiet

bench: $(STAMP)
	for b in benchmarks/*.py; do $(BIN)/python $$b || exit 1; done

clean:
	rm -rf $(EXAMPLE)/build $(EXAMPLE)/results $(EXAMPLE)/report $(EXAMPLE)/diagnose
