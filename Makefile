# mudcrack — the user's entry point. `make demo` and `make test` are the contract (README).
# Each target installs what is missing (Debian 12 packages only), configures a Release build,
# builds, and then runs the demo shot or the test suite.
SHELL      := /bin/bash
.DEFAULT_GOAL := help
BUILD      ?= build
BUILD_TYPE ?= Release
JOBS       ?= $(shell nproc)
OUT        ?= out
CMAKE_ARGS ?=
include pipeline/farm.mk

# One apt-get line: everything the build, the tests, the demo asset and the previews need.
APT_PACKAGES := cmake make g++ pkg-config \
  libeigen3-dev libcgal-dev libgmp-dev libmpfr-dev libassimp-dev libopenvdb-dev libboost-iostreams-dev \
  libosmesa6-dev libtbb-dev libpng-dev zlib1g-dev nlohmann-json3-dev libcli11-dev \
  libgtest-dev libgmock-dev libbenchmark-dev libcgal-demo tetgen ffmpeg \
  slurm-wlm munge jq time

# The demo asset: CGAL's Stanford bunny, extracted from Debian's libcgal-demo (never committed).
CGAL_DATA  := /usr/share/doc/libcgal-dev/data.tar.gz
BUNNY      := shots/assets/bunny00.off

.PHONY: help deps test-deps configure build build-stages demo test bench clean assets shot shots gallery clean-shot \
        blender-addon blender-still fuzz-deps fuzz-build fuzz sanitize format format-check format-deps

# What only `make test` needs: Debian's Blender 3.4 (the add-on's playback test runs it headless)
# and clang-format 14 (the format test, tools/check_format.sh).
# `make demo` never installs it.
TEST_PACKAGES := blender clang-format

# What only `make fuzz` needs: clang and libFuzzer's runtime (Debian 12: clang 14). `make demo`
# and `make test` never install them.
FUZZ_PACKAGES := clang libclang-rt-14-dev
BUILD_FUZZ    ?= build-fuzz
BUILD_ASAN    ?= build-asan
FUZZ_SECONDS  ?= 60

help:
	@echo "make demo                  install missing packages, build, run the demo shot end to end"
	@echo "make test                  install missing packages, build, run the test suite (ctest)"
	@echo "make shot SHOT=x           run shots/x.json's stages (only what changed); FARM=slurm submits to Slurm"
	@echo "make shots                 every shot under shots/ (bench_* excluded)"
	@echo "make gallery               SHOTS (default: every figure shot) run to the end, then the README gallery"
	@echo "make farm-status SHOT=x    queued/running/done/failed tasks of a Slurm run"
	@echo "make report                accuracy against run time and the stability matrix (out/report)"
	@echo "make bench                 build and run the benchmarks"
	@echo "make fuzz                  libFuzzer on every input reader, FUZZ_SECONDS (60) each ($(BUILD_FUZZ))"
	@echo "make format               format every C++ source as .clang-format says (docs/style.md)"
	@echo "make format-check         fail on any source that differs from .clang-format (make test runs it too)"
	@echo "make sanitize              the unit and stage tests under ASan + UBSan ($(BUILD_ASAN))"
	@echo "make blender-addon         the Blender add-on as $(BUILD)/mudcrack_blender.zip (tools/blender)"
	@echo "make blender-still         the demo's last frame rendered by Blender next to mc-render's (docs/blender)"
	@echo "make clean                 remove the build tree"

# install_missing(packages): one apt-get line for those not installed; nothing when all are
define install_missing
	@missing=$$(for p in $(1); do \
	    dpkg-query -W -f='$${Status}\n' $$p 2>/dev/null | grep -q '^install ok installed' || echo $$p; done); \
	if [ -z "$$missing" ]; then exit 0; fi; \
	echo "mudcrack: missing Debian packages:" $$missing; \
	if [ "$$(id -u)" -ne 0 ]; then \
	    echo "mudcrack: not root; install them with: sudo apt-get install -y --no-install-recommends" $$missing; exit 1; fi; \
	(apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends $$missing) \
	  || { echo "mudcrack: apt-get failed installing:" $$missing; exit 1; }
