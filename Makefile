# mediated-transfer: `make help` lists the targets.
# PYTHON selects the interpreter (3.11, 3.12 or 3.13); EXTRAS what `make install` adds to the
# package: deep (torch and Stable-Baselines3: the DQN and SB3 learners) and test. `make test`
# always installs everything. Versions come from constraints.txt, the ones that produced the
# committed results (docs/install.md).
PYTHON      ?= python3
VENV        ?= .venv
EXTRAS      ?= deep,test
TORCH_INDEX ?=
SUPPORTED   := 3.11 3.12 3.13
SUPPORTED_TEXT := 3.11, 3.12 or 3.13
BIN         := $(VENV)/bin

comma := ,
# The interpreter's version, read once per make (empty when PYTHON cannot run).
PYVER := $(shell $(PYTHON) -c 'import sys; print("%d.%d" % sys.version_info[:2])' 2>/dev/null)
# One stamp per Python version and set of extras: another PYTHON or EXTRAS installs again.
STAMP      := $(VENV)/.installed-py$(PYVER)-$(subst $(comma),+,$(EXTRAS))
FULL_STAMP := $(VENV)/.installed-py$(PYVER)-deep+test

.DEFAULT_GOAL := help
.PHONY: help check-python install test test-no-torch bench carry-over

help: ## List the targets
	@grep -E '^[a-zA-Z0-9_-]+:.*?## ' $(MAKEFILE_LIST) | awk 'BEGIN {FS = ":.*?## "}; {printf "  %-18s %s\n", $$1, $$2}'

check-python: ## Stop at once unless PYTHON is a supported version (3.11, 3.12, 3.13)
	@case " $(SUPPORTED) " in \
		*" $(PYVER) "*) ;; \
		*) echo "mediated-transfer needs Python $(SUPPORTED_TEXT); $(PYTHON) is $(if $(PYVER),Python $(PYVER),not an interpreter that runs here); choose one with PYTHON=, e.g. make install PYTHON=python3.12" >&2; exit 1;; \
	esac

# Nothing is downloaded before the check. A $(VENV) of another Python version is made anew.
$(VENV)/.installed-py$(PYVER)-%: pyproject.toml constraints.txt | check-python
	@if [ -x $(BIN)/python ] && [ "$$($(BIN)/python -c 'import sys; print("%d.%d" % sys.version_info[:2])')" != "$(PYVER)" ]; then \
		echo "$(VENV) holds another Python version: making it anew for Python $(PYVER)"; rm -rf $(VENV); fi
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(if $(TORCH_INDEX),$(BIN)/pip install --quiet --no-deps -c constraints.txt torch --index-url $(TORCH_INDEX))
	$(BIN)/pip install --quiet -c constraints.txt -e '.[$(subst +,$(comma),$*)]'
	touch $@

install: $(STAMP) ## Create .venv and install the project (EXTRAS=deep,test; EXTRAS=test: no torch)

test: $(FULL_STAMP) ## Run the whole test suite (creates .venv with everything first)
	REQUIRE_DEEP=1 $(BIN)/python -m pytest -q -n auto --maxschedchunk=1

test-no-torch: $(STAMP) ## The suite without torch: its tests skip (PYTHON=, EXTRAS=test, VENV= of its own)
	$(BIN)/python -m pytest -q -n auto --maxschedchunk=1

bench: $(STAMP) ## Print speed ratios: environment, linear learners, DQN vs Stable-Baselines3, PPO's environments
	$(BIN)/python -m mediated_transfer.bench

# After a change of the code runs execute (docs/reliability.md#provenance-and-stale-results).
ACCEPT ?=
carry-over: $(STAMP) ## Carry results over changed code: each moved run kind's short run must reproduce its fingerprint (ACCEPT="why": a meant change)
	$(BIN)/python -m mediated_transfer.provenance.carry_over $(if $(ACCEPT),--accept "$(ACCEPT)") $(ARGS)

# --- experiments: sweeps, reports, tracking (README: "Reproducing Tables II-IV") ------------
SCALE       ?= paper
EXPERIMENTS ?= table2_rbf table3_fsr table4_dnn
ARGS        ?=
MLFLOW_PORT ?= 5000
MLFLOW_DB   ?= mlflow.db
.PHONY: reproduce-tables reports reproduction dqn-ablation mlflow-ui tune tune-snapshot refine table1 sensitivity curricula curricula-dqn slurm-check

# On SLURM (ARGS="hydra/launcher=slurm ..."), every table is queued first (wait=false), then
# each command again waits for its queued jobs: the tables share their time in the queue.
ON_SLURM := $(findstring hydra/launcher=slurm,$(ARGS))

reproduce-tables: $(STAMP) ## Run the Tables II-IV sweeps at SCALE=paper|quick|smoke (resumable), then build reports/; EXPERIMENTS=table5_ppo: Table V and its answer
ifneq ($(ON_SLURM),)
	@for experiment in $(EXPERIMENTS); do \
		$(BIN)/python -m mediated_transfer experiment=$$experiment scale=$(SCALE) $(ARGS) hydra.launcher.wait=false || exit 1; \
	done
