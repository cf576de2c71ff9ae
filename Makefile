# mediated-transfer: `make help` lists the targets.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed-test
BENCH_STAMP := $(VENV)/.installed-bench

.DEFAULT_GOAL := help
.PHONY: help install test bench

help: ## List the targets
	@grep -E '^[a-zA-Z_-]+:.*?## ' $(MAKEFILE_LIST) | awk 'BEGIN {FS = ":.*?## "}; {printf "  %-18s %s\n", $$1, $$2}'

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	# torch first and pinned: 2.13.0 is a local CPU wheel; anything else downloads CUDA.
	$(BIN)/pip install --quiet torch==2.13.0
	$(BIN)/pip install --quiet -e '.[test]' torch==2.13.0
	touch $@

$(BENCH_STAMP): $(STAMP)
	$(BIN)/pip install --quiet -e '.[test,bench]' torch==2.13.0
	touch $@

install: $(STAMP) ## Create .venv and install the project with its test extras

test: $(STAMP) ## Run the test suite (creates the environment first)
	$(BIN)/python -m pytest -q

bench: $(BENCH_STAMP) ## Print speed ratios: environment, linear learners, DQN vs Stable-Baselines3
	$(BIN)/python -m mediated_transfer.bench