endef

deps:
	$(call install_missing,$(APT_PACKAGES))

test-deps: deps
	$(call install_missing,$(TEST_PACKAGES))

# the house format (.clang-format; docs/style.md): only clang-format is needed
format-deps:
	$(call install_missing,clang-format)

format: format-deps
	tools/check_format.sh --fix

format-check: format-deps
	tools/check_format.sh

assets: $(BUNNY)
$(BUNNY): | deps
	@mkdir -p $(dir $@)
	@test -f $(CGAL_DATA) || { echo "mudcrack: $(CGAL_DATA) not found (package libcgal-demo)"; exit 1; }
	tar -xzf $(CGAL_DATA) -O data/meshes/bunny00.off > $@.tmp && mv $@.tmp $@

$(BUILD)/CMakeCache.txt: | deps
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=$(BUILD_TYPE) $(CMAKE_ARGS)

configure: $(BUILD)/CMakeCache.txt

# everything: libraries, stage binaries, tests, benchmarks, tools, the Blender add-on's zip
build: deps configure
	cmake --build $(BUILD) -j $(JOBS)

# only what a shot runs (the CMake target mudcrack_stages: mc-shot, mc-init, mc-sim, mc-surface,
# mc-render): `make demo` and `make shot` build no test, benchmark or tool
build-stages: deps configure
	@cmake --build $(BUILD) --target help 2>/dev/null | grep -q mudcrack_stages || cmake $(BUILD) >/dev/null
	cmake --build $(BUILD) -j $(JOBS) --target mudcrack_stages

test: test-deps build assets
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS) --timeout 900

# ---- hostile input and memory errors --------------------------------------------------------
# make fuzz: the fuzz targets of tests/fuzz built with clang's libFuzzer, AddressSanitizer and
# UndefinedBehaviorSanitizer, each run FUZZ_SECONDS from its seeds (tools/fuzz.sh)
fuzz-deps: deps
	$(call install_missing,$(FUZZ_PACKAGES))

$(BUILD_FUZZ)/CMakeCache.txt: | fuzz-deps
	CC=clang CXX=clang++ cmake -S . -B $(BUILD_FUZZ) -DCMAKE_BUILD_TYPE=RelWithDebInfo \
	  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g" -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O1 -g" \
	  -DMUDCRACK_FUZZ=ON -DMUDCRACK_SANITIZE="address;undefined" -DMUDCRACK_BUILD_BENCHMARKS=OFF $(CMAKE_ARGS)

fuzz-build: fuzz-deps $(BUILD_FUZZ)/CMakeCache.txt
	cmake --build $(BUILD_FUZZ) -j $(JOBS) --target mudcrack_fuzz_targets

fuzz: fuzz-build
	tools/fuzz.sh $(BUILD_FUZZ) $(FUZZ_SECONDS)

# make sanitize: the unit and stage tests (ctest label "unit", which includes the fuzz targets'
# replays of their seeds and regressions) built with g++ -Og -g1 under ASan + UBSan (line tables
# only: reports still name file and line, and the build is faster than with full debug info);
# the end-to-end tests (figures, report, farm, make, Blender), benchmarks and tools are not built.
# -Og, not -O1: the same checks, compiled in 0.60x the time (18 files, alternated, 2026-11-26),
# for tests that run 1.06x longer (docs/testing.md)
$(BUILD_ASAN)/CMakeCache.txt: | deps
	cmake -S . -B $(BUILD_ASAN) -DCMAKE_BUILD_TYPE=RelWithDebInfo \
	  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-Og -g1 -DNDEBUG" -DCMAKE_C_FLAGS_RELWITHDEBINFO="-Og -g1 -DNDEBUG" \
	  -DMUDCRACK_SANITIZE="address;undefined" -DMUDCRACK_BUILD_BENCHMARKS=OFF -DMUDCRACK_NATIVE=OFF $(CMAKE_ARGS)

