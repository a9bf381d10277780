"""Benchmarks. Each module bench_<area>.py exposes run() -> {"key": number} and
measures everything it reports in that call. `make bench` runs them all."""
