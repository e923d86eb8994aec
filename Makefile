# idmr — build, test, bench.
#   make [config=release|debug|sanitize]
#        [all|kernels|test|bench|bench-outofcore|demo|report|deps|clean]
#   make fuzz [FUZZ_SECONDS=60]
#
# bin/idmr is the CLI. Every host source outside host/cli/ goes into build/$(config)/libidmr.a,
# which the test and bench programs (tests/test_*.c, tests/bench_*.c) link as well.
#
# Dependencies: compiler and linker flags come from pkg-config for every library that has a .pc
# file (Embree has none on Debian 12 and is linked by name); MPI's, where Open MPI is installed
# (optional: without it idmr builds and runs as one process; `make MPI=0` leaves it out). They
# are written once to build/$(config)/flags.mk, *after* scripts/install-deps.sh has installed what is missing, and
# make reads them from there (it restarts itself once the file is made). The installer runs only
# when something is missing: flags.mk is remade when it does not exist, when the Makefile or the
# installer changed, or when a quick check (pkg-config and Embree's header) finds a gap.

config ?= release
BUILD := build/$(config)

WARNINGS := -Wall -Wextra -Wshadow -Wno-unused-parameter
PKG_MODULES := libxml-2.0 libcjson OpenCL openmesh OpenImageIO assimp zlib
TEST_PKG_MODULES := cmocka
# MPI is optional: where Open MPI's pkg-config file (or mpicc) is found, idmr is built with
# -DIDMR_MPI=1 and runs as MPI ranks under mpirun (host/core/ranks.h); elsewhere, without.
MPI_PKG_MODULE := ompi-c
EMBREE_HEADER := /usr/include/embree3/rtcore.h

CPPFLAGS += -Iinclude -Ihost -DIDMR_ROOT=\"$(CURDIR)\" -DCL_TARGET_OPENCL_VERSION=120
CFLAGS += -std=gnu11 $(WARNINGS) -g -MMD -MP -pthread
CXXFLAGS += -std=c++17 $(WARNINGS) -g -MMD -MP -pthread -Wno-deprecated-copy -Wno-class-memaccess \
            -Wno-maybe-uninitialized

ifeq ($(config),release)
  CFLAGS += -O2
  CXXFLAGS += -O2
else ifeq ($(config),debug)
  CFLAGS += -O0 -DIDMR_CHECK_FINITE
  CXXFLAGS += -O0 -DIDMR_CHECK_FINITE
else ifeq ($(config),sanitize)
  CFLAGS += -O1 -fsanitize=address,undefined -fno-omit-frame-pointer -DIDMR_CHECK_FINITE
  CXXFLAGS += -O1 -fsanitize=address,undefined -fno-omit-frame-pointer -DIDMR_CHECK_FINITE
  LDFLAGS += -fsanitize=address,undefined
  # UB stops the program (UBSan only prints by default); leaks in PoCL and LLVM are not ours.
  export UBSAN_OPTIONS := halt_on_error=1:print_stacktrace=1
  export LSAN_OPTIONS := suppressions=$(CURDIR)/tests/lsan.supp:print_suppressions=0
else ifeq ($(config),fuzz)
  # The libFuzzer targets (make fuzz): clang, coverage in every host object, ASan and UBSan.
  CC := clang
  CXX := clang++
  FUZZ_FLAGS := -O1 -fsanitize=fuzzer-no-link,address,undefined -fno-omit-frame-pointer
  CFLAGS += $(FUZZ_FLAGS)
  CXXFLAGS += $(FUZZ_FLAGS) -Wno-unknown-warning-option
  LDFLAGS += -fsanitize=address,undefined -fsanitize-link-c++-runtime
else
  $(error config must be release, debug, sanitize or fuzz)
endif

