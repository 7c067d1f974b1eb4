# One entry point for developers and CI.
PYTHON ?= python3
PIP := $(PYTHON) -m pip
CARGO_TARGET_DIR ?= target

.PHONY: demo test test-rust test-cpp test-python python lint bench compare fmt stubs docs

## Build the CLI and run it on the built-in 2.1 h urban drive; then a batch over three
## synthetic MCAP logs, with reports in demo/results/index.html.
LOOPS := cargo run --release --quiet -p loops-cli --
demo:
	$(LOOPS) demo
	$(LOOPS) synth demo/logs --count 3 --duration-s 3600 --force
	$(LOOPS) run demo/logs/urban-drive-0.mcap demo/logs/urban-drive-1.mcap demo/logs/urban-drive-2.mcap \
		--gamma 40 --budget 2000 --out demo/results --force
	@echo "open demo/results/index.html"

## Every test: Rust (unit, property, doc) and Python (pytest, doctests, stubs). The Python
## packages go in first: the Rust MCAP tests write their fixtures with the official Python writers.
test: python test-rust test-cpp test-python

## The fixture writers run in $(PYTHON); a test part that cannot run here is listed in
## $(SKIPPED) and counted after the run (under CI a missing fixture writer fails instead).
SKIPPED := $(abspath $(CARGO_TARGET_DIR))/skipped-rust-tests.txt
test-rust:
	mkdir -p $(dir $(SKIPPED)) && rm -f $(SKIPPED)
	PYTHON=$(PYTHON) LOOPS_SKIPPED_LOG=$(SKIPPED) cargo test --workspace --all-targets
	cargo test --workspace --doc
	@if [ -s $(SKIPPED) ]; then echo "Rust test parts skipped: $$(wc -l < $(SKIPPED))"; sed 's/^/  /' $(SKIPPED); \
	 else echo "Rust test parts skipped: 0"; fi

## The C ABI from C++: build the static library (crates/loops-capi), compile
## examples/cpp/online_replay.cpp against it with the system compiler, and check that it prints
## the candidates of the Python API (tests/python/test_capi.py, which runs the binary built here).
ifeq ($(origin CXX),default)
CXX := c++
endif
ONLINE_REPLAY := $(CARGO_TARGET_DIR)/cpp/online_replay
test-cpp: python
	cargo build -p loops-capi
	mkdir -p $(CARGO_TARGET_DIR)/cpp
	$(CXX) -std=c++17 -O2 -Wall -Wextra -Werror -Icrates/loops-capi/include examples/cpp/online_replay.cpp \
		$(CARGO_TARGET_DIR)/debug/libinexact_loops.a -lpthread -ldl -lm -o $(ONLINE_REPLAY)
	ONLINE_REPLAY=$(ONLINE_REPLAY) $(PYTHON) -m pytest -q tests/python/test_capi.py

## Build and install the Python package (release build) with its test dependencies and the
## documentation tools (tests/test_docs.py builds the site and runs its examples).
python:
	$(PIP) install --quiet --upgrade 'maturin>=1.9,<2'
	$(PIP) install --quiet '.[test,docs]'

## The documentation site, from docs/ and mkdocs.yml, into target/site (open
## target/site/index.html). Warnings are errors; the command-line reference is generated from
## the installed `loops`, the Python API from the package's docstrings and stubs.
docs: python
	NO_MKDOCS_2_WARNING=1 $(PYTHON) -m mkdocs build --strict

test-python: python
	$(PYTHON) -m mypy.stubtest inexact_loops._core
	$(PYTHON) -m pytest -q tests
	$(PYTHON) -m pytest -q --doctest-modules --pyargs inexact_loops

lint:
	cargo fmt --all -- --check
	cargo clippy --workspace --all-targets -- -D warnings
	$(PYTHON) -m ruff check python tests benches examples docs/hooks docs/scripts

fmt:
	cargo fmt --all
	$(PYTHON) -m ruff format python tests benches docs/hooks docs/scripts

## Copy the compiled module's docstrings into python/inexact_loops/_core.pyi (the stub IDEs
## show); tests/python/test_stubs.py fails until they are equal.
stubs: python
	$(PYTHON) tests/stubs.py

## Criterion benchmarks (Rust).
bench:
	cargo bench -p loops-benches

## Side-by-side comparison with scipy; writes BENCHMARKS.md.
compare: python
	$(PYTHON) benches/compare.py