sanitize: deps assets $(BUILD_ASAN)/CMakeCache.txt
	cmake --build $(BUILD_ASAN) -j $(JOBS) --target mudcrack_unit_tests
	cd $(BUILD_ASAN) && LSAN_OPTIONS=suppressions=$(CURDIR)/tests/fuzz/lsan.supp:print_suppressions=0 UBSAN_OPTIONS=print_stacktrace=1 \
	  ctest -L unit --output-on-failure -j $(JOBS) --timeout 900

# the README's Blender still of a shot's last frame next to mc-render's (tools/blender_still.sh)
blender-still: test-deps
	@$(MAKE) --no-print-directory shot SHOT=$(or $(SHOT),demo)
	tools/blender_still.sh $(OUT) $(or $(SHOT),demo)

blender-addon: configure
	@cmake --build $(BUILD) --target help 2>/dev/null | grep -q mudcrack_blender_zip || cmake $(BUILD) >/dev/null
	cmake --build $(BUILD) --target mudcrack_blender_zip
	@echo "mudcrack: $(BUILD)/mudcrack_blender.zip: Blender > Preferences > Add-ons > Install..."

bench: build assets
	@for b in $(BUILD)/bin/*_bench; do echo "== $$b"; $$b --benchmark_counters_tabular=true || exit 1; done
	tools/bench_init.sh $(BUILD)

demo: build-stages assets
	@$(MAKE) --no-print-directory shot SHOT=demo

# one shot end to end: only what changed runs (pipeline/shot.mk)
shot: build-stages assets
	@test -n "$(SHOT)" || { echo "usage: make shot SHOT=<name of shots/<name>.json>"; exit 2; }
	@test -f shots/$(SHOT).json || { echo "mudcrack: shots/$(SHOT).json: no such shot"; exit 1; }
	@$(BUILD)/bin/mc-shot validate shots/$(SHOT).json >/dev/null
	@$(MAKE) --no-print-directory -f Makefile -f pipeline/shot.mk \
	    $(if $(filter slurm,$(FARM)),farm-submit,shot-run shot-summary) SHOT=$(SHOT)

SHOTS ?= $(filter-out bench_%,$(basename $(notdir $(wildcard shots/*.json))))
shots: build-stages assets
	@for s in $(SHOTS); do $(MAKE) --no-print-directory shot SHOT=$$s || exit 1; done

# the README's gallery: each of SHOTS run to the end (only what changed runs), then its still,
# contact sheet, mc-measure numbers and stage costs (tools/gallery.sh); GALLERY_FRAMES names a
# frame for a shot, e.g. GALLERY_FRAMES="fig4_bunny@32"
GALLERY_FRAMES ?=
gallery: shots
	cmake --build $(BUILD) -j $(JOBS) --target mc-measure
	BUILD=$(BUILD) THREADS=$(JOBS) tools/gallery.sh $(OUT) \
	    $(foreach s,$(SHOTS),$(or $(filter $(s)@%,$(GALLERY_FRAMES)),$(s)))

clean-shot:
	@test -n "$(SHOT)" || { echo "usage: make clean-shot SHOT=<name>"; exit 2; }
	rm -rf $(OUT)/$(SHOT)

clean:
	rm -rf $(BUILD)

# ---- make report: error against run time, and the stability matrix ----------------
# Writes $(OUT)/report/report.md with PNG Pareto plots (gnuplot, installed here when missing,
# with the same "missing packages" logic as deps). REPORT_ARGS=--quick runs the reduced version.
REPORT_PACKAGES := gnuplot-nox
REPORT_ARGS     ?=
.PHONY: report report-deps
report-deps:
	$(call install_missing,$(REPORT_PACKAGES))

report: build assets report-deps
	$(BUILD)/bin/mc-report --out $(OUT)/report --threads $(JOBS) $(REPORT_ARGS)
