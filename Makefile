# Makefile — the two commands a user types, `make run` and `make test`, and everything behind
# them: the dependency check, the core and proto libraries, the isomesh and isomeshd programs,
# the viewer's npm install, the test suites (also built with ASan+UBSan), benchmarks, fuzzing.
#
# Sources are found by directory, so a new .c file needs no edit here:
#   core/**/*.c            -> libism_core.a   (libc + libm + pthreads only)
#   proto/**/*.c, *.cc     -> libism_proto.a  (jansson, libsodium, Draco)
#   server/common/*.c      -> shared by both programs
#   server/isomesh/*.c     -> isomesh   (CLI and worker)
#   server/isomeshd/*.c    -> isomeshd  (HTTP daemon)
#   tests/unit/core/*.c    -> one Criterion binary against core
#   tests/unit/proto/*.c   -> one Criterion binary against proto + core (+ *.cc helpers)
#   tests/unit/server/*.c  -> one Criterion binary against server/common + proto + core

SHELL := /bin/bash
.DEFAULT_GOAL := all

CC  := gcc
CXX := g++
OUT ?= build/release
SAN ?=
OPT ?= -O2
# Debug information. The sanitizer build of `make test` asks for -g1: line tables and function
# names (all a sanitizer's stack trace prints) for ~40% less compile CPU than full -g
# (draco_encode.cc: 6.7 s against 10.9 s at -O1 with ASan+UBSan).
DEBUG ?= -g
PYTHON ?= python3
LISTEN ?= 127.0.0.1:8080
# The daemon `make run` starts keeps its cache here (one per checkout, not one per user).
CACHE_DIR ?= $(OUT)/cache
# Parallel jobs for the builds behind `make run` and `make test` (all online cores).
JOBS ?= $(shell nproc 2>/dev/null || echo 2)

WARN     := -Wall -Wextra -Werror
CPPFLAGS := -I. -D_GNU_SOURCE -MMD -MP
# -ffp-contract=off: no a * b + c fused into an FMA (ISO C's default under GCC, stated so that
# a change to gnu11 or an fma clone cannot silently break sincos.h's exact steps and the
# scalar/lane bit identity)
CFLAGS   := -std=c11 -ffp-contract=off $(OPT) $(DEBUG) $(WARN) -pthread
CXXFLAGS := -std=c++17 $(OPT) $(DEBUG) $(WARN) -pthread
LDFLAGS  := -pthread
ifeq ($(SAN),1)
  SANFLAGS := -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined
  CFLAGS   += $(SANFLAGS)
  CXXFLAGS += $(SANFLAGS)
  LDFLAGS  += $(SANFLAGS)
  # The evaluators' baseline clones only (core/eval/avx2_clone.h): the release lane of `make
  # test` runs the AVX2 ones on an AVX2 machine, this lane the baseline, both against the same
  # expected bits (the two compile the same source, so the memory checks cover both).
  CPPFLAGS += -DISM_BASELINE_ONLY
endif

PKG_PROTO  := jansson libsodium
PKG_SERVER := libmicrohttpd libseccomp hiredis zlib
pkgcflags = $(shell pkg-config --cflags $(1) 2>/dev/null)
pkglibs   = $(shell pkg-config --libs $(1) 2>/dev/null)

LIBS_CORE   := -lm
LIBS_PROTO  := $(call pkglibs,$(PKG_PROTO)) -ldraco -lstdc++ $(LIBS_CORE)
LIBS_SERVER := $(call pkglibs,$(PKG_SERVER)) $(LIBS_PROTO)
CPPFLAGS    += $(call pkgcflags,$(PKG_PROTO) $(PKG_SERVER))

find_c  = $(shell find $(1) -name '*.c' 2>/dev/null | sort)
find_cc = $(shell find $(1) -name '*.cc' 2>/dev/null | sort)
objs    = $(patsubst %.c,$(OUT)/obj/%.o,$(filter %.c,$(1))) \
          $(patsubst %.cc,$(OUT)/obj/%.o,$(filter %.cc,$(1)))

