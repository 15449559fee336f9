# Translucency: the two commands a new user needs.
#   make demo   install missing Debian packages, configure, build the command line (the
#               core, the VTK modules, the CLI), render the bunny into out/, then build the
#               plugin (CMake target TranslucencyDemo; no test programs)
#   make test   install missing Debian packages, configure, build everything, run every test but
#               the slow tier with ctest (ctest -LE slow; tiers: Testing/TestTiers.cmake)
#   make test-all   the same with every test, the slow tier included (what CI runs)
# Reliability (Documentation/Reliability.md), each in its own build tree:
#   make test-sanitize   the core's GoogleTests under ASan + UBSan (gcc, build-sanitize)
#   make test-fuzz       a short run of every libFuzzer target (clang, build-fuzz)
#   make fuzz-long       >= 20,000 fuzzed and mutated inputs, summarised (long)
#   make test-soak       the 1,000-step kept-pipeline soak on a 200k-tet sphere (long)
# ccache (scripts/install-deps.sh) shares compiled objects between clones: paths
# below this checkout are hashed relative to it, wherever it is cloned.
export CCACHE_BASEDIR := $(CURDIR)
# The sanitizer and fuzzer trees build with debug info, for which ccache also
# hashes the build directory by default: a fresh clone (CI's) then missed the
# cache for every source. Shared across clones instead; the debug info of a
# cached object names the directory it was first compiled in.
export CCACHE_NOHASHDIR := 1
# Builds run JOBS compilers; `make test` runs TEST_JOBS tests at a time on
# the 2 cores, each with OpenMP's team: a waiting OpenMP thread should sleep,
# not spin on the core another test needs (Documentation/Performance.md,
# "Threads"). Three, not two: a test spends part of its time in one thread
# (process start-up, reading, Python), which a third test fills (README,
# "Time of make test").
export OMP_WAIT_POLICY ?= passive
BUILD_DIR ?= build
JOBS ?= 2
TEST_JOBS ?= 3
CMAKE_ARGS ?=
SANITIZE_DIR ?= build-sanitize
FUZZ_DIR ?= build-fuzz

.PHONY: all deps configure build demo test test-all test-sanitize fuzz-build test-fuzz fuzz-long test-soak bench clean

all: build

deps:
	bash scripts/install-deps.sh

configure: deps
	cmake -S . -B $(BUILD_DIR) -DCMAKE_BUILD_TYPE=Release \
	  -DPython3_EXECUTABLE=/usr/bin/python3 \
	  '-DCMAKE_INSTALL_RPATH=$$ORIGIN/../../..;$$ORIGIN' $(CMAKE_ARGS)

build: configure
	cmake --build $(BUILD_DIR) -j $(JOBS)

# The pictures first (the command line: TranslucencyDemoCommandLine), then the
# plugin and the rest of TranslucencyDemo (Documentation/Building.md).
demo: configure
	cmake --build $(BUILD_DIR) -j $(JOBS) --target TranslucencyDemoCommandLine
	bash scripts/demo.sh $(BUILD_DIR)
	cmake --build $(BUILD_DIR) -j $(JOBS) --target TranslucencyDemo

# Test tiers (ctest LABELS unit, integration, mpi, gui, slow): e.g.
# `cd build && ctest -L unit` for the core alone, `ctest -L slow` for the rest.
test: build
	cd $(BUILD_DIR) && ctest --output-on-failure -j $(TEST_JOBS) -LE slow

test-all: build
	cd $(BUILD_DIR) && ctest --output-on-failure -j $(TEST_JOBS)

# The core and its GoogleTests only (no VTK): every ASan/UBSan finding fails.
# The three refinement studies below run 30-75 s each under ASan and exercise
# no code the other sanitized tests do not (Documentation/Reliability.md);
# they run in `make test-all` (the slow tier).
SANITIZE_EXCLUDE ?= ^(QuadGraph\.RefinementStudyShowsTheSchemeIsInconsistent|FiniteElement\.DivergenceMatchesFemOnTheBunny|FiniteElement\.ConvergenceToManufacturedSolution)$$
test-sanitize: deps
	cmake -S . -B $(SANITIZE_DIR) -DCMAKE_BUILD_TYPE=RelWithDebInfo \
	  -DTRANSLUCENCY_CORE_ONLY=ON -DTRANSLUCENCY_SANITIZE=ON \
	  -DTRANSLUCENCY_USE_HYPRE=OFF
	cmake --build $(SANITIZE_DIR) -j $(JOBS)
	cd $(SANITIZE_DIR) && ASAN_OPTIONS=detect_leaks=1:strict_string_checks=1 \
	  UBSAN_OPTIONS=print_stacktrace=1 \
	  LSAN_OPTIONS=suppressions=$(CURDIR)/Testing/Sanitizers/lsan.supp \
	  ctest --output-on-failure -j $(JOBS) $(if $(SANITIZE_EXCLUDE),-E '$(SANITIZE_EXCLUDE)')

# The libFuzzer targets (clang), each fuzzed for a few seconds plus its regressions.
fuzz-build: deps
	cmake -S . -B $(FUZZ_DIR) -DCMAKE_BUILD_TYPE=RelWithDebInfo \
	  -DCMAKE_C_COMPILER=clang-14 -DCMAKE_CXX_COMPILER=clang++-14 \
	  -DTRANSLUCENCY_BUILD_FUZZERS=ON
	cmake --build $(FUZZ_DIR) -j $(JOBS)

test-fuzz: fuzz-build
	cd $(FUZZ_DIR) && ctest --output-on-failure -j $(JOBS)

# The long campaign (not in CI; hours on a loaded machine): every libFuzzer
# target for FUZZ_RUNS inputs, then the command-line mutation loops of
# scripts/, >= 20,000 cases in all; the table goes to $(FUZZ_DIR)/fuzz-long.md
# (Documentation/Reliability.md).
FUZZ_RUNS ?= 2500
fuzz-long: build fuzz-build
	nice -n 10 /usr/bin/python3 scripts/fuzz_long.py --cli $(BUILD_DIR)/bin/translucency \
	  --fuzz-dir $(FUZZ_DIR) --runs $(FUZZ_RUNS) --jobs $(JOBS) --summary $(FUZZ_DIR)/fuzz-long.md

# 1,000 seeded cuts, paints, relights and solver switches through one kept
# pipeline on a 200k-tet sphere, every invariant after every step and a cold
# solve compared every 25 steps (Documentation/Reliability.md).
test-soak: build
	cd $(BUILD_DIR) && TRANSLUCENCY_SOAK_TETS=200000 TRANSLUCENCY_SOAK_INCREMENTAL_STEPS=1000 \
	  ctest --output-on-failure -R 'Python.TestSoakIncremental$$' --timeout 14400

bench: build
	$(BUILD_DIR)/bin/translucency bench --mesh Data/bunny.ply --tets 100000,1000000 --runs 7

clean:
	rm -rf $(BUILD_DIR) $(SANITIZE_DIR) $(FUZZ_DIR) out
