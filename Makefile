# Two entry points: `make repro` (set up, then run the DVC pipeline) and `make test` (set up, then lint and test).
# Both create the virtual environment on first use; nothing else needs installing by hand.
VENV ?= .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.hexpipe-installed

.PHONY: setup repro test bench clean-venv

$(STAMP): pyproject.toml tools/mcap-check/package-lock.json
	python3 -m venv $(VENV)
	$(BIN)/pip install --quiet --disable-pip-version-check -e ".[dev]"
	cd tools/mcap-check && npm ci --silent --no-audit --no-fund
	touch $(STAMP)

setup: $(STAMP)

repro: setup
	PATH="$(abspath $(BIN)):$$PATH" $(BIN)/dvc repro

test: setup
	$(BIN)/ruff check .
	$(BIN)/pytest

bench: setup
	$(BIN)/hexpipe bench

clean-venv:
	rm -rf $(VENV)