# Sources sit one or two folders deep (host/core/scene.c, host/io/mitsuba/mitsuba_shape.c); objects
# and dependency files mirror the tree under $(BUILD)/host/.
LIB_SOURCES := $(filter-out host/cli/%,$(wildcard host/*/*.c host/*/*.cc host/*/*/*.c host/*/*/*.cc))
LIB_OBJECTS := $(patsubst host/%,$(BUILD)/host/%.o,$(LIB_SOURCES))
CLI_OBJECTS := $(patsubst host/%,$(BUILD)/host/%.o,$(wildcard host/cli/*.c))
TEST_PROGRAMS := $(patsubst tests/%.c,$(BUILD)/tests/%,$(wildcard tests/test_*.c))
BENCH_PROGRAMS := $(patsubst tests/%.c,$(BUILD)/tests/%,$(wildcard tests/bench_*.c))

.PHONY: all deps kernels test bench bench-outofcore demo report fuzz fuzz-targets clean FORCE
all: bin/idmr kernels

# ---- dependencies and the flags they give ----

FLAGS := $(BUILD)/flags.mk
ifneq ($(MAKECMDGOALS),clean)
-include $(FLAGS)
endif
DEPS_CHECK := pkg-config --exists $(PKG_MODULES) $(TEST_PKG_MODULES) && test -f $(EMBREE_HEADER)
ifneq ($(shell $(DEPS_CHECK) 2>/dev/null && echo yes),yes)
$(FLAGS): FORCE
endif

# After the installer, what is still missing stops the build with a message (no empty flags).
$(FLAGS): Makefile scripts/install-deps.sh
	@scripts/install-deps.sh
	@$(DEPS_CHECK) || { echo "make: after scripts/install-deps.sh, pkg-config still does not find" \
	    "all of $(PKG_MODULES) $(TEST_PKG_MODULES), or $(EMBREE_HEADER) is missing" >&2; exit 1; }
	@mkdir -p $(dir $@)
	@set -e; cflags=$$(pkg-config --cflags $(PKG_MODULES)); libs=$$(pkg-config --libs $(PKG_MODULES)); \
	 test_libs=$$(pkg-config --libs $(TEST_PKG_MODULES)); \
	 if pkg-config --exists $(MPI_PKG_MODULE); then \
	   mpi_cflags="-DIDMR_MPI=1 $$(pkg-config --cflags $(MPI_PKG_MODULE))"; \
	   mpi_libs=$$(pkg-config --libs $(MPI_PKG_MODULE)); \
	 elif command -v mpicc >/dev/null 2>&1 && mpicc --showme:compile >/dev/null 2>&1; then \
	   mpi_cflags="-DIDMR_MPI=1 $$(mpicc --showme:compile)"; mpi_libs=$$(mpicc --showme:link); \
	 else mpi_cflags=""; mpi_libs=""; fi; \
	 { echo "# written by make from pkg-config: $(PKG_MODULES) $(TEST_PKG_MODULES)"; \
	   echo "PKG_CFLAGS := $$cflags"; echo "PKG_LIBS := $$libs -lembree3"; \
	   echo "TEST_LIBS := $$test_libs"; \
	   echo "# MPI (optional: empty where Open MPI is not installed)"; \
	   echo "MPI_CFLAGS := $$mpi_cflags"; echo "MPI_LIBS := $$mpi_libs"; } > $@.tmp
	@cmp -s $@.tmp $@ && rm -f $@.tmp || mv -f $@.tmp $@

# Installs the Debian packages when one is missing (nothing to do otherwise).
deps:
	@scripts/install-deps.sh

# `make MPI=0` builds without MPI where it is installed (use another BUILD=, or make clean).
ifeq ($(MPI),0)
  MPI_CFLAGS :=
  MPI_LIBS :=
endif
CPPFLAGS += $(PKG_CFLAGS) $(MPI_CFLAGS)
LDLIBS = $(PKG_LIBS) $(MPI_LIBS) -lstdc++ -lm -pthread

# ---- the CLI and the library ----

$(BUILD)/idmr: $(CLI_OBJECTS) $(BUILD)/libidmr.a
	$(CC) $(LDFLAGS) -o $@ $^ $(LDLIBS)

# bin/idmr is the binary of the config last asked for. It is replaced only when it differs, and
# by a rename, so a running idmr (a long render in another terminal) keeps its file and a
# reader never sees half a binary.
bin/idmr: $(BUILD)/idmr FORCE
	@mkdir -p bin
	@cmp -s $< $@ || { cp $< $@.tmp && mv -f $@.tmp $@; }

FORCE:

$(BUILD)/libidmr.a: $(LIB_OBJECTS)
	@rm -f $@
	ar rcs $@ $^

$(BUILD)/host/%.c.o: host/%.c $(FLAGS)
	@mkdir -p $(dir $@)
	$(CC) $(CPPFLAGS) $(CFLAGS) -c -o $@ $<

$(BUILD)/host/%.cc.o: host/%.cc $(FLAGS)
	@mkdir -p $(dir $@)
	$(CXX) $(CPPFLAGS) $(CXXFLAGS) -c -o $@ $<

# Every kernel program variant compiled on the OpenCL device (idmr kernels), again whenever a
# kernel source, a shared layout or the binary changes: a kernel error fails the build.
KERNEL_SOURCES := $(wildcard kernels/*.cl kernels/lib/*.h include/idmr/*.h)
kernels: $(BUILD)/kernels.stamp
$(BUILD)/kernels.stamp: $(BUILD)/idmr $(KERNEL_SOURCES)
	@status=0; $(BUILD)/idmr kernels --quiet || status=$$?; \
	 if [ $$status -eq 2 ]; then echo "make: no OpenCL device: the kernels were not compiled" >&2; \
	 elif [ $$status -ne 0 ]; then exit $$status; else touch $@; fi

# ---- tests and benchmarks ----

# tests/device_test.c, the device-test driver, is linked into every test and bench program.
TEST_DRIVER := $(BUILD)/tests/device_test.o

$(TEST_DRIVER): tests/device_test.c $(FLAGS)
	@mkdir -p $(dir $@)
	$(CC) $(CPPFLAGS) -Itests $(CFLAGS) -c -o $@ $<

$(BUILD)/tests/%: tests/%.c $(TEST_DRIVER) $(BUILD)/libidmr.a $(FLAGS)
	@mkdir -p $(dir $@)
	$(CC) $(CPPFLAGS) -Itests $(CFLAGS) $(LDFLAGS) -o $@ $< $(TEST_DRIVER) $(BUILD)/libidmr.a \
	    $(TEST_LIBS) $(LDLIBS)

# The decimation benchmark compares with meshoptimizer (a reference, not a dependency of idmr;
# it has no pkg-config file).
$(BUILD)/tests/bench_decimation: tests/bench_decimation.c $(BUILD)/libidmr.a $(FLAGS)
	@mkdir -p $(dir $@)
	$(CC) $(CPPFLAGS) -Itests $(CFLAGS) $(LDFLAGS) -o $@ $< $(BUILD)/libidmr.a -lmeshoptimizer $(LDLIBS)

# Runs every test program; scripts/run-tests.sh prints one closing "N passed, N failed" line.
# Mitsuba 3 (test_mitsuba_renders) comes from .venv/, installed first when missing.
test: bin/idmr kernels $(TEST_PROGRAMS)
	@scripts/install-deps.sh --python
	@scripts/run-tests.sh $(TEST_PROGRAMS)

# The benchmark programs, then the reduction error of each method (scripts/bench-reduction-quality).
bench: bin/idmr kernels $(BENCH_PROGRAMS)
	@set -e; for b in $(BENCH_PROGRAMS); do $$b; done
	@scripts/bench-reduction-quality

# A 15-million-vertex scene reduced under a device-memory budget it does not fit
# (scripts/bench-outofcore): about five minutes on 2 cores, so not part of `make bench`.
bench-outofcore: bin/idmr kernels
	@scripts/bench-outofcore

# libFuzzer targets (tests/fuzz/): the scene loader with its includes and meshes, the glTF
# loader (document, checks, Assimp), the pbrt-v4 loader (with an include and a PLY), the
# simulation-file reader (reduce --simulation), and each mesh reader. `make fuzz` installs clang if missing, builds them in build/fuzz and runs each for
# FUZZ_SECONDS (scripts/run-fuzz.sh); test_fuzz_inputs replays their seeds and regressions.
FUZZ_SECONDS ?= 60
FUZZ_MESH_PROGRAMS := $(BUILD)/tests/fuzz_obj $(BUILD)/tests/fuzz_off $(BUILD)/tests/fuzz_ply \
                      $(BUILD)/tests/fuzz_stl
FUZZ_PROGRAMS := $(BUILD)/tests/fuzz_scene $(BUILD)/tests/fuzz_gltf $(BUILD)/tests/fuzz_simulation \
                 $(BUILD)/tests/fuzz_pbrt $(FUZZ_MESH_PROGRAMS)
fuzz:
	@scripts/install-deps.sh --fuzz
	@$(MAKE) --no-print-directory config=fuzz fuzz-targets
	@scripts/run-fuzz.sh $(FUZZ_SECONDS) $(subst $(BUILD),build/fuzz,$(FUZZ_PROGRAMS))

fuzz-targets: $(FUZZ_PROGRAMS)

$(BUILD)/tests/fuzz_scene $(BUILD)/tests/fuzz_gltf $(BUILD)/tests/fuzz_pbrt: $(BUILD)/tests/fuzz_%: tests/fuzz/fuzz_%.c \
                                                  tests/fuzz/fuzz_inputs.h $(BUILD)/libidmr.a $(FLAGS)
	@mkdir -p $(dir $@)
	$(CC) $(CPPFLAGS) -Itests $(CFLAGS) -fsanitize=fuzzer $(LDFLAGS) -o $@ $< $(BUILD)/libidmr.a $(LDLIBS)

$(BUILD)/tests/fuzz_simulation: tests/fuzz/fuzz_simulation.c tests/fuzz/fuzz_inputs.h $(BUILD)/libidmr.a $(FLAGS)
	@mkdir -p $(dir $@)
	$(CC) $(CPPFLAGS) -Itests $(CFLAGS) -fsanitize=fuzzer $(LDFLAGS) -o $@ $< $(BUILD)/libidmr.a $(LDLIBS)

$(FUZZ_MESH_PROGRAMS): $(BUILD)/tests/fuzz_%: tests/fuzz/fuzz_mesh.c tests/fuzz/fuzz_inputs.h \
                                            $(BUILD)/libidmr.a $(FLAGS)
	@mkdir -p $(dir $@)
	$(CC) $(CPPFLAGS) -Itests -DFUZZ_MESH_EXTENSION='".$*"' $(CFLAGS) -fsanitize=fuzzer $(LDFLAGS) \
	    -o $@ $< $(BUILD)/libidmr.a $(LDLIBS)

demo: bin/idmr kernels
	@scripts/demo.sh

# What accuracy costs in time on the shipped scene (scripts/report): out/report/report.md, its
# points.csv and plots; about 9 minutes on 2 cores. Made anew each time.
report: bin/idmr kernels
	@rm -rf out/report
	@scripts/report data/cornell/scene.xml -o out/report

clean:
	rm -rf build bin

-include $(wildcard $(BUILD)/host/*/*.d $(BUILD)/host/*/*/*.d $(BUILD)/tests/*.d)
