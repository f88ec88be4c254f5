# The one contract: `make demo`, `make test` (what CI runs), `make bench`, `make lint`, `make lock`;
# issue 9's long runs: `make stability` (full-length stability tests), `make fuzz` (fuzzers).
# Everything Python lives in .venv, created here from the pinned requirements/dev.txt.

PYTHON ?= python3
VENV := .venv
VPY := $(VENV)/bin/python
DEPS := $(VENV)/.deps-installed
export VIRTUAL_ENV := $(abspath $(VENV))
export PATH := $(VIRTUAL_ENV)/bin:$(PATH)
# The glue crate's build script (run by clippy too) must see the venv's interpreter.
export PYO3_PYTHON := $(abspath $(VPY))

.PHONY: demo test build lint rust-test stability-fast py-test path-test bench lock clean stability fuzz

# Attitude steps of the stability tests (crates/imukit/tests/stability*.rs); the rotation-matrix,
# covariance and memory runs use a tenth. Issue 9's lengths in `make stability`, a tenth in
# `make stability-fast`; `make test` runs them in the debug `cargo test` at 10^6 / 10^5 steps
# (a release build of the test binaries would add ~100 s from a fresh clone to the 15-minute CI budget).
STABILITY_STEPS ?= 1e8
FAST_STABILITY_STEPS ?= 1e7
STABILITY_TESTS := -p imukit --test stability --test stability_memory
# Seconds per fuzz target in `make fuzz`.
FUZZ_SECONDS ?= 60
FUZZ_TARGETS := attitude strapdown preint filters

$(VPY):
	$(PYTHON) -m venv $(VENV)

# torch's PyPI wheel pulls ~5.2 GB of CUDA libraries (no CPU-only torch is on PyPI). The torch stack
# is installed last, and by default (TORCH=auto) only where the disk still has TORCH_MIN_FREE_GB
# free: a CI machine short of disk then runs everything else, and imukit.torch's tests skip and its
# type check is left out, each saying why. TORCH=yes installs it regardless, TORCH=no never.
TORCH ?= auto
TORCH_MIN_FREE_GB ?= 12
TORCH_STACK := ^(torch|triton|pypose|nvidia-|cuda-)
HAVE_TORCH = $(VPY) -c 'import importlib.util, sys; sys.exit(importlib.util.find_spec("torch") is None)'

$(DEPS): requirements/dev.txt | $(VPY)
	$(VPY) -m pip install --quiet --no-cache-dir --upgrade pip
	grep -v -E '$(TORCH_STACK)' requirements/dev.txt > $(VENV)/requirements-core.txt
	grep -E '$(TORCH_STACK)' requirements/dev.txt > $(VENV)/requirements-torch.txt
	$(VPY) -m pip install --quiet --no-cache-dir -r $(VENV)/requirements-core.txt
	@free_gb=$$(df -Pk $(VENV) | awk 'NR == 2 { print int($$4 / 1048576) }'); \
	if [ "$(TORCH)" = yes ] || { [ "$(TORCH)" = auto ] && [ "$$free_gb" -ge $(TORCH_MIN_FREE_GB) ]; }; then \
		echo "$(VPY) -m pip install --quiet --no-cache-dir -r $(VENV)/requirements-torch.txt"; \
		$(VPY) -m pip install --quiet --no-cache-dir -r $(VENV)/requirements-torch.txt || exit 1; \
	else \
		echo "WARNING: torch not installed (TORCH=$(TORCH), $$free_gb GB free, auto needs $(TORCH_MIN_FREE_GB)):" \
			"imukit.torch's tests will skip and mypy leaves python/imukit/torch out"; \
	fi
	touch $@

build: $(DEPS)
	$(VENV)/bin/maturin develop --release --locked --quiet

demo: build
	$(VPY) -m imukit demo

lint: build
	cargo fmt --all --check
	cargo clippy --workspace --all-targets --locked -- -D warnings
	RUSTDOCFLAGS="-D warnings" cargo doc --workspace --no-deps --locked --quiet
	$(VPY) -m ruff check python tests bench
	$(VPY) -m ruff format --check python tests bench
	@if $(HAVE_TORCH); then echo "$(VPY) -m mypy"; $(VPY) -m mypy; else \
		echo "WARNING: torch not installed: mypy leaves python/imukit/torch out"; \
		echo "$(VPY) -m mypy --exclude 'python/imukit/torch/'"; \
		$(VPY) -m mypy --exclude 'python/imukit/torch/'; fi
	$(VPY) -m mypy.stubtest imukit._core

