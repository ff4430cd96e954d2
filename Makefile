# Every target creates or reuses the virtual environment in $(VENV).
PYTHON ?= python3
VENV ?= .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed-stamp
RESULTS ?= results
## Where pip gets torch 2.13.0: TORCH_INDEX_URL when set; otherwise a wheel pip already
## finds without any index (a machine with a local wheel, e.g. pip's find-links), else
## PyTorch's CPU wheel index, so that an ordinary Linux machine gets the CPU build, not the
## default index's CUDA build (GBs of GPU libraries). It applies when $(VENV) is created or
## pyproject.toml changes: a venv already installed keeps its torch (remove it first).
TORCH_INDEX_URL ?=
TORCH_CPU_INDEX := https://download.pytorch.org/whl/cpu
# $(call install_torch,<pip>): install torch==2.13.0 with <pip> by the rule above
install_torch = if [ -n "$(strip $(TORCH_INDEX_URL))" ]; then \
	  $(1) install --disable-pip-version-check -q torch==2.13.0 --index-url $(strip $(TORCH_INDEX_URL)); \
	elif $(1) install --disable-pip-version-check -q --dry-run --no-index --no-deps torch==2.13.0 >/dev/null 2>&1; then \
	  $(1) install --disable-pip-version-check -q torch==2.13.0; \
	else \
	  $(1) install --disable-pip-version-check -q torch==2.13.0 --index-url $(TORCH_CPU_INDEX); \
	fi

.PHONY: install benchmark demo test test-slow test-all lint format bench figures reproduce clean \
	check-install train-agent-v2

$(STAMP): pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	# torch first (install_torch): installed later, as a dependency of stable-baselines3,
	# it would come from the default index.
	$(call install_torch,$(PY) -m pip)
	$(PY) -m pip install --disable-pip-version-check -q -e ".[dev,ray]"
	touch $(STAMP)
	@echo "installed; the first run compiles the numba kernels once (1-2 min, announced)"

install: $(STAMP)

## Main job: every maintenance policy on the same 40 episodes of 2000 flight slots of
## ScasMaintenance-v2 (2 workers); prints the table, writes CSV/JSON/Markdown and plots.
## An earlier run's folder is kept unless OVERWRITE=1.
benchmark: install
	@if [ -z "$(filter 1,$(OVERWRITE))" ] && [ -n "$$(ls -A $(RESULTS)/benchmark 2>/dev/null)" ]; then \
	  echo "$(RESULTS)/benchmark holds an earlier run: 'make benchmark OVERWRITE=1' replaces it" >&2; \
	  exit 2; \
	fi
	$(VENV)/bin/scas-benchmark --out $(RESULTS)/benchmark $(if $(filter 1,$(OVERWRITE)),--overwrite)

## Physics demonstration: a pre-flight test and a flight window at three health states
## (signals as CSV, plots) and the paper's physics figures (experiments/, not installed);
## a second run needs OVERWRITE=1 (as demo, figures and reproduce below).
demo: install
	$(PY) -m experiments.paper.demo --out $(RESULTS)/demo $(if $(filter 1,$(OVERWRITE)),--overwrite)
	$(PY) -m experiments.paper.figures --out $(RESULTS)/figures $(if $(filter 1,$(OVERWRITE)),--overwrite)

## Default test suite (fast; slow checks are behind the `slow` marker).
test: install
	$(PY) -m pytest -m "not slow" -n 2 -q

test-slow: install
	$(PY) -m pytest -m slow -q

test-all: install
	$(PY) -m pytest -n 2 -q

lint: install
	$(PY) -m ruff check .
	$(PY) -m ruff format --check .

format: install
	$(PY) -m ruff format .
	$(PY) -m ruff check --fix .

