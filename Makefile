# One command sets up and runs the demo; one sets up and runs the tests.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: demo test lint bench clean browser docs

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	@echo "installing amronet and its dependencies into $(VENV) (about 2 minutes)..."
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[dev,cluster,docs,rl,optimum]'
	@# compile the numba kernels into their on-disk cache now, not in the first run; it prints a line per group of
	@# kernels as it starts (one updating line on a terminal). Should it fail, runs still work and compile what they
	@# use (tests/test_warmup.py runs the same warm-up and fails)
	@echo "compiling the simulator's kernels once (about a minute on 2 cores, a few on a busy machine)..."
	$(BIN)/amronet compile || echo "amronet compile failed: runs will compile their kernels on first use"
	touch $(STAMP)

demo: $(STAMP)
	$(BIN)/amronet run --preset demo-autolab --seed 1 --out runs/demo
	@echo "picture: runs/demo/snapshot.png"

# The replay viewer's test drives a real headless Chromium (Debian's package; Playwright from PyPI drives it).
# Set AMRONET_SKIP_BROWSER=1 to skip both the install and that test.
CHROMIUM := /usr/bin/chromium
SUDO := $(shell [ "$$(id -u)" = 0 ] || echo sudo)

browser:
	@if [ "$(AMRONET_SKIP_BROWSER)" != 1 ] && [ ! -x $(CHROMIUM) ]; then \
		echo "installing Debian's chromium for the replay viewer's browser test"; \
		$(SUDO) apt-get update -qq && DEBIAN_FRONTEND=noninteractive \
		$(SUDO) apt-get install -y -qq --no-install-recommends chromium >/dev/null; \
	fi

# numpy picks its SIMD code for exp, log, power, arctan2, ... by the processor; its AVX-512 versions differ from the
# AVX2 ones in the last bit, and a run's chaotic motion turns that into another run. The golden fingerprints
# (tests/test_golden.py) are taken with AVX2 at most, so the tests hold numpy there on every x86 machine (names a
# machine lacks are ignored).
NUMPY_SIMD := NPY_DISABLE_CPU_FEATURES="X86_V4 AVX512_ICL AVX512_SPR AVX512F AVX512_SKX AVX512_CLX AVX512_CNL"

test: $(STAMP) browser
	$(BIN)/ruff check src tests benchmarks tools
	$(BIN)/lint-imports
	$(MKDOCS) build --strict
	MPLBACKEND=Agg $(NUMPY_SIMD) $(BIN)/python -m pytest

lint: $(STAMP)
	$(BIN)/ruff check src tests benchmarks tools
	$(BIN)/lint-imports

# The documentation site (MkDocs + Material + mkdocstrings) into build/site; `make test` builds it with --strict,
# so a broken link, a missing page or a reference that does not resolve fails the tests.
MKDOCS := NO_MKDOCS_2_WARNING=1 DISABLE_MKDOCS_2_WARNING=true $(BIN)/mkdocs

docs: $(STAMP)
	$(MKDOCS) build --strict
	@echo "documentation: build/site/index.html (or: $(MKDOCS) serve)"

bench: $(STAMP)
	$(BIN)/python benchmarks/run_all.py

# amronet against Mesa at N = 30, 300, 3000 (issue #17); installs the optional `bench` extra (Mesa) first.
.PHONY: bench-peers
bench-peers: $(STAMP)
	$(BIN)/python -m pip install --quiet -e '.[bench]'
	$(BIN)/python benchmarks/bench_peers.py

clean:
	rm -rf $(VENV) runs build *.egg-info src/*.egg-info
