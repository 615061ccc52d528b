# slamaware: `make demo` and `make test` work on a fresh Debian machine (see README.md).
BUILD   ?= build
JOBS    ?= $(shell nproc)
SHARED  ?= ../shared/data
CTEST_ARGS ?=

.PHONY: all deps build test test-sanitize fuzz soak chaos demo teach eval eval-random bench record synth sample model configs format format-check spy clean

all: build

deps:
	@scripts/install-deps

$(BUILD)/CMakeCache.txt:
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release

build: $(BUILD)/CMakeCache.txt
	cmake --build $(BUILD) -j$(JOBS)

test: deps build
	cd $(BUILD) && ctest --output-on-failure --timeout 1200 $(CTEST_ARGS)

# The whole test suite built with AddressSanitizer + UBSan in $(SAN_BUILD) (scripts/test-sanitize):
# any memory error, leak or undefined behaviour fails the test that hit it.
SAN_BUILD ?= build-sanitize
test-sanitize: deps
	BUILD=$(SAN_BUILD) JOBS=$(JOBS) scripts/test-sanitize $(CTEST_ARGS)

# Every fuzz target (tests/fuzz) for SECONDS s each, clang + libFuzzer + ASan/UBSan in $(FUZZ_BUILD).
SECONDS ?= 60
FUZZ_BUILD ?= build-fuzz
fuzz: deps
	BUILD=$(FUZZ_BUILD) JOBS=$(JOBS) scripts/fuzz $(SECONDS)

# The supervised system on logs/sample.lcm (or SOURCE=...) looping in real time for MINUTES, in a
# private network namespace: memory, CPU, latency, restarts in $(BUILD)/soak/ (report.json, rss.png).
# `make chaos` adds kills, a hang and a damaged map save: $(BUILD)/chaos/ (tools/soak/README.md).
soak: MINUTES ?= 30
soak: deps build
	scripts/netns-run $(BUILD)/bin/slamaware-soak --minutes $(MINUTES) --source $(SOURCE) --out-dir $(BUILD)/soak
chaos: MINUTES ?= 10
chaos: deps build
	scripts/netns-run $(BUILD)/bin/slamaware-soak --chaos --minutes $(MINUTES) --source $(SOURCE) --out-dir $(BUILD)/chaos

# The whole pipeline on the bundled sample (or SOURCE=...), in a private network namespace
# unless NETNS=0 (then it runs on the host bus, ttl=0, for lcm-spy to watch).
SOURCE ?= logs/sample.lcm
NETNS ?= 1
demo: deps build
	scripts/demo "$(SOURCE)" $(NETNS)

# Teaching a new object on real data: the pipeline on views 0-23 of the temple ring, the temple
# labelled in the map, its views harvested, the class added to the model, and the temple's views
# 24-46 and the real UW frames classified before and after (scripts/teach): $(BUILD)/teach/report.md.
teach: deps build
	scripts/teach $(BUILD)

# Evaluation on the default suite or SEQUENCES="dir ..." (MODEL=file: another recognizer model):
# build/eval/report.{json,md} + plots.
eval: deps build
	MODEL="$(MODEL)" scripts/eval $(SEQUENCES)

# Generalisation run: N random scenes from seed SEED (slamaware-synth scene --random), the whole
# pipeline on each: build/eval-random/report.{json,md}, per-scene figures and the worst scene.
N ?= 20
SEED ?= 1
eval-random: deps build
	N=$(N) SEED=$(SEED) MODEL="$(MODEL)" scripts/eval-random

# Benchmarks: build/bench/report.json.
bench: deps build
	scripts/bench

# Records a camera session: make record SOURCE=... OUT=logs/session.lcm
OUT ?= $(BUILD)/record.lcm
record: deps build
	scripts/record "$(SOURCE)" "$(OUT)"

# Synthetic data: every scene of config/scenes (but the sample) into $(BUILD)/data/scenes/<name>,
# every object set of config/objects into $(BUILD)/data/objects/<name>; times and sizes in
# $(BUILD)/data/synth-summary.txt.
synth: deps build
	scripts/synth-all

# Regenerates the bundled sample recording logs/sample.lcm from config/scenes/sample.yaml.
sample: deps build
	scripts/make-sample

# Retrains the shipped recognizer model models/recognizer.model (synthetic 5-class object set, the
# photographed object sets of $(SHARED) when present, and the training scenes of config/training
# with the boxes the proposals stage draws on them; options of config/train-model.yaml; JOBS
# processes or threads at a time; about 50 minutes here on 2 cores without the renderings, 4.5 GB
# peak).
model: deps build
	FORCE=1 TRAIN_CONFIG=config/train-model.yaml PROPOSALS=1 scripts/demo-model

# config/<process>.yaml written from the built-in defaults (`slamaware-<process> --print-config`);
# tests fail when a file and the defaults differ.
configs: build
	for p in camera slam proposals recognizer objectmap; do $(BUILD)/bin/slamaware-$$p --print-config > config/$$p.yaml; done

# The sources against .clang-format (CI runs the check after the tests); `make format` applies it.
format-check: deps
	scripts/format-check
format: deps
	scripts/format-check --fix

spy: build
	scripts/lcm-spy

clean:
	rm -rf $(BUILD)
