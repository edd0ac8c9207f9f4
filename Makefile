# cdemblast: the two commands a newcomer needs.
#   make demo   install dependencies, build (Release), run the bundled example and its report
#   make test   the same build, then every test through CTest
BUILD ?= build
JOBS ?= $(shell nproc)
PY ?= /usr/bin/python3

.PHONY: all deps configure build demo test clean format

all: build

deps:
	@bash scripts/install-deps.sh

$(BUILD)/build.ninja:
	cmake -S . -B $(BUILD) -G Ninja -DCMAKE_BUILD_TYPE=Release

configure: deps $(BUILD)/build.ninja

build: configure
	cmake --build $(BUILD) -j $(JOBS)

demo: build
	bash scripts/demo.sh $(BUILD)/bin/cdemblast runs/demo

# ctest runs tests in parallel, each with OpenMP threads: passive waiting keeps the threads of
# one test from spinning while another test holds the cores (10-100x slower otherwise).
test: build
	cd $(BUILD) && OMP_WAIT_POLICY=PASSIVE ctest --output-on-failure -j $(JOBS)

format:
	find src apps tests bench -name '*.[ch]pp' | xargs clang-format -i

clean:
	rm -rf $(BUILD)
