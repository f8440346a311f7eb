# gaitopt — every target creates the virtual environment if it is missing.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: install gaits studies studies-check test test-slow bench lint clean

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[dev]'
	$(BIN)/python -m compileall -q gaitopt  # bytecode now: no process compiles the sources again
	$(BIN)/python -m gaitopt.kernels --warm  # compile the built-in models' kernels once
	touch $(STAMP)

install: $(STAMP)

gaits: $(STAMP)
	MPLBACKEND=Agg $(BIN)/python -m gaitopt.gaits --out results

test: $(STAMP)
	MPLBACKEND=Agg $(BIN)/python -m pytest -q -n auto -m "not slow"  # one worker per CPU (pytest-xdist)

test-slow: $(STAMP)  # the tests marked slow (>= 25 s each); CI runs them after `make test`
	MPLBACKEND=Agg $(BIN)/python -m pytest -q -n auto -m slow

studies: $(STAMP)
	@set -e; for script in problems/*.py; do \
	  [ -e "$$script" ] || { echo "no studies yet (problems/ is empty)"; break; }; \
	  echo "== $$script"; MPLBACKEND=Agg $(BIN)/python "$$script" --out results; \
	done

# Reproduce: run the studies (all, or STUDIES="a b") into a scratch folder and compare every number
# they write with the committed results/ (1e-8 relative; scripts/compare_results.py says what is exempt).
STUDIES ?= $(basename $(notdir $(wildcard problems/*.py)))
studies-check: $(STAMP)
	@set -e; fresh=$$(mktemp -d); for study in $(STUDIES); do \
	  echo "== $$study"; MPLBACKEND=Agg $(BIN)/python problems/$$study.py --out $$fresh; \
	done; $(BIN)/python scripts/compare_results.py $$fresh --results results

bench: $(STAMP)
	-$(BIN)/python -m pip install --quiet -e '.[peers]' || echo "Drake not installable here: benchmarking without peers"
	$(BIN)/python -m compileall -q gaitopt  # the sources may have changed since install: timed processes compile none
	MPLBACKEND=Agg $(BIN)/python -m bench --out results/bench.json

lint: $(STAMP)
	$(BIN)/ruff check gaitopt tests problems bench scripts
	$(BIN)/ruff format --check gaitopt tests problems bench scripts

clean:
	rm -rf $(VENV) build *.egg-info .pytest_cache .ruff_cache
	find . -name __pycache__ -type d -prune -exec rm -rf {} +
