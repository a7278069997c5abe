# Two commands: `make run` processes raw/ with Snakemake, `make test` runs the suite.
# Both first build .venv from pyproject.toml (re-done only when pyproject.toml changes).
# The interpreter is the first of python3.13, python3.12, python3.11, python3 that is
# Python >= 3.11; override with `make PYTHON=/path/to/python3 run`.
PYTHON ?= $(shell for p in python3.13 python3.12 python3.11 python3; do \
	command -v $$p >/dev/null 2>&1 && $$p -c 'import sys; sys.exit(sys.version_info < (3, 11))' 2>/dev/null \
	&& { echo $$p; break; }; done)
VENV := .venv
BIN := $(VENV)/bin
CORES ?= 2

.PHONY: run test docs bench mutation clean-results setup check-python

setup: $(VENV)/.installed

check-python:
	@test -n "$(PYTHON)" || { echo "ballimpact needs Python >= 3.11: none of python3.13, python3.12, python3.11, python3 on PATH is new enough (install one, or give PYTHON=/path/to/python3)"; exit 1; }

$(VENV)/.installed: pyproject.toml | check-python
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[test]'
	touch $@

run: setup
	$(BIN)/snakemake --cores $(CORES)

# the suite in TEST_WORKERS processes (pytest-xdist; its time: docs/development.md). The fixtures that run a whole
# workflow (the demo run, mixed_run, the reruns' run) are built once per test run, not once per worker
# (tests/shared_fixture.py).
TEST_WORKERS ?= 2

test: setup
	$(BIN)/python -m pytest -q -n $(TEST_WORKERS)

# The documentation site into site/ (not committed), strict: a warning (broken link, missing
# page, unresolved API reference) fails the build. The figures are made from the demo
# session by docs/gen_figures.py, called by docs/hooks.py when they are missing or stale.
$(VENV)/.docs-installed: $(VENV)/.installed
	$(BIN)/python -m pip install --quiet -e '.[test,docs]'
	touch $@

docs: $(VENV)/.docs-installed
	NO_MKDOCS_2_WARNING=1 $(BIN)/python -m mkdocs build --strict --site-dir site

bench: setup
	$(BIN)/python bench/run.py

# Mutation testing of the physics modules (model, gates, calibration, the signal subpackage
# and the core functions of fitting, listed by `bench/mutation_score.py --selection`) against
# their own fast tests (mutmut 3, config in pyproject.toml [tool.mutmut]); not part of
# `make test` or CI. By default a seeded random sample of MUTATION_SAMPLE mutants per module
# (score with a 95 % interval); MUTATION_SAMPLE=all runs the whole selection (hours on 2
# cores). Budget and measured time: docs/mutation-testing.md.
MUTATION_SAMPLE ?= 150
MUTATION_SEED ?= 0
mutation: setup
	$(BIN)/python -m pip install --quiet -e '.[test,mutation]'
	rm -rf mutants
	$(BIN)/python bench/mutation_score.py --generate
	if [ "$(MUTATION_SAMPLE)" = all ]; then \
	  $(BIN)/python bench/mutation_score.py --selection | xargs -d '\n' $(BIN)/mutmut run --max-children $(CORES) \
	  && $(BIN)/python bench/mutation_score.py; \
	else \
	  $(BIN)/python bench/mutation_score.py --sample $(MUTATION_SAMPLE) --seed $(MUTATION_SEED) --names \
	    | xargs -d '\n' $(BIN)/mutmut run --max-children $(CORES) \
	  && $(BIN)/python bench/mutation_score.py --sample $(MUTATION_SAMPLE) --seed $(MUTATION_SEED); \
	fi

clean-results:
	find results -mindepth 1 ! -name .gitkeep -exec rm -rf {} +
