# SPDX-License-Identifier: Apache-2.0
# The two commands of the README: `make demo` and `make test`. Both install what is missing.
WERROR := $(if $(CI),ON,OFF)
PREFIX ?= /usr/local
FUZZ_SECONDS ?= 30

.PHONY: all deps configure build test test-release test-sanitize test-tsan demo bench fuzz install clean

all: build

deps:
	@bash scripts/install-deps.sh

configure: deps
	cmake --preset release -DIDO_WERROR=$(WERROR) >/dev/null

# Everything: libraries, the ido tool, tests, examples, the Python module.
build: configure
	cmake --build --preset release

test-release: build
	ctest --preset release

# Unit tests again under AddressSanitizer + UndefinedBehaviorSanitizer (label "slow" skipped).
test-sanitize: deps
	cmake --preset dev -DIDO_WERROR=$(WERROR) >/dev/null
	cmake --build --preset dev
	ctest --preset dev

test: test-release test-sanitize

# Threaded code under ThreadSanitizer (tests labelled "threads").
test-tsan: deps
	cmake --preset tsan >/dev/null
	cmake --build --preset tsan
	ctest --preset tsan

# The demo runs only the ido tool (scripts/demo.sh), so only it and its libraries are built.
demo: configure
	cmake --build --preset release --target ido_cli
	@bash scripts/demo.sh build/release/bin/ido

bench: deps
	@bash scripts/install-deps.sh --bench
	cmake --preset bench >/dev/null
	cmake --build --preset bench
	@bash scripts/run-bench.sh build/bench

fuzz: deps
	cmake --preset fuzz >/dev/null
	cmake --build --preset fuzz
	@bash scripts/run-fuzz.sh build/fuzz $(FUZZ_SECONDS)

install: build
	cmake --install build/release --prefix $(PREFIX)

clean:
	rm -rf build
