# Developer entry points. CI runs `.ci/run`, which calls `make test` and `make lint`.
CARGO ?= cargo
# Extra flags for `make run`, e.g. make run ARGS="--rest-addr 127.0.0.1:8081 --log-format json"
ARGS ?=

.PHONY: build run test fmt lint fuzz

build:
	$(CARGO) build --bins

# graspd with the built-in defaults: gRPC 0.0.0.0:50051, REST 0.0.0.0:8080.
run:
	$(CARGO) run --bin graspd -- $(ARGS)

# The end-to-end tests start the real binaries, so build them first.
test:
	$(CARGO) build --bins
	$(CARGO) test --workspace
	scripts/python-client-test.sh

fmt:
	$(CARGO) fmt --all

lint:
	$(CARGO) fmt --all --check
	$(CARGO) clippy --workspace --all-targets -- -D warnings

# Every decoder of untrusted input under libFuzzer, FUZZ_SECONDS each (docs/fuzzing.md).
fuzz:
	scripts/fuzz.sh
