# Two commands do everything on a fresh Debian 12 machine: `make demo` and `make test`.
# Every target installs what is missing first (Debian packages, only those absent).

PRESET ?= release
BUILD  := build/$(PRESET)
CNCORE := $(BUILD)/src/app/cncore

DEB_PACKAGES := cmake ninja-build g++ make pkg-config \
  libcli11-dev libtomlplusplus-dev libfmt-dev nlohmann-json3-dev libfast-float-dev \
  libmuparser-dev libgtest-dev libgmock-dev libbenchmark-dev librapidcheck-dev libpng-dev time \
  chromium
# Node.js and npm (uPlot for the HTML report) come from Debian only when no `npm` is on the PATH:
# a machine with Node.js from elsewhere has its own npm, which Debian's package conflicts with.
NODE_PACKAGES := nodejs npm

.PHONY: all deps configure build test demo bench format clean fuzz test-sanitize

all: build

deps:
	@missing=""; for p in $(DEB_PACKAGES); do \
	  dpkg-query -W -f='$${Status}' $$p 2>/dev/null | grep -q "install ok installed" || missing="$$missing $$p"; \
	done; \
	command -v npm >/dev/null 2>&1 || missing="$$missing $(NODE_PACKAGES)"; \
	if [ -n "$$missing" ]; then \
	  echo "installing:$$missing"; \
	  SUDO=""; [ "$$(id -u)" -eq 0 ] || SUDO=sudo; \
	  $$SUDO apt-get update -qq && \
	  DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -qq --no-install-recommends $$missing; \
	fi

configure: deps
	@cmake --preset $(PRESET) >/dev/null

build: configure
	@cmake --build --preset $(PRESET)

test: build
	@bash tools/run-tests.sh $(BUILD)

demo: build
	@mkdir -p out
	$(CNCORE) run examples/seed-line-arc-line.ngc --summary out/demo-summary.json \
	  --trajectory out/demo-trajectory.csv --report out/demo-report.html
	@echo "wrote out/demo-summary.json, out/demo-trajectory.csv and out/demo-report.html"

bench: build
	@bash bench/run.sh $(BUILD)

# libFuzzer targets (clang), each run for FUZZ_SECONDS; prints executions and findings.
FUZZ_SECONDS ?= 60
fuzz: deps
	@command -v clang++ >/dev/null || { SUDO=""; [ "$$(id -u)" -eq 0 ] || SUDO=sudo; \
	  $$SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -qq clang; }
	@bash fuzz/run.sh $(FUZZ_SECONDS)

# The whole test suite under AddressSanitizer + UndefinedBehaviorSanitizer (gcc); any finding
# fails its test (halt_on_error). Ends with "N passed, N failed" like `make test`.
test-sanitize: deps
	@cmake --preset asan >/dev/null
	@cmake --build --preset asan -j2
	@ASAN_OPTIONS=halt_on_error=1:abort_on_error=1:detect_leaks=1:print_stacktrace=1 \
	  UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 bash tools/run-tests.sh build/asan

format:
	@git ls-files '*.cpp' '*.hpp' | xargs clang-format -i

clean:
	rm -rf build out
