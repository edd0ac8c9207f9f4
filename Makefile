# cdemblast: the two commands a newcomer needs.
#   make demo   install dependencies, build (Release), run the bundled example and its report
#   make test   the same build, then every test through CTest
# and the checks of untrusted input that CI runs too (docs/input_safety.md):
#   make sanitize-test   AddressSanitizer + UBSan build (library, program, unit tests), its tests
#   make fuzz-smoke      the two libFuzzer targets (clang) FUZZ_SECONDS each, then the regressions
BUILD ?= build
ASAN_BUILD ?= build-asan
FUZZ_BUILD ?= build-fuzz
FUZZ_SECONDS ?= 45
JOBS ?= $(shell nproc)
PY ?= /usr/bin/python3

.PHONY: all deps deps-test configure build demo test clean format sanitize sanitize-test fuzz fuzz-smoke

all: build

deps:
	@bash scripts/install-deps.sh

deps-test:
	@bash scripts/install-deps.sh --test

$(BUILD)/build.ninja:
	cmake -S . -B $(BUILD) -G Ninja -DCMAKE_BUILD_TYPE=Release

configure: deps $(BUILD)/build.ninja

build: configure
	cmake --build $(BUILD) -j $(JOBS)

demo: build
	bash scripts/demo.sh $(BUILD)/bin/cdemblast runs/demo

# ctest runs tests in parallel, each with OpenMP threads: passive waiting keeps the threads of
# one test from spinning while another test holds the cores (10-100x slower otherwise).
test: deps-test build
	cd $(BUILD) && OMP_WAIT_POLICY=PASSIVE ctest --output-on-failure -j $(JOBS)

# The sanitizer build is also the build without MPI (CDEM_MPI=OFF): CI builds and tests both.
$(ASAN_BUILD)/build.ninja:
	cmake -S . -B $(ASAN_BUILD) -G Ninja -DCMAKE_BUILD_TYPE=Debug -DCDEM_SANITIZE=ON -DCDEM_MPI=OFF

sanitize: deps $(ASAN_BUILD)/build.ninja
	cmake --build $(ASAN_BUILD) -j $(JOBS)

# Leaks inside libgmsh/OpenCASCADE are suppressed (tests/sanitizer/lsan.supp); everything else
# (a leak, an overflow, UB in cdemblast's code) fails the test.
sanitize-test: sanitize
	cd $(ASAN_BUILD) && OMP_WAIT_POLICY=PASSIVE \
	  LSAN_OPTIONS=suppressions=$(CURDIR)/tests/sanitizer/lsan.supp \
	  UBSAN_OPTIONS=print_stacktrace=1 \
	  ctest --output-on-failure -j $(JOBS)

$(FUZZ_BUILD)/build.ninja:
	CC=clang CXX=clang++ cmake -S tests/fuzz -B $(FUZZ_BUILD) -G Ninja

fuzz: deps $(FUZZ_BUILD)/build.ninja
	cmake --build $(FUZZ_BUILD) -j $(JOBS)

fuzz-smoke: fuzz
	bash scripts/fuzz.sh -b $(FUZZ_BUILD) -t $(FUZZ_SECONDS)

format:
	find src apps tests bench -name '*.[ch]pp' | xargs clang-format -i

clean:
	rm -rf $(BUILD) $(ASAN_BUILD) $(FUZZ_BUILD)
