# Thin wrapper over CMake. `make run` and `make test` are the README's quick start.
JOBS ?= $(shell nproc)
BUILD ?= build
ASAN_BUILD ?= build-asan

.PHONY: setup build run test test-fast asan fuzz bench install clean

setup:
	bash scripts/setup.sh

# the library and the program built with a profile of a short flume run (scripts/pgo.sh, made
# again only when a source changed; the same bits, faster code); PGO=0 builds without it
PGO ?= 1
build: setup
	@pgo=$$(PGO=$(PGO) bash scripts/pgo.sh $(BUILD)) || exit 1; \
	  set -x; cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release $$pgo
	cmake --build $(BUILD) -j $(JOBS)

# the paper's flume (examples/shibuya2009.yaml), replacing the last `make run`'s outputs; its
# threads pinned one per core unless the environment says otherwise (OMP_PROC_BIND=false to
# leave them free on a shared machine)
run: build
	OMP_PROC_BIND=$${OMP_PROC_BIND:-true} OMP_PLACES=$${OMP_PLACES:-cores} ./$(BUILD)/sabodem run examples/shibuya2009.yaml -o out/shibuya2009 --overwrite

# the whole suite, then again under AddressSanitizer + UndefinedBehaviorSanitizer
test: build
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS)
	$(MAKE) asan

test-fast: build
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS)

asan: setup
	cmake -S . -B $(ASAN_BUILD) -DCMAKE_BUILD_TYPE=RelWithDebInfo -DSD_SANITIZE=ON
	cmake --build $(ASAN_BUILD) -j $(JOBS)
	cd $(ASAN_BUILD) && SD_SANITIZED=1 ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 ctest --output-on-failure -j $(JOBS)

# the program, the shared library, headers, pkg-config file, CMake package, Python package,
# plotting scripts, man page and bash completion under PREFIX (docs/api.md)
PREFIX ?= /usr/local
install: build
	cmake --install $(BUILD) --prefix $(PREFIX)

# the fuzz harnesses (tests/fuzz/) with clang's libFuzzer, each for FUZZ_SECONDS (docs/reliability.md)
FUZZ_SECONDS ?= 60
fuzz:
	bash scripts/setup.sh --fuzz
	FUZZ_SECONDS=$(FUZZ_SECONDS) JOBS=$(JOBS) bash scripts/fuzz.sh

bench: build
	PGO=$(PGO) bash bench/run.sh

clean:
	rm -rf $(BUILD) $(ASAN_BUILD) build-fuzz
