# The two quick-start commands (see README.md). Both install missing Debian packages,
# configure once, build incrementally, then run.
#   make run    the main job: the aneurysm scene, headless, on the default device
#   make test   the whole test suite (ctest), every GPU test with the validation layer's core
#               and synchronization checks on; entries labelled 'manual' (the slow half of
#               GPU-assisted validation) run with: ctest --test-dir build/release -L manual
PRESET ?= release
BUILD := build/$(PRESET)

.PHONY: run test build deps bench clean

run: build
	$(BUILD)/apps/hemo-run scenes/aneurysm.json --out out/aneurysm

test: build
	ctest --test-dir $(BUILD) --output-on-failure -LE manual

bench: build
	$(BUILD)/apps/hemo-bench primitives --json $(BUILD)/bench-primitives.json

build: deps
	@if [ ! -f $(BUILD)/CMakeCache.txt ]; then cmake --preset $(PRESET); fi
	cmake --build $(BUILD)

deps:
	@.ci/install-deps.sh

clean:
	rm -rf build
