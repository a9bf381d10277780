"""Project tooling outside the installed package: evaluation, benchmarks, the demo and the
soak (`python -m tools.NAME` from the repository root, as the Makefile runs them)."""
