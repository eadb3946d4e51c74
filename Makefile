# Two commands do everything on a fresh Debian 12 machine: `make demo` and `make test`.
# Every target installs what is missing first (Debian packages, only those absent).

PRESET ?= release
BUILD  := build/$(PRESET)
CNCORE := $(BUILD)/src/app/cncore

# libpaho-mqtt*: the MQTT publisher of `cncore serve --mqtt`; mosquitto, mosquitto-clients and
# openssl: the broker, subscriber and test CA its tests start. udev: its `udevadm` is how CNCjs
# (the sender its test starts) lists serial ports; without it CNCjs's page lists none.
DEB_PACKAGES := cmake ninja-build g++ make pkg-config python3 \
  libcli11-dev libtomlplusplus-dev libfmt-dev nlohmann-json3-dev libfast-float-dev \
  libmuparser-dev libgtest-dev libgmock-dev libbenchmark-dev librapidcheck-dev libpng-dev time \
  chromium dpkg-dev libpaho-mqtt-dev libpaho-mqttpp-dev mosquitto mosquitto-clients openssl \
  libcpp-httplib-dev udev
# Node.js and npm (uPlot for the HTML report) come from Debian only when no `npm` is on the PATH:
# a machine with Node.js from elsewhere has its own npm, which Debian's package conflicts with.
NODE_PACKAGES := nodejs npm

.PHONY: all deps configure build cncore test demo install package bench format clean fuzz test-sanitize

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

# The `cncore` command alone (no tests, no benchmarks): all that `make demo` runs.
cncore: configure
	@cmake --build --preset $(PRESET) --target cncore

test: build
	@bash tools/run-tests.sh $(BUILD)

demo: cncore
	@mkdir -p out
	$(CNCORE) run examples/seed-line-arc-line.ngc --summary out/demo-summary.json \
	  --trajectory out/demo-trajectory.csv --report out/demo-report.html
	@echo "wrote out/demo-summary.json, out/demo-trajectory.csv and out/demo-report.html"

# The command, its man page and bash/zsh completions, the docs and the examples, under PREFIX
# (/usr/local by default: run as root, or give PREFIX=$$HOME/.local).
PREFIX ?= /usr/local
install: cncore
	@cmake --build --preset $(PRESET) --target cncore_manual
	cmake --install $(BUILD) --prefix $(PREFIX) --strip

# The same as a Debian package: out/cncore_VERSION_amd64.deb (apt-get install ./out/cncore_*.deb).
package: cncore
	@cmake --build --preset $(PRESET) --target cncore_manual
	@cpack -G DEB --config $(BUILD)/CPackConfig.cmake -B $(BUILD)/package >/dev/null
	@mkdir -p out && cp $(BUILD)/package/cncore_*_amd64.deb out/
	@ls out/cncore_*_amd64.deb

bench: build
	@bash bench/run.sh $(BUILD)

# libFuzzer targets (clang), each run for FUZZ_SECONDS; prints executions and findings.
FUZZ_SECONDS ?= 60
fuzz: deps
	@command -v clang++ >/dev/null || { SUDO=""; [ "$$(id -u)" -eq 0 ] || SUDO=sudo; \
	  $$SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -qq clang; }
	@bash fuzz/run.sh $(FUZZ_SECONDS)

# The whole test suite under AddressSanitizer + UndefinedBehaviorSanitizer (gcc); CI runs it
# after `make test`. Any finding aborts its process with SIGABRT (halt_on_error, abort_on_error;
# UBSan is compiled with -fno-sanitize-recover), so its test fails, also when the finding is in
# the cncore binary run by a test (exit 134 is none of the exit codes 0-3 the tests expect).
# ASan and LeakSanitizer reports also go to files in SANITIZER_LOGS (log_path; gcc's UBSan
# ignores it and prints to stderr): any file there fails the target even if every test passed
# (a leak in a child makes it exit 23, which a test expecting "non-zero" would accept), and the
# reports are printed at the end. The RapidCheck properties run SANITIZE_RC_CASES random cases
# each instead of 100 (RC_PARAMS; `make test` keeps 100): a random program can be long, and the
# sanitizers make every cycle several times slower. Ends with "N passed, N failed" like
# `make test`, then the count of sanitizer reports. Measured: 637 tests, 13.4 min on a machine
# shared with two other builds (416 CPU-s, ~4 min on an idle 2-core machine); the build adds
# ~10 min from scratch on 2 cores (fuzz/README.md).
SANITIZE_RC_CASES ?= 25
SANITIZER_LOGS := $(CURDIR)/build/asan/sanitizer-logs
test-sanitize: deps
	@cmake --preset asan >/dev/null
	@cmake --build --preset asan -j2
	@rm -rf $(SANITIZER_LOGS) && mkdir -p $(SANITIZER_LOGS)
	@rc=0; \
	RC_PARAMS="max_success=$(SANITIZE_RC_CASES)" \
	ASAN_OPTIONS=halt_on_error=1:abort_on_error=1:detect_leaks=1:print_stacktrace=1:log_path=$(SANITIZER_LOGS)/asan \
	UBSAN_OPTIONS=halt_on_error=1:abort_on_error=1:print_stacktrace=1 \
	LSAN_OPTIONS=suppressions=$(CURDIR)/tools/lsan-suppressions.txt:print_suppressions=0 \
	  bash tools/run-tests.sh build/asan || rc=$$?; \
	reports=$$(find $(SANITIZER_LOGS) -type f | wc -l); \
	if [ "$$reports" -gt 0 ]; then \
	  for f in $(SANITIZER_LOGS)/*; do echo "=== $$f"; cat "$$f"; done; \
	  echo "$$reports sanitizer report(s) (above; in $(SANITIZER_LOGS))"; rc=1; \
	else echo "0 sanitizer reports"; fi; \
	exit $$rc

format:
	@git ls-files '*.cpp' '*.hpp' | xargs clang-format -i

clean:
	rm -rf build out