## What a user gets from `pip install .` (no extras): build the wheel, install it into a
## fresh venv (torch first, by install_torch), then, outside the source tree
## so that only the installed package can be imported, run the README's Python snippets
## (they compile the env's numba kernels, once) and every command at a tiny size with its
## default options, in two lanes at once: the lab commands of experiments/ (not installed:
## run by the venv's Python with only experiments/ added to its path, so they use the
## installed wheel; the first compiles the physics kernels) and the console commands. Each
## lane stops at its first failure; the target fails if either does.
CHECK_DIR ?= $(abspath $(RESULTS))/check-install
check-install:
	rm -rf $(CHECK_DIR)
	$(PYTHON) -m venv $(CHECK_DIR)/venv
	$(call install_torch,$(CHECK_DIR)/venv/bin/pip)
	$(CHECK_DIR)/venv/bin/pip wheel --disable-pip-version-check -q --no-deps -w $(CHECK_DIR)/dist .
	$(CHECK_DIR)/venv/bin/pip install --disable-pip-version-check -q $(CHECK_DIR)/dist/*.whl
	$(PYTHON) .ci/readme_python.py README.md > $(CHECK_DIR)/readme_snippets.py
	cd $(CHECK_DIR) && venv/bin/python readme_snippets.py
	mkdir -p $(CHECK_DIR)/lab && ln -s $(CURDIR)/experiments $(CHECK_DIR)/lab/experiments
	cd $(CHECK_DIR) && export PYTHONPATH=lab && ( \
	  venv/bin/python -m experiments.paper.demo --window 1 --out runs/demo && \
	  venv/bin/python -m experiments.paper.figures --out runs/figures && \
	  venv/bin/python -m experiments.paper.campaign --runs 2 --levels 2 --out runs/campaign/c && \
	  venv/bin/python -m experiments.paper.reproduce --quick --runs 2 --levels 3 --paths 1 \
	    --out runs/reproduce && \
	  venv/bin/python -m experiments.build.surrogate --grid 2 --units 2 --runs 2 \
	    --paired-units 2 --out runs/surrogate.json && \
	  venv/bin/python -m experiments.build.calibration --windows 2 --whole-flights 2 \
	    --lives 100 --out runs/calibration.json \
	) & lab=$$!; \
	cd $(CHECK_DIR) && \
	  venv/bin/scas-benchmark --episodes 2 --slots 100 --out runs/benchmark && \
	  venv/bin/scas-train --timesteps 64 --out runs/train && \
	  venv/bin/scas-tune --trials 1 --episodes 2 --slots 100 --out runs/tune && \
	  venv/bin/scas-tune --fleet --families fleet_age --trials 1 --episodes 1 --workers 1 \
	    --out runs/tune_fleet && \
	  venv/bin/scas-value --episodes 2 --slots 100 --trials 1 --train-episodes 2 \
	    --out runs/value && \
	  venv/bin/scas-export-dataset --units 2 --max-slots 200 --out runs/dataset; \
	policy=$$?; wait $$lab && test $$policy -eq 0

## Speed, each beside a reference measured in the same run.
bench: install
	$(PY) -m experiments.integrator_speed
	$(PY) -m experiments.prognostics_speed
	$(PY) -m experiments.env_speed

## The paper's physics figures (experiments/, not installed).
figures: install
	$(PY) -m experiments.paper.figures --out $(RESULTS)/figures $(if $(filter 1,$(OVERWRITE)),--overwrite)

## The paper's sections 4-5 from our physics (quick mode; `--full` for the paper's sizes).
reproduce: install
	$(PY) -m experiments.paper.reproduce --quick $(if $(filter 1,$(OVERWRITE)),--overwrite)

## The shipped v2 agent from scratch (docs/rl.md, "From the rule"): clone the tuned filter
## rule (demonstrations + DAgger), fine-tune 3 seeds x 5 M decisions with MaskablePPO on the
## native decision-epoch env (the three at once), choose on validation seeds, write the agent
## to $(AGENT_DIR)/agent (the shipped one stays), compare on 1000 held-out episodes.
AGENT_DIR ?= $(RESULTS)/agent_v2
TRAIN_ARGS = --candidate imitation_g1 --init $(AGENT_DIR)/clone --bootstrap-horizon \
	--native-envs 64 --timesteps 5000000 --checkpoint-every 500000
train-agent-v2: install
	$(PY) -m experiments.epoch_agents.imitate_rule --candidate imitation_g1 \
		--rules-from docs/value_v2/ladder.json --out $(AGENT_DIR)/clone
	$(VENV)/bin/scas-train $(TRAIN_ARGS) --seed 0 --out $(AGENT_DIR)/runs/s0 & a=$$!; \
	$(VENV)/bin/scas-train $(TRAIN_ARGS) --seed 1 --out $(AGENT_DIR)/runs/s1 & b=$$!; \
	$(VENV)/bin/scas-train $(TRAIN_ARGS) --seed 2 --out $(AGENT_DIR)/runs/s2; c=$$?; \
	wait $$a && wait $$b && test $$c -eq 0
	mkdir -p $(AGENT_DIR)/agent
	$(PY) -m experiments.epoch_agents.ship --runs $(AGENT_DIR)/runs --name maskable_ppo_epochs_v2 \
		--rules-from docs/value_v2/ladder.json \
		--held-out-seed 2 --validation-episodes 200 --held-out-episodes 1000 \
		--ship-to $(AGENT_DIR)/agent --out $(AGENT_DIR)/selection

## Results, tool caches and numba's compiled kernels (*.nbi index, *.nbc code in __pycache__).
clean:
	rm -rf $(RESULTS) .pytest_cache .ruff_cache .hypothesis
	find . \( -path ./$(VENV) -o -path ./.git \) -prune -o -path '*/__pycache__/*' \
		\( -name '*.nbi' -o -name '*.nbc' \) -type f -exec rm -f {} +
