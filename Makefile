# estlab: `make demo` and `make test` do everything on a fresh Debian machine.
BUILD      ?= build
ASAN_BUILD ?= build-asan
JOBS       ?= 2
CMAKE_FLAGS ?=

DEB_PACKAGES := cmake g++ make git pkg-config ccache libsundials-dev libceres-dev libeigen3-dev \
                libboost-program-options-dev libgtest-dev libbenchmark-dev gnuplot-nox
SUDO := $(shell [ "$$(id -u)" = 0 ] || echo sudo)
ESTLAB := $(BUILD)/estlab
# ccache keys on paths relative to the clone, so clones share cache entries.
export CCACHE_BASEDIR := $(CURDIR)

.PHONY: all deps configure build test test-asan demo bench format clean

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

test: deps build
	ctest --test-dir $(BUILD) --output-on-failure -j$(JOBS)

# Address and undefined-behaviour sanitizers over the unit tests.
test-asan: deps
	cmake -S . -B $(ASAN_BUILD) -DCMAKE_BUILD_TYPE=Asan -DCMAKE_CXX_FLAGS_ASAN="-O1 -g1" \
	  -DESTLAB_WERROR=ON -DESTLAB_SANITIZE=ON
	cmake --build $(ASAN_BUILD) -j$(JOBS)
	ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
	  ctest --test-dir $(ASAN_BUILD) --output-on-failure -j$(JOBS) -L unit

# The main job: the paper-003 double pendulum, CVODES truth, noisy full-state measurements.
demo: deps build
	@mkdir -p results/demo
	$(ESTLAB) simulate --model double-pendulum --x0 theta1=0.7853981633974483,theta2=0.5235987755982988 \
	  --t-end 50 --dt 0.01 --measure full --meas-noise-var 0.0025,0.0009,0.0016,0.0004 \
	  --seed 1 --out results/demo/paper003_truth.csv
	@echo "demo: trajectory in results/demo/paper003_truth.csv (metadata in results/demo/paper003_truth.csv.json)"

bench: deps
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release -DESTLAB_WERROR=ON -DESTLAB_BUILD_BENCH=ON
	cmake --build $(BUILD) -j$(JOBS)
	@mkdir -p bench/results
	$(BUILD)/bench/estlab_bench --benchmark_out=bench/results/latest.json --benchmark_out_format=json

format:
	clang-format -i $$(git ls-files '*.h' '*.cpp')

clean:
	rm -rf $(BUILD) $(ASAN_BUILD)