rust-test:
	cargo test --locked

# Release build: the stability tests are long loops of the optimised kernels.
stability-fast:
	IMUKIT_STABILITY_STEPS=$(FAST_STABILITY_STEPS) cargo test --release --locked $(STABILITY_TESTS)

stability:
	IMUKIT_STABILITY_STEPS=$(STABILITY_STEPS) cargo test --release --locked $(STABILITY_TESTS) -- --nocapture --test-threads=1

# The Python suites on every core (pytest-xdist; at most four workers, each a file at a time so a
# module's fixtures are computed once): 415 s serial against 241 s on this project's 2-core host.
PYTEST_PARALLEL := -n auto --maxprocesses=4 --dist loadfile

py-test: build
	$(VPY) -m pytest $(PYTEST_PARALLEL) --doctest-modules --doctest-glob=README.md python/imukit README.md tests

# Issue 20: the agreement (GTSAM, Monte Carlo), accuracy, stability and fuzz-regression suites once
# more on every instruction-set path below the best one this CPU has, forced with IMUKIT_SIMD (the
# runs above take the best); tests/test_simd_paths.py compares the paths' results directly.
PATH_RUST_TESTS := --test preint --test preint_batch --test preint_midpoint --test preint_windows \
	--test propagate --test filters --test robust --test attitude --test allan --test sim \
	--test stability --test stability_fuzz_regressions
PATH_PY_TESTS := tests/test_preint_gtsam.py tests/test_propagate_monte_carlo.py tests/test_preint.py \
	tests/test_preint_lever_noise.py tests/test_preint_earth.py tests/test_propagate_earth.py \
	tests/test_strapdown.py tests/test_attitude.py tests/test_filters.py tests/test_filters_pinned.py \
	tests/test_filters_motion.py tests/test_robust.py tests/test_broad_accuracy.py tests/test_filters_data.py \
	tests/test_attitude_euroc.py tests/test_preint_euroc.py tests/test_strapdown_euroc.py \
	tests/test_noise_allan.py tests/test_sim.py tests/test_fuzz_regressions.py tests/test_extreme_values.py
LOWER_PATHS = $(VPY) -c 'import imukit as ik; o = ["baseline", "avx2", "avx512"]; print(*o[: o.index(ik.simd_path())])'

path-test: build
	@paths=$$($(LOWER_PATHS)) || exit 1; \
	if [ -z "$$paths" ]; then echo "path-test: the path in use, $$($(VPY) -c 'import imukit as ik; print(ik.simd_path())'), has no path below it"; fi; \
	for p in $$paths; do \
		echo "IMUKIT_SIMD=$$p: the suites on the $$p path"; \
		IMUKIT_SIMD=$$p cargo test --locked -p imukit $(PATH_RUST_TESTS) || exit 1; \
		IMUKIT_SIMD=$$p $(VPY) -m pytest -q -p no:cacheprovider $(PYTEST_PARALLEL) $(PATH_PY_TESTS) || exit 1; \
	done

test: lint rust-test py-test path-test

# cargo-fuzz needs the nightly toolchain (rustup toolchain install nightly). Each target runs
# FUZZ_SECONDS; a crash stops `make` with the input under fuzz/artifacts/<target>/.
fuzz: build
	command -v cargo-fuzz >/dev/null || cargo install cargo-fuzz --locked
	for target in $(FUZZ_TARGETS); do \
		cargo +nightly fuzz run $$target -- -max_total_time=$(FUZZ_SECONDS) || exit 1; \
	done
	mkdir -p fuzz/corpus/readers fuzz/artifacts/readers
	$(VPY) fuzz/python/fuzz_readers.py -max_total_time=$(FUZZ_SECONDS) \
		-artifact_prefix=fuzz/artifacts/readers/ fuzz/corpus/readers

bench: build
	$(VPY) bench/bench_so3.py
	$(VPY) bench/bench_attitude.py
	$(VPY) bench/bench_strapdown.py
	$(VPY) bench/bench_preint.py
	$(VPY) bench/bench_simd.py
	$(VPY) bench/bench_allan.py
	$(VPY) bench/bench_sim.py
	$(VPY) bench/bench_filters.py
	$(VPY) bench/bench_torch.py
	cargo bench --locked -p imukit-bench

# Re-pin the Python closure after editing requirements/dev.in.
lock: | $(VPY)
	$(VPY) -m pip install --quiet -r requirements/dev.in
	$(VPY) -m pip freeze --exclude-editable | grep -v '^imukit' > requirements/dev.txt

clean:
	cargo clean
	rm -rf $(VENV)
