# idmr — build, test, bench.  make [config=release|debug|sanitize] [all|test|bench|demo|clean]
#
# bin/idmr is the CLI. Every host source outside host/cli/ goes into build/$(config)/libidmr.a,
# which the test and bench programs (tests/test_*.c, tests/bench_*.c) link as well.
# Kernels are not built here: they are OpenCL C compiled at run time from kernels/.

config ?= release
BUILD := build/$(config)

CC ?= cc
CXX ?= c++
WARNINGS := -Wall -Wextra -Wshadow -Wno-unused-parameter
CPPFLAGS += -Iinclude -Ihost -DIDMR_ROOT=\"$(CURDIR)\" -DCL_TARGET_OPENCL_VERSION=120 \
            $(shell pkg-config --cflags libxml-2.0 libcjson 2>/dev/null)
CFLAGS += -std=gnu11 $(WARNINGS) -g -MMD -MP -pthread
CXXFLAGS += -std=c++17 $(WARNINGS) -g -MMD -MP -pthread -Wno-deprecated-copy -Wno-class-memaccess -Wno-maybe-uninitialized

ifeq ($(config),release)
  CFLAGS += -O2
  CXXFLAGS += -O2
else ifeq ($(config),debug)
  CFLAGS += -O0
  CXXFLAGS += -O0
else ifeq ($(config),sanitize)
  CFLAGS += -O1 -fsanitize=address,undefined -fno-omit-frame-pointer
  CXXFLAGS += -O1 -fsanitize=address,undefined -fno-omit-frame-pointer
  LDFLAGS += -fsanitize=address,undefined
else
  $(error config must be release, debug or sanitize)
endif

LDLIBS := -lOpenCL -lembree3 -lOpenMeshTools -lOpenMeshCore -lOpenImageIO -lOpenImageIO_Util \
          $(shell pkg-config --libs libxml-2.0 libcjson 2>/dev/null) -lstdc++ -lm -pthread

LIB_SOURCES := $(filter-out host/cli/%,$(wildcard host/*/*.c host/*/*.cc))
LIB_OBJECTS := $(patsubst host/%,$(BUILD)/host/%.o,$(LIB_SOURCES))
CLI_OBJECTS := $(patsubst host/%,$(BUILD)/host/%.o,$(wildcard host/cli/*.c))
TEST_PROGRAMS := $(patsubst tests/%.c,$(BUILD)/tests/%,$(wildcard tests/test_*.c))
BENCH_PROGRAMS := $(patsubst tests/%.c,$(BUILD)/tests/%,$(wildcard tests/bench_*.c))

.PHONY: all deps test bench demo clean FORCE
all: bin/idmr

# Installs the Debian packages when one is missing (a quick dpkg query otherwise).
deps:
	@scripts/install-deps.sh

$(BUILD)/idmr: $(CLI_OBJECTS) $(BUILD)/libidmr.a | deps
	$(CC) $(LDFLAGS) -o $@ $^ $(LDLIBS)

# bin/idmr is the binary of the config last asked for: copied every time, so that switching
# config never leaves the other one's binary in place.
bin/idmr: $(BUILD)/idmr FORCE
	@mkdir -p bin
	@cp $< $@

FORCE:

$(BUILD)/libidmr.a: $(LIB_OBJECTS)
	@rm -f $@
	ar rcs $@ $^

$(BUILD)/host/%.c.o: host/%.c | deps
	@mkdir -p $(dir $@)
	$(CC) $(CPPFLAGS) $(CFLAGS) -c -o $@ $<

$(BUILD)/host/%.cc.o: host/%.cc | deps
	@mkdir -p $(dir $@)
	$(CXX) $(CPPFLAGS) $(CXXFLAGS) -c -o $@ $<

# tests/device_test.c, the device-test driver, is linked into every test and bench program.
TEST_DRIVER := $(BUILD)/tests/device_test.o

$(TEST_DRIVER): tests/device_test.c | deps
	@mkdir -p $(dir $@)
	$(CC) $(CPPFLAGS) -Itests $(CFLAGS) -c -o $@ $<

$(BUILD)/tests/%: tests/%.c $(TEST_DRIVER) $(BUILD)/libidmr.a | deps
	@mkdir -p $(dir $@)
	$(CC) $(CPPFLAGS) -Itests $(CFLAGS) $(LDFLAGS) -o $@ $< $(TEST_DRIVER) $(BUILD)/libidmr.a -lcmocka $(LDLIBS)

# The decimation benchmark compares with meshoptimizer (a reference, not a dependency of idmr).
$(BUILD)/tests/bench_decimation: tests/bench_decimation.c $(BUILD)/libidmr.a | deps
	@mkdir -p $(dir $@)
	$(CC) $(CPPFLAGS) -Itests $(CFLAGS) $(LDFLAGS) -o $@ $< $(BUILD)/libidmr.a -lmeshoptimizer $(LDLIBS)

# Runs every test program; scripts/run-tests.sh prints one closing "N passed, N failed" line.
test: bin/idmr $(TEST_PROGRAMS)
	@scripts/run-tests.sh $(TEST_PROGRAMS)

bench: bin/idmr $(BENCH_PROGRAMS)
	@set -e; for b in $(BENCH_PROGRAMS); do $$b; done

demo: bin/idmr
	@scripts/demo.sh

clean:
	rm -rf build bin

-include $(wildcard $(BUILD)/host/*/*.d $(BUILD)/tests/*.d)
