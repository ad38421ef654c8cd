# estlab: `make demo` and `make test` do everything on a fresh Debian machine.
BUILD      ?= build
ASAN_BUILD ?= build-asan
JOBS       ?= 2
CMAKE_FLAGS ?=

DEB_PACKAGES := cmake g++ make git pkg-config ccache libsundials-dev libceres-dev libeigen3-dev \
                libboost-program-options-dev libgtest-dev libbenchmark-dev gnuplot-nox \
                libsleef-dev pybind11-dev python3-dev python3-numpy python3-pytest python3-matplotlib
SUDO := $(shell [ "$$(id -u)" = 0 ] || echo sudo)
ESTLAB := $(BUILD)/estlab
# ccache keys on paths relative to the clone, so clones share cache entries.
export CCACHE_BASEDIR := $(CURDIR)
# ... also for the sanitizer build (-g1): do not key on the build folder.
export CCACHE_NOHASHDIR := 1

.PHONY: all deps configure build install test test-asan test-slurm demo bench format clean

all: build

# Installs whatever of DEB_PACKAGES is missing (through sudo when not root).
deps:
	@missing=""; \
	for p in $(DEB_PACKAGES); do \
	  dpkg-query -W -f='$${Status}' $$p 2>/dev/null | grep -q "ok installed" || missing="$$missing $$p"; \
	done; \
	if [ -n "$$missing" ]; then \
	  echo "make deps: installing$$missing"; \
	  $(SUDO) env DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends $$missing || \
	  { $(SUDO) apt-get update && \
	    $(SUDO) env DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends $$missing; }; \
	else echo "make deps: all packages present"; fi

configure:
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release -DESTLAB_WERROR=ON $(CMAKE_FLAGS)

build: configure
	cmake --build $(BUILD) -j$(JOBS)

# The binary, libraries, headers and CMake package (find_package(estlab);
# docs/models.md) under PREFIX; the Python module in
# PREFIX/lib/python3/dist-packages/estlab (docs/python.md).
PREFIX ?= /usr/local
install: build
	cmake --install $(BUILD) --prefix $(PREFIX)

test: deps build
	ctest --test-dir $(BUILD) --output-on-failure -j$(JOBS)

# Address and undefined-behaviour sanitizers over the unit tests, less four
# long checks that repeat, 50 or 200 times or a thousand EM iterations over,
# code the other unit tests run under the sanitizer: 370-900 s each there
# (stop 47 and stop 57, ctest timings), half of the run's test time;
# `make test` runs them (EmMissing's M-step runs under the sanitizer in
# SubsetUpdate.EmTakesPartialRowsAndAlsRefusesThem).
ASAN_SKIP := AlsOdelson.RecoversQAndRWithinThreeMonteCarloStandardErrors|EmLinear.DiagonalQAndCorrelatedFullR|EmMissing.PartialRowsReachTheLikelihoodTunersOptimum|TunerVerdict.TwoHundredRandomStartsStayAdmissibleAndHonest
test-asan: deps
	cmake -S . -B $(ASAN_BUILD) -DCMAKE_BUILD_TYPE=Asan -DCMAKE_CXX_FLAGS_ASAN="-O1 -g1" \
	  -DESTLAB_WERROR=ON -DESTLAB_SANITIZE=ON -DESTLAB_PYTHON=OFF
	cmake --build $(ASAN_BUILD) -j$(JOBS)
	ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
	  ctest --test-dir $(ASAN_BUILD) --output-on-failure -j$(JOBS) -L unit -E '$(ASAN_SKIP)'

# A study through a real Slurm (issue 17): a one-node cluster on this machine
# (Debian's slurm-wlm and munge, installed when missing; daemons started and
# stopped by the script), `estlab study --slurm 3`, a cancelled shard
# resubmitted; the merged results must equal a local run byte for byte.
test-slurm: deps build
	$(SUDO) tests/slurm/test_slurm.sh $(ESTLAB)

# The demo: hand-tuned vs auto-tuned vs oracle Q/R in one scenario of each of
# the five papers (studies/tuning_hand_vs_auto.ini) at DEMO_RUNS Monte Carlo
# runs instead of the study's 100 (the tuning on separate training runs is the
# same), then its figures. A fresh folder each time, so the numbers are the
# ones of this build.
DEMO_RUNS ?= 30
DEMO_OUT  ?= results/demo
demo: deps build
	@rm -rf $(DEMO_OUT)
	$(ESTLAB) study studies/tuning_hand_vs_auto.ini --out $(DEMO_OUT) --runs $(DEMO_RUNS) --jobs $(JOBS)
	$(ESTLAB) figures $(DEMO_OUT)
	@echo ""
	@echo "demo: report  $(DEMO_OUT)/report.md (hand / auto / oracle table under '## Hand-tuned vs auto-tuned vs oracle Q/R')"
	@echo "demo: figures $(DEMO_OUT)/figures/ (PNG and SVG, each with its .gp script and .dat data)"

bench: deps
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release -DESTLAB_WERROR=ON -DESTLAB_BUILD_BENCH=ON
	cmake --build $(BUILD) -j$(JOBS)
	@mkdir -p bench/results
	$(BUILD)/bench/estlab_bench --benchmark_out=bench/results/latest.json --benchmark_out_format=json

format:
	clang-format -i $$(git ls-files '*.h' '*.cpp')

clean:
	rm -rf $(BUILD) $(ASAN_BUILD)
