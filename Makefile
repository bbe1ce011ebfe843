# The two commands of the README's quick start: `make demo` and `make test`.
# Each one installs what it needs first (system pieces, .venv, the package), idempotently.
PYTHON ?= python3.11
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
SYSSTAMP := .venv-system.stamp
SEED ?= 0

.PHONY: demo test setup system browser lint bench clean

setup: $(STAMP)

system: $(SYSSTAMP)

$(SYSSTAMP): tools/setup_system.sh
	bash tools/setup_system.sh
	@touch $@

$(STAMP): pyproject.toml $(SYSSTAMP)
	@command -v $(PYTHON) >/dev/null 2>&1 || { echo "setup: $(PYTHON) not found; set PYTHON=/path/to/python3.11" >&2; exit 1; }
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip
	$(BIN)/python -m pip install -q -e '.[dev]'
	@touch $@

# Chromium, the Foxglove Studio web build and puppeteer-core for the browser tests (into .cache/browser/)
browser:
	bash tools/setup_browser.sh

demo: setup
	$(BIN)/bt-grasp demo --seed $(SEED)

test: setup browser
	$(BIN)/ruff check bt_grasp tests tools
	$(BIN)/mypy
	$(BIN)/python -m pytest -q -n 2 -m "not serial" --durations=15
	$(BIN)/python -m pytest -q -m serial

lint: setup
	$(BIN)/ruff check bt_grasp tests tools
	$(BIN)/mypy

bench: setup
	$(BIN)/bt-grasp bench plan
	$(BIN)/bt-grasp bench perception

clean:
	rm -rf $(VENV) $(SYSSTAMP) out
