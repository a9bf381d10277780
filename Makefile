# make demo | make test | make bench | make eval | make setup | make clean
SHELL := /bin/bash
ENV := ./env.sh
PYTEST_ARGS ?=
GUI ?= 0

.PHONY: setup demo test bench eval soak clean

setup:
	@bash tools/setup.sh

demo: setup
	@$(ENV) python -m leap_teleop.tools.demo --gui $(GUI)

test: setup
	@$(ENV) python -m pytest test/ $(PYTEST_ARGS)

bench: setup
	@$(ENV) python -m leap_teleop.bench

eval: setup
	@$(ENV) python -m leap_teleop.tools.evaluate

soak: setup
	@$(ENV) python -m leap_teleop.tools.soak

clean:
	rm -rf .ws build devel bench_results.json soak_results.json eval_results.json demo_output
