# The one contract: `make demo`, `make test` (what CI runs), `make bench`, `make lint`, `make lock`.
# Everything Python lives in .venv, created here from the pinned requirements/dev.txt.

PYTHON ?= python3
VENV := .venv
VPY := $(VENV)/bin/python
DEPS := $(VENV)/.deps-installed
export VIRTUAL_ENV := $(abspath $(VENV))
export PATH := $(VIRTUAL_ENV)/bin:$(PATH)
# The glue crate's build script (run by clippy too) must see the venv's interpreter.
export PYO3_PYTHON := $(abspath $(VPY))

.PHONY: demo test build lint rust-test py-test bench lock clean

$(VPY):
	$(PYTHON) -m venv $(VENV)

$(DEPS): requirements/dev.txt | $(VPY)
	$(VPY) -m pip install --quiet --upgrade pip
	$(VPY) -m pip install --quiet -r requirements/dev.txt
	touch $@

build: $(DEPS)
	$(VENV)/bin/maturin develop --release --locked --quiet

demo: build
	$(VPY) -m imukit demo

lint: build
	cargo fmt --all --check
	cargo clippy --workspace --all-targets --locked -- -D warnings
	$(VPY) -m ruff check python tests bench
	$(VPY) -m ruff format --check python tests bench
	$(VPY) -m mypy
	$(VPY) -m mypy.stubtest imukit._core

rust-test:
	cargo test --locked

py-test: build
	$(VPY) -m pytest --doctest-modules --doctest-glob=README.md python/imukit README.md tests

test: lint rust-test py-test

bench: build
	$(VPY) bench/bench_so3.py
	$(VPY) bench/bench_attitude.py
	$(VPY) bench/bench_strapdown.py
	$(VPY) bench/bench_preint.py
	$(VPY) bench/bench_allan.py
	$(VPY) bench/bench_sim.py
	$(VPY) bench/bench_filters.py
	cargo bench --locked -p imukit

# Re-pin the Python closure after editing requirements/dev.in.
lock: | $(VPY)
	$(VPY) -m pip install --quiet -r requirements/dev.in
	$(VPY) -m pip freeze --exclude-editable | grep -v '^imukit' > requirements/dev.txt

clean:
	cargo clean
	rm -rf $(VENV)
