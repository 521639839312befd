# Factor World for LeRobot. `make demo` and `make test` do all set-up on a fresh machine first.
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: setup demo findings contact-sheet test test-fast lint bench mutation

setup: $(STAMP)

$(STAMP): pyproject.toml scripts/setup.sh
	bash scripts/setup.sh
	touch $(STAMP)

# The main job: the quick generalization-gap study (collect, train, evaluate, report) in 3-10 minutes
# on 2 cores; writes outputs/study/quick/report.md, results.csv and the plots. Rerunning reuses its steps.
demo: setup
	MUJOCO_GL=egl $(BIN)/factorworld study --config configs/study/quick.yaml

# Every finding of docs/findings.md, each reusing the steps of those before it: at most 22-25 hours on 2 cores,
# resumable (run it again to go on). DRY_RUN=1 prints each one's cost and power; ONLY="f3_pairs ..." some.
findings: setup
	bash scripts/run_findings.sh

# A contact sheet of pick-place under every factor of variation.
contact-sheet: setup
	$(BIN)/factorworld contact-sheet --task=pick-place --out=outputs/contact_sheet.png

# Lint (style, the import-layer contract), then the whole suite (real MuJoCo scenes, real lerobot-eval), on all cores.
test: lint
	$(BIN)/pytest -n auto -q

test-fast: setup
	$(BIN)/pytest -n auto -q -m "not slow"

# ruff (with import-outside-toplevel) and import-linter's layer contract (pyproject.toml): a new upward import,
# a cycle, or an unexplained import inside a function fails here.
lint: setup
	$(BIN)/ruff check .
	$(BIN)/lint-imports

bench: setup
	$(BIN)/python scripts/bench_env.py
	$(BIN)/python scripts/bench_collect.py
	$(BIN)/python scripts/bench_policy.py
	$(BIN)/python scripts/bench_bc.py
	$(BIN)/python scripts/bench_malloc.py

# Mutation testing of the modules that compute what the project reports (slow, 1-2 hours on 2 cores; not part of
# `make test`): mutmut ([tool.mutmut] in pyproject.toml) in mutants/, then the score per module with the
# equivalent mutants of docs/testing.md left out (PYTHONPATH: a test's subprocess imports the mutated copy too).
# Reruns only what changed; `$(BIN)/mutmut show <name>` shows a mutant.
mutation: setup
	mkdir -p mutants
	PYTHONPATH=$(CURDIR)/mutants $(BIN)/mutmut run --max-children 2 > mutants/run.log 2>&1 || (tail -n 40 mutants/run.log; exit 1)
	$(BIN)/mutmut results --all true | $(BIN)/python scripts/mutation_scores.py
