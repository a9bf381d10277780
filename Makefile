# make demo | make test | make check | make lint | make bench | make eval | make train | make soak | make loaded | make setup | make clean
SHELL := /bin/bash
ENV := ./env.sh
PYTEST_ARGS ?=
GUI ?= 0

.PHONY: setup demo test check lint bench eval train soak loaded clean

setup:
	@bash tools/setup.sh

demo: setup
	@$(ENV) python -m tools.demo --gui $(GUI)

# Everything: the linter, then every test (unit, integration, rostests, the workspace), on
# TEST_WORKERS workers; test/conftest.py makes each file one work unit (its module fixtures
# are built once) except the rostests, one unit each, and hands the longest out first.
TEST_WORKERS ?= 2
test: setup
	@$(ENV) ruff check src tools test scripts
	@$(ENV) python -m pytest test/ -n $(TEST_WORKERS) --dist loadgroup --no-loadscope-reorder $(PYTEST_ARGS)

# The unit tests that need no ROS master, no simulator and no model fitting: for while you work.
check: setup
	@$(ENV) ruff check src tools test scripts
	@$(ENV) python -m pytest test/ -m 'not integration and not slow' -q $(PYTEST_ARGS)

lint: setup
	@$(ENV) ruff check src tools test scripts

bench: setup
	@$(ENV) python -m tools.bench

eval: setup
	@$(ENV) python -m tools.evaluation.evaluate

# Refit the shipped pose models (arrays + model cards in src/leap_teleop/hands/gestures/models/)
# from ../shared/data, with their leave-one-person-out figures.
train: setup
	@$(ENV) python -m leap_teleop.hands.gestures.train

soak: setup
	@$(ENV) python -m tools.soak

# The load margin: make demo, then every rostest, each beside two CPU hogs (one per core).
loaded: setup
	@$(ENV) python -m tools.under_load --hogs 2 -- python -m tools.demo --out demo_output
	@$(ENV) python -m tools.under_load --hogs 2 -- python -m pytest test/test_rostests.py -q

clean:
	rm -rf .ws build devel bench_results.json soak_results.json eval_results.json people_results.json demo_output