endif
	@for experiment in $(EXPERIMENTS); do \
		$(BIN)/python -m mediated_transfer experiment=$$experiment scale=$(SCALE) $(ARGS) || exit 1; \
	done
	$(BIN)/python -m mediated_transfer.reporting scale=$(SCALE) $(ARGS)
	$(if $(filter paper,$(SCALE)),$(BIN)/python -m mediated_transfer.reporting.reproduction)
	$(if $(filter table5_ppo,$(EXPERIMENTS)),$(BIN)/python -m mediated_transfer.reporting.transfer_answer --scale $(SCALE))

slurm-check: $(STAMP) ## Opt-in, not CI: the SLURM preset on a throwaway single-node SLURM (Debian's packages; root)
	PYTHON=$(BIN)/python bash scripts/slurm_check.sh

reports: $(STAMP) ## Build reports/ (tables, figures, MLflow summaries) from the finished runs at SCALE
	$(BIN)/python -m mediated_transfer.reporting scale=$(SCALE) $(ARGS)

reproduction: $(STAMP) ## Build reports/REPRODUCTION.md: a verdict on each of the paper's six claims, from the paper-scale runs
	$(BIN)/python -m mediated_transfer.reporting.reproduction

dqn-ablation: $(STAMP) ## The pre-registered DQN failure ablation (80 paper-scale runs, resumable), then reports/dqn_failure_ablation.md
	$(BIN)/python -m mediated_transfer experiment=dqn_failure_ablation $(ARGS)
	$(BIN)/python -m mediated_transfer.reporting.ablation

mlflow-ui: $(STAMP) ## Browse the runs in MLflow's UI, served on 127.0.0.1 only (MLFLOW_PORT=5000)
	@echo "Each table's training runs (MLflow 3 opens an experiment on its GenAI overview instead):"
	@$(BIN)/python -m mediated_transfer.sweep.tracking sqlite:///$(MLFLOW_DB) http://127.0.0.1:$(MLFLOW_PORT)
	$(BIN)/mlflow ui --backend-store-uri sqlite:///$(MLFLOW_DB) --host 127.0.0.1 --port $(MLFLOW_PORT)

# --- tuning: Table I (README: "Tuning") --------------------------------------------------------
LEARNER ?= rbf
WORKERS ?= 1
TRIALS  ?=

tune: $(STAMP) ## Random search of LEARNER=rbf|fsr|dqn|ppo (resumable; WORKERS=1, SCALE=paper|quick|smoke, TRIALS=)
	$(BIN)/python -m mediated_transfer.tuning $(LEARNER) --workers $(WORKERS) --scale $(SCALE) $(if $(TRIALS),--trials $(TRIALS)) $(ARGS)

SNAPSHOT := .cache/tune-snapshot/$(LEARNER)
tune-snapshot: $(STAMP) ## Stage for git a consistent copy of LEARNER's (running) paper-scale study.db and its trials.csv
	$(BIN)/python -m mediated_transfer.tuning.export $(LEARNER) --snapshot $(SNAPSHOT)
	@# Staged from the copy: the live files may change while a worker writes them.
	git update-index --add --cacheinfo 100644,$$(git hash-object -w $(SNAPSHOT)/study.db),tuning/$(LEARNER)/study.db
	git update-index --add --cacheinfo 100644,$$(git hash-object -w $(SNAPSHOT)/trials.csv),tuning/$(LEARNER)/trials.csv

refine: $(STAMP) ## Manual refinement of LEARNER=rbf|fsr|dqn|ppo: named candidates on more tuning seeds (resumable; WORKERS=1)
	$(BIN)/python -m mediated_transfer.tuning.refine $(LEARNER) --workers $(WORKERS) $(ARGS)

table1: $(STAMP) ## Build reports/table1.md and its figures from the committed tuning/*/trials.csv
	$(BIN)/python -m mediated_transfer.tuning.table1 $(ARGS)

sensitivity: $(STAMP) ## Issue 13's pre-registered sensitivity study at SCALE (resumable sweep), then reports/SENSITIVITY.md
	$(BIN)/python -m mediated_transfer experiment=sensitivity scale=$(SCALE) $(ARGS)
	$(BIN)/python -m mediated_transfer.sensitivity scale=$(SCALE) $(ARGS)

# The curricula are a plugin package (src/auto_curricula) on the config search path, as a user's.
CURRICULA_PATH := 'hydra.searchpath=[pkg://auto_curricula.conf]'

curricula: $(STAMP) ## Issue 42's pre-registered curricula study at SCALE: the linear sweep (resumable), then reports/CURRICULA.md
	$(BIN)/python -m mediated_transfer experiment=curricula2 $(CURRICULA_PATH) scale=$(SCALE) $(ARGS)
	$(BIN)/python -m mediated_transfer.curricula scale=$(SCALE) $(CURRICULA_PATH) $(ARGS)

curricula-dqn: $(STAMP) ## The study's DQN arms (the registered rule picks two curricula from the linear runs), then the report
	cells=$$($(BIN)/python -m mediated_transfer.curricula --dqn-cells scale=$(SCALE) $(CURRICULA_PATH) $(ARGS)) && \
	$(BIN)/python -m mediated_transfer experiment=curricula2_dqn $(CURRICULA_PATH) scale=$(SCALE) \
		cell=$$cells $(ARGS)
	$(BIN)/python -m mediated_transfer.curricula scale=$(SCALE) $(CURRICULA_PATH) $(ARGS)