CORE_SRC    := $(call find_c,core)
PROTO_SRC   := $(call find_c,proto) $(call find_cc,proto)
COMMON_SRC  := $(call find_c,server/common)
ISOMESH_SRC := $(call find_c,server/isomesh)
DAEMON_SRC  := $(call find_c,server/isomeshd)

CORE_LIB  := $(OUT)/libism_core.a
PROTO_LIB := $(OUT)/libism_proto.a
COMMON_LIB := $(OUT)/libism_common.a
ISOMESH   := $(OUT)/isomesh
ISOMESHD  := $(OUT)/isomeshd

UNIT_CORE_SRC   := $(wildcard tests/unit/core/*.c)
UNIT_PROTO_SRC  := $(wildcard tests/unit/proto/*.c tests/unit/proto/*.cc)
UNIT_SERVER_SRC := $(wildcard tests/unit/server/*.c)
BENCH_SRC := $(wildcard tests/bench/*.c)
BENCH_BINS := $(patsubst tests/bench/%.c,$(OUT)/bench/%,$(BENCH_SRC))
UNIT_BINS := $(if $(UNIT_CORE_SRC),$(OUT)/tests/unit_core) \
             $(if $(UNIT_PROTO_SRC),$(OUT)/tests/unit_proto) \
             $(if $(UNIT_SERVER_SRC),$(OUT)/tests/unit_server)
PROGRAMS := $(if $(ISOMESH_SRC),$(ISOMESH)) $(if $(DAEMON_SRC),$(ISOMESHD))

# ---------------------------------------------------------------------------------------
# User-facing targets

.PHONY: all programs run test check-includes deps deps-test deps-bench build unit-bins web-deps test-deps bench soak fuzz clean

all: deps build web-deps

build: $(PROGRAMS) $(UNIT_BINS)

programs: $(PROGRAMS)

# Only what it runs (the two programs, the viewer's npm packages), on every core.
run: deps web-deps
	$(MAKE) -j$(JOBS) programs
	$(ISOMESHD) --listen $(LISTEN) --web-root web --cache-dir $(CACHE_DIR)

# The suites run $(JOBS) at once; the sanitizer build is made while the first release suites run
# (the suites against it wait for it).
test: deps-test check-includes
	$(MAKE) -j$(JOBS) build web-deps test-deps
	$(PYTHON) tests/run_suites.py --jobs $(JOBS) --release build/release --asan build/asan \
	    --asan-build '$(MAKE) -j$(JOBS) OUT=build/asan SAN=1 OPT=-O1 DEBUG=-g1 unit-bins'

# The include rule (server -> proto -> core, no cycles in a folder or between folders): a second.
check-includes:
	$(PYTHON) tests/check_includes.py

# BENCH_ONLY=NAME runs only the benchmark scripts whose name contains NAME (e.g. bench_front).
bench: deps-bench build $(BENCH_BINS)
	$(PYTHON) tests/bench/run_bench.py --build $(OUT) --only "$(BENCH_ONLY)"

# The load/soak benchmark alone (wrk mix for 60 s, RSS series, slowloris): tests/bench/bench_load.py
soak: deps-test build
	$(PYTHON) tests/bench/run_bench.py --build $(OUT) --only bench_load

fuzz: deps-test
	$(MAKE) -C . -f tests/fuzz/fuzz.mk

deps:
	@deploy/install-deps.sh --check run 2>/dev/null || deploy/install-deps.sh run

deps-test:
	@deploy/install-deps.sh --check test 2>/dev/null || deploy/install-deps.sh test

deps-bench:
	@deploy/install-deps.sh --check bench 2>/dev/null || deploy/install-deps.sh bench

unit-bins: $(UNIT_BINS) $(PROGRAMS)

# npm ci only when the lockfile changed since the last install.
web-deps: web/node_modules/.package-lock.json
web/node_modules/.package-lock.json: web/package-lock.json
	cd web && npm ci --no-audit --no-fund
	@touch $@

test-deps: tests/node_modules/.package-lock.json
tests/node_modules/.package-lock.json: tests/package-lock.json
	cd tests && npm ci --no-audit --no-fund
	@touch $@

clean:
	rm -rf build

# ---------------------------------------------------------------------------------------
# Objects, libraries, programs

# The batched interval evaluator runs in round-down mode: gcc must keep its operations as
# written (no -(a*b) for a*(-b), no folding that assumes round-to-nearest); no trapping
# (FP traps are never enabled) lets it compute both sides of a select and so vectorise it.
$(OUT)/obj/core/eval/eval_interval_batch.o: CFLAGS += -frounding-math -fno-trapping-math

$(OUT)/obj/%.o: %.c
	@mkdir -p $(dir $@)
	$(CC) $(CPPFLAGS) $(CFLAGS) -c $< -o $@

$(OUT)/obj/%.o: %.cc
	@mkdir -p $(dir $@)
	$(CXX) $(CPPFLAGS) $(CXXFLAGS) -c $< -o $@

$(CORE_LIB): $(call objs,$(CORE_SRC))
	@mkdir -p $(dir $@)
	rm -f $@ && ar rcs $@ $^

$(PROTO_LIB): $(call objs,$(PROTO_SRC))
	@mkdir -p $(dir $@)
	rm -f $@ && ar rcs $@ $^

$(COMMON_LIB): $(call objs,$(COMMON_SRC))
	@mkdir -p $(dir $@)
	rm -f $@ && ar rcs $@ $^

SERVER_LIBS := $(if $(COMMON_SRC),$(COMMON_LIB)) $(if $(PROTO_SRC),$(PROTO_LIB)) $(CORE_LIB)

$(ISOMESH): $(call objs,$(ISOMESH_SRC)) $(SERVER_LIBS)
	$(CXX) $(LDFLAGS) -o $@ $(call objs,$(ISOMESH_SRC)) $(SERVER_LIBS) $(LIBS_SERVER)

$(ISOMESHD): $(call objs,$(DAEMON_SRC)) $(SERVER_LIBS)
	$(CXX) $(LDFLAGS) -o $@ $(call objs,$(DAEMON_SRC)) $(SERVER_LIBS) $(LIBS_SERVER)

CRITERION := $(call pkglibs,criterion)

$(OUT)/tests/unit_core: $(call objs,$(UNIT_CORE_SRC)) $(CORE_LIB)
	@mkdir -p $(dir $@)
	$(CC) $(LDFLAGS) -o $@ $^ $(CRITERION) $(LIBS_CORE)

$(OUT)/tests/unit_proto: $(call objs,$(UNIT_PROTO_SRC)) $(if $(PROTO_SRC),$(PROTO_LIB)) $(CORE_LIB)
	@mkdir -p $(dir $@)
	$(CXX) $(LDFLAGS) -o $@ $^ $(CRITERION) $(LIBS_PROTO)

$(OUT)/tests/unit_server: $(call objs,$(UNIT_SERVER_SRC)) $(SERVER_LIBS)
	@mkdir -p $(dir $@)
	$(CXX) $(LDFLAGS) -o $@ $^ $(CRITERION) $(LIBS_SERVER)

# Each tests/bench/NAME.c is one benchmark program linked against everything.
$(OUT)/bench/%: $(OUT)/obj/tests/bench/%.o $(SERVER_LIBS)
	@mkdir -p $(dir $@)
	$(CXX) $(LDFLAGS) -o $@ $< $(SERVER_LIBS) $(LIBS_SERVER)

-include $(shell find $(OUT)/obj -name '*.d' 2>/dev/null)
