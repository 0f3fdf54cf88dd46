# fuzz.mk — `make fuzz`: builds the libFuzzer targets of tests/fuzz/ with clang
# (-fsanitize=fuzzer,address,undefined) into build/fuzz/, runs each for FUZZ_SECONDS from a
# scratch copy of its committed seed corpus and regression inputs, and prints one table:
# target, executions, exec/s, coverage (cov, ft) and crashes. Fails when a target crashed;
# the crashing inputs are in build/fuzz/run/TARGET/artifacts/.
#
#   make fuzz                                  every target, 60 s each
#   make fuzz FUZZ_SECONDS=600 FUZZ_TARGETS=expr
#   make -f tests/fuzz/fuzz.mk fuzz-bins       build only
#
# The core and proto sources are compiled here with clang (coverage + sanitizers), not
# taken from the gcc build; Draco's C++ is never linked (no target needs it).

SHELL := /bin/bash
.DEFAULT_GOAL := fuzz-run

FUZZ_SECONDS ?= 60
FUZZ_TARGETS ?= expr request frame polygonise
FUZZ_OUT     ?= build/fuzz
FUZZ_CC      ?= clang
PYTHON       ?= python3
# FUZZ_KEEP=1 keeps the corpus grown by earlier runs instead of starting from the seeds.
FUZZ_KEEP    ?=

SAN       := -fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer
CFLAGS_FZ := -std=c11 -g -O1 -Wall -Wextra -pthread -I. -D_GNU_SOURCE -MMD -MP \
             $(shell pkg-config --cflags jansson libsodium 2>/dev/null)
LIB_FLAGS := $(CFLAGS_FZ) $(SAN) -fsanitize=fuzzer-no-link
TGT_FLAGS := $(CFLAGS_FZ) -Werror $(SAN) -fsanitize=fuzzer-no-link
LD_FLAGS  := $(SAN) -fsanitize=fuzzer -pthread

CORE_SRC  := $(shell find core -name '*.c' | sort)
PROTO_REQ := proto/request.c proto/request_compile.c proto/request_error.c \
             proto/request_key.c proto/format.c proto/presets.c proto/json_writer.c
LIBS_REQ  := $(shell pkg-config --libs jansson libsodium 2>/dev/null)

fz_objs = $(patsubst %.c,$(FUZZ_OUT)/obj/%.o,$(1))

# What each target links, its -max_len, and its dictionary (if any).
SRC_expr        := $(CORE_SRC)
SRC_polygonise  := $(CORE_SRC)
SRC_request     := $(CORE_SRC) $(PROTO_REQ)
SRC_frame       := proto/frame.c
LIBS_expr       := -lm
LIBS_polygonise := -lm
LIBS_request    := $(LIBS_REQ) -lm
LIBS_frame      :=
MAXLEN_expr       := 4096
MAXLEN_polygonise := 1024
MAXLEN_request    := 8192
MAXLEN_frame      := 4096
DICT_expr         := tests/fuzz/expr.dict
DICT_polygonise   := tests/fuzz/expr.dict
DICT_request      := tests/fuzz/request.dict
DICT_frame        :=

FUZZ_BINS := $(foreach t,$(FUZZ_TARGETS),$(FUZZ_OUT)/fuzz_$(t))

.PHONY: fuzz-run fuzz-bins
.SECONDARY:
fuzz-bins: $(FUZZ_BINS)

$(FUZZ_OUT)/obj/tests/fuzz/%.o: tests/fuzz/%.c
	@mkdir -p $(dir $@)
	$(FUZZ_CC) $(TGT_FLAGS) -c $< -o $@

$(FUZZ_OUT)/obj/%.o: %.c
	@mkdir -p $(dir $@)
	$(FUZZ_CC) $(LIB_FLAGS) -c $< -o $@

.SECONDEXPANSION:
$(FUZZ_OUT)/fuzz_%: $(FUZZ_OUT)/obj/tests/fuzz/fuzz_%.o $$(call fz_objs,$$(SRC_$$*))
	$(FUZZ_CC) $(LD_FLAGS) -o $@ $^ $(LIBS_$*)

# One bounded run of target $(1) (shell text; sets status=1 when libFuzzer fails): a scratch
# corpus from the committed seeds and regression inputs, crashes into artifacts/.
run_target = run=$(FUZZ_OUT)/run/$(1); \
	if [ -z "$(FUZZ_KEEP)" ]; then rm -rf $$run; fi; \
	mkdir -p $$run/corpus $$run/artifacts; rm -f $$run/artifacts/*; \
	for d in tests/fuzz/corpus/$(1) tests/fuzz/regressions/$(1); do \
	  if [ -d $$d ]; then cp -n $$d/* $$run/corpus/ 2>/dev/null || true; fi; \
	done; \
	echo "fuzz: $(1) for $(FUZZ_SECONDS) s (log: $$run/log)"; \
	$(FUZZ_OUT)/fuzz_$(1) $$run/corpus $(if $(DICT_$(1)),-dict=$(DICT_$(1))) \
	  -max_len=$(MAXLEN_$(1)) -timeout=10 -rss_limit_mb=2048 \
	  -max_total_time=$(FUZZ_SECONDS) -print_final_stats=1 \
	  -artifact_prefix=$$run/artifacts/ > $$run/log 2>&1 || status=1;

# The targets one after the other (the machine has two cores and other users), then the table.
fuzz-run: $(FUZZ_BINS)
	@status=0; \
	$(foreach t,$(FUZZ_TARGETS),$(call run_target,$(t))) \
	$(PYTHON) tests/fuzz/fuzz_summary.py $(FUZZ_OUT)/run $(FUZZ_TARGETS) || status=1; \
	exit $$status

-include $(shell find $(FUZZ_OUT)/obj -name '*.d' 2>/dev/null)
