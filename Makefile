# Translucency: the two commands a new user needs.
#   make demo   install missing Debian packages, configure, build, render the bunny into out/
#   make test   install missing Debian packages, configure, build, run every test with ctest
BUILD_DIR ?= build
JOBS ?= 2
CMAKE_ARGS ?=

.PHONY: all deps configure build demo test bench clean

all: build

deps:
	bash scripts/install-deps.sh

configure: deps
	cmake -S . -B $(BUILD_DIR) -DCMAKE_BUILD_TYPE=Release \
	  -DPython3_EXECUTABLE=/usr/bin/python3 \
	  '-DCMAKE_INSTALL_RPATH=$$ORIGIN/../../..;$$ORIGIN' $(CMAKE_ARGS)

build: configure
	cmake --build $(BUILD_DIR) -j $(JOBS)

demo: build
	bash scripts/demo.sh $(BUILD_DIR)

test: build
	cd $(BUILD_DIR) && ctest --output-on-failure -j $(JOBS)

bench: build
	$(BUILD_DIR)/bin/translucency bench --mesh Data/bunny.ply --tets 100000,1000000 --runs 7

clean:
	rm -rf $(BUILD_DIR) out
