# Developer entry points. CI runs `.ci/run`, which calls `make test` and `make lint`.
CARGO ?= cargo
# Extra flags for `make run`, e.g. make run ARGS="--rest-addr 127.0.0.1:8081 --log-format json"
ARGS ?=

.PHONY: build run test fmt lint fuzz models models-grasp-type models-tactile models-recogniser models-grasp-quality models-in-hand sim-bench sim-stabilize sim-clutter

# The ONNX Runtime library that ort loads at run time (grasp-type model, docs/model-contract.md);
# `run` and `test` fetch it first with scripts/fetch-onnxruntime.sh.
run test: export ORT_DYLIB_PATH = $(CURDIR)/.tools/onnxruntime/libonnxruntime.so.1.31.1
# MuJoCo 3.17.0, which clients/sim links (scripts/fetch-mujoco.sh fetches it from the PyPI wheel);
# every target that compiles the workspace needs it.
export MUJOCO_DYNAMIC_LINK_DIR = $(CURDIR)/.tools/mujoco

build:
	scripts/fetch-mujoco.sh
	$(CARGO) build --bins

# The shared hand models, imported at start by `make run` when ../shared/testdata/hands exists.
HANDS ?= ../shared/testdata/hands
HAND_IMPORTS = $(if $(wildcard $(HANDS)/shadow_hand/right_hand.xml),\
	--import-hand shadow_mjcf=$(HANDS)/shadow_hand/right_hand.xml \
	--import-hand allegro=$(HANDS)/wonik_allegro/right_hand.xml \
	--import-hand robotiq_2f85=$(HANDS)/robotiq_2f85/2f85.xml \
	--import-hand barrett_mjcf=$(HANDS)/barrett/wam_barrett_gripper.xml)

# graspd with the built-in defaults (gRPC 0.0.0.0:50051, REST 0.0.0.0:8080), the shared hands
# imported when present, registered hands kept in .hands/ and tactile calibrations in
# .calibrations/.
run:
	scripts/fetch-onnxruntime.sh
	$(CARGO) run --bin graspd -- --hands-dir .hands --calibrations-dir .calibrations $(HAND_IMPORTS) $(ARGS)

# The end-to-end tests start the real binaries, so build them first.
test:
	scripts/fetch-onnxruntime.sh
	scripts/fetch-mujoco.sh
	$(CARGO) build --bins
	$(CARGO) test --workspace
	scripts/python-client-test.sh
	scripts/browser-test.sh

fmt:
	$(CARGO) fmt --all

lint:
	scripts/fetch-mujoco.sh
	$(CARGO) fmt --all --check
	$(CARGO) clippy --workspace --all-targets -- -D warnings

# Every decoder of untrusted input under libFuzzer, FUZZ_SECONDS each (docs/fuzzing.md).
fuzz:
	scripts/fuzz.sh

# Retrains the shipped models (models/*/MODEL_CARD.md) from generated data on the CPU: installs
# PyTorch into .tools/models-venv, generates the data with fixed seeds, trains, exports the ONNX
# files over the committed ones and checks them against PyTorch. About 20 + 10 + 12 minutes on two
# cores; never run by CI.
models: models-grasp-type models-tactile models-recogniser models-grasp-quality

models-grasp-type:
	models/grasp_type/train.sh

models-tactile:
	models/tactile/train.sh

models-recogniser:
	models/recogniser/train.sh

# Labels sampled 2F-85 grasps in MuJoCo (about 27 min on 2 cores), then trains (about 8 min).
models-grasp-quality:
	models/grasp_quality/train.sh

# The in-hand rotation policies of dissertation ch. 7 (docs/in-hand.md): five algorithms × block
# and egg in MuJoCo, IN_HAND_STEPS environment steps each (default 200,000: about 2 h on two
# cores), curves into docs/in-hand/. Not part of `make models`: it ships no model yet.
models-in-hand:
	models/in_hand/train.sh

# The grasp benchmark in MuJoCo (clients/sim/README.md, docs/sim-benchmark.md): starts a release
# graspd on loopback and runs graspd-sim bench with the Robotiq 2F-85, Barrett, Shadow and Allegro
# hands, 20 trials per cell with placements within ±10 cm: the Table 5.2 objects from a single
# RGB-D view, all 13 shared objects, and the Table 5.2 objects from 3 fused views (about 45
# minutes on two cores: 14 + 19 + 14 on 2026-12-03); results in sim-results/. SIM_ARGS="--trials 5 ..." runs one bench with
# those arguments instead.
# `make sim-stabilize` runs the tactile closed loop against a constant-force baseline under an
# added load (graspd-sim stabilize; results in sim-results/).
# `make sim-clutter` runs reach-to-grasp in clutter, laid out like the dissertation's Table 3.1
# (graspd-sim clutter: the 2F-85, each of the 12 shared YCB objects named 4 times among 3–6
# objects, one worker so that the request timings are graspd's own; about a minute; results in
# sim-results/clutter).
SIM_ARGS ?=
sim-bench sim-stabilize sim-clutter: export ORT_DYLIB_PATH = $(CURDIR)/.tools/onnxruntime/libonnxruntime.so.1.31.1
sim-bench sim-stabilize sim-clutter:
	scripts/fetch-onnxruntime.sh
	scripts/fetch-mujoco.sh
	$(CARGO) build --release --bin graspd --bin graspd-sim
	scripts/sim-bench.sh $(patsubst sim-%,%,$@) $(SIM_ARGS)
