# The two quick-start commands (see README.md). Both install missing Debian packages,
# configure once, build incrementally, then run.
#   make run    the main job: the aneurysm scene, headless, on the default device
#   make test   the whole test suite (ctest), every GPU test with the validation layer's core
#               and synchronization checks on; entries labelled 'manual' (the slow half of
#               GPU-assisted validation, the soak) run with: ctest --test-dir build/release -L manual.
#               With the release preset (CI's) it then runs `make sanitize`.
#   make sanitize  the asan preset (AddressSanitizer, UndefinedBehaviorSanitizer, LeakSanitizer)
#               built in build/asan, and its unit and cli entries run, the fuzzers on a short
#               budget (HEMO_FUZZ_MUTANTS); `make test PRESET=asan` runs every entry under it
PRESET ?= release
BUILD := build/$(PRESET)
FUZZ_MUTANTS ?= 400

.PHONY: run test sanitize build deps bench clean

run: build
	$(BUILD)/apps/hemo-run scenes/aneurysm.json --out out/aneurysm

test: build
	ctest --test-dir $(BUILD) --output-on-failure -LE manual
ifeq ($(PRESET),release)
	@$(MAKE) --no-print-directory sanitize
endif

sanitize: deps
	@if [ ! -f build/asan/CMakeCache.txt ]; then cmake --preset asan; fi
	cmake --build build/asan
	HEMO_FUZZ_MUTANTS=$(FUZZ_MUTANTS) ctest --test-dir build/asan --output-on-failure -L 'unit|cli'

bench: build
	$(BUILD)/apps/hemo-bench primitives --json $(BUILD)/bench-primitives.json

build: deps
	@if [ ! -f $(BUILD)/CMakeCache.txt ]; then cmake --preset $(PRESET); fi
	cmake --build $(BUILD)

deps:
	@.ci/install-deps.sh

clean:
	rm -rf build
